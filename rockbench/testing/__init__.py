"""Consistency checks for your own test suites.

* :func:`assert_agree` - does a backend's run agree with the analytic reference (peak rotation,
  history, eta of every impact, overturning verdict)? Raises ``AssertionError`` saying which
  metric failed, by how much and where in time.
* :func:`check_backend` - does a backend adapter (a new or modified one) honour the contract of
  :mod:`rockbench.engines.base`? Like Gymnasium's environment checker.
* a pytest plugin (installed with rockbench, :mod:`rockbench.testing.plugin`): the fixture
  ``rockbench_backend`` is parametrized over the registered engines (those that cannot run
  here skipped with the reason; :func:`engine_params` for your own ``parametrize``), ``rockbench_reference``
  runs (and caches) the analytic reference. See ``docs/testing.md``.

Modules: :mod:`~rockbench.testing.agree` (``assert_agree``), :mod:`~rockbench.testing.contract`
(``check_backend`` and its ``check_*`` functions), :mod:`~rockbench.testing.plugin`. The names
are imported on first use, so that the pytest plugin (a submodule, loaded by every pytest run)
stays cheap to import.
"""

from __future__ import annotations

from typing import Any

__all__ = ["assert_agree", "check_backend", "BackendReport", "Check", "engine_params",
           "needs_engine"]

#: Public name -> the submodule that defines it.
_HOME = {"assert_agree": "agree", "check_backend": "contract", "BackendReport": "contract",
         "Check": "contract", "engine_params": "plugin",
         "needs_engine": "plugin"}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        from importlib import import_module

        return getattr(import_module(f"{__name__}.{_HOME[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)

"""pytest plugin registered by rockbench (entry point ``pytest11``), loaded by every pytest run
in an environment where rockbench is installed.

Fixtures
--------
``rockbench_backend``
    The name of a backend (str). A test that requests it runs once per available engine
    (the analytic reference excluded), test ids ``[pymunk]``, ``[mujoco]``, ...; with no engine
    available the test is skipped. ``--rockbench-engines=pymunk,mujoco`` restricts the list.
``rockbench_reference``
    A function ``reference(scene, motion=None, *, duration=None, phi0=0.0, **settings) ->
    Result`` running the analytic reference, cached for the session (a test parametrized over
    four engines computes it once).

Importing this module is cheap: rockbench and the engines are imported only when a test asks for
one of the fixtures.
"""

from __future__ import annotations

from typing import Any

import pytest

_OPTION = "--rockbench-engines"
_available_cache: list[str] | None = None


def pytest_addoption(parser: Any) -> None:
    group = parser.getgroup("rockbench")
    group.addoption(_OPTION, action="store", default=None, metavar="NAMES",
                    help="comma-separated backends for the rockbench_backend fixture "
                         "(default: every available engine, analytic excluded)")


def _engines(config: Any) -> list[str]:
    global _available_cache
    if _available_cache is None:
        from rockbench.engines import available_backends  # imported only when used

        _available_cache = [n for n in available_backends() if n != "analytic"]
    wanted = config.getoption(_OPTION) if config is not None else None
    if not wanted:
        return list(_available_cache)
    names = [n.strip() for n in wanted.split(",") if n.strip()]
    from rockbench.engines import REGISTRY

    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        raise pytest.UsageError(f"{_OPTION}: unknown backend(s) {unknown}; registered: "
                                f"{', '.join(REGISTRY)}")
    return [n for n in names if n in _available_cache]


def pytest_generate_tests(metafunc: Any) -> None:
    if "rockbench_backend" in metafunc.fixturenames:
        names = _engines(metafunc.config)
        metafunc.parametrize("rockbench_backend", names, ids=names, indirect=True)


@pytest.fixture
def rockbench_backend(request):
    """Name of an available engine backend (str): the test runs once per engine."""
    return request.param


@pytest.fixture(scope="session")
def rockbench_reference():
    """``reference(scene, motion=None, *, duration=None, phi0=0.0, **settings) -> Result``:
    the analytic run of the case, computed once per session."""
    import rockbench as rb

    cache: dict[Any, Any] = {}

    def reference(scene, motion=None, *, duration=None, phi0=0.0, **settings):
        key = (id(scene), repr(scene), repr(motion.describe()) if motion is not None else None,
               duration, float(phi0), tuple(sorted((k, repr(v)) for k, v in settings.items())))
        if key not in cache:
            cache[key] = (scene, rb.run(scene, motion, engine="analytic", duration=duration,
                                        phi0=phi0, **settings))
        return cache[key][1]

    return reference

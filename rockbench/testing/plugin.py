"""pytest plugin registered by rockbench (entry point ``pytest11``), loaded by every pytest run
in an environment where rockbench is installed.

Fixtures
--------
``rockbench_backend``
    The name of a backend (str). A test that requests it runs once per **registered** engine
    (the analytic reference excluded), test ids ``[pymunk]``, ``[mujoco]``, ...; an engine that
    cannot run here is a skipped test whose reason says why and what installs it (never a test
    that silently does not exist). ``--rockbench-engines=pymunk,mujoco`` restricts the list.
``rockbench_reference``
    A function ``reference(scene, motion=None, *, duration=None, phi0=0.0, **settings) ->
    Result`` running the analytic reference, cached for the session (a test parametrized over
    four engines computes it once).

:func:`engine_params` gives the same parametrization to a test's own ``parametrize``. With the
environment variable ``ROCKBENCH_REQUIRE_ENGINES`` set (``all`` or names), a required engine
that cannot run is an error instead of a skip: the run stops at its start, naming it.

Importing this module is cheap: rockbench and the engines are imported only when a test asks for
one of the fixtures.
"""

from __future__ import annotations

from typing import Any

import pytest

_OPTION = "--rockbench-engines"


def pytest_configure(config: Any) -> None:
    config.addinivalue_line("markers", "rockbench_engine(name): the test runs backend NAME "
                                       "(rockbench.testing.needs_engine)")


def pytest_addoption(parser: Any) -> None:
    group = parser.getgroup("rockbench")
    group.addoption(_OPTION, action="store", default=None, metavar="NAMES",
                    help="comma-separated backends for the rockbench_backend fixture "
                         "(default: every registered engine, analytic excluded; those that "
                         "cannot run here are skipped with the reason)")


def engine_params(*, analytic: bool = False, names: list[str] | None = None) -> list[Any]:
    """``pytest.param`` per registered backend (``names``: these, in this order; ``analytic``:
    include the reference), each engine that cannot run here marked skip with its reason and
    remedy. Raises ``pytest.UsageError`` when ``ROCKBENCH_REQUIRE_ENGINES`` requires one of
    them and it cannot run."""
    from rockbench.engines import REGISTRY, engine_info, required_engines
    from rockbench.errors import RockbenchError

    chosen = list(REGISTRY) if names is None else list(names)
    if not analytic:
        chosen = [n for n in chosen if n != "analytic"]
    try:
        required = set(required_engines())
    except RockbenchError as e:
        raise pytest.UsageError(str(e)) from None
    out = []
    for r in engine_info(chosen):
        if r["available"]:
            out.append(pytest.param(r["name"], id=r["name"]))
            continue
        why = f"{r['name']} cannot run here: {r['reason']}; remedy: {r['remedy']}"
        if r["name"] in required:
            raise pytest.UsageError(f"ROCKBENCH_REQUIRE_ENGINES requires it: {why}")
        out.append(pytest.param(r["name"], id=r["name"], marks=pytest.mark.skip(reason=why)))
    return out


def needs_engine(name: str) -> Any:
    """A ``pytest.mark.skip`` with the reason and remedy when backend ``name`` cannot run here
    (a no-op mark when it can; a usage error when ``ROCKBENCH_REQUIRE_ENGINES`` requires it)."""
    (param,) = engine_params(analytic=True, names=[name])
    skip = [m for m in param.marks if m.name == "skip"]
    return skip[0] if skip else pytest.mark.rockbench_engine(name)


def _engines(config: Any) -> list[Any]:
    wanted = config.getoption(_OPTION) if config is not None else None
    if not wanted:
        return engine_params()
    names = [n.strip() for n in wanted.split(",") if n.strip()]
    from rockbench.engines import REGISTRY

    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        raise pytest.UsageError(f"{_OPTION}: unknown backend(s) {unknown}; registered: "
                                f"{', '.join(REGISTRY)}")
    return engine_params(names=names)


def pytest_generate_tests(metafunc: Any) -> None:
    if "rockbench_backend" in metafunc.fixturenames:
        metafunc.parametrize("rockbench_backend", _engines(metafunc.config), indirect=True)


@pytest.fixture
def rockbench_backend(request):
    """Name of an engine backend (str): the test runs once per registered engine (skipped,
    with the reason, where it cannot run)."""
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

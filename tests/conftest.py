"""Suite-wide options and the engines' account.

* Slow tests run only with ``--run-slow`` (CI runs them separately).
* An engine that cannot run here is skipped by every test that needs it, with the reason and
  the remedy (:func:`rockbench.testing.engine_params`), and the run ends by naming each such
  engine in one line. With ``ROCKBENCH_REQUIRE_ENGINES`` set (``all`` or names; ``.ci/run``
  sets it for the engines it installs) a required engine that cannot run stops the run at its
  start instead: a missing engine turns CI red rather than making the suite smaller.
"""

import pytest


def pytest_addoption(parser):
    parser.addoption("--run-slow", action="store_true", default=False,
                     help="also run tests marked slow (exhaustive checks)")


def pytest_configure(config):
    if hasattr(config, "workerinput"):       # an xdist worker: the controller checked it
        return
    from rockbench.engines import check_required
    from rockbench.errors import RockbenchError

    try:
        check_required()
    except RockbenchError as e:
        raise pytest.UsageError(str(e)) from None


def pytest_collection_modifyitems(config, items):
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: run with --run-slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def pytest_terminal_summary(terminalreporter):
    from rockbench.engines import unavailable_lines

    lines = unavailable_lines()
    if lines:
        terminalreporter.section("rockbench: engines not tested here")
        for line in lines:
            terminalreporter.write_line(line)

"""rockbench.testing: assert_agree, check_backend and the pytest plugin."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import rockbench as rb
from rockbench.engines import available_backends
from rockbench.testing import engine_params
from rockbench.engines.analytic import AnalyticBackend
from rockbench.testing import assert_agree, check_backend

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[1]
BLOCK = rb.load_scene("housner-block")
PULSE = rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=BLOCK.structure)
ENGINES = [n for n in available_backends() if n != "analytic"]


@pytest.fixture(scope="module")
def ref():
    return rb.run(BLOCK, PULSE, duration=6.0)


def _phi(r, phi):
    h = r.history.copy()
    h["phi"] = phi
    mx = float(np.max(np.abs(phi)))
    s = replace(r.summary, max_abs_phi=mx, max_abs_phi_over_alpha=mx / r.scene.alpha)
    return replace(r, backend="fake", history=h, summary=s)


# --- assert_agree ----------------------------------------------------------------------------
def test_a_run_agrees_with_itself(ref):
    assert ref.summary.n_impacts >= 2
    assert_agree(ref, ref)


def test_peak_failure_says_by_how_much_and_when(ref):
    fake = _phi(ref, 1.05 * ref.history["phi"].to_numpy())
    with pytest.raises(AssertionError) as e:
        assert_agree(fake, ref, nrmse=None)
    msg = str(e.value)
    t_peak = ref.history["t"].iloc[int(np.argmax(np.abs(ref.history["phi"])))]
    assert "1 of 3 checks failed" in msg and "peak:" in msg and "off by +5 %" in msg
    assert f"t = {t_peak:.4g} s" in msg and "tolerance 3 %" in msg
    assert_agree(fake, ref, peak_rtol=0.06, nrmse=None)      # within a looser tolerance


def test_nrmse_failure_points_at_the_largest_error(ref):
    t = ref.history["t"].to_numpy()
    bump = 0.2 * BLOCK.alpha * np.exp(-((t - 1.0) / 0.05) ** 2)
    fake = _phi(ref, ref.history["phi"].to_numpy() + bump)
    with pytest.raises(AssertionError) as e:
        assert_agree(fake, ref, peak_rtol=None)
    msg = str(e.value)
    assert "nrmse:" in msg and "largest error +0.2 alpha at t = 1 s" in msg
    assert "peak" not in msg


def test_eta_failure_names_the_impact(ref):
    ev = ref.events.copy()
    imp = ev.index[ev["kind"] == "impact"]
    ev.loc[imp[1], "eta"] *= 1.01
    fake = replace(ref, backend="fake", events=ev)
    with pytest.raises(AssertionError) as e:
        assert_agree(fake, ref)
    msg = str(e.value)
    assert "eta: impact 1 at t = " + f"{ev.loc[imp[1], 't']:.4g} s" in msg
    assert "off by +1 %" in msg and "1 of 2 measured impacts outside: 1" in msg
    assert_agree(fake, ref, eta_rtol=0.02)


def test_verdict_failure_and_skipping_it(ref):
    s = replace(ref.summary, overturned=True, t_overturn=2.5)
    fake = replace(ref, backend="fake", summary=s)
    with pytest.raises(AssertionError, match="verdict: fake overturned at t = 2.5 s, the "
                                             "reference analytic did not overturn"):
        assert_agree(fake, ref)
    assert_agree(fake, ref, verdict=False)


def test_a_diverged_run_fails_at_once(ref):
    s = replace(ref.summary, status="diverged", reason="NaN at t=1 s")
    with pytest.raises(AssertionError, match="is diverged: NaN at t=1 s"):
        assert_agree(replace(ref, summary=s), ref)


def test_runs_of_another_case_are_refused(ref):
    """assert_agree compares two runs of one case: another scene, motion or phi0 is a
    ParameterError naming what differs, never a pass (issue 15)."""
    other_scene = replace(ref, scene=rb.Scene(rb.Block(width=1.0, height=4.0), name="other"))
    with pytest.raises(rb.ParameterError, match="same scene parameters.*differ in structure"):
        assert_agree(other_scene, ref)
    renamed = replace(ref, scene=replace(BLOCK, name="renamed", description="a label"))
    assert_agree(renamed, ref)                     # a name is not a parameter
    weaker = rb.RickerPulse.dimensionless(A=2.0, W=4.0, structure=BLOCK.structure)
    with pytest.raises(rb.ParameterError, match="same ground motion"):
        assert_agree(replace(ref, motion=weaker.describe()), ref)
    free = rb.run(BLOCK, None, phi0=0.5 * BLOCK.alpha, duration=1.0)
    with pytest.raises(rb.ParameterError, match="same ground motion"):
        assert_agree(free, ref)
    other_phi0 = rb.run(BLOCK, None, phi0=0.3 * BLOCK.alpha, duration=1.0)
    with pytest.raises(rb.ParameterError, match="same initial rotation"):
        assert_agree(other_phi0, free)
    assert_agree(free, free)


def test_assert_agree_defaults_are_the_tolerance_table():
    import inspect

    from rockbench.comparison import TOLERANCES

    sig = inspect.signature(assert_agree).parameters
    assert {k: sig[k].default for k in TOLERANCES["assert_agree"]} == TOLERANCES["assert_agree"]
    assert TOLERANCES["assert_agree"] == dict(peak_rtol=0.03, eta_rtol=0.005, nrmse=0.005,
                                              verdict=True)


def test_bad_tolerances_raise_parameter_error(ref):
    with pytest.raises(rb.ParameterError, match="peak_rtol"):
        assert_agree(ref, ref, peak_rtol=-0.1)
    with pytest.raises(rb.ParameterError, match="reference"):
        assert_agree(ref, "analytic")


# --- check_backend ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", engine_params(analytic=True))
def test_shipped_backends_pass_the_contract(name):
    """Every available backend, the analytic reference included, honours the contract."""
    report = check_backend(name)
    assert report.ok and not report.failed
    names = [c.name for c in report.checks]
    assert names == ["available", "settings", "schema", "units", "phi definition",
                     "repeatability", "free-rocking eta", "bad input", "divergence reported"]
    assert {c.status for c in report.checks} <= {"pass", "skip"}
    assert "free-rocking eta" in str(report)


class _Degrees(AnalyticBackend):
    """Reports phi in degrees: breaks the phi definition and the units."""

    name = "degrees"

    def run(self, motion=None, *, duration=None, phi0=0.0):
        r = super().run(motion, duration=duration, phi0=phi0)
        h = r.history.copy()
        h["phi"] = np.degrees(h["phi"])
        return replace(r, backend=self.name, history=h)


class _Noisy(AnalyticBackend):
    """Not repeatable, and lax about its input."""

    name = "noisy"
    _rng = np.random.default_rng()

    def run(self, motion=None, *, duration=None, phi0=0.0):
        if duration is not None:
            duration = abs(duration)
        r = super().run(motion, duration=duration, phi0=phi0)
        h = r.history.copy()
        h["phi"] = h["phi"] + 1e-9 * self._rng.standard_normal(len(h))
        return replace(r, backend=self.name, history=h)


def test_a_backend_reporting_degrees_fails_phi_definition_and_units():
    with pytest.raises(AssertionError) as e:
        check_backend(_Degrees)
    msg = str(e.value)
    assert "phi definition: history starts at phi = +5.65" in msg  # 0.0987 rad in degrees
    assert "units:" in msg and "summary.max_abs_phi" in msg
    assert "repeatability" not in msg


def test_a_non_repeatable_lax_backend_fails_those_checks():
    with pytest.raises(AssertionError) as e:
        check_backend(_Noisy)
    msg = str(e.value)
    assert "repeatability: two identical runs differ: history column 'phi'" in msg
    assert "bad input: duration=-1 did not raise" in msg
    assert "phi definition" not in msg and "free-rocking eta" not in msg


@pytest.mark.skipif("pymunk" not in ENGINES, reason="pymunk not installed")
def test_an_engine_that_raises_instead_of_reporting_divergence_fails():
    from rockbench.engines.pymunk import PymunkBackend

    class Raising(PymunkBackend):
        name = "raising"

        def run(self, motion=None, *, duration=None, phi0=0.0):
            r = super().run(motion, duration=duration, phi0=phi0)
            if r.status == "diverged":
                raise RuntimeError(r.summary.reason)
            return r

    with pytest.raises(AssertionError, match=r"divergence reported: raised RuntimeError: "
                                             r"penetration"):
        check_backend(Raising)


def test_check_backend_rejects_unknown_names():
    with pytest.raises(rb.ParameterError, match="engine"):
        check_backend("nope")


# --- the pytest plugin -----------------------------------------------------------------------
REGISTERED = [n for n in rb.backend_names() if n != "analytic"]


def test_plugin_parametrizes_over_the_registered_engines(pytester):
    example = (ROOT / "tests" / "user_example" / "test_my_scene.py").read_text()
    pytester.makepyfile(test_plugin_example=example)
    res = pytester.runpytest_inprocess("--collect-only", "-q", "-p", "no:cacheprovider",
                                       "-p", "no:hypothesispytest", "-p", "no:xdist")
    ids = [ln.split("[")[1].rstrip("]") for ln in res.outlines if "::" in ln]
    assert ids == REGISTERED


def _ids(params):
    return [p.id for p in params]


def test_plugin_option_restricts_the_engines():
    from rockbench.testing import plugin

    class Config:
        def __init__(self, value):
            self.value = value

        def getoption(self, name):
            assert name == "--rockbench-engines"
            return self.value

    assert _ids(plugin._engines(Config(None))) == REGISTERED
    assert _ids(plugin._engines(Config(",".join(reversed(REGISTERED))))) == REGISTERED[::-1]
    with pytest.raises(pytest.UsageError, match="nope"):
        plugin._engines(Config("pymunk,nope"))


@pytest.fixture
def missing_engine(monkeypatch):
    """pymunk made unavailable for this test (its once-per-process answer replaced)."""
    from rockbench.engines import base, get_backend

    cls = get_backend("pymunk")
    monkeypatch.setitem(base._STATUS, cls, (False, "pymunk does not import: planted"))
    monkeypatch.delenv("ROCKBENCH_REQUIRE_ENGINES", raising=False)
    return "pymunk"


def test_a_missing_engine_is_a_skipped_test_with_the_reason_and_remedy(missing_engine):
    (p,) = engine_params(names=[missing_engine])
    (mark,) = p.marks
    assert mark.name == "skip"
    assert "planted" in mark.kwargs["reason"] and "pip install 'rockbench[pymunk]'" in \
        mark.kwargs["reason"]
    assert missing_engine not in rb.available_backends()
    assert any(line.startswith("pymunk: ") for line in rb.engines.unavailable_lines())


def test_a_required_engine_that_is_missing_is_an_error(missing_engine, monkeypatch, capsys):
    from rockbench.cli.main import main
    from rockbench.errors import BackendUnavailable

    monkeypatch.setenv("ROCKBENCH_REQUIRE_ENGINES", "pymunk,mujoco")
    with pytest.raises(pytest.UsageError, match="requires it: pymunk cannot run here: .*planted"):
        engine_params()
    with pytest.raises(BackendUnavailable, match="pymunk: pymunk does not import: planted"):
        rb.available_backends()
    assert main(["report", "--quick", "--out", "/nonexistent/never-written"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ROCKBENCH_REQUIRE_ENGINES" in err[0] and "pymunk" in err[0]
    monkeypatch.setenv("ROCKBENCH_REQUIRE_ENGINES", "pymunk,nope")
    with pytest.raises(rb.ParameterError, match="ROCKBENCH_REQUIRE_ENGINES"):
        rb.available_backends()


def test_availability_is_decided_once_per_process_and_an_interrupt_decides_nothing(monkeypatch):
    from rockbench.engines import base
    from rockbench.engines.analytic import AnalyticBackend

    calls = []

    class Probed(AnalyticBackend):
        name = "probed"

        @classmethod
        def _probe(cls):
            calls.append(1)
            if len(calls) == 1:
                raise KeyboardInterrupt
            if len(calls) == 2:
                raise RuntimeError("first answer")
            return True, "later answer"

    monkeypatch.setattr(base, "_STATUS", {})
    with pytest.raises(KeyboardInterrupt):
        Probed.available()
    assert Probed.available() == (False, "RuntimeError: first answer")
    for _ in range(5):                     # decided: the probe is not asked again
        assert Probed.available() == (False, "RuntimeError: first answer")
    assert len(calls) == 2


def test_user_example_is_the_one_in_the_docs():
    example = (ROOT / "tests" / "user_example" / "test_my_scene.py").read_text()
    doc = (ROOT / "docs" / "testing.md").read_text()
    body = example.split('"""', 2)[2].strip()
    assert body in doc
    assert len([ln for ln in body.splitlines() if ln.strip()]) <= 10


def test_plugin_import_is_cheap():
    code = ("import sys, rockbench.testing.plugin; "
            "print(sorted(m for m in ('pymunk', 'mujoco', 'pybullet', 'scipy', "
            "'rockbench.testing.contract', 'rockbench.testing.agree', 'rockbench.comparison', "
            "'rockbench.engines.pymunk') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


# --- assert_agree with the analytic model's sensitivity band (issue 14) ----------------------
def test_band_option_judges_the_peak_against_the_models_own_sensitivity(ref):
    from rockbench.studies.sensitivity import band

    b = band(BLOCK, PULSE, duration=6.0)
    assert b.high > b.nominal
    assert_agree(ref, ref, band=b)
    # a peak inside the band passes even under a tolerance it would fail without the band
    f = 1.0 + 0.5 * (b.high / b.nominal - 1.0)
    inside = _phi(ref, f * ref.history["phi"].to_numpy())
    with pytest.raises(AssertionError):
        assert_agree(inside, ref, peak_rtol=1e-6, nrmse=None, eta_rtol=None)
    assert_agree(inside, ref, peak_rtol=1e-6, nrmse=None, eta_rtol=None, band=b)
    # a deliberately wrong result (history x 1.3) falls outside, and the message says by how much
    wrong = _phi(ref, 1.3 * ref.history["phi"].to_numpy())
    with pytest.raises(AssertionError) as e:
        assert_agree(wrong, ref, nrmse=None, eta_rtol=None, band=b)
    msg = str(e.value)
    assert "sensitivity band" in msg and "outside it, by" in msg
    with pytest.raises(rb.ParameterError, match="band"):
        assert_agree(ref, ref, band="not a band")
    with pytest.raises(rb.ParameterError, match="band"):
        assert_agree(ref, ref, band=replace(b, scene="another"))

"""Which path the analytic backend takes (``AnalyticSettings.method``): records through the
compiled path by default ("auto", when numba imports), pulses and free rocking through
``solve_ivp``; ``method="DOP853"`` chooses ``solve_ivp`` for a record, ``"compiled"`` the numba
path for anything. Both agree on the well-conditioned quantities (docs/reproducibility.md)."""

from __future__ import annotations

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic import kernels
from rockbench.analytic.compiled import NUMBA_AVAILABLE
from rockbench.analytic.solver import AnalyticSettings
from rockbench.errors import ParameterError
from rockbench.scene.motion import RickerPulse
from rockbench.scene.records import load_bundled

needs_numba = pytest.mark.skipif(not NUMBA_AVAILABLE, reason="numba not available")
SCENE = rb.load_scene("paper-asymmetric")
DURATION = 3.0      # s of El Centro 1940: uplift at 1.69 s, then 60 impacts


@pytest.fixture(scope="module")
def record():
    return load_bundled("IV1940_ElCentro_180")


def test_default_method_is_auto():
    assert AnalyticSettings().method == "auto"


@needs_numba
def test_record_runs_compiled_by_default_and_solve_ivp_on_request(record):
    fast = rb.run(SCENE, record, duration=DURATION)
    plain = rb.run(SCENE, record, duration=DURATION, method="DOP853")
    assert fast.settings["path"] == "compiled" and fast.settings["method"] == "auto"
    assert plain.settings["path"] == "solve_ivp"
    assert fast.summary.uplifted and fast.summary.n_impacts > 10
    # the well-conditioned quantities agree (docs/reproducibility.md)
    for k in ("overturned", "exceeded_critical", "fractured", "uplifted", "status"):
        assert getattr(fast.summary, k) == getattr(plain.summary, k), k
    assert fast.summary.max_abs_phi_over_alpha == pytest.approx(
        plain.summary.max_abs_phi_over_alpha, abs=1e-6)
    assert fast.summary.t_uplift == pytest.approx(plain.summary.t_uplift, abs=1e-9)
    assert len(fast.history) == len(plain.history)
    dphi = (fast.history["phi"] - plain.history["phi"]).abs().max() / SCENE.alpha
    assert dphi <= 1e-6
    # no timing here (benchmarks/compiled_analytic.py measures the speed): only that the
    # one-off loading or compiling of kernels is reported apart from the run's own cost
    for r in (fast, plain):
        assert r.cost.cpu_s > 0.0 and r.cost.compile_cpu_s >= 0.0
    assert plain.cost.compile_cpu_s == 0.0       # solve_ivp compiles nothing


@needs_numba
def test_a_first_runs_compilation_is_reported_apart():
    """A kernel compiled (or loaded from the cache) inside a run is ``compile_cpu_s``, not
    ``cpu_s``: a clock around a freshly defined kernel sees its compilation, and a second call
    sees none."""
    from rockbench._jit import CpuClock, numba

    @numba.njit
    def kernel(x):
        s = 0.0
        for i in range(x.size):
            s += x[i] * x[i]
        return s

    x = np.ones(10)
    with CpuClock() as first:
        kernel(x)
    with CpuClock() as second:
        kernel(x)
    assert first.compile_s > 0.0 and second.compile_s == 0.0
    assert first.cpu_s >= 0.0 and second.cpu_s >= 0.0


def test_pulses_and_free_rocking_stay_on_solve_ivp():
    m = RickerPulse.dimensionless(2.5, 2.0, SCENE.structure, "antisymmetric", -1)
    assert rb.run(SCENE, m).settings["path"] == "solve_ivp"
    assert rb.run(SCENE, None, phi0=0.05, duration=2.0).settings["path"] == "solve_ivp"


@needs_numba
def test_method_compiled_takes_the_numba_path_for_a_pulse():
    m = RickerPulse.dimensionless(2.5, 2.0, SCENE.structure, "antisymmetric", -1)
    assert rb.run(SCENE, m, method="compiled").settings["path"] == "compiled"


def test_without_numba_a_record_falls_back_to_solve_ivp(record, monkeypatch):
    monkeypatch.setattr(kernels, "NUMBA_AVAILABLE", False)
    r = rb.run(SCENE, record, duration=1.8)       # at rest until 1.69 s: cheap on solve_ivp
    assert r.settings["path"] == "solve_ivp" and r.summary.uplifted


def test_unknown_method_names_the_choices():
    with pytest.raises(ParameterError, match="auto") as e:
        AnalyticSettings(method="Euler")
    assert "method" in str(e.value) and "DOP853" in str(e.value)

"""The map path (issue 27 section 3): what a map keeps, computed without the history frame
and without measuring every impact's eta.

* ``finish(..., keep="summary")`` (``rb.run(..., keep="summary")``) gives the full Result's
  Summary field by field, bit for bit (the same arithmetic on the same samples), except
  ``eta_measured`` (empty), on cells that survive, overturn, fracture, diverge and are
  invalid, for pymunk and MuJoCo;
* a sweep row through the summary path equals the row of the full path but for the eta means
  (NaN: not measured);
* the first impact measured on the history up to the end of the excursion after it is the
  full history's first impact, bit for bit (what the map path's validity rule reads);
* the compiled loop, returning to Python every ``DRIVE_CHUNKS`` chunks, still ends a run
  that diverges where the Python loop ends it (samples, steps, events: a fracture and an
  overturn found after that are not recorded);
* MuJoCo's batched rollout stopped at the verdict gives the verdicts and peaks of the batch
  that runs every case to its end.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np

import pytest

import rockbench as rb
from rockbench.testing import engine_params, needs_engine
from rockbench.engines.base import run_window
from rockbench.engines.loop import Outcome
from rockbench.measure import excursions, measure_impacts
from rockbench.errors import ParameterError
from rockbench.sweep.runs import TIMING_COLUMNS, run_case

#: (scene, A, W, shape, sign, settings, what the full path says): every kind of map cell
CELLS = [
    ("paper-asymmetric", 2.0, 3.0, "symmetric", 1, {}, "survives"),
    ("paper-asymmetric", 6.0, 3.0, "symmetric", 1, {}, "overturns"),
    ("paper-asymmetric-hybrid-eps1", 10.0, 3.0, "symmetric", 1, {}, "fractures"),
    ("paper-asymmetric", 3.0, 3.0, "antisymmetric", -1, {"max_penetration": 1e-7},
     "diverged"),
    ("paper-asymmetric", 2.0, 3.0, "symmetric", 1, {"output_dt": 5e-2}, "invalid"),
    # the map path's rule falls back to measuring every impact: the first has no eta
    ("paper-asymmetric", 2.0, 3.0, "symmetric", 1, {"output_dt": 3e-2}, "first-unmeasured"),
]


def _engines():
    return engine_params(names=["pymunk", "mujoco"])


#: Summary fields a map's Outcome does not fill (it does not measure eta)
NOT_KEPT = {"eta_measured"}


def _same(a, b) -> bool:
    """Equal, NaN equal to NaN (bit for bit otherwise)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b and type(a) is type(b)


def _full_and_summary(engine, name, A, W, shape, sign, settings):
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(A, W, scene.structure, shape, sign)
    duration = pulse.t_end - pulse.t_start + 3.0
    full = rb.run(scene, pulse, engine=engine, duration=duration, **settings)
    light = rb.run(scene, pulse, engine=engine, duration=duration, keep="summary",
                   **settings)
    return full, light


@pytest.mark.parametrize("engine", _engines())
@pytest.mark.parametrize("cell", CELLS, ids=[c[-1] for c in CELLS])
def test_summary_path_equals_the_full_summary(engine, cell):
    *args, what = cell
    full, light = _full_and_summary(engine, *args)
    assert isinstance(light, Outcome) and light.backend == full.backend
    # the cell is of the kind it stands for (else the test would not cover it)
    s = full.summary
    kind = {"survives": s.status == "ok" and not s.overturned,
            "overturns": s.status == "ok" and s.overturned,
            "fractures": s.fractured,
            "diverged": s.status == "diverged",
            "invalid": s.status == "invalid",
            "first-unmeasured": (s.status == "ok" and math.isnan(s.eta_measured[0])
                                 and any(map(math.isfinite, s.eta_measured)))}[what]
    assert kind, (what, s)
    a, b = asdict(s), asdict(light.summary)
    assert a.keys() == b.keys()
    differ = {k: (a[k], b[k]) for k in a if k not in NOT_KEPT and not _same(a[k], b[k])}
    assert not differ, differ
    assert (light.cost.steps, light.cost.sim_time) == (full.cost.steps, full.cost.sim_time)
    # no eta measured, no impact rows; the full path measured them (the count is theirs)
    assert light.summary.eta_measured == [] and light.impacts == []
    assert len(full.impacts()) == s.n_impacts == len(s.eta_measured)


@pytest.mark.parametrize("engine", _engines())
def test_sweep_row_of_the_summary_path_equals_the_full_row(engine):
    case = {"scene": "paper-asymmetric", "engine": engine, "duration": 6.0,
            "motion": {"kind": "ricker", "shape": "antisymmetric", "sign": 1, "A": 3.0,
                       "W": 4.0}}
    full, light = run_case(case), run_case(case, keep="summary")
    assert full["status"] == "ok" and full["n_impacts"] >= 2
    eta = {"eta_ccw_mean", "eta_cw_mean"}
    skip = set(TIMING_COLUMNS) | {"wall_s", "real_time_factor"} | eta
    differ = {k: (full[k], light.get(k)) for k in full
              if k not in skip and not _same(full[k], light.get(k))}
    assert not differ, differ
    assert set(full) == set(light)
    assert all(math.isfinite(full[k]) for k in eta)
    assert all(math.isnan(light[k]) for k in eta)


def test_keep_is_checked():
    scene = rb.load_scene("housner-block")
    with pytest.raises(ParameterError, match="keep"):
        rb.run(scene, None, phi0=0.05, duration=0.1, keep="summary")      # analytic


@needs_engine("pymunk")
def test_keep_is_checked_for_an_engine():
    scene = rb.load_scene("housner-block")
    with pytest.raises(ParameterError, match="keep"):
        rb.run(scene, None, engine="pymunk", phi0=0.05, duration=0.1, keep="history")


def _mujoco_chunk():
    if "mujoco" not in rb.available_backends():
        pytest.skip("mujoco is not installed")
    scene = rb.load_scene("paper-asymmetric")
    motions = [rb.RickerPulse.dimensionless(A, 3.0, scene.structure, "symmetric", 1)
               for A in (2.0, 6.0)]
    return scene, motions


def test_batched_mujoco_stops_at_the_verdict_with_unchanged_results():
    from rockbench.engines import mujoco_batch as M

    scene, motions = _mujoco_chunk()
    duration = motions[0].t_end - motions[0].t_start + 3.0
    chunked = M.run_batch(scene, motions, duration=duration, nthread=1)
    whole = M.run_batch(scene, motions, duration=duration, nthread=2)  # one call, to the end
    light = M.run_batch(scene, motions, duration=duration, nthread=1, keep="summary")
    assert [r.summary.overturned for r in whole] == [False, True]
    for a, b, c in zip(whole, chunked, light):
        sa, sb, sc_ = asdict(a.summary), asdict(b.summary), asdict(c.summary)
        assert all(_same(sa[k], sb[k]) for k in sa), (sa, sb)
        assert all(_same(sa[k], sc_[k]) for k in sa if k not in NOT_KEPT), (sa, sc_)
        assert a.cost.steps == b.cost.steps == c.cost.steps
    # the rollout itself stopped: fewer steps simulated than the window holds when it
    # overturned, all of them when it survived
    b = M.MujocoBackend(scene)
    b.build(0.0)
    import mujoco
    from mujoco import rollout

    m = b.model
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, b.data, s0, spec)
    masses = np.array([sp.mass for sp in b.specs])
    n_steps = int(round(duration / b.settings.dt))
    runner = rollout.Rollout(nthread=None)
    simulated = []
    for mo in motions:
        t0 = run_window(scene, mo, duration, 0.0)[0]
        t = t0 + b.settings.dt * (np.arange(n_steps) + 0.5)
        ctrl = np.zeros((n_steps, m.nv))
        ctrl[:, 0:3 * len(masses):3] = -np.asarray(mo.acceleration(t))[:, None] * masses
        simulated.append(len(M._rollout_to_verdict(runner, m, mujoco.MjData(m), s0, ctrl,
                                                   n_steps, scene.fall_angles)))
    assert simulated[0] == n_steps
    assert simulated[1] < n_steps - M.VERDICT_CHUNK


@needs_engine("pymunk")
@pytest.mark.parametrize("name, pulse", [
    ("paper-asymmetric", (2.0, 3.0, "symmetric", 1)),
    ("paper-asymmetric-hybrid", (3.0, 3.0, "antisymmetric", -1)),
    ("housner-block", None)])                                   # free rocking: energy estimate
def test_first_impact_on_its_prefix_is_the_full_first_impact(name, pulse):
    """What the map path's validity rule reads (loop._first_eta_finite): the first impact
    measured on the samples up to the last of the excursion it begins is the full history's
    first impact, bit for bit (an impact's measurement reads only its two excursions)."""
    from rockbench.engines.loop import impact_arguments
    from rockbench.engines.pymunk import PymunkSettings

    scene = rb.load_scene(name)
    if pulse is None:
        motion, kw = None, dict(phi0=0.5 * scene.alpha, duration=6.0)
    else:
        motion, kw = rb.RickerPulse.dimensionless(*pulse[:2], scene.structure, *pulse[2:]), {}
    h = rb.run(scene, motion, engine="pymunk", **kw).history
    t, phi, pd_ = (h[c].to_numpy() for c in ("t", "phi", "phidot"))
    intact = h["devices_intact"].to_numpy()
    args = impact_arguments(scene, motion, PymunkSettings(),
                            motion is None and not scene.has_devices)
    full = measure_impacts(t, phi, pd_, intact=intact, **args)
    exc = excursions(t, phi, pd_, uplift_tol=args["uplift_tol"], rest_rate=args["rest_rate"])
    assert len(full) == sum(x.after_impact for x in exc) >= 2     # what the map path counts
    m = next(x for x in exc if x.after_impact).i1 + 1
    assert m < t.size // 2                  # the prefix is a small part of the history
    first = measure_impacts(t[:m], phi[:m], pd_[:m], intact=intact[:m], **args)
    assert len(first) == 1 and math.isfinite(first[0]["eta"])
    assert first[0] == full[0]


#: (engine, max_penetration [m]) first exceeded in samples 4000-4499 of the run below
#: (measured: pymunk 1.6e-5 before, 3.5e-5 there; MuJoCo 2.0e-5 before, 1.5e-4 there)
_STOPS = [("pymunk", 2.5e-5), ("mujoco", 5e-5)]


@pytest.mark.parametrize("engine, limit", _STOPS)
def test_compiled_loop_stops_a_diverged_run_where_the_python_loop_does(engine, limit):
    """The compiled loop returns to Python every DRIVE_CHUNKS x PROBE_CHUNK samples (4000):
    a run whose penetration check fails in samples 4000-4499 is stopped at sample 4500 by the
    Python loop, while the kernel stepped on past its fracture (t = 0.36 s, sample ~4700) and
    its overturn: the compiled run ends where the Python one does, with neither recorded."""
    from rockbench.engines import loop as L

    if engine not in rb.available_backends():
        pytest.skip(f"{engine} is not installed")
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    motion = rb.RickerPulse.dimensionless(10.0, 3.0, scene.structure, "symmetric", 1)
    free = rb.run(scene, motion, engine=engine, keep="summary")
    assert free.summary.fractured and free.summary.overturned      # without the limit
    plain = rb.run(scene, motion, engine=engine, loop="python", max_penetration=limit)
    fast = rb.run(scene, motion, engine=engine, max_penetration=limit)
    assert plain.summary.status == "diverged" and "penetration" in plain.summary.reason
    assert not plain.summary.fractured and not plain.summary.overturned
    assert len(plain.history) == 9 * L.PROBE_CHUNK != L.DRIVE_CHUNKS * L.PROBE_CHUNK
    assert fast.cost.steps == plain.cost.steps
    assert fast.summary.status == "diverged" and fast.summary.reason == plain.summary.reason
    assert plain.events["kind"].tolist() == fast.events["kind"].tolist()
    assert (plain.summary.fractured, plain.summary.overturned, plain.summary.n_impacts) == (
        fast.summary.fractured, fast.summary.overturned, fast.summary.n_impacts)
    x, y = plain.history.to_numpy(float), fast.history.to_numpy(float)
    assert x.shape == y.shape
    # a scene with devices: the compiled loop's tendon lengths come from the C library's hypot,
    # one ulp from CPython's in some calls on some CPUs (test_fast_paths.py): 1e-8 relative
    scale = np.maximum(np.nanmax(np.abs(x), axis=0), 1e-12)
    assert np.nanmax(np.abs(x - y) / scale) < 1e-8

"""The map path (issue 27 section 3): what a map keeps, computed without the history frame.

* ``finish(..., keep="summary")`` (``rb.run(..., keep="summary")``) gives the full Result's
  Summary field by field, bit for bit (the same arithmetic on the same samples), on cells
  that survive, overturn, fracture, diverge and are invalid, for pymunk and MuJoCo;
* a sweep row through the summary path equals the row of the full path;
* MuJoCo's batched rollout stopped at the verdict gives the verdicts and peaks of the batch
  that runs every case to its end.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np

import pytest

import rockbench as rb
from rockbench.engines.base import run_window
from rockbench.engines.loop import Outcome
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
]


def _engines():
    have = rb.available_backends()
    return [e for e in ("pymunk", "mujoco") if e in have]


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
            "invalid": s.status == "invalid"}[what]
    assert kind, (what, s)
    a, b = asdict(s), asdict(light.summary)
    assert a.keys() == b.keys()
    differ = {k: (a[k], b[k]) for k in a if not _same(a[k], b[k])}
    assert not differ, differ
    assert (light.cost.steps, light.cost.sim_time) == (full.cost.steps, full.cost.sim_time)
    # the impact rows are the full events' impacts
    imp = full.impacts()
    assert len(light.impacts) == len(imp)
    assert [r["t"] for r in light.impacts] == imp["t"].tolist()


@pytest.mark.parametrize("engine", _engines())
def test_sweep_row_of_the_summary_path_equals_the_full_row(engine):
    case = {"scene": "paper-asymmetric", "engine": engine, "duration": 6.0,
            "motion": {"kind": "ricker", "shape": "antisymmetric", "sign": 1, "A": 3.0,
                       "W": 4.0}}
    full, light = run_case(case), run_case(case, keep="summary")
    assert full["status"] == "ok" and full["n_impacts"] >= 2
    skip = set(TIMING_COLUMNS) | {"wall_s", "real_time_factor"}
    differ = {k: (full[k], light.get(k)) for k in full
              if k not in skip and not _same(full[k], light.get(k))}
    assert not differ, differ
    assert set(full) == set(light)


def test_keep_is_checked():
    scene = rb.load_scene("housner-block")
    with pytest.raises(ParameterError, match="keep"):
        rb.run(scene, None, phi0=0.05, duration=0.1, keep="summary")      # analytic
    if "pymunk" in rb.available_backends():
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
        assert all(_same(sa[k], sc_[k]) for k in sa), (sa, sc_)
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

"""The verdict rule of every backend, said once (``rockbench/verdict.py``): the critical-angle
predicate, a fall under way at a run's end, and the one policy that finishes it - used by the
analytic backend, a map's compiled cells and an engine run that stopped past its critical
angle, each fall finished once (a map on the solve_ivp path leaves it to the backend)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.compiled import NUMBA_AVAILABLE
from rockbench.analytic.reference import reference_of
from rockbench.constants import FALL_EXTENSION
from rockbench.run_length import pulse_run_length
from rockbench.verdict import fall_under_way, finish_fall, past_critical

#: Critical angles of a hybrid frame: none while the tendons hold, 0.14 / 0.15 rad after.
CRIT = {(1, True): math.inf, (-1, True): math.inf, (1, False): 0.14, (-1, False): 0.15}


def test_past_critical_is_the_angle_of_its_direction_and_device_state():
    phi = np.array([0.0, 0.1, 0.141, -0.141, -0.151, 0.5, -0.5, 0.141])
    on = np.array([False, False, False, False, False, True, True, True])
    assert past_critical(phi, on, CRIT).tolist() == [False, False, True, False, True, False,
                                                     False, False]
    assert past_critical(0.141, False, CRIT) is True
    assert past_critical(-0.141, False, CRIT) is False
    assert past_critical(9.0, True, CRIT) is False             # infinite: never passed
    rng = np.random.default_rng(3)
    phi, on = rng.uniform(-0.3, 0.3, 500), rng.random(500) < 0.5
    brute = [(s := 1 if p > 0 else -1) * p > CRIT[(s, bool(f))] for p, f in zip(phi, on)]
    assert past_critical(phi, on, CRIT).tolist() == brute
    assert past_critical(np.zeros(0), np.zeros(0, bool), CRIT).shape == (0,)


def test_a_fall_is_under_way_only_after_the_motion_in_an_ok_run_not_yet_fallen():
    assert fall_under_way("ok", False, 0.2, False, CRIT)
    assert not fall_under_way("ok", False, 0.2, False, CRIT, motion_over=False)
    assert not fall_under_way("ok", True, 0.2, False, CRIT)
    assert not fall_under_way("diverged", False, 0.2, False, CRIT)
    assert not fall_under_way("ok", False, 0.1, False, CRIT)
    mask = fall_under_way(np.array(["ok", "ok", "invalid"]), np.array([False, True, False]),
                          np.array([0.2, 0.2, 0.2]), np.zeros(3, bool), CRIT)
    assert mask.tolist() == [True, False, False]


def test_finish_fall_runs_only_the_falls_under_way_and_keeps_a_longer_run_that_fell():
    asked = []

    def longer(ix, extension):
        asked.append((list(ix), extension))
        return [("longer", i, i == 0) for i in ix]

    runs = [("short", 0), ("short", 1), ("short", 2)]
    out, more = finish_fall(runs, [True, False, True], longer, fell=lambda r: r[2])
    assert asked == [([0, 2], FALL_EXTENSION)]
    assert out == [("longer", 0, True), ("short", 1), ("short", 2)]   # 2 did not fall
    assert sorted(more) == [0, 2]
    assert finish_fall(runs, [False] * 3, longer, fell=lambda r: True) == (runs, {})
    assert len(asked) == 1


# --- the callers -----------------------------------------------------------------------------
SCENE = rb.load_scene("paper-asymmetric")
#: Ends past its clockwise critical angle 0.05 s after the pulse (tail 0.05 s): falls at 5.72 s.
FALLING = ("symmetric", -1, 7.36, 5.09)
#: Passes its critical angle during the pulse and comes back.
BACK = ("antisymmetric", 1, 4.2307692, 2.5384615)
TAIL = 0.05


def _cell_run(cell, method):
    shape, sign, A, W = cell
    p = rb.RickerPulse.dimensionless(A, W, SCENE.structure, shape, sign)
    return rb.run(SCENE, p, duration=pulse_run_length(W, SCENE.p, TAIL),
                  **({"method": method} if method else {}))


def test_a_map_on_the_reference_path_finishes_each_fall_once(monkeypatch):
    """On the solve_ivp path the backend finishes a fall (two integrations: the run and the
    longer one) and the map takes its row; a cell that came back is run once (the map ran it
    again 20 s longer, after the backend, and kept that row)."""
    import rockbench.engines.analytic as backend
    from rockbench.studies import maps

    real = backend.simulate
    calls = []
    monkeypatch.setattr(backend, "simulate", lambda *a, **k: calls.append(1) or real(*a, **k))
    rows = maps._analytic_cells(SCENE, [FALLING], "solve_ivp", TAIL)
    assert bool(rows["overturned"].iloc[0]) and len(calls) == 2
    calls.clear()
    rows = maps._analytic_cells(SCENE, [BACK], "solve_ivp", TAIL)
    r = rows.iloc[0]
    assert bool(r["exceeded_critical"]) and not bool(r["overturned"]) and len(calls) == 1


@pytest.mark.skipif(not NUMBA_AVAILABLE, reason="numba is not installed")
def test_a_map_s_compiled_cells_give_the_backend_s_verdict_and_run():
    """A compiled map cell whose fall is under way is finished as the backend finishes it; a
    cell that came back is the map's own run (its impacts within the map's run length)."""
    from rockbench.studies import maps

    rows = maps._analytic_cells(SCENE, [FALLING, BACK], "compiled", TAIL)
    for cell, (_, row) in zip((FALLING, BACK), rows.iterrows()):
        s = _cell_run(cell, "compiled").summary
        assert (bool(row["overturned"]), bool(row["exceeded_critical"])) == (
            s.overturned, s.exceeded_critical)
        assert row["max_abs_phi_over_alpha"] == pytest.approx(s.max_abs_phi_over_alpha,
                                                              rel=1e-9)
        assert int(row["n_impacts"]) == s.n_impacts
    assert bool(rows["overturned"].iloc[0]) and not bool(rows["overturned"].iloc[1])
    ref = maps._analytic_cells(SCENE, [FALLING, BACK], "solve_ivp", TAIL)
    assert rows["overturned"].tolist() == ref["overturned"].tolist()


def test_an_engine_run_stopped_past_its_critical_angle_is_finished_by_the_model():
    """An engine's samples that end (a divergence) past the critical angle after the motion:
    the analytic model continues from that state and the frame falls; inside it, with too
    little energy, the peak measured stands."""
    from rockbench.engines.verdicts import _judge_stopped

    ref = reference_of(SCENE)
    crit = ref.critical[(-1, True)]
    t = np.linspace(0.0, 1.0, 11)
    phi = np.linspace(0.0, -1.05 * crit, 11)
    over, t_o, note = _judge_stopped(SCENE, None, ref, t, phi, np.zeros(11),
                                     np.ones(11, bool), 0.0)
    assert over and t_o > 1.0 and "finished with the analytic model" in note
    phi = np.linspace(0.0, -0.5 * crit, 11)
    phi[-1] = -0.4 * crit
    over, t_o, note = _judge_stopped(SCENE, None, ref, t, phi, np.zeros(11),
                                     np.ones(11, bool), 0.0)
    assert not over and t_o is None and "are final" in note

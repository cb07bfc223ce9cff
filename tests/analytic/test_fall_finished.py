"""A fall under way is finished: an analytic run that ends after the ground motion with the frame
past its critical angle is integrated longer (``constants.FALL_EXTENSION``) and reports the
overturn, as the engines' collapse rule does (docs/conventions.md); a run that ends during the
ground motion is not extended.

The cell (paper-asymmetric, symmetric pulse -, A = 7.36, W = 5.09): the frame passes its
clockwise critical angle at t = 1.78 s, the pulse ends at 2.57 s, it falls at 5.72 s."""

from __future__ import annotations

import pytest

import rockbench as rb
from rockbench.analytic.compiled import NUMBA_AVAILABLE
from rockbench.analytic.reference import reference_of
from rockbench.constants import FALL_EXTENSION

SCENE = rb.load_scene("paper-asymmetric")
PULSE = rb.make_pulse("symmetric", -1, structure=SCENE, A=7.36, W=5.09)
WINDOW = PULSE.t_end - PULSE.t_start
METHODS = ["DOP853"] + (["compiled"] if NUMBA_AVAILABLE else [])


@pytest.mark.parametrize("method", METHODS)
def test_run_ending_mid_fall_after_the_motion_is_finished(method):
    ref = reference_of(SCENE)
    full = rb.run(SCENE, PULSE, method=method)               # motion + 10 s: falls in it
    assert full.summary.overturned
    t_fall = full.summary.t_overturn
    assert PULSE.t_end + 1.0 < t_fall < PULSE.t_end + FALL_EXTENSION
    short = rb.run(SCENE, PULSE, duration=WINDOW + 0.05, method=method)
    s = short.summary
    assert s.status == "ok" and s.overturned and s.exceeded_critical
    assert s.t_overturn == pytest.approx(t_fall, abs=1e-6)
    # the history goes on past the requested end, to the fall angle
    assert short.history["t"].iloc[-1] > PULSE.t_start + WINDOW + 1.0
    assert abs(short.history["phi"].iloc[-1]) == pytest.approx(ref.fall[-1], rel=1e-3)


@pytest.mark.parametrize("method", METHODS)
def test_run_ending_during_the_motion_is_not_extended(method):
    # past the critical angle at 1.78 s, but the ground still moves until 2.57 s
    d = 2.2 - PULSE.t_start
    r = rb.run(SCENE, PULSE, duration=d, method=method)
    assert r.summary.exceeded_critical and not r.summary.overturned
    assert r.history["t"].iloc[-1] == pytest.approx(PULSE.t_start + d, abs=0.02)


def test_a_run_that_never_passes_its_critical_angle_is_not_extended():
    small = rb.make_pulse("symmetric", -1, structure=SCENE, A=2.0, W=5.09)
    r = rb.run(SCENE, small, duration=WINDOW + 0.5)
    assert not r.summary.exceeded_critical and not r.summary.overturned
    assert r.history["t"].iloc[-1] == pytest.approx(small.t_start + WINDOW + 0.5, abs=0.02)

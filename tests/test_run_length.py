"""The one run-length rule (``rockbench/run_length.py``) gives, to the last bit, the durations
of the formulas it replaced - each written here as it stood in its module - so that every
store keyed by its runs and every committed result reproduces."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.constants import FALL_EXTENSION, FREE_TAIL
from rockbench.run_length import (STRONG_END, describe, pulse_run_length, pulse_window,
                                  run_length)

SCENES = [rb.load_scene(n) for n in rb.builtin_scenes()]
#: A map's W axis (the default grid), the validation set's W_GRID and the paper plan's points.
WS = sorted(set(np.round(np.linspace(0.5, 10.0, 100), 12).tolist())
            | {1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 1.0, 2.5, 5.0, 0.3, 17.3})
TAILS = (None, 0.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0, 10.0)


# --- the formulas as they were ------------------------------------------------------------
def _old_cell_duration(scene, W, tail):                       # studies/maps.py
    if tail is None:
        return None
    return 6.0 * 2.0 * math.pi / (W * scene.p) + tail


def _old_map_rerun(scene, W, tail, extra):                    # studies/maps.py, a fall rerun
    return _old_cell_duration(scene, W, (FREE_TAIL if tail is None else tail) + extra)


def _old_validation(p, tail):                                 # studies/validation.py
    return round(1.5 * p.period + tail - p.t_start, 4)


def _old_run_window(motion):                                  # engines/base.py
    t0 = float(motion.t_start) if motion is not None else 0.0
    return (max(motion.t_end - t0, 0.0) if motion is not None else 0.0) + FREE_TAIL


def _old_fracture_search(p):                                  # campaign/plan.py
    return round(6 * p.period + 3.0, 3)


def _old_record(r, tail):                                     # campaign/run.py (records)
    tail = tail if tail is not None else 10.0
    return float(r.t_end - r.t_start + tail)


# ------------------------------------------------------------------------------------------
def test_a_map_cell_and_a_campaign_pulse_case_last_as_long_as_before():
    for sc in SCENES:
        for W in WS:
            for tail in TAILS:
                assert pulse_run_length(W, sc.p, tail) == _old_cell_duration(sc, W, tail), \
                    (sc.name, W, tail)
                assert pulse_run_length(W, sc.p, tail, FALL_EXTENSION) == \
                    _old_map_rerun(sc, W, tail, FALL_EXTENSION)


def test_the_default_run_and_the_validation_runs_last_as_long_as_before():
    for sc in SCENES:
        for W in WS:
            for shape, sign in (("symmetric", 1), ("antisymmetric", -1)):
                p = rb.RickerPulse.dimensionless(2.0, W, sc.structure, shape, sign)
                assert run_length(p) == _old_run_window(p)
                for tail in (2.5, 8.0):
                    assert run_length(p, tail, window="strong") == _old_validation(p, tail)
                assert round(run_length(p, 3.0), 3) == _old_fracture_search(p)
    assert run_length(None) == _old_run_window(None) == FREE_TAIL
    rec = rb.load_record(rb.scene.records.bundled_dir() / "IV1940_ElCentro_180.AT2")
    assert run_length(rec) == _old_run_window(rec)
    for tail in (None, 2.0, 5.0):
        assert run_length(rec, tail) == _old_record(rec, tail)


def test_the_rule_in_words_is_the_map_stores_identity():
    """A map store's ``_inputs.json`` keeps this text: it may not change."""
    for tail in (None, 0.5, 4.0):
        assert describe("pulse", tail) == \
            f"pulse window (6 T_g) + {FREE_TAIL if tail is None else tail:g} s"


def test_the_windows_are_what_their_names_say():
    sc = SCENES[0]
    p = rb.RickerPulse.dimensionless(2.0, 3.0, sc.structure)
    T = p.period
    assert run_length(p, 0.0) == pytest.approx(6 * T, rel=1e-15)
    assert pulse_window(3.0, sc.p) == pytest.approx(6 * T, rel=1e-15)
    assert run_length(p, 1.0, window="strong") == pytest.approx((3 + STRONG_END) * T + 1.0,
                                                                abs=1e-4)
    # past the strong part the pulse is below 4e-5 of its peak (the reason of the window)
    for shape in ("symmetric", "antisymmetric"):
        q = rb.RickerPulse(1.0, 1.0, shape)
        t = np.linspace(STRONG_END, 3.0, 200)
        assert np.abs(q.acceleration(t)).max() < 4e-5
    assert run_length(12.5, 1.0) == 13.5                   # a window given in seconds
    with pytest.raises(ValueError, match="window"):
        run_length(p, window="middle")


def test_the_compiled_grid_kernel_runs_a_cell_for_the_rule_s_default():
    """The map kernel computes its default length in compiled code (it cannot call Python):
    a cell run for the rule's explicit length is the same run, to the last bit."""
    pytest.importorskip("numba")
    from rockbench.analytic.compiled import run_pulse_grid

    sc = rb.load_scene("paper-symmetric")
    cells = [("symmetric", 1, 2.5, 3.0), ("antisymmetric", -1, 4.0, 1.7)]
    default = run_pulse_grid(sc, cells)
    for i, (shape, sign, A, W) in enumerate(cells):
        p = rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)
        one = run_pulse_grid(sc, [cells[i]], duration=run_length(p))
        cols = ["overturned", "max_abs_phi_over_alpha", "n_impacts", "phi_end"]
        assert one[cols].iloc[0].tolist() == default[cols].iloc[i].tolist()

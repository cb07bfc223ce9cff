"""The evidence's overturning thresholds (rockbench.studies.validation.overturn_threshold):
found with the maps' compiled kernel, each verdict finishing a fall under way as the analytic
backend does, they are those of whole analytic runs."""

from __future__ import annotations

import pytest

import rockbench as rb
from rockbench.run_length import run_length
from rockbench.studies import validation as V

pytest.importorskip("numba")


@pytest.mark.parametrize("W,shape,sign", [(6.0, "symmetric", 1), (3.0, "antisymmetric", -1),
                                          (1.5, "symmetric", -1)])
def test_thresholds_are_those_of_whole_analytic_runs(W, shape, sign):
    """paper-asymmetric at W = 6, symmetric +: the bisection meets runs that end with their
    fall under way (the kernel alone calls them survived, 0.08 % below the threshold of whole
    runs); the same bisection meets the same verdicts: the same threshold (the two paths
    differ only at a run whose verdict is within rounding of the boundary)."""
    scene = rb.load_scene("paper-asymmetric")
    sc = scene.replace(fall_angle=V._fall(scene))
    dur = run_length(V._pulse(sc, 1.0, W, shape, sign), V._OVER_TAIL, window="strong")

    def over(A):
        return bool(rb.run(sc, V._pulse(sc, A, W, shape, sign), engine="analytic",
                           duration=dur, method="compiled").summary.overturned)

    whole = V.bisect_threshold(over, 1e-3)
    assert V.overturn_threshold(scene, W, shape, sign) == pytest.approx(whole, rel=1e-9)


def test_bisection_finds_the_first_overturning_amplitude():
    """A monotone verdict: the threshold is bracketed to the relative width asked, from
    above; nothing overturning up to A = 30 gives inf."""
    a = V.bisect_threshold(lambda A: A >= 7.3, 1e-4)
    assert 7.3 <= a <= 7.3 * (1 + 1e-4)
    assert V.bisect_threshold(lambda A: False, 1e-3) == float("inf")

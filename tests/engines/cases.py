"""The cross-engine cases of issue 3, from rockbench's case catalogue
(``rockbench/scenarios/cases.toml``, whose comments say how each was chosen; read by
:func:`rockbench.sweep.cases.catalogue`).

Every engine is held to the same bars on these runs (``tests/engines/test_cross_engine.py``):
``FREE_CASES`` (free rocking from phi0 = 0.5 alpha of three scenes), ``SURVIVE_CASES`` (two
(A, W) points per frame scene under the four Ricker pulses, which the analytic frame survives
with max |phi| / alpha in [0.3, 0.8]) and ``OVERTURN_CASES`` (per frame scene, two W and the
four pulses at ``OVERTURN_FACTOR`` x the analytic overturning threshold ``OVERTURN_THRESHOLDS``,
fall angle ``OVERTURN_FALL`` alpha). Analytic peaks of the survive cases (max |phi| / alpha):
paper-asymmetric (6.5, 6) 0.520 / 0.494 / 0.487 / 0.483, (5, 5) 0.629 / 0.598 / 0.444 / 0.456;
hybrid eps1 (7, 3) 0.348 / 0.339 / 0.385 / 0.377, (10, 4) 0.352 / 0.344 / 0.420 / 0.413 (pulses
in the order of ``PULSES``).

Run ``python tests/engines/cases.py`` to recompute the thresholds and the analytic peaks (a
minute or two).
"""

from __future__ import annotations

import math

import rockbench as rb
from rockbench.sweep.cases import FreeCase, PulseCase, catalogue

_C = catalogue()

#: (shape, sign) of the four Ricker pulses.
PULSES = _C.pulses
#: Initial rotation of the free-rocking runs, as a multiple of alpha.
FREE_PHI0 = _C.free_phi0
#: Window [s] over which the history RMS error is measured (from the start of the run).
NRMSE_WINDOW = _C.nrmse_window
#: Free-rocking scenes and run durations [s].
FREE_DURATIONS = _C.free_durations
#: Survive points (A, W) per scene, and the end of the survive runs [s] after the pulse centre.
SURVIVE_POINTS = _C.survive_points
SURVIVE_END = _C.survive_end
#: Overturn runs: W per scene, A = OVERTURN_FACTOR x the analytic threshold, end [s] after the
#: pulse centre, fall angle [alpha]; thresholds keyed by (scene, W, shape, sign).
OVERTURN_W = _C.overturn_w
OVERTURN_FACTOR = _C.overturn_factor
OVERTURN_END = _C.overturn_end
OVERTURN_FALL = _C.overturn_fall
OVERTURN_THRESHOLDS = _C.overturn_thresholds

FREE_CASES = _C.free_cases
SURVIVE_CASES = _C.survive_cases
OVERTURN_CASES = _C.overturn_cases

__all__ = ["FreeCase", "PulseCase", "PULSES", "FREE_PHI0", "NRMSE_WINDOW", "FREE_DURATIONS",
           "SURVIVE_POINTS", "SURVIVE_END", "OVERTURN_W", "OVERTURN_FACTOR", "OVERTURN_END",
           "OVERTURN_FALL", "OVERTURN_THRESHOLDS", "FREE_CASES", "SURVIVE_CASES",
           "OVERTURN_CASES", "overturn_threshold"]


# ------------------------------------------------------------------------------------------
def _overturns(scene, A: float, W: float, shape: str, sign: int) -> bool:
    case = PulseCase(scene.name, A, W, shape, sign, OVERTURN_END, OVERTURN_FALL)
    return rb.run(scene, **case.kwargs(scene)).summary.overturned


def overturn_threshold(scene, W: float, shape: str, sign: int, rtol: float = 1e-4) -> float:
    """Smallest A [-] (to relative width ``rtol``) at which the analytic ``scene`` (with its
    fall angle set to OVERTURN_FALL alpha) overturns under the pulse (W, shape, sign): scan
    upwards from A = 1 in steps of 5 %, then bisect."""
    A = 1.0
    while not _overturns(scene, A, W, shape, sign):
        A *= 1.05
        if A > 100.0:
            return math.inf
    lo, hi = A / 1.05, A
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if _overturns(scene, mid, W, shape, sign):
            hi = mid
        else:
            lo = mid
    return hi


def _main() -> None:  # pragma: no cover - a maintenance script
    for s, Ws in OVERTURN_W.items():
        scene = PulseCase(s, 1.0, 1.0, "symmetric", 1, OVERTURN_END, OVERTURN_FALL).load()
        for W in Ws:
            for shape, sign in PULSES:
                thr = overturn_threshold(scene, W, shape, sign)
                ok = [f for f in (1.1, 1.15, 1.2, 1.25, 1.3)
                      if _overturns(scene, f * thr, W, shape, sign)]
                print(f'    ["{s}", {W}, "{shape}", {sign}, {thr:.4f}],  '
                      f'# overturns at {ok} x')
    for case in SURVIVE_CASES:
        scene = case.load()
        r = rb.run(scene, **case.kwargs(scene))
        print(f"{case.id}: max|phi|/alpha = {r.summary.max_abs_phi_over_alpha:.4f}, "
              f"overturned {r.summary.overturned}, fractured {r.summary.fractured}")


if __name__ == "__main__":  # pragma: no cover
    _main()

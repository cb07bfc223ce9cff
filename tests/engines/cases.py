"""The cross-engine cases of issue 3, chosen with the analytic backend.

Every engine is held to the same bars on these runs (``tests/engines/test_cross_engine.py``):

* ``FREE_CASES``: free rocking from phi0 = 0.5 alpha of three scenes. The durations end between
  the peak that follows the second impact and the third impact, so that the run contains one
  impact of each direction and both are bracketed by complete excursions (the effective eta is
  then measured from the energy of successive peaks).
* ``SURVIVE_CASES``: two (A, W) points per frame scene (A = a_g / (g tan alpha), W = omega_g / p),
  each under the four Ricker pulses (symmetric / antisymmetric, sign +1 / -1): the analytic frame
  survives every one with max |phi| / alpha in [0.3, 0.8]. The points avoid the steep parts of the
  response (d ln(peak) / d ln(A) between 0.8 and 3, measured) and, for the hybrid frame, stay below
  the fracture rotation (0.485 alpha ccw, 0.476 alpha cw): beyond it the frame overturns.
* ``OVERTURN_CASES``: per frame scene, two W and the four pulses (8 runs), at
  A = ``OVERTURN_FACTOR`` (1.2) x the analytic overturning threshold of that pulse (the smallest
  A that overturns, by bisection, stored in ``OVERTURN_THRESHOLDS``), with the scene's fall
  angle set to ``OVERTURN_FALL`` = 4 alpha. The analytic frame overturns at every A from 1.1 to
  1.3 x the threshold for all of them (checked when they were chosen: some pulses have survival
  islands above the threshold, e.g. paper-asymmetric at W = 2, symmetric +1, survives at 1.2 and
  1.25 x; such W were not used), at t = 1.5 to 4.8 s after the pulse centre at 1.2 x.

Runs are short to keep the suite fast: a pulse run starts at the pulse's ``t_start`` (-3 T_g) and
ends ``end`` seconds after the pulse centre (t = 0). The largest |phi| of every survive run occurs
before t = 1.9 s; every overturn run overturns before its end. Analytic peaks of the survive
cases (max |phi| / alpha): paper-asymmetric (6.5, 6) 0.520 / 0.494 / 0.487 / 0.483, (5, 5)
0.629 / 0.598 / 0.444 / 0.456; hybrid eps1 (7, 3) 0.348 / 0.339 / 0.385 / 0.377, (10, 4)
0.352 / 0.344 / 0.420 / 0.413 (pulses in the order of ``PULSES``).

Run ``python tests/engines/cases.py`` to recompute the thresholds and the analytic peaks (a
minute or two).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import rockbench as rb

#: (shape, sign) of the four Ricker pulses.
PULSES = (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1), ("antisymmetric", -1))

#: Initial rotation of the free-rocking runs, as a multiple of alpha.
FREE_PHI0 = 0.5
#: Window [s] over which the history RMS error is measured (from the start of the run).
NRMSE_WINDOW = 2.0

#: Free-rocking scenes and run durations [s].
FREE_DURATIONS = {"housner-block": 3.0, "paper-symmetric": 4.5, "paper-asymmetric": 4.1}

#: Survive points (A, W) per scene.
SURVIVE_POINTS = {
    "paper-asymmetric": ((6.5, 6.0), (5.0, 5.0)),
    "paper-asymmetric-hybrid-eps1": ((7.0, 3.0), (10.0, 4.0)),
}
#: End of the survive runs [s] after the pulse centre.
SURVIVE_END = 2.5

#: W of the overturn runs per scene.
OVERTURN_W = {"paper-asymmetric": (3.0, 4.0), "paper-asymmetric-hybrid-eps1": (2.0, 3.0)}
#: A of an overturn run = OVERTURN_FACTOR x the analytic threshold.
OVERTURN_FACTOR = 1.2
#: End of the overturn runs [s] after the pulse centre.
OVERTURN_END = 8.0
#: Fall angle of the overturn runs, as a multiple of alpha (overrides the scenes' default of
#: 0.98 x the four-bar's toggle angle, 6.8 alpha counterclockwise and 8.75 alpha clockwise):
#: the frame is down long before (its critical angle is alpha), and beyond about 4.8 alpha,
#: close to the toggle, pymunk's pivots slide and penetrate by centimetres.
OVERTURN_FALL = 4.0

#: Analytic overturning thresholds A (smallest A that overturns the frame; bisection to a
#: relative width of 1e-4, runs from -3 T_g to OVERTURN_END after the pulse centre), keyed by
#: (scene, W, shape, sign). Recomputed by ``python tests/engines/cases.py``.
OVERTURN_THRESHOLDS = {
    ("paper-asymmetric", 3.0, "symmetric", 1): 3.2342,
    ("paper-asymmetric", 3.0, "symmetric", -1): 3.2134,
    ("paper-asymmetric", 3.0, "antisymmetric", 1): 4.7794,
    ("paper-asymmetric", 3.0, "antisymmetric", -1): 2.2240,
    ("paper-asymmetric", 4.0, "symmetric", 1): 4.1274,
    ("paper-asymmetric", 4.0, "symmetric", -1): 4.2042,
    ("paper-asymmetric", 4.0, "antisymmetric", 1): 5.7191,
    ("paper-asymmetric", 4.0, "antisymmetric", -1): 5.7320,
    ("paper-asymmetric-hybrid-eps1", 2.0, "symmetric", 1): 6.6648,
    ("paper-asymmetric-hybrid-eps1", 2.0, "symmetric", -1): 6.7100,
    ("paper-asymmetric-hybrid-eps1", 2.0, "antisymmetric", 1): 6.3029,
    ("paper-asymmetric-hybrid-eps1", 2.0, "antisymmetric", -1): 6.3190,
    ("paper-asymmetric-hybrid-eps1", 3.0, "symmetric", 1): 9.9447,
    ("paper-asymmetric-hybrid-eps1", 3.0, "symmetric", -1): 9.9795,
    ("paper-asymmetric-hybrid-eps1", 3.0, "antisymmetric", 1): 8.5663,
    ("paper-asymmetric-hybrid-eps1", 3.0, "antisymmetric", -1): 8.5772,
}


class FreeCase(NamedTuple):
    """Free rocking of ``scene`` from phi0 = FREE_PHI0 alpha for ``duration`` seconds."""

    scene: str
    duration: float

    @property
    def id(self) -> str:
        return f"free-{self.scene}"

    def load(self):
        return rb.load_scene(self.scene)

    def kwargs(self, scene) -> dict:
        """Keyword arguments of ``rb.run`` (besides scene and engine)."""
        return dict(motion=None, duration=self.duration, phi0=FREE_PHI0 * scene.alpha)


class PulseCase(NamedTuple):
    """``scene`` under the Ricker pulse (A, W, shape, sign), from -3 T_g to ``end`` seconds
    after the pulse centre; ``fall`` (a multiple of alpha, or None for the scene's own)
    overrides the scene's fall angle."""

    scene: str
    A: float
    W: float
    shape: str
    sign: int
    end: float
    fall: float | None = None

    @property
    def id(self) -> str:
        return (f"{self.scene}-A{self.A:.4g}-W{self.W:g}-{self.shape[:4]}"
                f"{'+' if self.sign > 0 else '-'}")

    def load(self):
        scene = rb.load_scene(self.scene)
        if self.fall is not None:
            scene = scene.replace(fall_angle=self.fall * scene.alpha)
        return scene

    def pulse(self, scene):
        return rb.RickerPulse.dimensionless(self.A, self.W, scene.structure, self.shape,
                                            self.sign)

    def kwargs(self, scene) -> dict:
        p = self.pulse(scene)
        return dict(motion=p, duration=self.end - p.t_start)


FREE_CASES = [FreeCase(s, d) for s, d in FREE_DURATIONS.items()]

SURVIVE_CASES = [PulseCase(s, A, W, shape, sign, SURVIVE_END)
                 for s, points in SURVIVE_POINTS.items() for A, W in points
                 for shape, sign in PULSES]

OVERTURN_CASES = [PulseCase(s, round(OVERTURN_FACTOR * OVERTURN_THRESHOLDS[(s, W, shape, sign)], 4),
                            W, shape, sign, OVERTURN_END, OVERTURN_FALL)
                  for s, Ws in OVERTURN_W.items() for W in Ws for shape, sign in PULSES]


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
                print(f'    ("{s}", {W}, "{shape}", {sign}): {thr:.4f},  '
                      f'# overturns at {ok} x')
    for case in SURVIVE_CASES:
        scene = case.load()
        r = rb.run(scene, **case.kwargs(scene))
        print(f"{case.id}: max|phi|/alpha = {r.summary.max_abs_phi_over_alpha:.4f}, "
              f"overturned {r.summary.overturned}, fractured {r.summary.fractured}")


if __name__ == "__main__":  # pragma: no cover
    _main()

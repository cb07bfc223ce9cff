"""The validation set of a scene: the runs every setting of every engine is measured on
(``rockbench tradeoff``, ``rockbench advise``; ``docs/choosing.md``), chosen with the analytic
model for that scene.

:func:`validation_set` (free rocking from two amplitudes in both directions, Ricker pulses spread
over the survive region and close to the overturning boundary, two overturning pulses), built on
:func:`overturn_threshold` (the analytic overturning threshold of a pulse, by bisection). Both are
cached in memory per scene data. Units: SI, radians; A = a_g / (g tan alpha), W = omega_g / p.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from typing import Any

__all__ = ["ValidationCase", "validation_set", "overturn_threshold"]

# Validation-set design (the analytic model chooses the pulses; see validation_set)
_W_VALUES = (3.0, 4.0)
_PULSES = (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1), ("antisymmetric", -1))
_SURVIVE_FACTORS = (0.6, 0.95)       # x the analytic overturning threshold
_OVERTURN_FACTOR = 1.25
_FREE_PHI0 = (0.3, 0.7)              # x alpha, both directions
_SURVIVE_END = 2.5                   # s after the pulse centre
_OVERTURN_END = 8.0                  # s after the pulse centre
_FALL = 4.0                          # x alpha: fall angle of the overturning cases
_A_MAX = 30.0                        # no overturning below this A: the pulse is left out


# =========================================================================================
# The validation set
# =========================================================================================
@dataclass(frozen=True)
class ValidationCase:
    """One run of the validation set (plain data: picklable, hashable, JSON-able).

    kind : "free" (free rocking from ``phi0``), "survive" (a Ricker pulse the analytic frame
        survives) or "overturn" (one that overturns it);
    name : short label, e.g. ``"free+0.3"``, ``"symm+ A=2.1 W=3"``;
    motion : a motion spec (:func:`rockbench.scene.motion.motion_from_spec`) or None;
    phi0 : initial rotation [rad]; duration : simulated time [s];
    fall : fall angle [rad] of the run (None: the scene's own);
    peak_ref : analytic max |phi| / alpha [-] (for the record).
    """

    kind: str
    name: str
    motion: tuple | None
    phi0: float
    duration: float
    fall: float | None = None
    peak_ref: float = math.nan

    def motion_spec(self) -> dict[str, Any] | None:
        return None if self.motion is None else dict(self.motion)

    def load(self, scene):
        """(scene with this case's fall angle, GroundMotion or None)."""
        from .scene.motion import motion_from_spec

        sc = scene if self.fall is None else scene.replace(fall_angle=self.fall)
        return sc, motion_from_spec(self.motion_spec(), sc.structure)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "name": self.name, "motion": self.motion_spec(),
                "phi0": self.phi0, "duration": self.duration, "fall": self.fall,
                "peak_ref": None if not math.isfinite(self.peak_ref) else self.peak_ref}


def _scene_key(scene) -> str:
    return json.dumps(scene.to_dict(), sort_keys=True, default=str)


@functools.lru_cache(maxsize=64)
def _scene_from_key(text: str):
    from .scene.scene import Scene

    return Scene.from_dict(json.loads(text))


def _pulse(scene, A: float, W: float, shape: str, sign: int):
    from .scene.motion import RickerPulse

    return RickerPulse.dimensionless(A, W, scene.structure, shape, sign)


def _analytic(scene, motion, duration: float, phi0: float = 0.0):
    from .runner import run

    return run(scene, motion, engine="analytic", duration=duration, phi0=phi0)


def _fall(scene) -> float:
    return min(_FALL * scene.alpha, min(scene.fall_angles.values()))


@functools.lru_cache(maxsize=256)
def _threshold(key: str, W: float, shape: str, sign: int, rtol: float) -> float:
    scene = _scene_from_key(key)
    sc = scene.replace(fall_angle=_fall(scene))

    def overturns(A: float) -> bool:
        p = _pulse(sc, A, W, shape, sign)
        return bool(_analytic(sc, p, _OVERTURN_END - p.t_start).summary.overturned)

    lo, hi = 1.0, 1.5
    while not overturns(hi):
        lo, hi = hi, hi * 1.5
        if hi > _A_MAX:
            return math.inf
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if overturns(mid):
            hi = mid
        else:
            lo = mid
    return hi


def overturn_threshold(scene, W: float, shape: str = "symmetric", sign: int = 1, *,
                       rtol: float = 1e-3) -> float:
    """The smallest A = a_g / (g tan alpha) [-] of a Ricker pulse (``W`` = omega_g / p,
    ``shape``, ``sign``) that overturns ``scene`` in the analytic model (fall angle
    min(4 alpha, the scene's)), found by scanning A up from 1 by factors of 1.5 and bisecting
    the first bracket to a relative width ``rtol`` (inf when nothing up to A = 30 overturns
    it: such a pulse is left out of the validation set). Cached in memory per scene data."""
    return _threshold(_scene_key(scene), float(W), str(shape), int(sign), float(rtol))


def _free_duration(scene, phi0: float) -> float:
    """End of a free-rocking run [s]: between the peak after the third impact and the fourth
    impact of the analytic run, so that every impact is bracketed by complete excursions."""
    r = _analytic(scene, None, 20.0, phi0)
    t = r.impacts()["t"].to_numpy(dtype=float)
    if t.size >= 4:
        return float(t[2] + 0.75 * (t[3] - t[2]))
    if t.size >= 2:
        return float(t[-1] + 0.75 * (t[-1] - t[-2]))
    return 10.0


@functools.lru_cache(maxsize=16)
def _validation_set(key: str, quick: bool) -> tuple[ValidationCase, ...]:
    scene = _scene_from_key(key)
    alpha = scene.alpha
    cases: list[ValidationCase] = []
    free = _FREE_PHI0[1:] if quick else _FREE_PHI0
    for f in free:
        for s in ((1,) if quick else (1, -1)):
            phi0 = s * f * alpha
            cases.append(ValidationCase("free", f"free{'+' if s > 0 else '-'}{f:g}", None, phi0,
                                        round(_free_duration(scene, phi0), 3), None, f))
    combos = [(W, shape, sign) for W in _W_VALUES for shape, sign in _PULSES]
    if quick:
        combos = [(3.0, "symmetric", 1), (4.0, "antisymmetric", -1)]
    fall = _fall(scene)
    sc_fall = scene.replace(fall_angle=fall)
    for W, shape, sign in combos:
        A_ov = overturn_threshold(scene, W, shape, sign, rtol=1e-2 if quick else 1e-3)
        if not math.isfinite(A_ov):
            continue
        factors = _SURVIVE_FACTORS if (W == _W_VALUES[0] or quick) else _SURVIVE_FACTORS[:1]
        for f in factors:
            A = round(f * A_ov, 4)
            p = _pulse(scene, A, W, shape, sign)
            dur = round(_SURVIVE_END - p.t_start, 4)
            r = _analytic(scene, p, dur)
            if r.summary.overturned or not r.summary.uplifted:
                continue
            spec = (("A", A), ("W", W), ("kind", "ricker"), ("shape", shape), ("sign", sign))
            cases.append(ValidationCase("survive", p.label() if hasattr(p, "label") else
                                        f"{shape} {sign} A={A} W={W}", spec, 0.0, dur, None,
                                        float(r.summary.max_abs_phi_over_alpha)))
    over = [(3.0, "symmetric", 1), (4.0, "antisymmetric", -1)]
    for W, shape, sign in (over[:1] if quick else over):
        A_ov = overturn_threshold(scene, W, shape, sign, rtol=1e-2 if quick else 1e-3)
        if not math.isfinite(A_ov):
            continue
        A = round(_OVERTURN_FACTOR * A_ov, 4)
        p = _pulse(sc_fall, A, W, shape, sign)
        dur = round(_OVERTURN_END - p.t_start, 4)
        r = _analytic(sc_fall, p, dur)
        if not r.summary.overturned:
            continue
        spec = (("A", A), ("W", W), ("kind", "ricker"), ("shape", shape), ("sign", sign))
        cases.append(ValidationCase("overturn", p.label(), spec, 0.0, dur, fall,
                                    float(r.summary.max_abs_phi_over_alpha)))
    return tuple(cases)


def validation_set(scene, *, quick: bool = False) -> list[ValidationCase]:
    """The validation set of ``scene``, chosen with the analytic model (cached in memory per
    scene data):

    * free rocking from phi0 = +-0.3 alpha and +-0.7 alpha (4 runs), each ending between the
      peak after the third impact and the fourth impact;
    * 12 Ricker pulses the analytic structure survives: the four pulses (symmetric and
      antisymmetric, both signs) at W = 3 and W = 4, at A = 0.6 x the analytic overturning
      threshold of that pulse (:func:`overturn_threshold`), and the four at W = 3 also at
      0.95 x the threshold (near the overturning boundary, where the response is steep), each
      from -3 T_g to 2.5 s after the pulse centre (pulses that do not uplift or that overturn
      are dropped);
    * 2 overturning pulses at 1.25 x the threshold (symmetric +1 at W = 3, antisymmetric -1 at
      W = 4), to 8 s after the centre, with the fall angle min(4 alpha, the scene's).

    ``quick``: 1 free run (+0.7 alpha), 4 surviving pulses (2 pulses x 2 factors) and 1
    overturning pulse: for tests and ``rockbench advise --quick``.
    """
    return list(_validation_set(_scene_key(scene), bool(quick)))

"""What an engine run's samples say beyond its own stepping (used by
:func:`rockbench.engines.loop.finish` and the sample checks), by the verdict rule of every
backend (:mod:`rockbench.verdict`): the collapse rule, energy growth between peaks, what a run
that stopped early still says (a fall finished by the analytic model from its last state, a
peak and verdict that are final, or an unknown verdict), and whether a run that finished moved
when it had to (``docs/errors.md``).

Units: SI and radians.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..constants import G
from ..scene.scene import Scene
from ..verdict import finish_fall, past_critical


def _energy_floor(ref) -> float:
    """[J] The potential at |phi| = alpha / 20 (the smaller of the two directions): the floor
    of the energy scale of the divergence checks (as :func:`_peak_energy_growth` uses it)."""
    return min(ref.dyn[s].energy(s * 0.05 * ref.alpha, 0.0, True) for s in (1, -1))


def _judge_stopped(scene: Scene, motion, ref, t: np.ndarray, phi: np.ndarray,
                   phidot: np.ndarray, intact: np.ndarray, t0: float
                   ) -> tuple[bool, float | None, str | None]:
    """(overturned, t_overturn [s], note) of a run that diverged at its last sample, by the
    verdict rule of every backend:

    * past its critical angle: the fall is finished with the analytic model from the engine's
      last state (phi, phidot at t, under what is left of the ground motion;
      :func:`rockbench.verdict.finish_fall`): the verdict is the model's from there, and the
      note says so;
    * inside it, with the ground motion over and the mechanical energy left unable to lift
      |phi| past the peak measured (impacts and dampers only remove energy): the peak and the
      verdict (survived) measured before the divergence are final, and the note says so;
    * otherwise the verdict is unknown, and the note says so (the summary's ``overturned``
      is then False only because no fall was seen)."""
    j = phi.size - 1
    p, pd, t_j, on = float(phi[j]), float(phidot[j]), float(t[j]), bool(intact[j])
    s = 1 if p > 0 else -1
    alpha = ref.alpha
    where = f"{p / alpha:.4g} alpha, phidot {pd:.3g} rad/s at t = {t_j:.4g} s"
    if past_critical(p, on, ref.critical):
        from ..analytic.solver import simulate

        sc = scene if (on or not scene.has_devices) else scene.replace(devices=None)
        rest = _Remaining(motion, t_j) if motion is not None else None
        remaining = max(float(motion.t_end) - t_j, 0.0) if motion is not None else 0.0
        try:
            (r,), _ = finish_fall(
                [None], [True],
                lambda _, extension: [simulate(sc, rest, duration=remaining + extension,
                                               phi0=p, phidot0=pd,
                                               reference=ref if sc is scene else None)],
                fell=lambda r: r.summary.overturned and r.summary.t_overturn is not None)
        except Exception as e:  # noqa: BLE001 - the verdict stays unknown
            return False, None, f"it stopped past its critical angle ({where}); finishing the " \
                                f"fall with the analytic model failed ({type(e).__name__})"
        off = 0.0 if motion is not None else t_j
        if r is not None:                     # it fell
            t_o = float(r.summary.t_overturn) + off
            return True, t_o, (f"it diverged past its critical angle ({where}): finished with "
                               f"the analytic model from that state, it overturns at "
                               f"t = {t_o:.4g} s (verdict overturned)")
        return False, None, (f"it diverged past its critical angle ({where}): finished with "
                             "the analytic model from that state, it comes back and survives")
    quiet = t0 if motion is None else float(motion.t_end)
    unknown = (f"its verdict is unknown: it stopped inside its critical angle ({where})")
    if t_j < quiet:
        return False, None, f"{unknown} before the ground motion was over (t = {quiet:.4g} s)"
    dyn = ref.dyn
    peak = float(np.max(np.abs(phi)))
    left = dyn[s].energy(p, pd, on)
    bound = min(dyn[d].energy(d * peak, 0.0, on) for d in (1, -1))
    if left <= bound and not past_critical(np.array([peak, -peak]), on, ref.critical).any():
        return False, None, (f"it diverged after its peak ({where}): the ground motion was "
                             f"over and the energy left ({left:.4g} J) cannot lift |phi| past "
                             f"the peak measured ({peak / alpha:.4g} alpha, {bound:.4g} J): "
                             "the peak and the verdict (survived) measured before are final")
    return False, None, (f"{unknown} with energy left ({left:.4g} J) that could lift |phi| past "
                         f"its peak ({peak / alpha:.4g} alpha, {bound:.4g} J)")


class _Remaining:
    """What is left of a ground motion from ``t`` [s] on (the same acceleration; the run
    starts at ``t``): the analytic model's input when it finishes a fall an engine left."""

    def __init__(self, motion, t: float):
        self._m, self.t_start = motion, t
        self.t_end = max(float(motion.t_end), t)

    def acceleration(self, t):
        return self._m.acceleration(t)

    def knots(self, t0: float, t1: float) -> np.ndarray:
        return self._m.knots(t0, t1)

    def max_abs_after(self, t: float) -> float:
        return self._m.max_abs_after(t)

    @property
    def peak(self) -> float:
        return self._m.max_abs_after(self.t_start)

    def describe(self) -> dict[str, Any]:
        return dict(self._m.describe(), t_start_s=self.t_start)


#: Slip [m] of a contact point beyond which a structure that did not rotate still moved (a
#: base that slid responded to the ground motion: it is not a frozen world). The contact probe's
#: own contact tolerance, 1 mm.
SLID = 1e-3


def _frozen(scene: Scene, motion, ref, t: np.ndarray, phi: np.ndarray, intact: np.ndarray,
            phi0: float, t0: float, uplift_phi: float, slid: float = 0.0) -> str | None:
    """Why a run that finished cleanly did not move when it had to (None if it moved or did not
    have to): its contacts slid no more than :data:`SLID` (``slid``: the run's largest slip [m];
    a base that slides instead of rocking, friction below its slenderness, moved) and
    |phi - phi0| stayed within ``uplift_phi`` [rad] over the whole run while

    * free rocking from phi0 != 0: gravity accelerates the structure at phi'' (Eq. 17 at rest)
      and moves it by min(|phi0|, phi'' T^2 / 2) >= 10 ``uplift_phi`` within the run's T;
    * under a ground motion whose peak exceeds the uplift threshold (min lambda g): the analytic
      model, run only in this case, lifts it by at least 10 ``uplift_phi``.

    A frozen world (bodies that do not respond to gravity or to the ground motion: a
    negligible mass against the engine's contact regularisation, a broken step) is not a
    result: its status is "invalid" with this reason."""
    if not phi.size:
        return None
    moved = float(np.max(np.abs(phi - phi0)))
    if moved > uplift_phi or slid > SLID:
        return None
    span = float(t[-1] - t0)
    if motion is None:
        if phi0 == 0.0:
            return None
        s = 1 if phi0 > 0 else -1
        acc = abs(ref.dyn[s].acceleration(phi0, 0.0, 0.0, bool(intact[0])))
        expect = min(abs(phi0), 0.5 * acc * span * span)
        what = f"gravity moves it {expect:.3g} rad within the run (phi'' = {acc:.3g} rad/s^2 " \
               "at release)"
    else:
        lam = min(abs(ref.lam[1]), abs(ref.lam[-1])) * G
        if not float(motion.peak) > 1.5 * lam or span <= 0.0:
            return None
        from ..analytic.solver import simulate

        try:
            r = simulate(scene, motion, duration=span, phi0=0.0, reference=ref)
        except Exception:  # noqa: BLE001 - no reference, no verdict
            return None
        expect = float(r.summary.max_abs_phi)
        what = (f"the analytic model rocks it to {expect:.3g} rad under this ground motion "
                f"(peak {float(motion.peak):.3g} m/s^2 > 1.5 x its uplift acceleration "
                f"{lam:.3g} m/s^2)")
    if expect < 10.0 * uplift_phi:
        return None
    return (f"the structure did not move: |phi - phi0| stayed below {moved:.3g} rad (uplift_tol "
            f"alpha = {uplift_phi:.3g} rad) over the whole run, while {what}: its bodies do not "
            "respond (a frozen world)")


def _peak_energy_growth(exc: list, t: np.ndarray, phi: np.ndarray, intact: np.ndarray, dyn,
                        t_quiet: float, tol: float, alpha: float) -> str | None:
    """Reason string if the energy of an excursion (its potential at its peak: gravity and
    intact tendons) exceeds that of the previous one by more than ``tol`` (relative) plus
    ``tol`` times the potential at |phi| = alpha / 20, for excursions after the ground motion
    ended (``t_quiet`` [s]); None otherwise. Impacts and dampers only remove energy."""
    if dyn is None or len(exc) < 2:
        return None
    floor = tol * min(dyn[s].energy(s * 0.05 * alpha, 0.0, True) for s in (1, -1))
    prev = None
    for x in exc:
        if not x.complete or t[x.i0] < t_quiet:
            prev = None
            continue
        V = dyn[x.sign].energy(x.sign * x.peak, 0.0, bool(intact[x.ipk]))
        if prev is not None and x.after_impact and V > prev[0] * (1 + tol) + floor:
            return (f"mechanical energy grew without input: peak {x.sign * x.peak:.4g} rad at "
                    f"t={t[x.ipk]:.4g} s holds {V:.4g} J, the previous peak (t={prev[1]:.4g} s) "
                    f"{prev[0]:.4g} J")
        prev = (V, float(t[x.ipk]))
    return None


def _collapse(t: np.ndarray, phi: np.ndarray, intact: np.ndarray, crit: dict,
              t_quiet: float) -> int | None:
    """Index of the sample from which an engine's structure stayed beyond its critical angle to
    the end of a run that ends after the ground motion (``t_quiet`` [s]): it has collapsed -
    come to rest on another body or on the ground before reaching the fall angle, which no
    rigid-impact model allows (past the critical angle, with no input, the potential only
    falls: :mod:`rockbench.verdict`). None when the run does not end that way."""
    if not t.size or t[-1] < t_quiet:
        return None
    beyond = past_critical(phi, intact, crit)
    if not beyond[-1]:
        return None
    inside = np.flatnonzero(~beyond)
    return int(inside[-1] + 1) if inside.size else 0

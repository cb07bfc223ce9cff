"""The validity of the analytic model, one rule for every caller (advise, report, map, stress,
fragility): on which side of the model's assumptions a case lies, in the same words everywhere.

The analytic SDOF model keeps its pivots in contact and never sliding. A case is **outside the
model** when its ground motion asks the base for more friction than the contact has: a rigid base
at rest slides under the ground's own horizontal acceleration once |a_g| > mu (g + a_v) (Newmark
1965), whatever the structure rocks; rocking changes that demand (the pivot's reaction turns
with the rotation, :mod:`rockbench.analytic.reactions`). It is also outside once the ground
falls faster than gravity, g + a_v <= 0: the structure leaves the ground (free flight).
mu is the scene's Coulomb friction of the base contact (:func:`friction_of`: the scene's
``[contact] friction`` when it has one, else :data:`DEFAULT_FRICTION`, the engines' common
default); the beam of a frame rests on its columns with :func:`beam_friction_of`.

Two tests, one rule:

* **a priori**, from the motion alone (:func:`motion_validity`): with no vertical motion,
  PGA > mu g; with one, |a_g(t)| > mu (g + a_v(t)) at some t, or g + a_v(t) <= 0 at some t
  (the first instant, :func:`lift_off_time`). This is the demand of the structure at rest, the
  test that needs no run.
* **along a run** of the analytic model (:func:`run_validity`): the friction its contacts
  need at every output step while they hold (:func:`rockbench.analytic.reactions.
  demand_history`), against mu; the first time a contact needs more is the run's
  ``sliding_onset`` (the base, or the beam on its columns), a loss of contact its
  ``t_lift_off``. The model's history is still computed after a sliding onset (it is the
  rocking model's answer, the one an engine's run can be compared with up to that time) and
  the run says from when it is outside the model; at a loss of contact the model stops.

Outside the model, an engine's run is physics of another kind (sliding, slide-rock), not an
error against the analytic reference: it is never evidence for the engine's accuracy, never an
"ok" against the reference in silence, and every table says which side each case is on
(:data:`INSIDE`, or the reason that starts with "outside").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .constants import G

__all__ = ["DEFAULT_FRICTION", "INSIDE", "Validity", "friction_of", "beam_friction_of",
           "pga_limit", "lift_off_time", "motion_validity", "run_validity"]

#: Coulomb friction of the base contact the validity rule assumes when a scene gives none [-]
#: (each engine's own default ``friction`` is at least this, docs/engines/README.md, so a case
#: inside the model with it is inside for every engine).
DEFAULT_FRICTION = 1.0

#: The word for a case inside the model's assumptions.
INSIDE = "inside"


@dataclass(frozen=True)
class Validity:
    """Which side of the model's assumptions a case is on: ``inside`` (bool) and ``reason``
    (:data:`INSIDE`, or a sentence that starts with "outside")."""

    inside: bool
    reason: str

    def __bool__(self) -> bool:
        return self.inside


def friction_of(scene: Any) -> float:
    """The Coulomb friction coefficient mu [-] of ``scene``'s base contact: its own when the
    scene gives one (``scene.friction``), else :data:`DEFAULT_FRICTION`."""
    mu = getattr(scene, "friction", None)
    return float(mu) if mu is not None else DEFAULT_FRICTION


def beam_friction_of(scene: Any) -> float:
    """The Coulomb friction coefficient [-] of a frame's beam on its columns: the scene's
    ``[contact] beam_friction`` when it gives one, else the base's (:func:`friction_of`)."""
    mu = getattr(getattr(scene, "contact", None), "beam_friction", None)
    return float(mu) if mu is not None else friction_of(scene)


def pga_limit(scene: Any) -> float:
    """The largest peak ground acceleration [m/s^2] inside the model without vertical motion:
    mu g (beyond it a base at rest slides under the ground's own acceleration)."""
    return friction_of(scene) * G


def lift_off_time(motion: Any, t0: float | None = None, t1: float | None = None,
                  scale: float = 1.0) -> float | None:
    """The first time t [s] in [t0, t1] (default: the motion's window) at which the ground
    falls at least as fast as gravity, g + scale a_v(t) <= 0 (a_v: ``motion.vertical``, up
    positive): the structure leaves the ground there. None when it never does (or the motion
    has no vertical part). Exact up to 1e-13 s: a_v is monotonic between the vertical's knots,
    the crossing is refined by Brent's method and stepped to the first instant where
    g + a_v <= 0 holds."""
    vert = getattr(motion, "vertical", None) if motion is not None else None
    if vert is None:
        return None
    import numpy as np
    from scipy.optimize import brentq

    a = float(vert.t_start if t0 is None else t0)
    b = float(vert.t_end if t1 is None else t1)
    if not b >= a:
        return None
    k = float(scale)

    def n(tt: float) -> float:              # g + a_v [m/s^2]
        return G + k * float(vert.acceleration(tt))

    ks = vert.knots(a, b)
    vals = G + k * np.asarray(vert.acceleration(ks), dtype=float)
    hit = np.flatnonzero(vals <= 0.0)
    if hit.size == 0:
        return None
    i = int(hit[0])
    if i == 0:
        return float(ks[0])
    lo, hi = float(ks[i - 1]), float(ks[i])
    t = brentq(n, lo, hi, xtol=1e-13, rtol=1e-14)
    step = 1e-13 * max(1.0, abs(t))
    while t < hi and not n(t) <= 0.0:
        t = min(hi, t + step)
        step *= 2.0
    return float(t)


def motion_validity(scene: Any, motion: Any = None, *, scale: float = 1.0) -> Validity:
    """The a-priori validity of ``scene`` under ``motion`` (a GroundMotion, or None for free
    rocking) scaled by ``scale`` (both components): outside when the ground falls faster than
    gravity at some time (g + a_v <= 0, :func:`lift_off_time`), or when the horizontal
    acceleration exceeds the base friction of the structure at rest, |a_g(t)| > mu (g + a_v(t))
    at some t (without vertical motion: the PGA exceeds :func:`pga_limit`). The test is exact
    on the motion's knots (between them |a_g| - mu (g + a_v) is monotonic on each side of 0,
    :class:`~rockbench.scene.motion.GroundMotion`)."""
    if motion is None:
        return Validity(True, INSIDE)
    mu = friction_of(scene)
    vert = getattr(motion, "vertical", None)
    if vert is None:
        peak = abs(float(scale)) * float(motion.peak)
        lim = pga_limit(scene)
        if not math.isfinite(peak) or peak > lim:
            return Validity(False, f"outside the model: PGA {peak / G:.3g} g exceeds the base "
                                   f"friction mu g = {lim / G:.3g} g, the base slides")
        return Validity(True, INSIDE)
    import numpy as np

    t_lift = lift_off_time(motion, motion.t_start, motion.t_end, scale)
    if t_lift is not None:
        return Validity(False, f"outside the model: the ground falls faster than gravity "
                               f"(g + a_v <= 0) at t = {t_lift:.6g} s, the structure leaves "
                               "the ground")
    ks = np.unique(np.concatenate([motion.knots(motion.t_start, motion.t_end),
                                   vert.knots(motion.t_start, motion.t_end)]))
    k = float(scale)
    ag = k * np.asarray(motion.acceleration(ks), dtype=float)
    ge = G + k * np.asarray(vert.acceleration(ks), dtype=float)
    ratio = np.abs(ag) / ge
    i = int(np.argmax(ratio))
    if not math.isfinite(float(ratio[i])) or ratio[i] > mu:
        return Validity(False, f"outside the model: |a_g| = {abs(ag[i]) / G:.3g} g exceeds "
                               f"mu (g + a_v) = {mu * ge[i] / G:.3g} g at t = {ks[i]:.6g} s, "
                               "the base slides")
    return Validity(True, INSIDE)


def run_validity(scene: Any, *, sliding_onset: float | None = None,
                 sliding_contact: str | None = None, demand: float | None = None,
                 t_lift_off: float | None = None) -> Validity:
    """Which side of the model a run of the analytic model is on, from what it found: the
    first time a contact needs more friction than it has (``sliding_onset`` [s], at contact
    ``sliding_contact``, "base" or "beam", with ``demand`` = |T| / N [-] there, inf when the
    contact opens) and the loss of contact (``t_lift_off`` [s]). Inside when neither happened;
    otherwise the reason says from when the run is outside the model, and why."""
    events = []
    if sliding_onset is not None and math.isfinite(sliding_onset):
        mu = beam_friction_of(scene) if sliding_contact == "beam" else friction_of(scene)
        where = "the beam on its columns" if sliding_contact == "beam" else "the base"
        d = float(demand) if demand is not None else math.nan
        why = (f"{where} opens (a contact would have to pull)" if d == math.inf else
               f"{where} needs friction {d:.3g} > mu = {mu:.3g}, it slides" if d == d else
               f"{where} slides (mu = {mu:.3g})")
        events.append((float(sliding_onset), why))
    if t_lift_off is not None and math.isfinite(t_lift_off):
        events.append((float(t_lift_off), "the ground falls faster than gravity "
                                          "(g + a_v <= 0), the structure leaves the ground"))
    if not events:
        return Validity(True, INSIDE)
    t, why = min(events)
    return Validity(False, f"outside the model from t = {t:.6g} s: {why}")

"""The validity of the analytic model, one rule for every caller (advise, report, map, stress,
fragility): on which side of the model's assumptions a case lies, in the same words everywhere.

The analytic SDOF model keeps its pivots in contact and never sliding. A case is **outside the
model** when its ground motion asks the base for more friction than the contact has: a rigid base
at rest slides under the ground's own horizontal acceleration once |a_g| > mu (g + a_v) (Newmark
1965), whatever the structure rocks; rocking adds to that demand (the pivot's reaction turns
with the rotation, :mod:`rockbench.analytic.reactions`). With no vertical motion the a-priori
test is PGA > mu g. mu is the scene's Coulomb friction of the base contact
(:func:`friction_of`: the scene's ``[contact] friction`` when it has one, else
:data:`DEFAULT_FRICTION`, the engines' common default).

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

__all__ = ["DEFAULT_FRICTION", "INSIDE", "Validity", "friction_of", "pga_limit",
           "motion_validity"]

#: Coulomb friction of the base contact when a scene gives none [-] (every engine's contact
#: takes it, ``EngineSettings.friction``).
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


def pga_limit(scene: Any) -> float:
    """The largest peak ground acceleration [m/s^2] inside the model without vertical motion:
    mu g (beyond it a base at rest slides under the ground's own acceleration)."""
    return friction_of(scene) * G


def motion_validity(scene: Any, motion: Any = None, *, scale: float = 1.0) -> Validity:
    """The a-priori validity of ``scene`` under ``motion`` (a GroundMotion, or None for free
    rocking) scaled by ``scale``: outside when the peak horizontal ground acceleration exceeds
    :func:`pga_limit`."""
    if motion is None:
        return Validity(True, INSIDE)
    peak = abs(float(scale)) * float(motion.peak)
    lim = pga_limit(scene)
    if not math.isfinite(peak) or peak > lim:
        return Validity(False, f"outside the model: PGA {peak / G:.3g} g exceeds the base "
                               f"friction mu g = {lim / G:.3g} g, the base slides")
    return Validity(True, INSIDE)

"""The scene's contact: the Coulomb friction of the base contacts and of the beam on its columns.

A scene file's optional ``[contact]`` table::

    [contact]
    friction = 0.4          # base contacts (block or column bases on the foundation) [-]
    beam_friction = 0.6     # frames only: the beam on its columns' top corners [-]

Both are Coulomb coefficients, static = kinetic, in (0, 10]. **No friction given** (no table, or
``friction`` left out) means what the rocking model assumes: pivots that do not slide. Each
engine then uses its own ``EngineSettings.friction`` (listed in ``docs/engines/README.md``),
high enough that the cases it is checked on do not slide, and a base that slides beyond the
engine's ``max_sliding`` marks the run diverged. A friction given
is physics: every engine uses exactly that value for every base contact pair (and
``beam_friction``, default ``friction``, for the beam on the column tops), and sliding is
modelled, not an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

from ..errors import ParameterError

__all__ = ["Contact", "FRICTION_RANGE"]

#: The valid range of a Coulomb coefficient in a scene (open below, closed above): no engine
#: can model a frictionless contact, and PyBullet clamps a pair's coefficient at 10.
FRICTION_RANGE = (0.0, 10.0)


def _check_friction(name: str, value: Any) -> float | None:
    if value is None:
        return None
    lo, hi = FRICTION_RANGE
    ok = not isinstance(value, bool) and isinstance(value, (int, float))
    x = float(value) if ok else math.nan
    if not (ok and math.isfinite(x) and lo < x <= hi):
        raise ParameterError(name, value, f"in ({lo:g}, {hi:g}] (a Coulomb coefficient [-]), "
                                          "or left out")
    return x


@dataclass(frozen=True)
class Contact:
    """The scene's contact friction.

    friction : float or None
        Coulomb coefficient [-] (static = kinetic) of the base contacts, in (0, 10]. None: not
        given (each engine's default, the rocking model's non-sliding pivots; module
        docstring).
    beam_friction : float or None
        Coulomb coefficient [-] of the beam on its columns' top corners, in (0, 10]; frames
        only (:class:`~rockbench.scene.scene.Scene` refuses it on a block). None: the base
        ``friction``. Needs ``friction``.
    """

    friction: float | None = None
    beam_friction: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "friction", _check_friction("contact.friction", self.friction))
        object.__setattr__(self, "beam_friction",
                           _check_friction("contact.beam_friction", self.beam_friction))
        if self.beam_friction is not None and self.friction is None:
            raise ParameterError("contact.beam_friction", self.beam_friction,
                                 "given together with contact.friction",
                                 "without a base friction the engines use their own defaults "
                                 "for every contact: give friction too")

    @property
    def given(self) -> bool:
        """Whether the scene states a friction (sliding is then physics, not an error)."""
        return self.friction is not None

    @property
    def beam(self) -> float | None:
        """The beam-on-column coefficient in use [-]: ``beam_friction``, else ``friction``."""
        return self.beam_friction if self.beam_friction is not None else self.friction

    def to_dict(self) -> dict[str, float]:
        """The fields given (none: an empty dict)."""
        return {k: v for k, v in (("friction", self.friction),
                                  ("beam_friction", self.beam_friction)) if v is not None}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> "Contact":
        return cls(**dict(data or {}))

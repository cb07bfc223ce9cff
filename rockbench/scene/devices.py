"""Supplemental devices of the hybrid rocking frame: unbonded tendons and viscous dampers.

One tendon per column runs along the column centre line, without pretension, from the foundation
to the beam. It is a linear spring of stiffness ``k`` and free length ``l``; its elongation is
the opening of the base joint plus the opening of the top joint (paper, Eq. 9-11 with the sign of
the beam rotation corrected, see ``docs/paper-discrepancies.md``), each opening being the chord
``2 b sin(|relative rotation| / 2)`` travelled by the centre line's end point. The strain is
``elongation / l``. The tendon is elastic until brittle fracture at strain ``eps_f``.

One linear viscous damper per column acts along the chord between the uplifting heel corner and
its rest position (the geometry of the paper's Eq. 16): for a column rotating by ``theta`` about
its base pivot the chord is ``4 b sin(|theta|/2)`` and the damper force is ``C d(chord)/dt``.

When either tendon reaches ``eps_f`` all tendons and dampers are removed for the rest of the run
(paper: simultaneous brittle failure).

Every parameter is required (the paper's devices are in ``rockbench/scenarios/
paper-asymmetric-hybrid.toml``): ``docs/scenes.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from ..errors import ParameterError, check_finite, check_nonnegative, check_positive
from .schema import fields_of

#: smallest fracture strain [-]: 0.01 %, far below any tendon's (steel yields near 0.2 %)
MIN_FRACTURE_STRAIN = 1e-4

__all__ = ["Devices"]


@dataclass(frozen=True)
class Devices:
    """Tendons and dampers of a hybrid frame (one of each per column).

    Parameters (all required)
    ----------
    tendon_stiffness : float
        k = EA / l [N/m], >= 0 (paper: 23.5e6). 0 means no tendons.
    tendon_length : float
        Free length l [m], > 0 (paper: 8.5).
    fracture_strain : float or None
        eps_f [-], in [1e-4, 1), or None (say it: ``fracture_strain=None``) for tendons that never
        fracture (paper: None, 0.02, 0.01).
    damping : float
        Damper constant C [N s/m], >= 0 (paper: 25.3e6). 0 means no dampers.
    """

    tendon_stiffness: float = ...  # type: ignore[assignment]  # required: ... is refused
    tendon_length: float = ...  # type: ignore[assignment]
    fracture_strain: float | None = ...  # type: ignore[assignment]
    damping: float = ...  # type: ignore[assignment]

    def __post_init__(self) -> None:
        for f in fields_of("devices"):
            if getattr(self, f.name) is ...:
                raise ParameterError(f.name, "missing", "given",
                                     f"devices field: {f.meaning} [{f.unit}], {f.range_text()}; "
                                     "docs/scenes.md")
        object.__setattr__(self, "tendon_stiffness",
                           check_nonnegative("tendon_stiffness", self.tendon_stiffness))
        object.__setattr__(self, "tendon_length",
                           check_positive("tendon_length", self.tendon_length))
        object.__setattr__(self, "damping", check_nonnegative("damping", self.damping))
        if self.fracture_strain is not None:
            # one message with the whole range (a strain <= 0 said only "> 0")
            eps = check_finite("fracture_strain", self.fracture_strain)
            if not MIN_FRACTURE_STRAIN <= eps < 1.0:
                raise ParameterError("fracture_strain", self.fracture_strain,
                                     f"in [{MIN_FRACTURE_STRAIN:g}, 1) or None (no fracture)",
                                     "no tendon breaks below 0.01 % strain (tendon steel "
                                     "yields near 0.2 %); a smaller strain is reached by the "
                                     "round-off of the structure at rest")
            object.__setattr__(self, "fracture_strain", eps)

    @property
    def has_tendons(self) -> bool:
        return self.tendon_stiffness > 0.0

    @property
    def has_dampers(self) -> bool:
        return self.damping > 0.0

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

"""Rigid structures: the free-standing block (Housner 1963) and the three-block rocking frame.

Geometry follows Dimitrakopoulos & Giouvanidis (2015), section "Seismic Stability of the
Asymmetric Rocking Frame", and ``docs/conventions.md``:

* x horizontal (positive to the right), y vertical (positive up), origin at the centre of the
  base of the left (taller) column AB.
* The left column has width ``2b`` and height ``2H``; the right column CD has width ``2b`` and
  height ``2H1 <= 2H`` and stands on a foundation step of height ``2(H - H1)`` so that both tops
  are level at ``y = 2H``. Column centre lines are ``L`` apart.
* The cap beam (width ``beam_width``, height ``2h``) rests on both column tops; its centre of
  mass is at mid-span between the outer column faces (``x = L/2``) and mid-depth (``y = 2H + h``).

All lengths are metres, masses kilograms, densities kg/m^3, inertias kg m^2, angles radians.
Every quantity derived from the geometry (alpha, p, R, pivots, masses, inertias) is computed here
and nowhere else.

No field takes a value from the paper: the dimensions are required, and the defaults are
physical (``docs/scenes.md``, generated from :mod:`rockbench.scene.schema`). The paper's frame is
``load_scene("paper-asymmetric").structure``. These classes check that each field is a positive
finite number and that the parts fit together; the physical ranges of the fields and the limits
of the model (eta >= 0, the frame's mechanism) are checked by :class:`rockbench.Scene`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, ClassVar

from ..constants import G
from ..errors import ParameterError, check_positive
from .schema import fields_of

__all__ = ["Block", "Frame", "Structure", "check_direction"]


def _given(obj: Any, names: tuple[str, ...]) -> None:
    """Check that the fields ``names`` of ``obj`` are given (not None) and positive finite
    numbers (stored as float); a missing one raises a ParameterError saying what it is."""
    table = obj.kind
    for name in names:
        value = getattr(obj, name)
        if value is None:
            f = next(f for f in fields_of(table) if f.name == name)
            raise ParameterError(name, "missing", "given", f"{table} field: {f.meaning} [{f.unit}], "
                                 f"{f.range_text()}; docs/scenes.md")
        object.__setattr__(obj, name, check_positive(name, value))


def _frequency_parameter(R: float) -> float:
    """Housner's frequency parameter p = sqrt(3 g / (4 R)) [rad/s] of a rectangular block of
    half-diagonal R [m]."""
    return math.sqrt(3.0 * G / (4.0 * R))


@dataclass(frozen=True)
class Block:
    """A free-standing rectangular rigid block on a rigid foundation (Housner 1963).

    Parameters (all > 0)
    ----------
    width : float
        Base width 2b [m], required.
    height : float
        Height 2H [m], required.
    depth : float
        Out-of-plane depth [m] (default 1.0).
    density : float
        Mass density [kg/m^3] (default 2500, normal-weight concrete).
    """

    width: float = None  # type: ignore[assignment]  # required: None is refused
    height: float = None  # type: ignore[assignment]
    depth: float = 1.0
    density: float = 2500.0

    kind: ClassVar[str] = "block"

    def __post_init__(self) -> None:
        _given(self, tuple(f.name for f in fields(self)))

    # --- derived quantities -------------------------------------------------------------
    @property
    def b(self) -> float:
        """Half width [m]."""
        return 0.5 * self.width

    @property
    def H(self) -> float:
        """Half height [m]."""
        return 0.5 * self.height

    @property
    def R(self) -> float:
        """Half diagonal, distance from a base corner to the centre of mass [m]."""
        return math.hypot(self.b, self.H)

    @property
    def alpha(self) -> float:
        """Slenderness angle alpha = atan(b / H) [rad]."""
        return math.atan2(self.b, self.H)

    @property
    def p(self) -> float:
        """Frequency parameter p = sqrt(3 g / (4 R)) [rad/s]."""
        return _frequency_parameter(self.R)

    @property
    def mass(self) -> float:
        """Mass [kg]."""
        return self.density * self.width * self.height * self.depth

    @property
    def inertia_cm(self) -> float:
        """Moment of inertia about the centre of mass, in the plane [kg m^2] = m R^2 / 3."""
        return self.mass * self.R**2 / 3.0

    @property
    def eta_housner(self) -> float:
        """Housner's coefficient of restitution 1 - 1.5 sin^2(alpha) [-]."""
        return 1.0 - 1.5 * math.sin(self.alpha) ** 2

    def to_dict(self) -> dict[str, Any]:
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["type"] = self.kind
        return d


@dataclass(frozen=True)
class Frame:
    """The planar rocking frame: two rigid columns capped by a rigid beam, joined by contacts only.

    The six dimensions are required (the paper's frame is ``load_scene("paper-asymmetric")``);
    the beam's mass and radius of gyration default to a uniform solid beam.

    Parameters
    ----------
    column_width : float
        Width 2b of both columns [m], > 0.
    column_height_left : float
        Height 2H of the left, taller column AB [m], > 0. Defines alpha and p.
    column_height_right : float
        Height 2H1 of the right column CD [m], 0 < 2H1 <= 2H. It stands on a foundation step of
        height 2(H - H1).
    span : float
        Centre-to-centre distance L of the columns [m], > column_width (columns may not overlap).
    beam_width : float
        Length of the cap beam [m], >= span + column_width (it must cover both column tops).
    beam_height : float
        Depth 2h of the cap beam [m], > 0.
    beam_gyration_radius : float or None
        Polar radius of gyration rho of the beam about its centre of mass [m], > 0. None: a
        uniform rectangle's, sqrt((beam_width^2 + beam_height^2) / 12) (the paper: 3.58 m
        for a 13 m x 2 m beam, whose uniform value is 3.80 m).
    depth : float
        Out-of-plane depth of the columns [m] (default 1.0).
    density : float
        Column mass density [kg/m^3] (default 2500, normal-weight concrete).
    mass_ratio : float or None
        Beam mass / left column mass [-] (the paper: 10, after Mander & Cheng 1997): one way to
        give the beam's mass.
    beam_mass : float or None
        Beam mass m_BC [kg]: the other way. Given with ``mass_ratio``, the two must agree (to
        1e-9, relative) and ``beam_mass`` is kept. Neither: a solid beam of ``density``,
        density x beam_width x beam_height x depth.
    """

    column_width: float = None  # type: ignore[assignment]  # required: None is refused
    column_height_left: float = None  # type: ignore[assignment]
    column_height_right: float = None  # type: ignore[assignment]
    span: float = None  # type: ignore[assignment]
    beam_width: float = None  # type: ignore[assignment]
    beam_height: float = None  # type: ignore[assignment]
    beam_gyration_radius: float | None = None
    depth: float = 1.0
    density: float = 2500.0
    mass_ratio: float | None = None
    beam_mass: float | None = None

    kind: ClassVar[str] = "frame"

    def __post_init__(self) -> None:
        _given(self, ("column_width", "column_height_left", "column_height_right", "span",
                      "beam_width", "beam_height", "depth", "density"))
        _given(self, tuple(n for n in ("beam_gyration_radius", "mass_ratio", "beam_mass")
                           if getattr(self, n) is not None))
        if self.beam_mass is not None and self.mass_ratio is not None:
            m = self.mass_left   # 0 or inf for lengths out of range: the Scene refuses those
            usable = 0.0 < m < math.inf and math.isfinite(self.mass_ratio * m)
            if usable and not abs(self.beam_mass - self.mass_ratio * m) <= (
                    1e-9 * self.mass_ratio * m):
                implied = self.beam_mass / m
                raise ParameterError("mass_ratio", self.mass_ratio,
                                     f"beam_mass / left column mass = {implied:.10g}, or left out",
                                     f"beam_mass = {self.beam_mass:g} kg is given too, and the "
                                     f"left column weighs {self.mass_left:g} kg")
            if usable:
                object.__setattr__(self, "mass_ratio", None)
        if self.column_height_right > self.column_height_left:
            raise ParameterError("column_height_right", self.column_height_right,
                                 f"<= column_height_left = {self.column_height_left:g}",
                                 "the left column AB is the taller one by convention")
        if self.span <= self.column_width:
            raise ParameterError("span", self.span, f"> column_width = {self.column_width:g}",
                                 "the columns would overlap")
        need = self.span + self.column_width
        if self.beam_width < need - 1e-12:
            raise ParameterError("beam_width", self.beam_width,
                                 f">= span + column_width = {need:g}",
                                 "the beam must cover both column tops")

    # --- half dimensions (paper notation) -------------------------------------------------
    @property
    def b(self) -> float:
        """Half column width b [m]."""
        return 0.5 * self.column_width

    @property
    def H(self) -> float:
        """Half height H of the left column [m]."""
        return 0.5 * self.column_height_left

    @property
    def H1(self) -> float:
        """Half height H1 of the right column [m]."""
        return 0.5 * self.column_height_right

    @property
    def h(self) -> float:
        """Half depth h of the beam [m]."""
        return 0.5 * self.beam_height

    @property
    def L(self) -> float:
        """Column centre-to-centre distance L [m]."""
        return self.span

    @property
    def step(self) -> float:
        """Height 2(H - H1) of the foundation step under the right column [m]."""
        return self.column_height_left - self.column_height_right

    @property
    def symmetric(self) -> bool:
        """True when both columns have the same height (H1 = H)."""
        return self.column_height_right == self.column_height_left

    @property
    def R0(self) -> float:
        """Half diagonal of the left column [m]."""
        return math.hypot(self.b, self.H)

    @property
    def R1(self) -> float:
        """Half diagonal of the right column [m]."""
        return math.hypot(self.b, self.H1)

    R = R0

    @property
    def alpha(self) -> float:
        """Slenderness alpha = atan(b/H) of the taller column [rad] (the paper's scaling)."""
        return math.atan2(self.b, self.H)

    @property
    def alpha1(self) -> float:
        """Slenderness alpha1 = atan(b/H1) of the right column [rad]."""
        return math.atan2(self.b, self.H1)

    @property
    def p(self) -> float:
        """Frequency parameter p = sqrt(3 g / (4 R0)) of the taller column [rad/s]."""
        return _frequency_parameter(self.R0)

    # --- masses and inertias ----------------------------------------------------------------
    @property
    def mass_left(self) -> float:
        """Mass m_AB of the left column [kg]."""
        return self.density * self.column_width * self.column_height_left * self.depth

    @property
    def mass_right(self) -> float:
        """Mass m_CD of the right column [kg]."""
        return self.density * self.column_width * self.column_height_right * self.depth

    @property
    def mass_beam(self) -> float:
        """Mass m_BC of the beam [kg]: ``beam_mass``, or ``mass_ratio`` * m_AB, or (neither
        given) a solid beam, density x beam_width x beam_height x depth."""
        if self.beam_mass is not None:
            return self.beam_mass
        if self.mass_ratio is not None:
            return self.mass_ratio * self.mass_left
        return self.density * self.beam_width * self.beam_height * self.depth

    @property
    def rho(self) -> float:
        """Polar radius of gyration of the beam [m]: ``beam_gyration_radius``, or a uniform
        rectangle's sqrt((beam_width^2 + beam_height^2) / 12)."""
        if self.beam_gyration_radius is not None:
            return self.beam_gyration_radius
        return math.sqrt((self.beam_width**2 + self.beam_height**2) / 12.0)

    @property
    def inertia_left(self) -> float:
        """I^G_AB = m_AB R0^2 / 3 [kg m^2], about the column's centre of mass."""
        return self.mass_left * self.R0**2 / 3.0

    @property
    def inertia_right(self) -> float:
        """I^G_CD = m_CD R1^2 / 3 [kg m^2]."""
        return self.mass_right * self.R1**2 / 3.0

    @property
    def inertia_beam(self) -> float:
        """I^G_BC = m_BC rho^2 [kg m^2]."""
        return self.mass_beam * self.rho**2

    @property
    def gamma(self) -> float:
        """Makris & Vassiliou's mass ratio gamma = m_BC / (2 m_AB) [-]."""
        return self.mass_beam / (2.0 * self.mass_left)

    # --- rest positions (origin: centre of the left column's base) ---------------------------
    @property
    def com_left(self) -> tuple[float, float]:
        """Rest position of G_AB [m]."""
        return (0.0, self.H)

    @property
    def com_right(self) -> tuple[float, float]:
        """Rest position of G_CD [m]."""
        return (self.L, self.step + self.H1)

    @property
    def com_beam(self) -> tuple[float, float]:
        """Rest position of G_BC [m]: mid-span between outer column faces, mid-depth."""
        return (0.5 * self.L, self.column_height_left + self.h)

    def pivots(self, direction: int) -> dict[str, tuple[float, float]]:
        """Rest positions [m] of the four pivots of the mechanism rocking in ``direction``.

        ``direction`` is +1 (counterclockwise, the frame sways left: A, D are the bottom-left
        corners, B, C the top-right corners) or -1 (clockwise: A', D' bottom-right, B', C'
        top-left).
        """
        s = check_direction(direction)
        b, L = self.b, self.L
        top = self.column_height_left
        return {"A": (-s * b, 0.0), "B": (s * b, top), "C": (L + s * b, top),
                "D": (L - s * b, self.step)}

    def beam_offset(self, direction: int) -> tuple[float, float]:
        """(r_BC, psi_BC): distance [m] from the top pivot B (or B') to G_BC and the angle [rad]
        of that vector above the beam soffit (x axis) at rest."""
        B = self.pivots(direction)["B"]
        gx, gy = self.com_beam
        return math.hypot(gx - B[0], gy - B[1]), math.atan2(gy - B[1], gx - B[0])

    def to_dict(self) -> dict[str, Any]:
        """The fields as a scene file's ``[structure]`` table (optional fields left as None,
        i.e. at their default, are left out)."""
        d = {f.name: getattr(self, f.name) for f in fields(self)
             if getattr(self, f.name) is not None}
        d["type"] = self.kind
        return d


Structure = Block | Frame


def check_direction(direction: int) -> int:
    """``direction`` as int if it is +1 (counterclockwise) or -1 (clockwise); ParameterError
    otherwise."""
    if direction not in (1, -1):
        raise ParameterError("direction", direction, "+1 (counterclockwise) or -1 (clockwise)")
    return int(direction)

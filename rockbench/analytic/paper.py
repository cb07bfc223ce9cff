"""The paper's closed forms, transcribed from the printed equations (Dimitrakopoulos &
Giouvanidis 2015, J. Eng. Mech. 141(8) 04015003), with the corrections the derivation demands.

This module is an independent check, not part of the model: the analytic reference
(:mod:`~rockbench.scene.mechanism`, :mod:`~rockbench.analytic.dynamics`,
:mod:`~rockbench.analytic.impact`) is built from first principles, and
``tests/analytic/test_paper.py`` compares the two. Where a printed equation disagrees with the
derivation, the function takes ``corrected``: ``corrected=False`` evaluates the equation *as
printed* (with its error), ``corrected=True`` (the default) the corrected form, which equals
the derivation. Every discrepancy is listed in ``docs/paper-discrepancies.md``.

Notation and conventions (the paper's, translated to rockbench's):

* ``direction`` s = +1: counterclockwise rocking (the paper's subscript p, upper sign of every
  +-); s = -1: clockwise (subscript n, lower sign).
* ``phi`` [rad] is rockbench's rocking rotation of the left column AB from rest (the paper's
  rocking rotation, Eq. 12). The paper's generalized coordinate is the *absolute* angle of the
  diagonal AB with the x axis, ``varphi = phi + varphi_0`` with ``varphi_0 = pi/2 - s alpha``
  (:func:`absolute_angle`). Derivatives with respect to phi and varphi are the same.
* alpha = atan(b/H), alpha1 = atan(b/H1) (the paper prints alpha1 = b/H1, see
  :func:`rocking_rotations`); hbar = H/H1, bbar = b/L.
* r_BC, psi_BC: distance [m] and angle [rad] above the soffit from the top pivot B (B') to the
  beam's centre of mass. By default they come from the frame's geometry
  (:meth:`rockbench.scene.structure.Frame.beam_offset`); every function that uses them accepts
  ``r_BC`` / ``psi_BC`` overrides (e.g. the printed 3.68 / 4.64 m, :data:`PRINTED_R_BC`).
* Eq. 5 positions are in the paper's coordinates (x right, y up, y = 0 on the foundation under
  AB, x = 2b at the pivot A of the current mechanism), whose origin differs from rockbench's
  (centre of the base of AB) and from one mechanism to the other: compare displacements or
  derivatives, which do not depend on the origin.

All functions are vectorized over ``phi`` (scalars or numpy arrays) and use SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_finite, check_nonnegative, check_positive
from ..scene.devices import Devices
from ..scene.structure import Frame, check_direction
from .dynamics import Terms

__all__ = [
    "PRINTED_R_BC",
    "AngleRates",
    "Symbols",
    "absolute_angle",
    "angle_rates",
    "bd",
    "com_derivatives",
    "com_positions",
    "damping_force_eq16",
    "damping_term",
    "eta_coefficients_eq37",
    "eta_eq23_27",
    "eta_eq28",
    "eta_eq36",
    "fracture_rotation",
    "gravity_energy",
    "gravity_term",
    "ground_force_eq15",
    "ground_term",
    "impact_system",
    "inertia",
    "kinetic_energy",
    "phi_bc",
    "phi_cd",
    "printed_beam_offset_height",
    "rest_angle",
    "rocking_rotations",
    "symbols",
    "tendon_energy",
    "tendon_energy_eq31",
    "tendon_energy_linear_eq34",
    "tendon_openings",
    "tendon_term",
    "tendon_term_linear_eq35",
    "terms",
    "uplift_threshold_eq20",
    "uplift_threshold_eq21",
    "velocity_term",
]

#: r_BC [m] printed in the section "Seismic Stability of the Asymmetric Rocking Frame":
#: 3.68 m for counterclockwise (p, pivot B) and 4.64 m for clockwise (n, pivot B') rocking.
PRINTED_R_BC = {1: 3.68, -1: 4.64}


# ---------------------------------------------------------------------------------------------
# symbols
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Symbols:
    """The paper's symbols for one frame rocking in one direction (lengths m, masses kg,
    inertias kg m^2, angles rad)."""

    s: int            # +1 counterclockwise (upper sign), -1 clockwise (lower sign)
    b: float          # half column width
    H: float          # half height of AB
    H1: float         # half height of CD
    h: float          # half depth of the beam
    L: float          # column centre-to-centre distance (= |BC|)
    R0: float         # half diagonal of AB
    R1: float         # half diagonal of CD
    r0: float         # half length of the ground link AD
    phi_AD: float     # angle of AD with the x axis
    alpha: float      # atan(b/H)
    alpha1: float     # atan(b/H1)
    r_BC: float       # |B G_BC|
    psi_BC: float     # angle of B->G_BC above the soffit at rest
    m_AB: float
    m_BC: float
    m_CD: float
    IG_AB: float      # about the centre of mass
    IG_BC: float
    IG_CD: float

    @property
    def hbar(self) -> float:
        """H / H1 [-] (asymmetry indicator)."""
        return self.H / self.H1

    @property
    def bbar(self) -> float:
        """b / L [-]."""
        return self.b / self.L

    @property
    def phi0(self) -> float:
        """Rest value of the absolute angle of AB, pi/2 - s alpha [rad] (varphi_{0,p/n})."""
        return 0.5 * math.pi - self.s * self.alpha

    @property
    def I_AB(self) -> float:
        """Moment of inertia of AB about its pivot A (A') [kg m^2]."""
        return self.IG_AB + self.m_AB * self.R0 ** 2

    @property
    def I_CD(self) -> float:
        """Moment of inertia of CD about its pivot D (D') [kg m^2]."""
        return self.IG_CD + self.m_CD * self.R1 ** 2

    @property
    def I_BC(self) -> float:
        """Moment of inertia of the beam about its pivot B (B') [kg m^2] (Eq. 19: depends on
        the direction through r_BC)."""
        return self.IG_BC + self.m_BC * self.r_BC ** 2


def _frame(frame) -> Frame:
    if not isinstance(frame, Frame):
        raise ParameterError("frame", type(frame).__name__, "a rockbench Frame")
    return frame


def symbols(frame: Frame, direction: int, *, r_BC: float | None = None,
            psi_BC: float | None = None) -> Symbols:
    """The paper's symbols of ``frame`` rocking in ``direction`` (+1 ccw, -1 cw).

    ``r_BC`` [m] and ``psi_BC`` [rad] default to the frame's geometry (beam centre of mass at
    mid-span and mid-depth); pass them to evaluate the closed forms with other values.
    """
    f = _frame(frame)
    s = check_direction(direction)
    r_geo, psi_geo = f.beam_offset(s)
    r = r_geo if r_BC is None else check_positive("r_BC", r_BC)
    psi = psi_geo if psi_BC is None else check_finite("psi_BC", psi_BC)
    step = f.step
    return Symbols(s=s, b=f.b, H=f.H, H1=f.H1, h=f.h, L=f.L, R0=f.R0, R1=f.R1,
                   r0=0.5 * math.hypot(f.L, step), phi_AD=math.atan2(step, f.L),
                   alpha=f.alpha, alpha1=f.alpha1, r_BC=r, psi_BC=psi,
                   m_AB=f.mass_left, m_BC=f.mass_beam, m_CD=f.mass_right,
                   IG_AB=f.inertia_left, IG_BC=f.inertia_beam, IG_CD=f.inertia_right)


def rest_angle(frame: Frame, direction: int) -> float:
    """varphi_0 [rad]: the absolute angle of AB at rest, pi/2 - alpha (ccw) or pi/2 + alpha
    (cw) (text before Eq. 2 and Eq. 12)."""
    return symbols(frame, direction).phi0


def absolute_angle(frame: Frame, direction: int, phi):
    """The paper's generalized coordinate varphi = phi + varphi_0 [rad] (Eq. 12 inverted)."""
    x = np.asarray(phi, dtype=float)
    if not np.all(np.isfinite(x)):
        raise ParameterError("phi", phi, "finite real numbers [rad]")
    return x + rest_angle(frame, direction)


# ---------------------------------------------------------------------------------------------
# kinematics: Eqs. 1-5
# ---------------------------------------------------------------------------------------------
def _bd2(S: Symbols, vphi):
    c = vphi - S.phi_AD
    return 4 * S.R0 ** 2 + 4 * S.r0 ** 2 - 8 * S.R0 * S.r0 * np.cos(c)


def bd(frame: Frame, direction: int, phi):
    """Length BD [m] (Eq. 2): BD^2 = (2R0)^2 + (2r0)^2 - 8 R0 r0 cos(varphi - varphi_AD)."""
    S = symbols(frame, direction)
    return np.sqrt(_bd2(S, absolute_angle(frame, direction, phi)))


def _u(S: Symbols, bd2):
    """Argument of the arccos in Eq. 1, (BD^2 + 4R1^2 - L^2) / (4 R1 BD)."""
    return (bd2 + 4 * S.R1 ** 2 - S.L ** 2) / (4 * S.R1 * np.sqrt(bd2))


def _check_reach(u, phi) -> None:
    if np.any(np.abs(u) > 1.0):
        raise ParameterError("phi", phi, "within the reach of the four-bar linkage",
                             "the arccos of Eq. 1 has no real value: the frame cannot be "
                             "assembled at this rotation")


def _phi_cd(S: Symbols, vphi, phi, corrected: bool):
    wx = S.R0 * np.cos(vphi) - S.r0 * math.cos(S.phi_AD)
    wy = S.R0 * np.sin(vphi) - S.r0 * math.sin(S.phi_AD)
    # printed: arctan of the quotient, which loses the quadrant of the vector D->B (it points
    # up and to the left, so arctan returns its angle minus pi)
    theta = np.arctan2(wy, wx) if corrected else np.arctan(wy / wx)
    u = _u(S, _bd2(S, vphi))
    _check_reach(u, phi)
    return theta - np.arccos(u)


def phi_cd(frame: Frame, direction: int, phi, *, corrected: bool = True):
    """Absolute angle varphi_CD [rad] of the column diagonal D->C (Eq. 1, second line).

    Printed: ``arctan[(R0 sin varphi - r0 sin varphi_AD) / (R0 cos varphi - r0 cos varphi_AD)]
    - arccos[...]``. The quotient is the slope of D->B, which points up and to the left, so the
    single-argument arctan returns its angle minus pi: the printed form gives varphi_CD - pi
    (C below D). Corrected: the two-argument (quadrant-aware) arctan.
    """
    S = symbols(frame, direction)
    return _phi_cd(S, absolute_angle(frame, direction, phi), phi, corrected)


def _phi_bc(S: Symbols, vphi, pcd):
    X = -S.R0 * np.cos(vphi) + S.r0 * math.cos(S.phi_AD) + S.R1 * np.cos(pcd)
    Y = -S.R0 * np.sin(vphi) + S.r0 * math.sin(S.phi_AD) + S.R1 * np.sin(pcd)
    return np.arctan(Y / X), X, Y


def phi_bc(frame: Frame, direction: int, phi, *, corrected: bool = True):
    """Absolute angle varphi_BC [rad] of the beam link B->C (Eq. 1, first line), 0 at rest.

    The printed arctan of a quotient is correct here (B->C points to the right); ``corrected``
    selects the form of varphi_CD it is built on (see :func:`phi_cd`). With the printed
    varphi_CD the quotient no longer describes B->C.
    """
    S = symbols(frame, direction)
    vphi = absolute_angle(frame, direction, phi)
    return _phi_bc(S, vphi, _phi_cd(S, vphi, phi, corrected))[0]


class AngleRates(NamedTuple):
    """varphi_BC, varphi_CD [rad] and their first [-] and second [1/rad] derivatives with
    respect to the generalized coordinate (Eqs. 3-4)."""

    phi_bc: np.ndarray
    phi_cd: np.ndarray
    d_bc: np.ndarray
    d_cd: np.ndarray
    dd_bc: np.ndarray
    dd_cd: np.ndarray


def _rates(S: Symbols, vphi, phi) -> AngleRates:
    """Closed-form derivatives of Eq. 1 (chain rule; the paper only names them, Eqs. 3-4)."""
    R0, R1, r0, L = S.R0, S.R1, S.r0, S.L
    c = vphi - S.phi_AD
    Sbd = _bd2(S, vphi)                       # BD^2
    dS = 8 * R0 * r0 * np.sin(c)
    ddS = 8 * R0 * r0 * np.cos(c)
    # angle of D->B
    num = R0 - r0 * np.cos(c)
    dth = 4 * R0 * num / Sbd
    ddth = 4 * R0 * (r0 * np.sin(c) * Sbd - num * dS) / Sbd ** 2
    # beta = arccos(u), u = (S + k) / (4 R1 sqrt(S)), k = 4 R1^2 - L^2
    k = 4 * R1 ** 2 - L ** 2
    u = _u(S, Sbd)
    _check_reach(u, phi)
    u_S = (Sbd - k) / (8 * R1 * Sbd ** 1.5)
    u_SS = (3 * k - Sbd) / (16 * R1 * Sbd ** 2.5)
    du = u_S * dS
    ddu = u_SS * dS ** 2 + u_S * ddS
    w = 1.0 - u * u
    dbeta = -du / np.sqrt(w)
    ddbeta = -(ddu * w + u * du ** 2) / w ** 1.5
    pcd = _phi_cd(S, vphi, phi, True)
    dcd = dth - dbeta
    ddcd = ddth - ddbeta
    # beam link B->C: (X, Y) = (C - B) / 2
    pbc, X, Y = _phi_bc(S, vphi, pcd)
    dX = R0 * np.sin(vphi) - R1 * np.sin(pcd) * dcd
    dY = -R0 * np.cos(vphi) + R1 * np.cos(pcd) * dcd
    ddX = R0 * np.cos(vphi) - R1 * np.cos(pcd) * dcd ** 2 - R1 * np.sin(pcd) * ddcd
    ddY = R0 * np.sin(vphi) - R1 * np.sin(pcd) * dcd ** 2 + R1 * np.cos(pcd) * ddcd
    M = X * X + Y * Y
    N = X * dY - Y * dX
    dbc = N / M
    ddbc = ((X * ddY - Y * ddX) * M - N * 2 * (X * dX + Y * dY)) / M ** 2
    return AngleRates(pbc, pcd, dbc, dcd, ddbc, ddcd)


def angle_rates(frame: Frame, direction: int, phi) -> AngleRates:
    """varphi_BC, varphi_CD and their first and second derivatives (Eqs. 1, 3, 4).

    The paper defines the derivatives (Eqs. 3-4) without closed forms; these are the
    chain-rule derivatives of the corrected Eq. 1 (a route independent of the loop-closure
    linear system used by :mod:`rockbench.scene.mechanism`).
    """
    S = symbols(frame, direction)
    return _rates(S, absolute_angle(frame, direction, phi), phi)


def _setup(frame, direction, phi, r_BC=None, psi_BC=None):
    S = symbols(frame, direction, r_BC=r_BC, psi_BC=psi_BC)
    vphi = absolute_angle(frame, direction, phi)
    return S, vphi, _rates(S, vphi, phi)


def com_positions(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """Centres of mass of AB, BC, CD [m] in the paper's coordinates (Eq. 5), shape
    (3, 2, ...): rows AB, BC, CD; columns x, y.

    The paper's origin lies 2b to the left of the current pivot A (A'), so it moves by 2b
    between the two mechanisms; only displacements and derivatives are comparable with
    rockbench's positions.
    """
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    b, R0, R1 = S.b, S.R0, S.R1
    ang = a.phi_bc + S.psi_BC
    x = [2 * b + R0 * np.cos(v),
         2 * b + 2 * R0 * np.cos(v) + S.r_BC * np.cos(ang),
         S.L + 2 * b + R1 * np.cos(a.phi_cd)]
    y = [R0 * np.sin(v),
         2 * R0 * np.sin(v) + S.r_BC * np.sin(ang),
         2 * S.H - 2 * S.H1 + R1 * np.sin(a.phi_cd)]
    return np.array([[xi, yi] for xi, yi in zip(x, y)])


def com_derivatives(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """d/dvarphi of Eq. 5 [m/rad], shape (3, 2, ...) (rows AB, BC, CD; columns x, y)."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    R0, R1, r = S.R0, S.R1, S.r_BC
    ang = a.phi_bc + S.psi_BC
    dx = [-R0 * np.sin(v),
          -2 * R0 * np.sin(v) - r * np.sin(ang) * a.d_bc,
          -R1 * np.sin(a.phi_cd) * a.d_cd]
    dy = [R0 * np.cos(v),
          2 * R0 * np.cos(v) + r * np.cos(ang) * a.d_bc,
          R1 * np.cos(a.phi_cd) * a.d_cd]
    return np.array([[xi, yi] for xi, yi in zip(dx, dy)])


# ---------------------------------------------------------------------------------------------
# tendons: Eqs. 9-12, 31
# ---------------------------------------------------------------------------------------------
def _alpha1(S: Symbols, corrected: bool) -> float:
    return S.alpha1 if corrected else S.b / S.H1


def rocking_rotations(frame: Frame, direction: int, phi, *, corrected: bool = True):
    """(phi, phi_1) [rad]: rocking rotations of AB and CD from rest (Eq. 12),
    phi = -pi/2 +- alpha + varphi, phi_1 = -pi/2 +- alpha1 + varphi_CD.

    Printed: alpha1 = b/H1, which is not the rest inclination of CD (that is atan(b/H1), as
    alpha = atan(b/H) is for AB, cf. Eq. 28), so the printed phi_1 is not zero at rest.
    """
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    pcd = _phi_cd(S, v, phi, True)
    a1 = _alpha1(S, corrected)
    return (-0.5 * math.pi + S.s * S.alpha + v, -0.5 * math.pi + S.s * a1 + pcd)


def tendon_openings(frame: Frame, direction: int, phi, *, corrected: bool = True):
    """(dl_A, dl_B, dl_C, dl_D) [m]: openings of the joints at the base and top of the AB and
    CD tendons (Eqs. 10-11).

    Printed: dl_A = 2b sin(phi/2), dl_B = 2b sin((phi + varphi_BC)/2), dl_D = 2b sin(phi_1/2),
    dl_C = 2b sin((phi_1 + varphi_BC)/2), with alpha1 = b/H1 in phi_1; the openings are
    negative in clockwise rocking.
    Corrected: the top joint opens by the rotation of the column *relative to the beam*,
    phi - varphi_BC (phi_1 - varphi_BC); alpha1 = atan(b/H1); each opening is the chord
    2b sin(|x|/2) >= 0.
    """
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    pcd = _phi_cd(S, v, phi, True)
    pbc = _phi_bc(S, v, pcd)[0]
    ph, ph1 = rocking_rotations(frame, direction, phi, corrected=corrected)
    b = S.b
    if corrected:
        s = S.s
        return (2 * b * np.sin(0.5 * s * ph), 2 * b * np.sin(0.5 * s * (ph - pbc)),
                2 * b * np.sin(0.5 * s * (ph1 - pbc)), 2 * b * np.sin(0.5 * s * ph1))
    return (2 * b * np.sin(0.5 * ph), 2 * b * np.sin(0.5 * (ph + pbc)),
            2 * b * np.sin(0.5 * (ph1 + pbc)), 2 * b * np.sin(0.5 * ph1))


def tendon_energy(frame: Frame, direction: int, phi, k: float, *, corrected: bool = True):
    """V_tend [J] (Eq. 9): 1/2 k (dl_A + dl_B)^2 + 1/2 k (dl_C + dl_D)^2 for tendon stiffness
    ``k`` [N/m], with the openings of :func:`tendon_openings` (printed or corrected)."""
    k = check_nonnegative("k", k)
    A, B, C, D = tendon_openings(frame, direction, phi, corrected=corrected)
    return 0.5 * k * (A + B) ** 2 + 0.5 * k * (C + D) ** 2


def tendon_energy_eq31(frame: Frame, direction: int, phi, k: float, *, corrected: bool = True):
    """V_tend [J] in the closed form of Appendix I (Eq. 31):
    4 k b^2 cos^2(varphi_BC/4) [2 -+ sin(alpha +- varphi +- varphi_BC/2)
    -+ sin(alpha1 +- varphi_CD +- varphi_BC/2)].

    Printed: the form above with alpha1 = b/H1; it is the exact sum-to-product rewriting of
    Eq. 9 with the printed openings (Eq. 10-11), so it inherits their sign error.
    Corrected: the varphi_BC/2 inside the sines takes the opposite sign (-+), alpha1 =
    atan(b/H1); equal to Eq. 9 with the corrected openings.
    """
    k = check_nonnegative("k", k)
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    pcd = _phi_cd(S, v, phi, True)
    pbc = _phi_bc(S, v, pcd)[0]
    s = S.s
    a1 = _alpha1(S, corrected)
    t = -s if corrected else s
    bracket = (2 - s * np.sin(S.alpha + s * v + t * 0.5 * pbc)
               - s * np.sin(a1 + s * pcd + t * 0.5 * pbc))
    return 4 * k * S.b ** 2 * np.cos(0.25 * pbc) ** 2 * bracket


# ---------------------------------------------------------------------------------------------
# energies and the terms of Eq. 17 (Eqs. 8, 13, 15, 16, 18)
# ---------------------------------------------------------------------------------------------
def gravity_energy(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """V_fr [J] (Eq. 8): g [(m_AB + 2 m_BC) R0 sin varphi + m_BC r_BC sin(varphi_BC + psi_BC)
    + m_CD (2H - 2H1 + R1 sin varphi_CD)], with g = rockbench.constants.G."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    return G * ((S.m_AB + 2 * S.m_BC) * S.R0 * np.sin(v)
                + S.m_BC * S.r_BC * np.sin(a.phi_bc + S.psi_BC)
                + S.m_CD * (2 * S.H - 2 * S.H1 + S.R1 * np.sin(a.phi_cd)))


def kinetic_energy(frame: Frame, direction: int, phi, phidot, *, r_BC=None, psi_BC=None):
    """T [J] (Eq. 13) at rotation ``phi`` [rad] and rate ``phidot`` [rad/s]:
    1/2 I_AB vphi'^2 + 1/2 I_BC (d varphi_BC vphi')^2 + 1/2 I_CD (d varphi_CD vphi')^2
    + 1/2 m_BC [(2R0)^2 + 4 R0 r_BC cos(varphi - varphi_BC - psi_BC) d varphi_BC] vphi'^2,
    with I_BC about B (I^G_BC + m_BC r_BC^2)."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    w = np.asarray(phidot, dtype=float)
    return (0.5 * S.I_AB * w ** 2 + 0.5 * S.I_BC * (a.d_bc * w) ** 2
            + 0.5 * S.I_CD * (a.d_cd * w) ** 2
            + 0.5 * S.m_BC * ((2 * S.R0) ** 2 + 4 * S.R0 * S.r_BC
                              * np.cos(v - a.phi_bc - S.psi_BC) * a.d_bc) * w ** 2)


def inertia(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """I_nl [kg m^2] (Eq. 18): I_AB + I_BC (d varphi_BC)^2 + I_CD (d varphi_CD)^2
    + 4 m_BC R0 [R0 + r_BC cos(varphi - varphi_BC - psi_BC) d varphi_BC]; I_AB, I_CD about
    the pivots, I_BC about B (B') (Eq. 19). Correct as printed."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    return (S.I_AB + S.I_BC * a.d_bc ** 2 + S.I_CD * a.d_cd ** 2
            + 4 * S.m_BC * S.R0 * (S.R0 + S.r_BC * np.cos(v - a.phi_bc - S.psi_BC) * a.d_bc))


def velocity_term(frame: Frame, direction: int, phi, *, corrected: bool = True,
                  r_BC=None, psi_BC=None):
    """J_nl [kg m^2] (Eq. 18), the coefficient of vphi'^2.

    Printed: -{I_BC d dd varphi_BC + I_CD d dd varphi_CD
    + 2 m_BC R0 r_BC [cos(.) dd varphi_BC + sin(.) (1 - d varphi_BC) d varphi_BC]},
    (.) = varphi - varphi_BC - psi_BC.
    Corrected: J = 1/2 dI_nl/dvarphi (Lagrange) = I_BC d dd varphi_BC + I_CD d dd varphi_CD
    + 2 m_BC R0 r_BC [cos(.) dd varphi_BC - sin(.) (1 - d varphi_BC) d varphi_BC]: the outer
    minus must go and the sine term keeps its (printed) negative sign.
    """
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    arg = v - a.phi_bc - S.psi_BC
    common = S.I_BC * a.d_bc * a.dd_bc + S.I_CD * a.d_cd * a.dd_cd
    cos_t = np.cos(arg) * a.dd_bc
    sin_t = np.sin(arg) * (1 - a.d_bc) * a.d_bc
    k = 2 * S.m_BC * S.R0 * S.r_BC
    if corrected:
        return common + k * (cos_t - sin_t)
    return -(common + k * (cos_t + sin_t))


def gravity_term(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """G_nl [kg m] (Eq. 18), multiplied by g in Eq. 17: (m_AB + 2 m_BC) R0 cos varphi
    + m_BC r_BC cos(varphi_BC + psi_BC) d varphi_BC + m_CD R1 cos varphi_CD d varphi_CD
    (= dV_fr/dvarphi / g). Correct as printed."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    return ((S.m_AB + 2 * S.m_BC) * S.R0 * np.cos(v)
            + S.m_BC * S.r_BC * np.cos(a.phi_bc + S.psi_BC) * a.d_bc
            + S.m_CD * S.R1 * np.cos(a.phi_cd) * a.d_cd)


def ground_term(frame: Frame, direction: int, phi, *, r_BC=None, psi_BC=None):
    """B_nl [kg m] (Eq. 18), the coefficient of u_g'' on the right of Eq. 17:
    m_AB R0 sin varphi + m_CD R1 sin varphi_CD d varphi_CD
    + m_BC [2 R0 sin varphi + r_BC sin(varphi_BC + psi_BC) d varphi_BC]
    (= -sum_i m_i dx_i/dvarphi). Correct as printed (with Eq. 17's sign)."""
    S, v, a = _setup(frame, direction, phi, r_BC, psi_BC)
    return (S.m_AB * S.R0 * np.sin(v) + S.m_CD * S.R1 * np.sin(a.phi_cd) * a.d_cd
            + S.m_BC * (2 * S.R0 * np.sin(v)
                        + S.r_BC * np.sin(a.phi_bc + S.psi_BC) * a.d_bc))


def ground_force_eq15(frame: Frame, direction: int, phi, *, corrected: bool = True,
                      r_BC=None, psi_BC=None):
    """Q_G / u_g'' [kg m]: the generalized ground-inertia force per unit ground acceleration
    (Eq. 15).

    Printed: Q_G = -{B_nl} u_g''. Corrected: Q_G = -u_g'' sum_i m_i dx_i/dvarphi = +B_nl u_g'',
    which is what Eq. 17 has on its right-hand side.
    """
    B = ground_term(frame, direction, phi, r_BC=r_BC, psi_BC=psi_BC)
    return B if corrected else -B


def tendon_term(frame: Frame, direction: int, phi, k: float, *, corrected: bool = True):
    """K_nl [N m] (Eq. 18) for tendon stiffness ``k`` [N/m]: dV_tend/dvarphi.

    Printed: -4 k b^2 {1/4 sin(varphi_BC/2) d varphi_BC [2 -+ sin(A) -+ sin(A1)]
    + cos^2(varphi_BC/4) [cos(A) (1 + 1/2 d varphi_BC) + cos(A1) (d varphi_CD
    + 1/2 d varphi_BC)]}, A = alpha +- varphi +- varphi_BC/2, A1 = alpha1 +- varphi_CD
    +- varphi_BC/2, alpha1 = b/H1: the exact derivative of the printed Eq. 31.
    Corrected: the derivative of the corrected Eq. 31: A = alpha +- varphi -+ varphi_BC/2,
    A1 = alpha1 +- varphi_CD -+ varphi_BC/2, the 1/2 d varphi_BC terms change sign,
    alpha1 = atan(b/H1).
    """
    k = check_nonnegative("k", k)
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    a = _rates(S, v, phi)
    s = S.s
    a1 = _alpha1(S, corrected)
    t = -s if corrected else s          # sign of varphi_BC/2 inside the sines
    A = S.alpha + s * v + t * 0.5 * a.phi_bc
    A1 = a1 + s * a.phi_cd + t * 0.5 * a.phi_bc
    half = s * t * 0.5 * a.d_bc          # +1/2 d varphi_BC printed, -1/2 corrected
    bracket = 2 - s * np.sin(A) - s * np.sin(A1)
    return -4 * k * S.b ** 2 * (0.25 * np.sin(0.5 * a.phi_bc) * a.d_bc * bracket
                                + np.cos(0.25 * a.phi_bc) ** 2
                                * (np.cos(A) * (1 + half) + np.cos(A1) * (a.d_cd + half)))


def damping_term(frame: Frame, direction: int, phi, C: float, *, corrected: bool = True):
    """D_nl [N m s] (Eq. 18) for damper constant ``C`` [N s/m]:
    2 C b^2 {[1 +- sin(alpha +- varphi)] + [1 +- sin(alpha1 +- varphi_CD)] (d varphi_CD)^2}.

    Printed: alpha (not alpha1) in the second bracket. Corrected: alpha1 = atan(b/H1), as in
    Eq. 16.
    """
    C = check_nonnegative("C", C)
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    a = _rates(S, v, phi)
    s = S.s
    a1 = S.alpha1 if corrected else S.alpha
    return 2 * C * S.b ** 2 * ((1 + s * np.sin(S.alpha + s * v))
                               + (1 + s * np.sin(a1 + s * a.phi_cd)) * a.d_cd ** 2)


def damping_force_eq16(frame: Frame, direction: int, phi, C: float, *,
                       corrected: bool = True):
    """-Q_D / vphi' [N m s] (Eq. 16): 2 C b^2 {[1 +- sin(alpha +- varphi)]
    + [1 +- sin(alpha1 +- varphi_CD)] (d varphi_CD)^2}.

    Printed: alpha1 = b/H1 (Eq. 12). Corrected: alpha1 = atan(b/H1). Otherwise this is the
    generalized force of two dampers along the chords travelled by the heel corners,
    C (d chord/dvarphi)^2 with chord = 4 b sin(|phi|/2).
    """
    C = check_nonnegative("C", C)
    S = symbols(frame, direction)
    v = absolute_angle(frame, direction, phi)
    a = _rates(S, v, phi)
    s = S.s
    a1 = _alpha1(S, corrected)
    return 2 * C * S.b ** 2 * ((1 + s * np.sin(S.alpha + s * v))
                               + (1 + s * np.sin(a1 + s * a.phi_cd)) * a.d_cd ** 2)


def terms(frame: Frame, direction: int, phi: float, devices: Devices | None = None, *,
          corrected: bool = True, r_BC=None, psi_BC=None) -> Terms:
    """All coefficients of Eq. 17 at ``phi`` [rad] from Eq. 18, as a
    :class:`rockbench.analytic.dynamics.Terms` (same units), so that they compare one to one
    with :meth:`rockbench.analytic.dynamics.Dynamics.terms`."""
    kw = {"r_BC": r_BC, "psi_BC": psi_BC}
    K = D = 0.0
    if devices is not None:
        K = float(tendon_term(frame, direction, phi, devices.tendon_stiffness,
                              corrected=corrected))
        D = float(damping_term(frame, direction, phi, devices.damping, corrected=corrected))
    return Terms(float(inertia(frame, direction, phi, **kw)),
                 float(velocity_term(frame, direction, phi, corrected=corrected, **kw)),
                 float(gravity_term(frame, direction, phi, **kw)),
                 float(ground_term(frame, direction, phi, **kw)), K, D)


# ---------------------------------------------------------------------------------------------
# uplift: Eqs. 20-21
# ---------------------------------------------------------------------------------------------
def uplift_threshold_eq20(frame: Frame, direction: int, *, r_BC=None, psi_BC=None) -> float:
    """lambda = G_nl(0) / B_nl(0) [-] (Eq. 20): the ground acceleration, in units of g, that
    starts rocking in ``direction`` (> 0 counterclockwise, < 0 clockwise)."""
    kw = {"r_BC": r_BC, "psi_BC": psi_BC}
    return float(gravity_term(frame, direction, 0.0, **kw)
                 / ground_term(frame, direction, 0.0, **kw))


def uplift_threshold_eq21(frame: Frame, direction: int, *, corrected: bool = True) -> float:
    """lambda [-] in closed form (Eq. 21):
    -+ (b/H) {m_AB + m_BC [1 + hbar - 2 bbar (+-hbar -+ 1)] + m_CD hbar}
    / {m_AB + 2 m_BC [bbar h/H (+-hbar -+ 1) + 1] + m_CD}.

    Printed: the leading -+ makes lambda negative for counterclockwise rocking, the opposite of
    Eq. 20 (G_nl(0) and B_nl(0) are both positive for it). Corrected: leading +-. The fraction
    itself is right; it places G_BC at mid-span, h above the soffit.
    """
    S = symbols(frame, direction)
    s, hb, bb = S.s, S.hbar, S.bbar
    num = S.m_AB + S.m_BC * (1 + hb - 2 * bb * (s * hb - s)) + S.m_CD * hb
    den = S.m_AB + 2 * S.m_BC * (bb * S.h / S.H * (s * hb - s) + 1) + S.m_CD
    lead = s if corrected else -s
    return lead * S.b / S.H * num / den


# ---------------------------------------------------------------------------------------------
# impact: Eqs. 23-28, 36-37
# ---------------------------------------------------------------------------------------------
def impact_system(frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """The impact equations (Eqs. 23-27) as printed, for a unit pre-impact rate
    (vphi'^- = 1 rad/s), as ``(A, rhs)`` with ``A @ x = rhs`` and
    x = (Lambda_Ax, Lambda_Ay, Lambda_Dx, Lambda_Dy [N s], vphi'^+ [rad/s]).

    The printed case: the frame rocked counterclockwise (pivots A, D at the bottom-left
    corners) and returns with a clockwise angular velocity; the impulses act at the new
    pivots A', D' (bottom-right corners) and it rocks clockwise afterwards. Its
    vphi'^+ / vphi'^- is therefore ``eta_cw`` (rockbench's name for the impact after which the
    frame rocks clockwise). Rows: 23 (x momentum), 24 (y momentum), 25 (moment about A'),
    26 (moment of AB about B'), 27 (moment of CD about C').
    """
    S = symbols(frame, -1)
    b, H, H1, h, L, hb, bb = S.b, S.H, S.H1, S.h, S.L, S.hbar, S.bbar
    mAB, mBC, mCD = S.m_AB, S.m_BC, S.m_CD
    A = np.zeros((5, 5))
    rhs = np.zeros(5)

    def row(i, lhs, P, Q):
        """lhs . Lambda = P (w+ - w-) + Q (w+ + w-), with w- = 1."""
        A[i, :4] = lhs
        A[i, 4] = -(P + Q)
        rhs[i] = Q - P

    M = mAB + mCD + 2 * mBC
    # 23: L_Ax + L_Dx = M H (w- - w+) - 2 m_BC bbar h (1 - hbar) (w+ + w-)
    row(0, (1, 0, 1, 0), -M * H, -2 * mBC * bb * h * (1 - hb))
    # 24: L_Ay + L_Dy = [-m_AB b - m_CD b hbar - m_BC b (hbar + 1)] (w+ + w-)
    #                   - 2 m_BC b bbar (hbar - 1) (w+ - w-)
    row(1, (0, 1, 0, 1), -2 * mBC * b * bb * (hb - 1),
        -mAB * b - mCD * b * hb - mBC * b * (hb + 1))
    # 25: L L_Dy - (2H - 2H1) L_Dx = P25 (w+ - w-) + Q25 (w+ + w-)
    P25 = (S.IG_AB + S.IG_CD * hb + mAB * H ** 2 + mCD * H * (2 * H - H1)
           + 2 * mBC * (2 * H + h) * H - 2 * mBC * (L / 2 - b) * b * bb * (hb - 1))
    Q25 = (-S.IG_BC * 2 * bb * (hb - 1) + mAB * b ** 2 - mCD * b * hb * (L - b)
           + 2 * mBC * (2 * H + h) * bb * h * (1 - hb) - mBC * b * (L / 2 - b) * (1 + hb))
    row(2, (0, 0, -(2 * H - 2 * H1), L), P25, Q25)
    # 26: 2H L_Ax + 2b L_Ay = (I^G_AB - m_AB H^2) (w+ - w-) - m_AB b^2 (w+ + w-)
    row(3, (2 * H, 2 * b, 0, 0), S.IG_AB - mAB * H ** 2, -mAB * b ** 2)
    # 27: 2H1 L_Dx + 2b L_Dy = (hbar I^G_CD - m_CD H H1) (w+ - w-) - m_CD b^2 hbar (w+ + w-)
    row(4, (0, 0, 2 * H1, 2 * b), hb * S.IG_CD - mCD * H * H1, -mCD * b ** 2 * hb)
    return A, rhs


def eta_eq23_27(frame: Frame) -> float:
    """vphi'^+ / vphi'^- [-] from the solution of the printed Eqs. 23-27: the coefficient of
    restitution of the impact after which the frame rocks clockwise (``eta_cw``)."""
    A, rhs = impact_system(frame)
    return float(np.linalg.solve(A, rhs)[4])


def eta_eq28(frame: Frame) -> float:
    """eta [-] of the symmetric frame (Eq. 28, Makris & Vassiliou 2012):
    (1 - 3/2 sin^2 alpha + 3 gamma cos 2 alpha) / (1 + 3 gamma), gamma = m_BC / (2 m_AB).
    Exact only for H1 = H (a ParameterError otherwise)."""
    f = _frame(frame)
    if not f.symmetric:
        raise ParameterError("column_height_right", f.column_height_right,
                             f"= column_height_left = {f.column_height_left:g}",
                             "Eq. 28 holds for the symmetric frame only")
    a, g = f.alpha, f.gamma
    return (1 - 1.5 * math.sin(a) ** 2 + 3 * g * math.cos(2 * a)) / (1 + 3 * g)


def eta_coefficients_eq37(frame: Frame, direction: int) -> tuple[float, ...]:
    """(a_1, ..., a_10) of Eq. 37 for the sign of ``direction`` (upper sign: +1), as printed
    (units: kg m^2)."""
    S = symbols(frame, direction)
    s, b, H, H1, h, L, hb, bb = S.s, S.b, S.H, S.H1, S.h, S.L, S.hbar, S.bbar
    mAB, mBC, mCD = S.m_AB, S.m_BC, S.m_CD
    a1 = (mAB + mCD + 2 * mBC) * H ** 2
    a2 = 2 * mBC * bb * (1 - hb) * H * h
    a3 = s * mAB * b ** 2 + s * mCD * b ** 2 * hb + s * mBC * b ** 2 * (1 + hb)
    a4 = 2 * mBC * b ** 2 * bb * (hb - 1)
    a5 = (S.IG_AB + S.IG_CD * hb + mAB * H ** 2 + mCD * H * (2 * H - H1)
          + 2 * mBC * H * (2 * H + h) - 2 * mBC * b * bb * (L / 2 + s * b) * (hb - 1))
    a6 = (s * S.IG_BC * 2 * bb * (hb - 1) + mAB * b ** 2 + s * mCD * b * hb * (L + s * b)
          - s * 2 * mBC * bb * h * (2 * H + h) * (1 - hb)
          + s * mBC * b * (L / 2 + s * b) * (hb + 1))
    a7 = S.IG_AB - mAB * H ** 2
    a8 = mAB * b ** 2
    a9 = hb * S.IG_CD - mCD * H * H1
    a10 = mCD * b ** 2 * hb
    return a1, a2, a3, a4, a5, a6, a7, a8, a9, a10


def eta_eq36(frame: Frame, direction: int, *, corrected: bool = True) -> float:
    """eta [-] of the asymmetric frame in closed form (Eq. 36 with Eq. 37).

    The upper sign (``direction=+1``) gives the impact after which the frame rocks
    counterclockwise (``eta_ccw``), the lower sign (-1) the one after which it rocks clockwise
    (``eta_cw``, the case of Eqs. 23-27).
    Printed lower sign is wrong twice: (i) the term -+a_4 (numerator and denominator) must be
    -a_4 for both signs, and (ii) the numerator's [bbar (hbar - 1) -+ hbar/2] (a_9 + a_10)
    lacks the leading +- that the denominator's a_9 term carries. The upper sign is correct.
    """
    return _eta_eq36(frame, direction, fix_a4=corrected, fix_a9=corrected)


def _eta_eq36(frame: Frame, direction: int, *, fix_a4: bool, fix_a9: bool) -> float:
    """Eq. 36 with each of its two corrections switched on or off separately."""
    S = symbols(frame, direction)
    s, hb, bb = S.s, S.hbar, S.bbar
    a1, a2, a3, a4, a5, a6, a7, a8, a9, a10 = eta_coefficients_eq37(frame, direction)
    t4 = a4 if fix_a4 else s * a4             # printed: -+ a4
    t9 = s if fix_a9 else 1.0                 # printed: no leading +- in the numerator
    kap = 2 * bb * (hb - 1) - s
    c7 = s * bb * (hb - 1) - 0.5
    c9 = bb * (hb - 1) - s * 0.5 * hb
    num = (kap * (s * a1 + a2 - a3 - t4) + s * bb * (hb - 1) * (a6 - a5)
           + c7 * (a7 + a8) + t9 * c9 * (a9 + a10))
    den = (kap * (s * a1 - a2 + a3 - t4) + s * bb * (1 - hb) * (a5 + a6)
           + c7 * (a7 - a8) + s * c9 * (a9 - a10))
    return num / den


# ---------------------------------------------------------------------------------------------
# Appendix I linearization (Eqs. 32-35), fracture rotation
# ---------------------------------------------------------------------------------------------
def _linear_stiffness(S: Symbols, corrected: bool) -> float:
    """d^2 V_tend / dphi^2 at rest divided by k b^2 [-]."""
    if not corrected:
        return 4 * (1 + S.hbar ** 2)
    kap = S.s * 2 * S.bbar * (S.hbar - 1)     # d varphi_BC / dphi at rest
    return (2 - kap) ** 2 + (2 * S.hbar - kap) ** 2


def tendon_energy_linear_eq34(frame: Frame, direction: int, phi, k: float, *,
                              corrected: bool = False):
    """V_tend,lin [J] (Eq. 34), small rotations: 2 k b^2 (1 + hbar^2) phi^2.

    Printed (``corrected=False``, the default since it is an approximation rather than an
    error): the openings are taken as b phi and b phi_1 = b hbar phi at both ends (Eqs. 32-33),
    i.e. the beam rotation is neglected at the top joints. ``corrected=True``: the exact
    second-order expansion of the corrected Eq. 9, 1/2 k b^2 [(2 - kappa)^2 + (2 hbar -
    kappa)^2] phi^2 with kappa = +-2 bbar (hbar - 1) = d varphi_BC/dphi at rest.
    """
    k = check_nonnegative("k", k)
    S = symbols(frame, direction)
    ph = np.asarray(phi, dtype=float)
    return 0.5 * k * S.b ** 2 * _linear_stiffness(S, corrected) * ph ** 2


def tendon_term_linear_eq35(frame: Frame, direction: int, phi, k: float, *,
                            corrected: bool = False):
    """K_lin = dV_tend,lin/dphi [N m] (Eq. 35): 4 k b^2 (1 + hbar^2) phi (printed) or the
    tangent of the exact K at rest (``corrected=True``); see :func:`tendon_energy_linear_eq34`."""
    k = check_nonnegative("k", k)
    S = symbols(frame, direction)
    ph = np.asarray(phi, dtype=float)
    return k * S.b ** 2 * _linear_stiffness(S, corrected) * ph


def fracture_rotation(frame: Frame, direction: int, fracture_strain: float,
                      tendon_length: float, *, corrected: bool = True) -> float:
    """|phi_f| [rad]: rocking rotation at which a tendon reaches ``fracture_strain`` [-]
    (free length ``tendon_length`` [m]), in the small-rotation approximation.

    Printed (section "Seismic Stability ..."): phi_f = eps_f l / (2b), the AB tendon opening
    2 b phi. Corrected: the first tendon to reach eps_f is the one that opens most; with the
    openings of Eq. 32-33 corrected for the beam rotation, its elongation is
    b max(2 - kappa, 2 hbar - kappa) |phi| (kappa as in :func:`tendon_energy_linear_eq34`),
    i.e. the CD tendon of an asymmetric frame (hbar > 1).
    """
    eps = check_positive("fracture_strain", fracture_strain)
    ell = check_positive("tendon_length", tendon_length)
    S = symbols(frame, direction)
    if not corrected:
        return eps * ell / (2 * S.b)
    kap = S.s * 2 * S.bbar * (S.hbar - 1)
    return eps * ell / (S.b * max(2 - kap, 2 * S.hbar - kap))


# ---------------------------------------------------------------------------------------------
# r_BC
# ---------------------------------------------------------------------------------------------
def printed_beam_offset_height(frame: Frame, direction: int) -> float:
    """Height [m] of G_BC above the beam soffit that reproduces the printed r_BC
    (:data:`PRINTED_R_BC`) with G_BC at mid-span: sqrt(r_BC^2 - (L/2 - s b)^2).

    For the paper's frame: 1.137 m (ccw) and 1.131 m (cw), against h = 1.0 m (mid-depth of the
    2 m beam, which Eqs. 21, 23-27 and 37 use).
    """
    f = _frame(frame)
    s = check_direction(direction)
    dx = 0.5 * f.L - s * f.b
    r = PRINTED_R_BC[s]
    if r <= abs(dx):
        raise ParameterError("frame", f, f"a frame with |L/2 - s b| < {r} m",
                             "the printed r_BC cannot be reached")
    return math.sqrt(r * r - dx * dx)

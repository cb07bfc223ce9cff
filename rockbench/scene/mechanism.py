"""Kinematics of the rocking mechanisms (pure functions of the generalized coordinate phi).

A mechanism is the rigid-body motion of a structure rocking in one direction ``s`` (+1
counterclockwise, -1 clockwise) about fixed pivots. Its single generalized coordinate is
``phi``, the rotation [rad] of the left (taller) column AB from rest, positive counterclockwise
(for a block: the block's rotation). For every body the mechanism gives the position of the
centre of mass and the body's rotation, with their first and second derivatives with respect to
``phi``; the dynamics (:mod:`rockbench.analytic.dynamics`) is built from these alone.

The frame is a four-bar linkage A-B-C-D (paper, Eqs. 1-5): the ground link AD, the column
diagonals AB (length 2 R0) and DC (length 2 R1), and the beam link BC (length L between the
two top pivots, which lie on the beam soffit). We solve the loop closure exactly
(intersection of the circles |C - D| = 2 R1 and |C - B| = L, on the branch of the rest
configuration) and obtain the angular rates by differentiating the closure

    2 R0 e(phi_AB) + L e(phi_BC) - 2 R1 e(phi_CD) = D - A,     e(x) = (cos x, sin x),

which gives a 2x2 linear system for (phi_BC', phi_CD') and, differentiated again, for the second
derivatives. Finite differences check all derivatives in the tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from .structure import Block, Frame, check_direction

__all__ = ["BodyKinematics", "Configuration", "BlockMechanism", "FrameMechanism",
           "mechanism", "geometric_limit"]


class BodyKinematics(NamedTuple):
    """One rigid body at one value of phi.

    x, y : centre of mass [m]; theta : rotation from rest [rad];
    dx, dy, dtheta : derivatives with respect to phi [m/rad, m/rad, -];
    ddx, ddy, ddtheta : second derivatives with respect to phi.
    """

    x: float
    y: float
    theta: float
    dx: float
    dy: float
    dtheta: float
    ddx: float
    ddy: float
    ddtheta: float


class Configuration(NamedTuple):
    """All bodies of a mechanism at one phi, in the order of ``Mechanism.body_names``."""

    phi: float
    bodies: tuple[BodyKinematics, ...]


def _body_about_many(ox, oy, dox, doy, ddox, ddoy, rx, ry, th, dth, ddth) -> dict:
    """:func:`_body_about` over arrays (numpy broadcasting): the fields of
    :class:`BodyKinematics` as a dict of arrays."""
    import numpy as np

    c, s = np.cos(th), np.sin(th)
    qx, qy = c * rx - s * ry, s * rx + c * ry
    return {"x": ox + qx, "y": oy + qy, "theta": th,
            "dx": dox - dth * qy, "dy": doy + dth * qx, "dtheta": dth,
            "ddx": ddox - ddth * qy - dth * dth * qx, "ddy": ddoy + ddth * qx - dth * dth * qy,
            "ddtheta": ddth}


def _rotated(rx: float, ry: float, c: float, s: float) -> tuple[float, float]:
    return c * rx - s * ry, s * rx + c * ry


def _body_about(ox, oy, dox, doy, ddox, ddoy, rx, ry, th, dth, ddth) -> BodyKinematics:
    """Kinematics of a point P = O + Rot(th) r0 (r0 the rest offset of G from the point O that
    moves with the body), given O and its phi-derivatives and the body rotation th(phi)."""
    c, s = math.cos(th), math.sin(th)
    qx, qy = _rotated(rx, ry, c, s)  # current offset O -> G
    # d/dphi Rot(th) r0 = th' * perp(q), perp(q) = (-qy, qx)
    dx = dox - dth * qy
    dy = doy + dth * qx
    ddx = ddox - ddth * qy - dth * dth * qx
    ddy = ddoy + ddth * qx - dth * dth * qy
    return BodyKinematics(ox + qx, oy + qy, th, dx, dy, dth, ddx, ddy, ddth)


@dataclass(frozen=True)
class BlockMechanism:
    """A rectangular block rocking about its base corner: left corner for s = +1, right for -1."""

    block: Block
    direction: int

    body_names = ("block",)

    def __post_init__(self) -> None:
        check_direction(self.direction)

    @property
    def pivot(self) -> tuple[float, float]:
        """Rest position of the pivot [m] (origin at the centre of the base)."""
        return (-self.direction * self.block.b, 0.0)

    def configuration(self, phi: float) -> Configuration:
        """Kinematics at rotation ``phi`` [rad]."""
        px, py = self.pivot
        rx, ry = -px, self.block.H  # pivot -> G at rest
        body = _body_about(px, py, 0.0, 0.0, 0.0, 0.0, rx, ry, phi, 1.0, 0.0)
        return Configuration(phi, (body,))

    def configuration_many(self, phi) -> list[dict]:
        """:meth:`configuration` over an array ``phi`` [rad]: one dict per body of arrays
        keyed by the fields of :class:`BodyKinematics` (same formulas, tested against it)."""
        import numpy as np

        phi = np.asarray(phi, dtype=float)
        px, py = self.pivot
        one, zero = np.ones_like(phi), np.zeros_like(phi)
        return [_body_about_many(px, py, 0.0, 0.0, 0.0, 0.0, -px, self.block.H, phi, one, zero)]

    def limit(self) -> float:
        """Largest |phi| the mechanism can reach [rad] (a block lies on its side at pi/2 + ...;
        rotations beyond pi/2 are not physical here)."""
        return math.pi


@dataclass(frozen=True)
class FrameMechanism:
    """The three-block (four-bar) mechanism of the rocking frame rocking in ``direction``.

    Bodies, in order: ``left`` column AB, ``beam`` BC, ``right`` column CD. The configuration
    also exposes the beam rotation and the right column rotation through the body entries
    (``bodies[1].theta``, ``bodies[2].theta``).
    """

    frame: Frame
    direction: int

    body_names = ("left", "beam", "right")

    def __post_init__(self) -> None:
        s = check_direction(self.direction)
        f = self.frame
        piv = f.pivots(s)
        A, B0, C0, D = piv["A"], piv["B"], piv["C"], piv["D"]
        set_ = object.__setattr__
        set_(self, "_A", A)
        set_(self, "_D", D)
        set_(self, "_B0", B0)
        set_(self, "_rho0", 2.0 * f.R0)           # |AB|
        set_(self, "_rho1", 2.0 * f.R1)           # |DC|
        set_(self, "_L", math.hypot(C0[0] - B0[0], C0[1] - B0[1]))  # |BC| = L
        set_(self, "_phiAB0", math.atan2(B0[1] - A[1], B0[0] - A[0]))
        set_(self, "_phiCD0", math.atan2(C0[1] - D[1], C0[0] - D[0]))
        set_(self, "_phiBC0", math.atan2(C0[1] - B0[1], C0[0] - B0[0]))
        # offsets (rest) from the moving reference points to the centres of mass
        gl, gb, gr = f.com_left, f.com_beam, f.com_right
        set_(self, "_rl", (gl[0] - A[0], gl[1] - A[1]))
        set_(self, "_rb", (gb[0] - B0[0], gb[1] - B0[1]))
        set_(self, "_rr", (gr[0] - D[0], gr[1] - D[1]))
        # branch of the circle intersection that contains the rest configuration
        set_(self, "_branch", 1.0)
        cx, cy = self._solve_C(0.0)[:2]
        if math.hypot(cx - C0[0], cy - C0[1]) > 1e-9 * f.L:
            set_(self, "_branch", -1.0)

    # ------------------------------------------------------------------------------------
    def _solve_C(self, phi: float) -> tuple[float, float, float, float]:
        """Position of the top pivot C and of B for the left column rotated by ``phi``."""
        Ax, Ay = self._A
        Dx, Dy = self._D
        a = self._phiAB0 + phi
        Bx = Ax + self._rho0 * math.cos(a)
        By = Ay + self._rho0 * math.sin(a)
        ux, uy = Bx - Dx, By - Dy
        d2 = ux * ux + uy * uy
        d = math.sqrt(d2)
        r1, L = self._rho1, self._L
        ap = (d2 + r1 * r1 - L * L) / (2.0 * d)
        h2 = r1 * r1 - ap * ap
        if h2 < 0.0:
            raise ValueError(f"phi={phi!r} rad is beyond the reach of the frame mechanism "
                             f"(direction {self.direction:+d}); see geometric_limit()")
        hh = self._branch * math.sqrt(h2)
        Cx = Dx + (ap * ux - hh * uy) / d
        Cy = Dy + (ap * uy + hh * ux) / d
        return Cx, Cy, Bx, By

    def closure_margin(self, phi: float) -> float:
        """Squared distance margin of the loop closure [m^2]: > 0 while the four-bar linkage can
        be assembled, 0 at its toggle (B, C, D collinear)."""
        Ax, Ay = self._A
        Dx, Dy = self._D
        a = self._phiAB0 + phi
        ux = Ax + self._rho0 * math.cos(a) - Dx
        uy = Ay + self._rho0 * math.sin(a) - Dy
        d2 = ux * ux + uy * uy
        ap = (d2 + self._rho1**2 - self._L**2) / (2.0 * math.sqrt(d2))
        return self._rho1**2 - ap * ap

    def angles(self, phi: float) -> tuple[float, float]:
        """(theta_beam, theta_right): rotations from rest [rad] of the beam and right column."""
        Cx, Cy, Bx, By = self._solve_C(phi)
        Dx, Dy = self._D
        th_b = math.atan2(Cy - By, Cx - Bx) - self._phiBC0
        th_r = math.atan2(Cy - Dy, Cx - Dx) - self._phiCD0
        return th_b, th_r

    def configuration(self, phi: float) -> Configuration:
        """Kinematics of the three bodies at left-column rotation ``phi`` [rad]."""
        Cx, Cy, Bx, By = self._solve_C(phi)
        Ax, Ay = self._A
        Dx, Dy = self._D
        L, r0, r1 = self._L, self._rho0, self._rho1
        pab = self._phiAB0 + phi
        pbc = math.atan2(Cy - By, Cx - Bx)
        pcd = math.atan2(Cy - Dy, Cx - Dx)
        sab, cab = math.sin(pab), math.cos(pab)
        sbc, cbc = math.sin(pbc), math.cos(pbc)
        scd, ccd = math.sin(pcd), math.cos(pcd)
        # d/dphi of closure:  r0 e'(pab) + L e'(pbc) x - r1 e'(pcd) y = 0, e'(a) = (-sin a, cos a)
        # unknowns x = pbc', y = pcd':  [ -L sbc   r1 scd ] [x]   [ r0 sab ]
        #                                [  L cbc  -r1 ccd ] [y] = [ -r0 cab ]
        m11, m12, m21, m22 = -L * sbc, r1 * scd, L * cbc, -r1 * ccd
        det = m11 * m22 - m12 * m21          # = L r1 sin(pcd - pbc)
        f1, f2 = r0 * sab, -r0 * cab
        dbc = (f1 * m22 - m12 * f2) / det
        dcd = (m11 * f2 - f1 * m21) / det
        # second derivative: same matrix, rhs = r0 e(pab) + L e(pbc) x^2 - r1 e(pcd) y^2
        g1 = r0 * cab + L * cbc * dbc * dbc - r1 * ccd * dcd * dcd
        g2 = r0 * sab + L * sbc * dbc * dbc - r1 * scd * dcd * dcd
        ddbc = (g1 * m22 - m12 * g2) / det
        ddcd = (m11 * g2 - g1 * m21) / det
        # B moves on a circle about A: B' = perp(B - A), B'' = -(B - A)
        bx, by = Bx - Ax, By - Ay
        left = _body_about(Ax, Ay, 0.0, 0.0, 0.0, 0.0, *self._rl, phi, 1.0, 0.0)
        beam = _body_about(Bx, By, -by, bx, -bx, -by, *self._rb, pbc - self._phiBC0, dbc, ddbc)
        right = _body_about(Dx, Dy, 0.0, 0.0, 0.0, 0.0, *self._rr, pcd - self._phiCD0, dcd, ddcd)
        return Configuration(phi, (left, beam, right))

    def limit(self) -> float:
        """Largest |phi| [rad] up to which the linkage can be assembled (its toggle), or pi."""
        return geometric_limit(self)

    def _closure_many(self, phi):
        """The loop closure over an array ``phi`` [rad], the one vectorized form that
        :meth:`configuration_many` and :meth:`angles_many` share: sin and cos of AB's angle, B,
        the angles of BC and CD [rad], the closure's Jacobian (m11, m12, m21, m22, det) and the
        derivatives of BC's and CD's angles with respect to phi [-]. ValueError beyond the
        linkage's reach."""
        import numpy as np

        Ax, Ay = self._A
        Dx, Dy = self._D
        L, r0, r1 = self._L, self._rho0, self._rho1
        pab = self._phiAB0 + phi
        sab, cab = np.sin(pab), np.cos(pab)
        Bx, By = Ax + r0 * cab, Ay + r0 * sab
        ux, uy = Bx - Dx, By - Dy
        d2 = ux * ux + uy * uy
        d = np.sqrt(d2)
        ap = (d2 + r1 * r1 - L * L) / (2.0 * d)
        h2 = r1 * r1 - ap * ap
        if np.any(h2 < 0.0):
            raise ValueError("phi beyond the reach of the frame mechanism; see "
                             "geometric_limit()")
        hh = self._branch * np.sqrt(h2)
        Cx = Dx + (ap * ux - hh * uy) / d
        Cy = Dy + (ap * uy + hh * ux) / d
        pbc = np.arctan2(Cy - By, Cx - Bx)
        pcd = np.arctan2(Cy - Dy, Cx - Dx)
        m11, m12 = -L * np.sin(pbc), r1 * np.sin(pcd)
        m21, m22 = L * np.cos(pbc), -r1 * np.cos(pcd)
        det = m11 * m22 - m12 * m21
        f1, f2 = r0 * sab, -r0 * cab
        dbc = (f1 * m22 - m12 * f2) / det
        dcd = (m11 * f2 - f1 * m21) / det
        return sab, cab, Bx, By, pbc, pcd, m11, m12, m21, m22, det, dbc, dcd

    def configuration_many(self, phi) -> list[dict]:
        """:meth:`configuration` over an array ``phi`` [rad]: one dict per body (left, beam,
        right) of arrays keyed by the fields of :class:`BodyKinematics` (same closed forms,
        tested against it). ValueError beyond the linkage's reach."""
        import numpy as np

        phi = np.asarray(phi, dtype=float)
        Ax, Ay = self._A
        Dx, Dy = self._D
        L, r0, r1 = self._L, self._rho0, self._rho1
        sab, cab, Bx, By, pbc, pcd, m11, m12, m21, m22, det, dbc, dcd = self._closure_many(phi)
        sbc, cbc = np.sin(pbc), np.cos(pbc)
        scd, ccd = np.sin(pcd), np.cos(pcd)
        g1 = r0 * cab + L * cbc * dbc * dbc - r1 * ccd * dcd * dcd
        g2 = r0 * sab + L * sbc * dbc * dbc - r1 * scd * dcd * dcd
        ddbc = (g1 * m22 - m12 * g2) / det
        ddcd = (m11 * g2 - g1 * m21) / det
        bx, by = Bx - Ax, By - Ay
        one, zero = np.ones_like(phi), np.zeros_like(phi)
        left = _body_about_many(Ax, Ay, 0.0, 0.0, 0.0, 0.0, *self._rl, phi, one, zero)
        beam = _body_about_many(Bx, By, -by, bx, -bx, -by, *self._rb, pbc - self._phiBC0, dbc,
                                ddbc)
        right = _body_about_many(Dx, Dy, 0.0, 0.0, 0.0, 0.0, *self._rr, pcd - self._phiCD0,
                                 dcd, ddcd)
        return [left, beam, right]

    def angles_many(self, phi) -> tuple:
        """Vectorized over an array ``phi`` [rad]: (theta_beam, theta_right) [rad] and their
        derivatives with respect to phi [-], by the same closed forms as
        :meth:`configuration` (tested against it)."""
        import numpy as np

        _, _, _, _, pbc, pcd, _, _, _, _, _, dbc, dcd = self._closure_many(
            np.asarray(phi, dtype=float))
        return pbc - self._phiBC0, pcd - self._phiCD0, dbc, dcd


def geometric_limit(mech) -> float:
    """First |phi| [rad] in the mechanism's direction at which the mechanism ends, searched on
    (0, pi]: the loop closure fails (toggle of the four-bar linkage), or a column stops rotating
    in the rocking direction relative to the foundation or the beam (the beam would then bear
    on the column's other top corner); ``pi`` if neither happens."""
    if not isinstance(mech, FrameMechanism):
        return mech.limit()
    s = mech.direction
    if _parallelogram(mech):
        # equal, parallel columns: the linkage stays a parallelogram (the beam translates) and
        # folds flat when the columns' pivot-to-top-corner lines AB, DC reach the base line,
        # i.e. when AB's angle phiAB0 + s phi [rad] reaches pi (s = +1) or 0 (s = -1): the
        # tangency the search below finds numerically (tested against it)
        return math.pi - mech._phiAB0 if s > 0 else mech._phiAB0
    return _searched_limit(mech)


def _parallelogram(mech: "FrameMechanism") -> bool:
    """Equal and parallel columns (B0 - A = C0 - D)."""
    return (abs(mech._rho0 - mech._rho1) <= 1e-12 * mech._rho0
            and abs(mech._phiAB0 - mech._phiCD0) <= 1e-12)


def _searched_limit(mech: "FrameMechanism") -> float:
    """:func:`geometric_limit` by search: the loop closure's margin stepped over (0, pi], a
    crossing bisected, a tangency minimized."""
    s = mech.direction
    scale = mech._rho1 ** 2

    def margin(x: float) -> float:
        return mech.closure_margin(s * x) / scale

    def same_sense(x: float) -> bool:
        # the mechanism holds while both columns rotate, relative to the foundation and to the
        # beam, in the rocking direction (else the beam would bear on the other top corner)
        th_b, th_r = mech.angles(s * x)
        return s * (s * x - th_b) > 0.0 and s * (th_r - th_b) > 0.0 and s * th_r > 0.0

    n = 720
    xs = [0.0]
    ms = [margin(0.0)]
    for i in range(1, n + 1):
        x = math.pi * i / n
        m = margin(x)
        if m <= 0.0 or not same_sense(x):  # the linkage cannot be assembled, or stops
            lo, hi = xs[-1], x             # being this mechanism: bisect the crossing
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if margin(mid) > 0.0 and same_sense(mid):
                    lo = mid
                else:
                    hi = mid
            return lo
        if len(ms) >= 2 and ms[-1] < ms[-2] and ms[-1] < m and ms[-1] < 1e-2:
            # a tangency (e.g. the parallelogram of the symmetric frame folding flat)
            from scipy.optimize import minimize_scalar
            r = minimize_scalar(margin, bounds=(xs[-2], x), method="bounded",
                                options={"xatol": 1e-12})
            if r.fun < 1e-9:
                return float(r.x)
        xs.append(x)
        ms.append(m)
    return math.pi


def mechanism(structure: Block | Frame, direction: int) -> BlockMechanism | FrameMechanism:
    """The mechanism of ``structure`` rocking in ``direction`` (+1 ccw, -1 cw)."""
    if isinstance(structure, Block):
        return BlockMechanism(structure, direction)
    if isinstance(structure, Frame):
        return FrameMechanism(structure, direction)
    raise TypeError(f"unsupported structure {type(structure).__name__}")

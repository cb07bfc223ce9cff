"""Equation of motion of a rocking mechanism, built from its kinematics (paper, Eq. 17).

    I(phi) phi'' + J(phi) phi'^2 + G(phi) g + K(phi) + D(phi) phi' = B(phi) u_g''

With T = 1/2 I(phi) phi'^2 and the bodies' centres of mass G_i(phi), rotations theta_i(phi)
(:mod:`rockbench.scene.mechanism`), Lagrange's equation (Eq. 6) gives

    I = sum_i m_i |dG_i/dphi|^2 + I^G_i (dtheta_i/dphi)^2              [kg m^2]
    J = 1/2 dI/dphi = sum_i m_i dG_i.d2G_i + I^G_i dtheta_i d2theta_i  [kg m^2]
    G = sum_i m_i dy_i/dphi             (gravity: V_fr = g sum m_i y_i)  [kg m]
    B = -sum_i m_i dx_i/dphi            (ground: Q = -u_g'' sum m_i dx_i/dphi)  [kg m]
    K = dV_tend/dphi = k sum_j e_j de_j/dphi  (tendon j elongation e_j)       [N m]
    D = C sum_j (dc_j/dphi)^2           (damper j chord c_j)                  [N m s]

These are compared with the paper's closed forms (Eq. 18) in the tests; the differences are
listed in ``docs/paper-discrepancies.md``.

Vertical ground acceleration a_v(t) [m/s^2, up positive]: while the pivots stay on the ground,
g is replaced by g + a_v in the gravity term, G (g + a_v) (derivation:
:mod:`rockbench.analytic.reactions`). The devices' terms K and D do not change: the tendons'
elongations and the dampers' chords depend on the bodies' rotations relative to the
foundation only, not on gravity or on the foundation's motion.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from ..constants import G
from ..scene.devices import Devices
from ..scene.structure import Block, Frame
from ..scene.mechanism import Configuration, mechanism

__all__ = ["Terms", "DeviceState", "Dynamics"]


class Terms(NamedTuple):
    """Coefficients of Eq. 17 at one phi (SI units, see module docstring)."""

    inertia: float   # I [kg m^2]
    velocity: float  # J [kg m^2]
    gravity: float   # G [kg m]  (multiplied by g in the equation)
    ground: float    # B [kg m]
    tendon: float    # K [N m]
    damping: float   # D [N m s]


class DeviceState(NamedTuple):
    """Tendon elongations [m], their phi-derivatives [m/rad], and damper chord rates [m/rad] of
    the left and right columns."""

    elong_left: float
    elong_right: float
    delong_left: float
    delong_right: float
    dchord_left: float
    dchord_right: float


def _opening(b: float, x: float, dx: float) -> tuple[float, float]:
    """Chord 2 b sin(|x|/2) [m] of a joint opened by relative rotation x, and its derivative."""
    ax = abs(x)
    sgn = 1.0 if x >= 0.0 else -1.0
    return 2.0 * b * math.sin(0.5 * ax), b * math.cos(0.5 * ax) * sgn * dx


class Dynamics:
    """Equation-of-motion terms of ``structure`` (with optional ``devices``) rocking in
    ``direction`` (+1 counterclockwise, -1 clockwise)."""

    def __init__(self, structure: Block | Frame, direction: int, devices: Devices | None = None):
        self.structure = structure
        self.direction = direction
        self.mechanism = mechanism(structure, direction)
        if isinstance(structure, Block):
            if devices is not None:
                raise TypeError("devices are defined for frames only")
            self._m = (structure.mass,)
            self._I = (structure.inertia_cm,)
        else:
            self._m = (structure.mass_left, structure.mass_beam, structure.mass_right)
            self._I = (structure.inertia_left, structure.inertia_beam, structure.inertia_right)
        self.devices = devices
        self._k = devices.tendon_stiffness if devices is not None else 0.0
        self._c = devices.damping if devices is not None else 0.0

    # ---------------------------------------------------------------------------------------
    def configuration(self, phi: float) -> Configuration:
        return self.mechanism.configuration(phi)

    def device_state(self, config: Configuration) -> DeviceState:
        """Tendon elongations and damper chord rates at ``config`` (frame only)."""
        b = self.structure.b
        left, beam, right = config.bodies
        out = []
        for col in (left, right):
            eb, deb = _opening(b, col.theta, col.dtheta)
            et, det = _opening(b, col.theta - beam.theta, col.dtheta - beam.dtheta)
            out.append((eb + et, deb + det, 2.0 * deb))  # chord 4 b sin(|th|/2) = 2 * base opening
        (el, del_, dcl), (er, der, dcr) = out
        return DeviceState(el, er, del_, der, dcl, dcr)

    def device_state_many(self, phi, angles=None) -> tuple:
        """Vectorized over an array ``phi`` [rad] of this mechanism (frame only): tendon
        elongations [m] (left, right) and damper chord rates dc/dphi [m/rad] (left, right), by
        the formulas of :meth:`device_state`. ``angles``: :meth:`FrameMechanism.angles_many`
        of ``phi`` if already computed."""
        import numpy as np

        phi = np.asarray(phi, dtype=float)
        th_b, th_r, dth_b, dth_r = angles if angles is not None else \
            self.mechanism.angles_many(phi)
        b = self.structure.b

        def opening(x, dx):
            return 2.0 * b * np.sin(0.5 * np.abs(x)), b * np.cos(0.5 * np.abs(x)) * np.where(
                x >= 0.0, 1.0, -1.0) * dx

        out = []
        for th, dth in ((phi, np.ones_like(phi)), (th_r, dth_r)):
            eb, deb = opening(th, dth)
            et, _ = opening(th - th_b, dth - dth_b)
            out.append((eb + et, 2.0 * deb))
        (el, dcl), (er, dcr) = out
        return el, er, dcl, dcr

    def terms(self, phi: float, devices_intact: bool = True) -> Terms:
        """The coefficients of Eq. 17 at ``phi`` [rad]."""
        cfg = self.mechanism.configuration(phi)
        return self.terms_at(cfg, devices_intact)

    def terms_at(self, cfg: Configuration, devices_intact: bool = True) -> Terms:
        I = J = Gm = Bm = 0.0
        for m, Ic, bk in zip(self._m, self._I, cfg.bodies):
            I += m * (bk.dx * bk.dx + bk.dy * bk.dy) + Ic * bk.dtheta * bk.dtheta
            J += m * (bk.dx * bk.ddx + bk.dy * bk.ddy) + Ic * bk.dtheta * bk.ddtheta
            Gm += m * bk.dy
            Bm -= m * bk.dx
        K = D = 0.0
        if devices_intact and (self._k > 0.0 or self._c > 0.0):
            ds = self.device_state(cfg)
            K = self._k * (ds.elong_left * ds.delong_left + ds.elong_right * ds.delong_right)
            D = self._c * (ds.dchord_left ** 2 + ds.dchord_right ** 2)
        return Terms(I, J, Gm, Bm, K, D)

    def acceleration(self, phi: float, phidot: float, ground_acc: float,
                     devices_intact: bool = True, vertical_acc: float = 0.0) -> float:
        """phi'' [rad/s^2] from Eq. 17 for the horizontal ground acceleration ``ground_acc``
        [m/s^2] and the vertical one ``vertical_acc`` [m/s^2, up positive; g -> g + a_v]."""
        t = self.terms(phi, devices_intact)
        return (t.ground * ground_acc - t.velocity * phidot * phidot
                - t.gravity * (G + vertical_acc) - t.tendon - t.damping * phidot) / t.inertia

    def potential_gradient(self, phi: float, devices_intact: bool = True) -> float:
        """dV/dphi = G g + K [N m]: gravity plus intact tendons."""
        t = self.terms(phi, devices_intact)
        return t.gravity * G + t.tendon

    def energy(self, phi: float, phidot: float, devices_intact: bool = True) -> float:
        """Mechanical energy T + V [J] relative to rest (gravity + tendon strain)."""
        cfg = self.mechanism.configuration(phi)
        t = self.terms_at(cfg, devices_intact)
        rest = self.mechanism.configuration(0.0)
        V = G * sum(m * (b.y - b0.y) for m, b, b0 in zip(self._m, cfg.bodies, rest.bodies))
        if devices_intact and self._k > 0.0:
            ds = self.device_state(cfg)
            V += 0.5 * self._k * (ds.elong_left ** 2 + ds.elong_right ** 2)
        return 0.5 * t.inertia * phidot * phidot + V

    def uplift_threshold(self) -> float:
        """lambda = G(0)/B(0) [-] (Eq. 20): the ground acceleration, in units of g, at which the
        structure at rest starts to rock in this direction (signed: > 0 for counterclockwise)."""
        t = self.terms(0.0)
        return t.gravity / t.ground

"""Contact forces of a rocking structure: what friction the rocking model needs.

The SDOF rocking model (Housner's block; the paper's frame, Dimitrakopoulos & Giouvanidis 2015)
assumes that every pivot stays on the ground without slipping, and, for the frame, that the
beam stays on the columns' top corners without slipping. This module computes the forces those
contacts must carry in a given state, so that the assumption can be checked against a friction
coefficient: the friction *demand* |T| / N of each contact.

Vertical ground motion: the equation of motion with g -> g + a_v
-----------------------------------------------------------------
While the pivots stay in contact they move with the foundation, whose acceleration is
(a_g, a_v) (a_g positive to the right, a_v positive up). In the foundation's frame each body i
(mass m_i, centre of mass G_i(phi), rotation theta_i(phi), :mod:`rockbench.scene.mechanism`)
feels gravity and the inertial force, together -m_i (a_g, g + a_v), constant over the body, so
no moment about G_i. The generalized force is then

    Q = -sum_i m_i (a_g dx_i/dphi + (g + a_v) dy_i/dphi) = B a_g - G (g + a_v)

with the paper's B = -sum m_i dx_i/dphi and G = sum m_i dy_i/dphi (Eq. 17, the terms of
:mod:`rockbench.analytic.dynamics`), and Lagrange's equation (Eq. 6) gives Eq. 17 with g
replaced by g + a_v(t):

    I(phi) phi'' + J(phi) phi'^2 + G(phi) (g + a_v) = B(phi) a_g        (free-standing)

At rest phi = phi' = 0 the structure uplifts when B a_g > G (g + a_v), i.e. (Eq. 20)

    a_g > lambda (g + a_v)  (counterclockwise),  a_g < lambda_cw (g + a_v)  (clockwise),

so |a_g| > |lambda| (g + a_v). Impacts are instantaneous and unchanged by a finite a_v. The
equation holds while g + a_v > 0 and every contact force below stays compressive.
:func:`rocking_acceleration` and :func:`uplift_direction` implement these two statements.

The contact forces: Newton-Euler for each body
----------------------------------------------
Given (phi, phi', phi''), each body's accelerations follow from the mechanism's
phi-derivatives: a_Gi = dG_i/dphi phi'' + d2G_i/dphi2 phi'^2 and alpha_i = dtheta_i/dphi phi''
+ d2theta_i/dphi2 phi'^2. With the body forces -m_i (a_g, g + a_v):

* block (one body, one pivot P): the pivot's force R = m (a_G + (a_g, g + a_v)) (Newton), and
  the moment about G, (P - G) x R = I_G alpha, is the equation of motion;
* frame (three bodies, four contacts: pivots A, D on the ground, top corners B, C under the
  beam): 9 equations (2 forces and 1 moment per body) for the 8 force components at A, B, C, D.
  One equation is redundant exactly when phi'' is the model's (virtual work: the combination of
  the 9 along the mechanism's motion is Eq. 17). We solve a square 9 x 9 system with a ninth
  unknown: phi'' itself (``phiddot=None``: Newton-Euler's own phi'', which the tests check
  against Eq. 17), or, for a given phi'', a moment M on column AB, ``moment_residual`` =
  I (phi'' - phi''_model) [N m], zero when the given phi'' is the model's. At rest (phi'' = 0,
  not rocking) M is the restoring moment the flat bases carry and the split between the contacts
  is a convention (the real one is statically indeterminate); their sums are exact.

Each contact is reported as the force on the body *above* it from the body below (ground on
column, column on beam), resolved on the contact surface: the ground for A and D, the beam's
soffit (rotated by the beam's rotation) for B and C. ``normal`` > 0 is compression; ``normal``
<= 0 means the contact would open (a pivot lifts, the beam leaves a column), and the friction
demand is then infinite. Devices (tendons, dampers) are not included: their forces act across
the same joints and would change these loads.

Along a run: the demand history
-------------------------------
:func:`demand_history` evaluates the demand at every output sample of a run of the model
(vectorized: one batched linear solve), for the two kinds of contact the model keeps: the
**base** (the pivots on the ground: the block's pivot, the frame's A and D; the larger
demand) and, for a frame, the **beam** on its columns (B and C; the larger). At rest (mode 0)
the structure moves with the ground as one rigid body, and every contact's total force is
m (a_g, g + a_v): the demand is |a_g| / (g + a_v) at the base and under the beam alike (the
split between two contacts at rest is statically indeterminate; they slide together). At rest
the devices are slack (no pretension) and the demand is exact.

While a hybrid frame rocks with its devices intact, their forces enter the nine equations as
known loads (:func:`_device_loads`): each central unbonded tendon, anchored at the
foundation and at the beam, pulls with k e_j on the column's base and top centres towards its
anchors and on the beam towards the column (e_j the model's own elongation, base plus top
opening), and each damper acts as a couple on its column, -C (dc_j/dt) dc_j/dtheta_j. Their
virtual work along the mechanism is the model's K and D phi' exactly, so Newton-Euler's own
phi'' with these loads is Eq. 17's (tested to round-off). The tendons are the paper's geometry;
the dampers' couple is a choice: the SDOF model fixes only their moment, and a damper whose
force acts at a column's heel (the engines' ``heel`` model,
:class:`~rockbench.engines.devices.DeviceGeometry`) would load the contacts differently.
:func:`first_excess` finds the first time a demand exceeds its friction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import pandas as pd

from ..constants import G
from ..errors import ParameterError, check_finite
from ..scene.structure import Block, Frame, check_direction
from . import rules
from .dynamics import Dynamics

__all__ = ["Contact", "BlockReactions", "FrameReactions", "rocking_acceleration",
           "uplift_direction", "block_reactions", "frame_reactions", "reaction_history",
           "demand_history", "first_excess"]


@dataclass(frozen=True)
class Contact:
    """The force [N] on the body above a contact from the body below, global (``fx``, ``fy``)
    and resolved on the contact surface: ``normal`` (compression > 0) and ``tangential`` (along
    the surface's x axis, to the right for the ground)."""

    fx: float
    fy: float
    normal: float
    tangential: float

    @property
    def opens(self) -> bool:
        """True when the contact cannot push (normal <= 0): a pivot lifts, the beam leaves."""
        return not self.normal > 0.0

    @property
    def demand(self) -> float:
        """Friction demand |tangential| / normal [-]; inf when the contact opens."""
        return abs(self.tangential) / self.normal if not self.opens else math.inf


@dataclass(frozen=True)
class BlockReactions:
    """The pivot's force, phi'' [rad/s^2] and the moment residual [N m] (0: phi'' is the
    model's)."""

    pivot: Contact
    phiddot: float
    moment_residual: float

    @property
    def max_demand(self) -> float:
        return self.pivot.demand


@dataclass(frozen=True)
class FrameReactions:
    """The pivots A (left column) and D (right column) on the ground, the top corners B and C
    under the beam, phi'' [rad/s^2] and the moment residual on column AB [N m]."""

    A: Contact
    B: Contact
    C: Contact
    D: Contact
    phiddot: float
    moment_residual: float

    @property
    def max_demand(self) -> float:
        """The larger friction demand of the two pivots [-]."""
        return max(self.A.demand, self.D.demand)


# ------------------------------------------------------------------------------------------------
@lru_cache(maxsize=64)
def _dynamics(structure: Block | Frame, direction: int) -> Dynamics:
    return Dynamics(structure, direction)


def _ge(a_v: float) -> float:
    """g + a_v [m/s^2], refused when the structure is not on the ground."""
    ge = G + check_finite("a_v", a_v)
    if not ge > 0.0:
        raise ParameterError("a_v", a_v, f"> -g = {-G:g} m/s^2",
                             "g + a_v <= 0: the structure leaves the ground (free flight)")
    return ge


def _check_structure(structure, kind) -> None:
    if not isinstance(structure, kind):
        raise ParameterError("structure", structure, f"a {kind.__name__}")


def rocking_acceleration(structure: Block | Frame, direction: int, phi: float, phidot: float,
                         a_g: float, a_v: float = 0.0) -> float:
    """phi'' [rad/s^2] of the free-standing ``structure`` rocking in ``direction`` (+1 ccw,
    -1 cw) at ``phi`` [rad], ``phidot`` [rad/s], under ground accelerations ``a_g``, ``a_v``
    [m/s^2]: Eq. 17 with g replaced by g + a_v (module docstring)."""
    s = check_direction(direction)
    t = _dynamics(structure, s).terms(check_finite("phi", phi))
    phidot = check_finite("phidot", phidot)
    return (t.ground * check_finite("a_g", a_g) - t.velocity * phidot * phidot
            - t.gravity * _ge(a_v)) / t.inertia


def uplift_direction(structure: Block | Frame, a_g: float, a_v: float = 0.0) -> int:
    """The direction a free-standing structure at rest starts rocking in: +1 when
    a_g > lambda_ccw (g + a_v), -1 when a_g < lambda_cw (g + a_v) (each exceeded by the
    relative margin :data:`rockbench.analytic.rules.UPLIFT_RTOL`), 0 otherwise (Eq. 20 with
    g + a_v)."""
    ge, a = _ge(a_v), check_finite("a_g", a_g)
    margin = 1.0 + rules.UPLIFT_RTOL
    if a > _dynamics(structure, 1).uplift_threshold() * ge * margin:
        return 1
    if a < _dynamics(structure, -1).uplift_threshold() * ge * margin:
        return -1
    return 0


def _cross(rx: float, ry: float, fx: float, fy: float) -> float:
    return rx * fy - ry * fx


def _rot(th: float, x: float, y: float) -> tuple[float, float]:
    c, s = math.cos(th), math.sin(th)
    return c * x - s * y, s * x + c * y


def _solve(bodies, joints, phidot: float, phiddot: float | None, a_g: float, ge: float):
    """Newton-Euler for the bodies (mass, inertia, BodyKinematics) with the unknown joint
    forces: ``joints`` = [(x, y, [(body, sign), ...])], the force F_j acting as sign * F_j on
    each body listed. The last unknown is phi'' (``phiddot`` None) or a moment on body 0.
    Returns (joint forces (n, 2), phi'', moment)."""
    nb, nj = len(bodies), len(joints)
    n = 2 * nj + 1
    M, rhs = np.zeros((3 * nb, n)), np.zeros(3 * nb)
    w2 = phidot * phidot
    for i, (m, inertia, k) in enumerate(bodies):
        r = 3 * i
        rhs[r] = m * (k.ddx * w2 + a_g)
        rhs[r + 1] = m * (k.ddy * w2 + ge)
        rhs[r + 2] = inertia * k.ddtheta * w2
        if phiddot is None:        # the phi'' terms move to the left-hand side
            M[r, -1], M[r + 1, -1], M[r + 2, -1] = -m * k.dx, -m * k.dy, -inertia * k.dtheta
        else:
            rhs[r] += m * k.dx * phiddot
            rhs[r + 1] += m * k.dy * phiddot
            rhs[r + 2] += inertia * k.dtheta * phiddot
            if i == 0:
                M[r + 2, -1] = 1.0
    for j, (px, py, acting) in enumerate(joints):
        for i, sign in acting:
            k = bodies[i][2]
            r = 3 * i
            M[r, 2 * j] += sign
            M[r + 1, 2 * j + 1] += sign
            M[r + 2, 2 * j] += -sign * (py - k.y)       # (P - G) x F, F = (1, 0)
            M[r + 2, 2 * j + 1] += sign * (px - k.x)    # (P - G) x F, F = (0, 1)
    x = np.linalg.solve(M, rhs)
    forces = x[:-1].reshape(nj, 2)
    if phiddot is None:
        return forces, float(x[-1]), 0.0
    return forces, float(phiddot), float(x[-1])


def _contact(fx: float, fy: float, surface: float) -> Contact:
    """The force (fx, fy) [N] on the body above a surface rotated by ``surface`` [rad]."""
    tx, ty = _rot(surface, 1.0, 0.0)
    return Contact(float(fx), float(fy), float(-ty * fx + tx * fy), float(tx * fx + ty * fy))


def block_reactions(block: Block, direction: int, phi: float, phidot: float,
                    phiddot: float | None, a_g: float, a_v: float = 0.0) -> BlockReactions:
    """The pivot's force on a block rocking in ``direction`` (+1 about its left corner, -1
    about its right) at ``phi`` [rad], ``phidot`` [rad/s], ``phiddot`` [rad/s^2] (None: the
    model's, from the moment balance) under ``a_g``, ``a_v`` [m/s^2]: H = m (x_G'' + a_g),
    V = m (y_G'' + g + a_v) (Newton for the centre of mass)."""
    _check_structure(block, Block)
    s = check_direction(direction)
    mech = _dynamics(block, s).mechanism
    k = mech.configuration(check_finite("phi", phi)).bodies[0]
    px, py = mech.pivot
    forces, pdd, res = _solve([(block.mass, block.inertia_cm, k)], [(px, py, [(0, 1.0)])],
                              check_finite("phidot", phidot),
                              None if phiddot is None else check_finite("phiddot", phiddot),
                              check_finite("a_g", a_g), _ge(a_v))
    return BlockReactions(_contact(*forces[0], 0.0), pdd, res)


def frame_reactions(frame: Frame, direction: int, phi: float, phidot: float,
                    phiddot: float | None, a_g: float, a_v: float = 0.0) -> FrameReactions:
    """The contact forces of the frame's mechanism rocking in ``direction`` (+1 ccw, -1 cw) at
    ``phi`` [rad], ``phidot`` [rad/s], ``phiddot`` [rad/s^2] (None: Newton-Euler's own, equal to
    Eq. 17's) under ``a_g``, ``a_v`` [m/s^2]: the nine equations of the three bodies (module
    docstring). Free-standing frames only (devices would add forces at the same joints)."""
    _check_structure(frame, Frame)
    s = check_direction(direction)
    mech = _dynamics(frame, s).mechanism
    cfg = mech.configuration(check_finite("phi", phi))
    left, beam, right = cfg.bodies
    piv = frame.pivots(s)
    A, D = piv["A"], piv["D"]
    bx, by = _rot(cfg.phi, piv["B"][0] - A[0], piv["B"][1] - A[1])
    cx, cy = _rot(right.theta, piv["C"][0] - D[0], piv["C"][1] - D[1])
    B, C = (A[0] + bx, A[1] + by), (D[0] + cx, D[1] + cy)
    bodies = [(frame.mass_left, frame.inertia_left, left),
              (frame.mass_beam, frame.inertia_beam, beam),
              (frame.mass_right, frame.inertia_right, right)]
    # unknown forces: at A and D the ground on the columns; at B and C the columns on the beam
    joints = [(*A, [(0, 1.0)]), (*B, [(1, 1.0), (0, -1.0)]), (*C, [(1, 1.0), (2, -1.0)]),
              (*D, [(2, 1.0)])]
    forces, pdd, res = _solve(bodies, joints, check_finite("phidot", phidot),
                              None if phiddot is None else check_finite("phiddot", phiddot),
                              check_finite("a_g", a_g), _ge(a_v))
    fa, fb, fc, fd = forces
    return FrameReactions(_contact(*fa, 0.0), _contact(*fb, beam.theta),
                          _contact(*fc, beam.theta), _contact(*fd, 0.0), pdd, res)


def reaction_history(structure: Block | Frame, direction: int, phi, phidot, phiddot, a_g,
                     a_v=0.0) -> pd.DataFrame:
    """:func:`block_reactions` or :func:`frame_reactions` along arrays of states (one
    direction; ``phiddot`` may be None for the model's, ``a_v`` a scalar or an array): columns
    ``phiddot`` [rad/s^2], and for each contact (``pivot``; or ``A``, ``B``, ``C``, ``D``)
    ``normal_X`` [N], ``tangential_X`` [N], ``demand_X`` [-]."""
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    n = phi.size
    cols = [np.broadcast_to(np.asarray(x, dtype=float), (n,))
            for x in (phidot, a_g, a_v)]
    pdd = [None] * n if phiddot is None else np.broadcast_to(np.asarray(phiddot, float), (n,))
    block = isinstance(structure, Block)
    fn = block_reactions if block else frame_reactions
    names = ("pivot",) if block else ("A", "B", "C", "D")
    rows = []
    for i in range(n):
        r = fn(structure, direction, phi[i], cols[0][i], pdd[i], cols[1][i], cols[2][i])
        row = {"phiddot": r.phiddot}
        for name in names:
            c = getattr(r, name)
            row.update({f"normal_{name}": c.normal, f"tangential_{name}": c.tangential,
                        f"demand_{name}": c.demand})
        rows.append(row)
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------------------------------
# Along a run: the demand at every output sample, vectorized
def _solve_many(bodies, joints, phidot, a_g, ge, loads=None, *, with_phiddot: bool = False):
    """:func:`_solve` over n samples at once (phi'' the ninth unknown: the model's): ``bodies``
    = [(m, I, k)] with k a dict of arrays (n,) x, y, dx, dy, ddx, ddy, dtheta, ddtheta;
    ``joints`` = [(px (n,), py (n,), [(body, sign)])]; ``loads``: None or, per body, the known
    external force and moment about its centre of mass (fx, fy, mz) (n,) [N, N m] (the
    devices, :func:`_device_loads`). Returns the joint forces (n, nj, 2) (and phi'' (n,)
    [rad/s^2] with ``with_phiddot``)."""
    nb, nj, n = len(bodies), len(joints), phidot.size
    M = np.zeros((n, 3 * nb, 2 * nj + 1))
    rhs = np.zeros((n, 3 * nb))
    w2 = phidot * phidot
    for i, (m, inertia, k) in enumerate(bodies):
        r = 3 * i
        rhs[:, r] = m * (k["ddx"] * w2 + a_g)
        rhs[:, r + 1] = m * (k["ddy"] * w2 + ge)
        rhs[:, r + 2] = inertia * k["ddtheta"] * w2
        M[:, r, -1] = -m * k["dx"]
        M[:, r + 1, -1] = -m * k["dy"]
        M[:, r + 2, -1] = -inertia * k["dtheta"]
        if loads is not None:
            fx, fy, mz = loads[i]
            rhs[:, r] -= fx
            rhs[:, r + 1] -= fy
            rhs[:, r + 2] -= mz
    for j, (px, py, acting) in enumerate(joints):
        for i, sign in acting:
            k = bodies[i][2]
            r = 3 * i
            M[:, r, 2 * j] += sign
            M[:, r + 1, 2 * j + 1] += sign
            M[:, r + 2, 2 * j] += -sign * (py - k["y"])
            M[:, r + 2, 2 * j + 1] += sign * (px - k["x"])
    x = np.linalg.solve(M, rhs[..., None])[..., 0]
    if with_phiddot:
        return x[:, :-1].reshape(n, nj, 2), x[:, -1]
    return x[:, :-1].reshape(n, nj, 2)


def _device_loads(frame: Frame, devices, s: int, kin, phidot):
    """The forces of a frame's intact devices on its bodies (left, beam, right) along a run,
    as (fx, fy, mz) per body [N, N, N m] (mz about the body's centre of mass), in the state
    of the mechanism rocking in direction ``s`` (``kin``: its configuration_many at the
    samples; ``phidot`` [rad/s]).

    Tendon of column j (central, unbonded, anchored at the foundation F_j, the rest position
    of the column's base centre, and at the beam T_j, the rest position of its top centre):
    elongation e_j = |P_j - F_j| + |T_j - Q_j| (P_j, Q_j the column's base and top centres
    now) - exactly the model's base plus top opening, 2 b sin(|theta|/2) each - and tension
    k e_j acting on the column at P_j towards F_j and at Q_j towards T_j, and on the beam at
    T_j towards Q_j: their virtual work is -k e_j de_j, the model's K. Damper of column j: the
    model's dashpot on the chord c_j = 4 b sin(|theta_j|/2) as a couple on the column,
    M_j = -C (dc_j/dt) (dc_j/dtheta_j), with no resultant force: its virtual power is the
    model's -D phi'^2 and it takes no side on where a real damper's force would reach the
    contacts (module docstring)."""
    n = phidot.size
    k, c, b = devices.tendon_stiffness, devices.damping, frame.b
    rest = mechanism_rest(frame, s)
    beam = kin[1]
    loads = [[np.zeros(n), np.zeros(n), np.zeros(n)] for _ in range(3)]
    cb, sb = np.cos(beam["theta"]), np.sin(beam["theta"])
    for j, h in ((0, 0.5 * frame.column_height_left), (2, 0.5 * frame.column_height_right)):
        col, (gx0, gy0), (bx0, by0) = kin[j], rest[j], rest[1]
        cc, sc = np.cos(col["theta"]), np.sin(col["theta"])
        P = (col["x"] + sc * h, col["y"] - cc * h)            # G + R(theta) (0, -h)
        Q = (col["x"] - sc * h, col["y"] + cc * h)            # G + R(theta) (0, +h)
        F = (gx0, gy0 - h)
        tx0, ty0 = gx0 - bx0, gy0 + h - by0                   # T in the beam's rest frame
        T = (beam["x"] + cb * tx0 - sb * ty0, beam["y"] + sb * tx0 + cb * ty0)
        dbx, dby = F[0] - P[0], F[1] - P[1]
        dtx, dty = T[0] - Q[0], T[1] - Q[1]
        eb, et = np.hypot(dbx, dby), np.hypot(dtx, dty)
        tension = k * (eb + et)
        # an end that has not opened pulls along the tendon's rest line (vertical)
        ub = np.where(eb > 1e-12, dbx / np.where(eb > 1e-12, eb, 1.0), 0.0), \
            np.where(eb > 1e-12, dby / np.where(eb > 1e-12, eb, 1.0), -1.0)
        ut = np.where(et > 1e-12, dtx / np.where(et > 1e-12, et, 1.0), 0.0), \
            np.where(et > 1e-12, dty / np.where(et > 1e-12, et, 1.0), 1.0)
        fpx, fpy = tension * ub[0], tension * ub[1]           # on the column at P
        fqx, fqy = tension * ut[0], tension * ut[1]           # on the column at Q
        lc = loads[j]
        lc[0] += fpx + fqx
        lc[1] += fpy + fqy
        lc[2] += (_cross_many(P[0] - col["x"], P[1] - col["y"], fpx, fpy)
                  + _cross_many(Q[0] - col["x"], Q[1] - col["y"], fqx, fqy))
        lb = loads[1]                                          # on the beam at T
        lb[0] -= fqx
        lb[1] -= fqy
        lb[2] += _cross_many(T[0] - beam["x"], T[1] - beam["y"], -fqx, -fqy)
        th, dth = col["theta"], col["dtheta"]
        dc = 2.0 * b * np.cos(0.5 * np.abs(th)) * np.where(th >= 0.0, 1.0, -1.0)  # dc/dtheta
        lc[2] += -c * dc * dth * phidot * dc
    return [tuple(x) for x in loads]


def _cross_many(rx, ry, fx, fy):
    return rx * fy - ry * fx


@lru_cache(maxsize=64)
def _rest_of(frame: Frame, s: int) -> tuple[tuple[float, float], ...]:
    kin = _dynamics(frame, s).mechanism.configuration_many(np.zeros(1))
    return tuple((float(b["x"][0]), float(b["y"][0])) for b in kin)


def mechanism_rest(frame: Frame, s: int) -> tuple[tuple[float, float], ...]:
    """The bodies' centres of mass (x, y) [m] at rest (phi = 0), left, beam, right."""
    return _rest_of(frame, s)


def _demand_many(forces, surface):
    """max |T| / N over the contacts ``forces`` (n, k, 2) on surfaces rotated by ``surface``
    ((n, k) [rad]); inf where a contact opens (N <= 0)."""
    tx, ty = np.cos(surface), np.sin(surface)
    fx, fy = forces[..., 0], forces[..., 1]
    normal = -ty * fx + tx * fy
    tang = tx * fx + ty * fy
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(normal > 0.0, np.abs(tang) / np.where(normal > 0.0, normal, 1.0), np.inf)
    return d.max(axis=1)


def _rocking_demand(structure, s, phi, phidot, a_g, ge, devices=None):
    """(base, beam) demands [-] of ``structure`` rocking in direction ``s`` at the samples,
    with the intact ``devices`` of a frame (:func:`_device_loads`; None: free-standing)."""
    mech = _dynamics(structure, s).mechanism
    kin = mech.configuration_many(phi)
    n = phi.size
    if isinstance(structure, Block):
        (k,) = kin
        px, py = mech.pivot
        f = _solve_many([(structure.mass, structure.inertia_cm, k)],
                        [(np.full(n, px), np.full(n, py), [(0, 1.0)])], phidot, a_g, ge)
        return _demand_many(f, np.zeros((n, 1))), np.full(n, np.nan)
    left, beam, right = kin
    piv = structure.pivots(s)
    A, D = piv["A"], piv["D"]
    c0, s0 = np.cos(phi), np.sin(phi)
    bx0, by0 = piv["B"][0] - A[0], piv["B"][1] - A[1]
    cth, sth = np.cos(right["theta"]), np.sin(right["theta"])
    cx0, cy0 = piv["C"][0] - D[0], piv["C"][1] - D[1]
    B = (A[0] + c0 * bx0 - s0 * by0, A[1] + s0 * bx0 + c0 * by0)
    C = (D[0] + cth * cx0 - sth * cy0, D[1] + sth * cx0 + cth * cy0)
    bodies = [(structure.mass_left, structure.inertia_left, left),
              (structure.mass_beam, structure.inertia_beam, beam),
              (structure.mass_right, structure.inertia_right, right)]
    joints = [(np.full(n, A[0]), np.full(n, A[1]), [(0, 1.0)]),
              (B[0], B[1], [(1, 1.0), (0, -1.0)]), (C[0], C[1], [(1, 1.0), (2, -1.0)]),
              (np.full(n, D[0]), np.full(n, D[1]), [(2, 1.0)])]
    loads = None if devices is None else _device_loads(structure, devices, s, kin, phidot)
    f = _solve_many(bodies, joints, phidot, a_g, ge, loads)
    base = _demand_many(f[:, [0, 3]], np.zeros((n, 2)))
    th_b = np.repeat(beam["theta"][:, None], 2, axis=1)
    return base, _demand_many(f[:, [1, 2]], th_b)


def demand_history(scene, t, phi, phidot, mode, intact, a_g, a_v=0.0, *,
                   reference=None) -> pd.DataFrame:
    """The friction demand |T| / N [-] of the contacts of ``scene``'s analytic model along a
    run: columns ``t`` [s], ``base`` (the larger demand of the pivots on the ground) and
    ``beam`` (the larger of the beam's two contacts on the columns; NaN for a block), at the
    samples ``t`` [s] of the history ``phi`` [rad], ``phidot`` [rad/s], ``mode`` (0 at rest,
    +-1 rocking), ``intact`` (devices in place) under the ground accelerations ``a_g``, ``a_v``
    [m/s^2] (arrays, or scalars for ``a_v``).

    At rest: |a_g| / (g + a_v) for every contact; rocking: the Newton-Euler contact forces of
    the mechanism with the model's phi'' (:func:`block_reactions`, :func:`frame_reactions`,
    vectorized; a hybrid frame's intact devices as loads, module docstring); inf where a
    contact opens. NaN where g + a_v <= 0 (no contact; the model ends there).
    """
    t = np.asarray(t, dtype=float)
    n = t.size
    phi, phidot, a_g = (np.broadcast_to(np.asarray(x, dtype=float), (n,))
                        for x in (phi, phidot, a_g))
    ge = G + np.broadcast_to(np.asarray(a_v, dtype=float), (n,))
    mode = np.broadcast_to(np.asarray(mode, dtype=np.int64), (n,))
    intact = np.broadcast_to(np.asarray(intact, dtype=bool), (n,))
    structure = scene.structure
    frame = isinstance(structure, Frame)
    base = np.full(n, np.nan)
    beam = np.full(n, np.nan)
    on = ge > 0.0
    rest = on & (mode == 0)
    with np.errstate(divide="ignore"):
        base[rest] = np.abs(a_g[rest]) / ge[rest]
    if frame:
        beam[rest] = base[rest]
    devices = scene.devices if scene.has_devices else None
    for s in (1, -1):
        for with_devices in ((False, True) if devices is not None else (False,)):
            sel = on & (mode == s)
            if devices is not None:
                sel &= intact if with_devices else ~intact
            idx = np.flatnonzero(sel)
            if idx.size:
                b, m = _rocking_demand(structure, s, phi[idx], phidot[idx], a_g[idx], ge[idx],
                                       devices if with_devices else None)
                base[idx] = b
                if frame:
                    beam[idx] = m
    return pd.DataFrame({"t": t, "base": base, "beam": beam})


def first_excess(demand: pd.DataFrame, mu: float,
                 mu_beam: float | None = None) -> tuple[float, str, float] | None:
    """The first time a contact needs more friction than it has: (time [s], "base" or "beam",
    the demand [-] at the first sample beyond), or None. ``demand`` is a
    :func:`demand_history` frame; ``mu`` the base's friction, ``mu_beam`` the beam's (default
    ``mu``). A demand *exceeds* mu strictly (NaN never does). The time is the linear
    interpolation of the demand's crossing of mu between the last sample at or below it and
    the first above (the first sample itself when the demand jumps to inf, a contact
    opening): within one output step of the first sample beyond."""
    mu = check_finite("mu", mu)
    mu_beam = mu if mu_beam is None else check_finite("mu_beam", mu_beam)
    t = demand["t"].to_numpy(dtype=float)
    best = None
    for name, lim in (("base", mu), ("beam", mu_beam)):
        d = demand[name].to_numpy(dtype=float)
        over = np.flatnonzero(d > lim)
        if not over.size:
            continue
        i = int(over[0])
        ti = float(t[i])
        if i > 0 and math.isfinite(d[i]) and math.isfinite(d[i - 1]) and d[i - 1] <= lim:
            ti = float(t[i - 1] + (lim - d[i - 1]) / (d[i] - d[i - 1]) * (t[i] - t[i - 1]))
        if best is None or ti < best[0]:
            best = (ti, name, float(d[i]))
    return best

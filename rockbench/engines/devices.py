"""Tendons and dampers computed from body poses, for engines without native springs and
dashpots (and as the reference formulas for those with them): elongations, tensions, damper
forces, the point forces that do the model's virtual work, fracture strain.

Forces in N, lengths in m, angles in rad (``docs/conventions.md``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import ParameterError
from ..scene.scene import Scene
from .bodies import BodySpec, body_specs

__all__ = ["PointForce", "DAMPER_MODELS", "DeviceGeometry", "device_forces", "net_wrenches"]


class PointForce(NamedTuple):
    """A force (fx, fy) [N] applied at world point (px, py) [m] on body ``body`` (index)."""

    body: int
    px: float
    py: float
    fx: float
    fy: float


def _world(pose, lx: float, ly: float) -> tuple[float, float]:
    x, y, th = pose[0], pose[1], pose[2]
    c, s = math.cos(th), math.sin(th)
    return x + c * lx - s * ly, y + s * lx + c * ly


#: How the dampers' force reaches the bodies (see :class:`DeviceGeometry`).
DAMPER_MODELS = ("couple", "heel", "distributed")


class DeviceGeometry:
    """Anchor points of tendons and dampers of a frame, in body-local coordinates.

    Tendon of column j: foundation anchor F_j (rest position of the column's base centre), the
    column's base centre P_j and top centre Q_j, and the beam point T_j (rest position of Q_j,
    fixed to the beam). Elongation e_j = |P_j - F_j| + |T_j - Q_j| (base + top opening); strain
    e_j / l. Tension k e_j acts at the column base towards F_j, at the column top towards T_j,
    and on the beam at T_j towards Q_j: these forces do exactly the virtual work -k e_j de_j.

    Damper of column j: along the chord between the heel (the base corner that lifts: the
    bottom-right corner while the column's rotation theta_j >= 0, bottom-left while < 0) and its
    rest position, the chord being that of a rigid rotation theta_j about the pivot corner:
    length c_j = 4 b sin(|theta_j|/2), unit vector u = (-sin(theta_j/2), cos(theta_j/2)), rate
    dc_j/dt = 2 b cos(theta_j/2) sgn(theta_j) omega_j, damper force C dc_j/dt [N]. The chord is
    built from the column's rotation only, never from corner displacements, so contact jitter,
    penetration and slip (micrometres, with large velocities in an impact step) cannot turn the
    damper (C ~ 1e7 N s/m) into a spurious force on a pivot.

    How the damper force reaches the bodies (``damper``; every model has the virtual power
    -C sum_j (dc_j/dt)^2, the analytic model's -D phi'^2, for the mechanism's motion):

    * "heel": the force -C (dc_j/dt) u at the heel corner, as a real damper would act;
    * "couple": its moment -C (dc_j/dt) dc_j/dtheta_j on the column as a pure couple (two
      opposite horizontal forces), with no resultant to lift the column;
    * "distributed": the total damper power taken from every body in proportion to its
      momentum, F_i = -lambda m_i v_i and M_i = -lambda I_i omega_i with lambda = C sum_j
      (dc_j/dt)^2 / sum_i (m_i v_i^2 + I_i omega_i^2): on the mechanism it is the analytic
      D phi' exactly, and, acting like an inertial field, it needs no contact to transmit it.

    Why it matters: the analytic model keeps every pivot closed, but the paper's dampers
    (25.3 MN s/m) exert 2-6 MN, more than the 1 MN of dead load on a column's pivot. At the
    heel they lift the column off its pivot in the closing half-cycle; as a couple they spin a
    column as soon as a contact opens for one step, which Chipmunk's first-order position update
    does every so often (the beam resting on a rotating column drifts off it by a dt^2 term).
    Measured in pymunk on the cases of ``tests/engines/cases.py`` (docs/engines/pymunk.md):
    heel, up to 1 m of slip, 11 of 35 runs diverged; couple, 3.7 cm of slip and peaks 4.8 %
    off; distributed, 0.8 mm and 0.3 %. Engines whose contacts stay closed (soft, penetrating
    contacts) may use the couple.
    """

    def __init__(self, scene: Scene, specs: list[BodySpec], damper: str = "couple"):
        if damper not in DAMPER_MODELS:
            raise ParameterError("damper", damper, f"one of {', '.join(DAMPER_MODELS)}")
        self.damper = damper
        self.mass = [sp.mass for sp in specs]
        self.inertia = [sp.inertia for sp in specs]
        self.k = scene.devices.tendon_stiffness
        self.c = scene.devices.damping
        self.l = scene.devices.tendon_length
        self.eps_f = scene.devices.fracture_strain
        left, beam, right = specs
        self.b = {0: left.half_width, 2: right.half_width}
        self.arm = {0: left.half_height, 2: right.half_height}
        self.columns = []
        for idx, sp in ((0, left), (2, right)):
            base_rest = (sp.x, sp.y - sp.half_height)
            top_rest = (sp.x, sp.y + sp.half_height)
            beam_local = (top_rest[0] - beam.x, top_rest[1] - beam.y)
            corners = [((-sp.half_width, -sp.half_height), (sp.x - sp.half_width, base_rest[1])),
                       ((sp.half_width, -sp.half_height), (sp.x + sp.half_width, base_rest[1]))]
            self.columns.append((idx, base_rest, (0.0, -sp.half_height), (0.0, sp.half_height),
                                 beam_local, corners))

    def elongations(self, state: np.ndarray) -> list[float]:
        """Tendon elongations [m] (left, right) for the bodies' ``state`` (n_bodies, >= 3)."""
        state = state.tolist() if isinstance(state, np.ndarray) else state
        out = []
        for idx, F, p_loc, q_loc, t_loc, _ in self.columns:
            P = _world(state[idx], *p_loc)
            Q = _world(state[idx], *q_loc)
            T = _world(state[1], *t_loc)
            out.append(math.hypot(P[0] - F[0], P[1] - F[1]) + math.hypot(T[0] - Q[0], T[1] - Q[1]))
        return out

    def forces(self, state: np.ndarray) -> tuple[list[PointForce], list[float], list[float]]:
        """Point forces of tendons and dampers, with tendon tensions [N] and damper forces [N]
        (C dc/dt, + resisting opening), for the bodies' ``state`` (n_bodies, 6)."""
        state = state.tolist() if isinstance(state, np.ndarray) else state
        out: list[PointForce] = []
        tensions, dampers, elong = [], [], []
        self.last_elongations = elong       # [m], for the caller's fracture check
        power = 0.0                         # damper power C sum (dc/dt)^2 [W]
        for idx, F, p_loc, q_loc, t_loc, corners in self.columns:
            st = state[idx]
            P = _world(st, *p_loc)
            Q = _world(st, *q_loc)
            T = _world(state[1], *t_loc)
            dbx, dby = F[0] - P[0], F[1] - P[1]
            dtx, dty = T[0] - Q[0], T[1] - Q[1]
            db, dt_ = math.hypot(dbx, dby), math.hypot(dtx, dty)
            elong.append(db + dt_)
            tension = self.k * (db + dt_)
            tensions.append(tension)
            if tension > 0.0:
                if db > 1e-12:
                    out.append(PointForce(idx, P[0], P[1], tension * dbx / db, tension * dby / db))
                if dt_ > 1e-12:
                    fx, fy = tension * dtx / dt_, tension * dty / dt_
                    out.append(PointForce(idx, Q[0], Q[1], fx, fy))
                    out.append(PointForce(1, T[0], T[1], -fx, -fy))
            # damper: chord of the column's rigid rotation about its pivot
            fd = 0.0
            if self.c > 0.0:
                th, w = st[2], st[5]
                sg = 1.0 if th >= 0.0 else -1.0
                half = 0.5 * th
                dchord = 2.0 * self.b[idx] * math.cos(half) * sg   # dc/dtheta [m/rad]
                fd = self.c * dchord * w                            # C dc/dt [N]
                if self.damper == "distributed":
                    power += fd * dchord * w
                elif self.damper == "heel":
                    loc = corners[1][0] if sg > 0 else corners[0][0]
                    X = _world(st, *loc)
                    out.append(PointForce(idx, X[0], X[1], fd * math.sin(half),
                                          -fd * math.cos(half)))
                else:  # the same moment as a couple: two opposite horizontal forces
                    tau = -fd * dchord
                    d = self.arm[idx]
                    out.append(PointForce(idx, st[0], st[1] + d, -0.5 * tau / d, 0.0))
                    out.append(PointForce(idx, st[0], st[1] - d, 0.5 * tau / d, 0.0))
            dampers.append(fd)
        if power > 0.0:
            # the damper power taken from every body in proportion to its momentum
            two_t = sum(m * (st[3] * st[3] + st[4] * st[4]) + i * st[5] * st[5]
                        for m, i, st in zip(self.mass, self.inertia, state))
            if two_t > 0.0:
                lam = power / two_t
                for j, (m, i, st) in enumerate(zip(self.mass, self.inertia, state)):
                    out.append(PointForce(j, st[0], st[1], -lam * m * st[3], -lam * m * st[4]))
                    tau = -lam * i * st[5]
                    if tau != 0.0:
                        out.append(PointForce(j, st[0], st[1] + 1.0, -0.5 * tau, 0.0))
                        out.append(PointForce(j, st[0], st[1] - 1.0, 0.5 * tau, 0.0))
        return out, tensions, dampers

    def history(self, states: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorized over states (n, n_bodies, 6): elongations [m], tendon tensions [N] and
        damper forces [N] (C dc/dt, + resisting opening), each (n, 2) for the left and right
        columns, by the same formulas as :meth:`elongations` and :meth:`forces`."""
        states = np.asarray(states, dtype=float)
        n = states.shape[0]
        el = np.zeros((n, 2))
        dmp = np.zeros((n, 2))

        def world(i, lx, ly):
            x, y, th = states[:, i, 0], states[:, i, 1], states[:, i, 2]
            c, s = np.cos(th), np.sin(th)
            return x + c * lx - s * ly, y + s * lx + c * ly

        for j, (idx, F, p_loc, q_loc, t_loc, _) in enumerate(self.columns):
            Px, Py = world(idx, *p_loc)
            Qx, Qy = world(idx, *q_loc)
            Tx, Ty = world(1, *t_loc)
            el[:, j] = np.hypot(Px - F[0], Py - F[1]) + np.hypot(Tx - Qx, Ty - Qy)
            th, w = states[:, idx, 2], states[:, idx, 5]
            sg = np.where(th >= 0.0, 1.0, -1.0)
            dmp[:, j] = self.c * 2.0 * self.b[idx] * np.cos(0.5 * th) * sg * w
        return el, self.k * el, dmp


def device_forces(scene: Scene, state: np.ndarray) -> list[PointForce]:
    """Tendon and damper point forces for the bodies' ``state`` (n_bodies, 6)."""
    if not scene.has_devices:
        return []
    return DeviceGeometry(scene, body_specs(scene)).forces(state)[0]


def net_wrenches(forces: list[PointForce], state: np.ndarray) -> np.ndarray:
    """(n_bodies, 3): the resultant force fx, fy [N] and moment about each body's centre of
    mass [N m] of ``forces`` for the bodies' ``state`` (n_bodies, 6). For engines that apply a
    force and a torque per body rather than forces at points."""
    pos = [(float(st[0]), float(st[1])) for st in state]
    out = [[0.0, 0.0, 0.0] for _ in pos]
    for f in forces:
        x, y = pos[f.body]
        w = out[f.body]
        w[0] += f.fx
        w[1] += f.fy
        w[2] += (f.px - x) * f.fy - (f.py - y) * f.fx
    return np.array(out)

"""The rocking frame as three free rigid bodies held by pin constraints: an independent
formulation (a KKT system over the bodies' poses, no mechanism derivatives) shared by the
analytic tests (test_reactions.py, test_vertical.py). SI units, radians."""

from __future__ import annotations

import math

import numpy as np

from rockbench.constants import G
from rockbench.scene.mechanism import mechanism


def _rot(th, v):
    c, s = math.cos(th), math.sin(th)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class ThreeBodies:
    """The frame as three free rigid bodies (x, y, theta each) held by 8 constraints: A and D
    fixed on the ground, B shared by the left column and the beam, C by the beam and the right
    column. Body-fixed offsets from each centre of mass to its pins are taken at rest."""

    def __init__(self, frame, s):
        self.frame, self.s = frame, s
        piv = frame.pivots(s)
        self.A, self.D = np.array(piv["A"]), np.array(piv["D"])
        g = [np.array(frame.com_left), np.array(frame.com_beam), np.array(frame.com_right)]
        P = {k: np.array(v) for k, v in piv.items()}
        # (point, body, sign): +1 the force lambda acts on the body, -1 its reaction
        self.pins = [("A", [(0, P["A"] - g[0], 1.0)]),
                     ("B", [(0, P["B"] - g[0], 1.0), (1, P["B"] - g[1], -1.0)]),
                     ("C", [(1, P["C"] - g[1], 1.0), (2, P["C"] - g[2], -1.0)]),
                     ("D", [(2, P["D"] - g[2], 1.0)])]
        self.ground = {"A": self.A, "D": self.D}
        self.m = np.array([frame.mass_left, frame.mass_beam, frame.mass_right])
        self.I = np.array([frame.inertia_left, frame.inertia_beam, frame.inertia_right])
        self.g0 = g

    def solve(self, q, qd, a_g, a_v, baumgarte=0.0, extra=None):
        """(q'' (9), {pin: lambda (2)}): M q'' = F + C^T lambda, C q'' = gamma. ``extra``: more
        generalized forces (9: fx, fy, moment about the centre of mass per body), e.g. the
        devices' (:func:`device_wrench`)."""
        Mm = np.diag(np.repeat(self.m, 3) * np.tile([1.0, 1.0, 0.0], 3)
                     + np.repeat(self.I, 3) * np.tile([0.0, 0.0, 1.0], 3))
        F = np.zeros(9)
        F[0::3], F[1::3] = -self.m * a_g, -self.m * (G + a_v)
        if extra is not None:
            F = F + extra
        C, gam = np.zeros((8, 9)), np.zeros(8)
        for j, (name, acting) in enumerate(self.pins):
            err, verr = np.zeros(2), np.zeros(2)
            for i, r0, sign in acting:
                th, w = q[3 * i + 2], qd[3 * i + 2]
                r = _rot(th, r0)
                C[2 * j:2 * j + 2, 3 * i:3 * i + 2] += sign * np.eye(2)
                C[2 * j:2 * j + 2, 3 * i + 2] += sign * np.array([-r[1], r[0]])
                gam[2 * j:2 * j + 2] += sign * w * w * r
                err += sign * (q[3 * i:3 * i + 2] + r)
                verr += sign * (qd[3 * i:3 * i + 2] + w * np.array([-r[1], r[0]]))
            if name in self.ground:
                err -= self.ground[name]
            gam[2 * j:2 * j + 2] -= 2 * baumgarte * verr + baumgarte**2 * err
        K = np.block([[Mm, -C.T], [C, np.zeros((8, 8))]])
        x = np.linalg.solve(K, np.concatenate([F, gam]))
        lam = {name: x[9 + 2 * j:11 + 2 * j] for j, (name, _) in enumerate(self.pins)}
        return x[:9], lam

    def state(self, phi, phidot):
        """q, q' of the mechanism's configuration at (phi, phi')."""
        cfg = mechanism(self.frame, self.s).configuration(phi)
        q = np.array([v for b in cfg.bodies for v in (b.x, b.y, b.theta)])
        qd = np.array([v for b in cfg.bodies for v in (b.dx, b.dy, b.dtheta)]) * phidot
        return q, qd


def device_wrench(scene, q, qd) -> np.ndarray:
    """The tendons' and dampers' generalized forces (9) on the three bodies at poses ``q`` and
    velocities ``qd``, from the engines' point forces (rockbench.engines.devices: computed from
    the poses, independently of the analytic model's K and D terms)."""
    from rockbench.engines.devices import device_forces, net_wrenches

    state = np.column_stack([q.reshape(3, 3), qd.reshape(3, 3)])
    return net_wrenches(device_forces(scene, state), state).reshape(9)

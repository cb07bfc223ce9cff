"""PyBullet (Bullet 3) backend: the 3-D engine kept in the plane by joint chains.

Mapping. rockbench's plane x-y is Bullet's x-z plane (Bullet's gravity acts along -z); the
out-of-plane axis is Bullet's y. Each rockbench body is one Bullet multibody with a fixed,
shapeless base at the world origin and a chain of three joints:

    base --prismatic x--> virtual link --prismatic z--> virtual link --revolute (0,-1,0)--> body

so the joint coordinates *are* the body's planar pose: q0 = x [m], q1 = y [m], q2 = theta [rad]
(the revolute axis points along -y, so a positive joint angle is counterclockwise in rockbench's
x-y plane), and the joint velocities are vx, vy [m/s] and omega [rad/s]. A free 6-dof body
does not stay planar in Bullet (``shared/notes/engines.md``); the chain does, exactly. The last
link carries the box collision shape and the body's TRUE mass and in-plane inertia from the
scene (the beam's is m rho^2, not the box's); its out-of-plane inertias are the box's (they never
act: the chain locks those rotations). The virtual links weigh ``virtual_mass_ratio`` times the
body's mass, sit at its centre of mass and so only scale its translational mass by
(1 + 2 ratio) (1e-6: far below every tolerance). The joints' default velocity motors are
disabled (VELOCITY_CONTROL, force 0), and so are Bullet's multibody linear/angular damping
(0.04 by default: they would dissipate energy) and joint damping.

Foundation: static boxes (ground, and the step under the right column), so that every contact
is box-box (Bullet's exact box-box detector, no rounded margins).

Contacts and friction. Bullet MULTIPLIES the two bodies' lateral friction coefficients (and
clamps the product at 10): the foundation, the columns and the beam get
:func:`~rockbench.engines.contacts.body_frictions` ("product": sqrt(mu) each when one
coefficient serves every pair), so that every base pair has exactly the base friction and the
beam on its columns the beam friction (:attr:`~rockbench.engines.base.EngineBackend.
friction_pairs`: the scene's, else ``settings.friction``). Restitution 0 on everything (also multiplied).
Friction anchors on. The contact breaking threshold, solver iterations, contact ERP and the
optional explicit contact stiffness/damping are settings (defaults measured: see
``docs/engines/pybullet.md``).

Ground motion: gravity (gravity_x, 0, gravity_y) set before every step (gravity_y = -(g + the
vertical ground acceleration)). Device forces (tendons,
dampers) from the shared machinery, applied with ``applyExternalForce(..., WORLD_FRAME)`` on
the body link before every step (Bullet clears external forces after each step).

Isolation: every run opens its own DIRECT physics client (``pybullet.connect(pybullet.DIRECT)``)
and passes its id to every call; ``_close`` disconnects it. Two runs in one process do not
share state, and a run is repeatable bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import ParameterError
from ._quiet import quiet_import
from .base import EngineBackend, EngineSettings
from .contacts import body_frictions
from .devices import DAMPER_MODELS, PointForce

__all__ = ["PybulletBackend", "PybulletSettings"]

#: The most solver iterations per step: Bullet's numSolverIterations is a C int (2^31 was an
#: OverflowError reported as "diverged") and every iteration is paid: 1e5 cost 4.7 s of CPU per
#: 0.3 s of a block's free rocking (measured).
MAX_ITERATIONS = 10_000

#: Bullet clamps the product of two friction coefficients at this value
#: (btManifoldResult::calculateCombinedFriction, MAX_FRICTION).
_BULLET_MAX_FRICTION = 10.0


@dataclass(frozen=True)
class PybulletSettings(EngineSettings):
    """PyBullet settings (see ``docs/engines/pybullet.md`` for the measurements behind them).

    friction : the Coulomb coefficient every contact pair gets when the scene gives no friction
        (each body gets its square root: Bullet multiplies the two, and clamps the product at
        10), in (0, 10]; default 2: from 0.6 up nothing slides more than 0.5 mm on the
        cross-engine cases, 2 keeps a factor of about 3 over the largest demand (as pymunk's
        default). A scene's ``[contact]`` friction replaces it (``docs/engines/README.md``).
    solver_iterations : constraint solver iterations per step (Bullet default 50), an integer in
        [1, :data:`MAX_ITERATIONS` = 1e4].
    contact_erp : error reduction parameter of contacts, in (0, 1]: the fraction of a contact's
        penetration removed per step (pybullet's own default, 0.08, measured best: 0.2 lets
        pivots slip 3.3 mm in an overturn, 0.5 and 0.8 19 and 46 mm). Used when
        ``contact_stiffness`` is 0.
    contact_stiffness, contact_damping : explicit contact stiffness [N/m] and damping [N s/m]
        (Bullet turns them into a per-contact ERP/CFM); 0 and 0 (the default) keep Bullet's
        rigid contact with ``contact_erp``. Both > 0 or both 0, each at most 1e15 (the range of
        OpenSees' toe stiffness).
    contact_breaking_threshold : distance [m] within which Bullet keeps (and creates) contact
        points (Bullet default 0.02 m biased the response; 1e-3 m), in (0, 0.05].
    friction_anchor : keep the friction anchor of persistent contact points, True, False or
        None (default: True when the scene gives no friction, False when it gives one). The
        anchor removes pivot creep of a rocking structure (off: peak 1.1 % off, slip 0.3 mm),
        but it is a position constraint to where a contact began: after a base has slid it
        drags the base back towards it (a squat block on mu = 0.3 under a Ricker pulse ended
        6.4 % short of Newmark's permanent slip with the anchor, 0.003 % without;
        ``docs/engines/README.md``). With a scene friction, sliding is the physics modelled.
    solver : constraint solver, "si" (Bullet's sequential impulse, its default). The only
        choice: Bullet's MLCP solvers were measured and rejected (LCP_PGS: NaN on the first
        step; LCP_DANTZIG: bit-identical results on these scenes, and it prints to stdout).
    split_impulse : Bullet's split impulse (penetration recovery kept out of the velocities),
        True, False or None (default: not set, Bullet's own choice).
    contact_slop : penetration [m] Bullet leaves uncorrected, >= 0 and < 0.01, or None
        (default: not set, Bullet's own).
    restitution : coefficient of restitution of every body [-], in [0, 1] (default 0: the
        analytic impact is plastic; a searchable contact parameter of ``rockbench advise``).
    virtual_mass_ratio : mass of each of the two virtual links of the planar joint chain as a
        fraction of the body's mass, in (0, 1e-3].
    damper : how the shared machinery applies the dampers' force (one of
        :data:`rockbench.engines.devices.DAMPER_MODELS`): "distributed" (default: forces in
        proportion to every body's momentum that dissipate exactly the damper's power and
        change no contact reaction), "couple" (a couple on each column) or "heel" (the force
        at the heel corner). With "couple" the right column's velocity chatters in Bullet's
        contact solver and the explicit 25 MN s/m damper amplifies it: the frame slides
        centimetres (docs/engines/pybullet.md).
    """

    solver_iterations: int = 50
    contact_erp: float = 0.08
    contact_stiffness: float = 0.0
    contact_damping: float = 0.0
    contact_breaking_threshold: float = 1e-3
    friction_anchor: bool | None = None
    solver: str = "si"
    virtual_mass_ratio: float = 1e-6
    damper: str = "distributed"
    friction: float = 2.0
    split_impulse: bool | None = None
    contact_slop: float | None = None
    restitution: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        it = self.solver_iterations
        if isinstance(it, bool) or not isinstance(it, (int, np.integer)) \
                or not 1 <= it <= MAX_ITERATIONS:
            raise ParameterError("solver_iterations", it,
                                 f"an integer in [1, {MAX_ITERATIONS}]")
        if not (isinstance(self.contact_erp, (int, float)) and 0.0 < self.contact_erp <= 1.0):
            raise ParameterError("contact_erp", self.contact_erp, "in (0, 1]")
        for nm in ("contact_stiffness", "contact_damping"):
            v = getattr(self, nm)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and 0.0 <= v <= 1e15):
                raise ParameterError(nm, v, "in [0, 1e15] (0 and 0: Bullet's rigid contact)")
        if (self.contact_stiffness > 0.0) != (self.contact_damping > 0.0):
            raise ParameterError("contact_damping", self.contact_damping,
                                 "> 0 when contact_stiffness > 0, and 0 when it is 0")
        cbt = self.contact_breaking_threshold
        if not (isinstance(cbt, (int, float)) and 0.0 < cbt <= 0.05):
            raise ParameterError("contact_breaking_threshold", cbt, "in (0, 0.05] m")
        if self.friction_anchor is not None \
                and not isinstance(self.friction_anchor, (bool, np.bool_)):
            raise ParameterError("friction_anchor", self.friction_anchor, "True, False or None")
        if self.solver not in _SOLVERS:
            raise ParameterError("solver", self.solver, f"one of {', '.join(_SOLVERS)}")
        vm = self.virtual_mass_ratio
        if not (isinstance(vm, (int, float)) and 0.0 < vm <= 1e-3):
            raise ParameterError("virtual_mass_ratio", vm, "in (0, 1e-3]")
        if self.damper not in DAMPER_MODELS:
            raise ParameterError("damper", self.damper, f"one of {', '.join(DAMPER_MODELS)}")
        if self.split_impulse is not None and not isinstance(self.split_impulse,
                                                             (bool, np.bool_)):
            raise ParameterError("split_impulse", self.split_impulse, "True, False or None")
        cs = self.contact_slop
        if cs is not None and not (isinstance(cs, (int, float)) and 0.0 <= cs < 0.01):
            raise ParameterError("contact_slop", cs, "None or in [0, 0.01) m")
        r = self.restitution
        if not (isinstance(r, (int, float)) and 0.0 <= r <= 1.0):
            raise ParameterError("restitution", r, "in [0, 1]")
        if self.friction > _BULLET_MAX_FRICTION:
            raise ParameterError("friction", self.friction,
                                 f"<= {_BULLET_MAX_FRICTION:g} (Bullet clamps the pair's product)")


#: settings.solver -> name of the pybullet constant (benchmarks/pybullet_settings.py adds the
#: rejected MLCP solvers to measure them)
_SOLVERS = {"si": "CONSTRAINT_SOLVER_LCP_SI"}


class PybulletBackend(EngineBackend):
    """The scene in PyBullet (DIRECT client per run, planar joint chains, box contacts)."""

    name: ClassVar[str] = "pybullet"
    Settings: ClassVar[type] = PybulletSettings
    #: The contact settings a search may try (rockbench advise --full; engines/base.py).
    contact_variants: ClassVar[tuple] = (
        {"contact_erp": 0.2}, {"contact_erp": 0.02}, {"solver_iterations": 150},
        {"contact_breaking_threshold": 1e-4}, {"split_impulse": False}, {"split_impulse": True},
        {"contact_slop": 1e-4}, {"restitution": 0.1})
    # a run's total_s is 1.7-3.8 x MuJoCo's and 1.9-3.6 x pymunk's on the four benchmark cases
    # (benchmarks/results/results.md, 2026-11-22); real-time factor 7-48, not ``fast``
    relative_cost: ClassVar[float] = 2.5

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        try:
            pybullet = quiet_import("pybullet")     # its build-time banner goes to /dev/null
        except Exception as e:  # pragma: no cover - depends on the machine
            return False, f"pybullet does not import: {e}"
        try:
            from importlib.metadata import version
            v = version("pybullet")
        except Exception:  # pragma: no cover - metadata missing
            v = "unknown"
        return True, f"pybullet {v} (Bullet API {pybullet.getAPIVersion()})"

    # --- building -----------------------------------------------------------------------------
    def _build(self) -> None:
        pb = quiet_import("pybullet")

        cfg = self.settings
        self._pb = pb
        self._cid = pb.connect(pb.DIRECT)
        if self._cid < 0:
            raise RuntimeError("pybullet could not open a DIRECT physics client")
        cid = self._cid
        pb.resetSimulation(physicsClientId=cid)
        pb.setPhysicsEngineParameter(
            fixedTimeStep=float(cfg.dt), numSubSteps=0,
            numSolverIterations=int(cfg.solver_iterations),
            contactERP=float(cfg.contact_erp),
            contactBreakingThreshold=float(cfg.contact_breaking_threshold),
            constraintSolverType=getattr(pb, _SOLVERS[cfg.solver]),
            deterministicOverlappingPairs=1,
            restitutionVelocityThreshold=0.0,
            physicsClientId=cid)
        extra = {}
        if cfg.split_impulse is not None:
            extra["useSplitImpulse"] = int(bool(cfg.split_impulse))
        if cfg.contact_slop is not None:
            extra["contactSlop"] = float(cfg.contact_slop)
        if extra:
            pb.setPhysicsEngineParameter(physicsClientId=cid, **extra)
        pb.setGravity(0.0, 0.0, -G, physicsClientId=cid)
        # Bullet multiplies the two coefficients of a pair: foundation, columns, beam
        mu, mu_c, mu_b = body_frictions(*self.friction_pairs, "product")
        self._anchor = (bool(cfg.friction_anchor) if cfg.friction_anchor is not None
                        else not self.scene.contact.given)

        # foundation: static boxes, top of the ground at z = 0
        fd = self.foundation
        depth = max(sp.depth for sp in self.specs)
        thick = 1.0
        boxes = [(0.5 * (fd.x_min + fd.x_max), 0.5 * (fd.x_max - fd.x_min), 0.0)]
        if fd.step_x0 is not None:
            boxes.append((0.5 * (fd.step_x0 + fd.step_x1), 0.5 * (fd.step_x1 - fd.step_x0),
                          fd.step_height))
        self._static = []
        for xc, hx, top in boxes:
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[hx, 2.0 * depth, thick],
                                            physicsClientId=cid)
            bid = pb.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                     basePosition=[xc, 0.0, top - thick],
                                     physicsClientId=cid)
            pb.changeDynamics(bid, -1, lateralFriction=mu, restitution=float(cfg.restitution),
                              spinningFriction=0.0, rollingFriction=0.0,
                              frictionAnchor=self._anchor,
                              contactProcessingThreshold=float(cfg.contact_breaking_threshold),
                              physicsClientId=cid)
            self._set_contact(bid, -1)
            self._static.append(bid)

        # bodies: fixed base, prismatic x, prismatic z, revolute about -y
        self._bodies = []
        frame = len(self.specs) == 3
        for i, (sp, pose) in enumerate(zip(self.specs, self.poses0)):
            self._bodies.append(self._make_body(sp, pose, mu_b if frame and i == 1 else mu_c))

    def _set_contact(self, bid: int, link: int) -> None:
        cfg = self.settings
        if cfg.contact_stiffness > 0.0:
            self._pb.changeDynamics(bid, link, contactStiffness=float(cfg.contact_stiffness),
                                    contactDamping=float(cfg.contact_damping),
                                    physicsClientId=self._cid)

    def _make_body(self, sp, pose, mu: float) -> int:
        """The planar joint chain of body ``sp`` at ``pose``, its box of lateral friction
        ``mu`` [-] (the body's coefficient: Bullet multiplies it with the other body's)."""
        pb, cid, cfg = self._pb, self._cid, self.settings
        hw, hh, hd = sp.half_width, sp.half_height, 0.5 * sp.depth
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[hw, hd, hh],
                                        physicsClientId=cid)
        m_v = cfg.virtual_mass_ratio * sp.mass
        i_v = cfg.virtual_mass_ratio * sp.inertia
        # out-of-plane inertias of the box (locked by the chain); in-plane: the scene's
        ixx = sp.mass * (hd ** 2 + hh ** 2) / 3.0
        izz = sp.mass * (hw ** 2 + hd ** 2) / 3.0
        bid = pb.createMultiBody(
            baseMass=0.0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=-1,
            basePosition=[0.0, 0.0, 0.0], baseOrientation=[0.0, 0.0, 0.0, 1.0],
            linkMasses=[m_v, m_v, sp.mass],
            linkCollisionShapeIndices=[-1, -1, shape],
            linkVisualShapeIndices=[-1, -1, -1],
            linkPositions=[[0.0, 0.0, 0.0]] * 3,
            linkOrientations=[[0.0, 0.0, 0.0, 1.0]] * 3,
            linkInertialFramePositions=[[0.0, 0.0, 0.0]] * 3,
            linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]] * 3,
            linkParentIndices=[0, 1, 2],
            linkJointTypes=[pb.JOINT_PRISMATIC, pb.JOINT_PRISMATIC, pb.JOINT_REVOLUTE],
            linkJointAxis=[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
            useMaximalCoordinates=False,
            physicsClientId=cid)
        if bid < 0:
            raise RuntimeError(f"pybullet could not create body {sp.name!r}")
        # mass= with localInertiaDiagonal= always (without it Bullet zeroes the mass)
        for link, (m, inertia) in enumerate(((m_v, (i_v, i_v, i_v)),
                                             (m_v, (i_v, i_v, i_v)),
                                             (sp.mass, (ixx, sp.inertia, izz)))):
            pb.changeDynamics(bid, link, mass=m, localInertiaDiagonal=list(inertia),
                              physicsClientId=cid)
        pb.changeDynamics(bid, -1, linearDamping=0.0, angularDamping=0.0,
                          physicsClientId=cid)
        for link in range(3):
            pb.changeDynamics(bid, link, jointDamping=0.0, lateralFriction=mu,
                              restitution=float(self.settings.restitution),
                              spinningFriction=0.0, rollingFriction=0.0,
                              frictionAnchor=self._anchor,
                              contactProcessingThreshold=float(cfg.contact_breaking_threshold),
                              physicsClientId=cid)
            pb.setJointMotorControl2(bid, link, pb.VELOCITY_CONTROL, targetVelocity=0.0,
                                     force=0.0, physicsClientId=cid)
        self._set_contact(bid, 2)
        for j, q in enumerate(pose):
            pb.resetJointState(bid, j, targetValue=float(q), targetVelocity=0.0,
                               physicsClientId=cid)
        return bid

    # --- stepping -----------------------------------------------------------------------------
    def _step(self, gravity_x: float, forces: list[PointForce], gravity_y: float = -G) -> None:
        pb, cid = self._pb, self._cid
        pb.setGravity(float(gravity_x), 0.0, float(gravity_y), physicsClientId=cid)
        for f in forces:
            pb.applyExternalForce(self._bodies[f.body], 2, [f.fx, 0.0, f.fy],
                                  [f.px, 0.0, f.py], pb.WORLD_FRAME, physicsClientId=cid)
        pb.stepSimulation(physicsClientId=cid)

    def _state(self) -> np.ndarray:
        pb, cid = self._pb, self._cid
        out = np.empty((len(self._bodies), 6))
        for i, bid in enumerate(self._bodies):
            js = pb.getJointStates(bid, (0, 1, 2), physicsClientId=cid)
            out[i, 0:3] = (js[0][0], js[1][0], js[2][0])
            out[i, 3:6] = (js[0][1], js[1][1], js[2][1])
        return out

    def _close(self) -> None:
        cid = getattr(self, "_cid", None)
        if cid is not None and cid >= 0:
            try:
                if self._pb.isConnected(physicsClientId=cid):
                    self._pb.disconnect(physicsClientId=cid)
            finally:
                self._cid = None
        self._bodies = []
        self._static = []

"""Drake backend: the planar scene in Drake's MultibodyPlant, with a discrete contact solver
(SAP, "similar", "lagged") at a fixed step, or Drake's error-controlled CENIC integrator.

Model (built from the scene alone)
----------------------------------
rockbench's plane x-y (y up) is Drake's x-y plane (gravity set to (0, -g, 0)); the
out-of-plane axis is Drake's z. Each body is a ``RigidBody`` with the scene's true mass and, about
z, the scene's in-plane moment of inertia (the beam's m rho^2, not the box's; the two
out-of-plane moments are set equal to it: the joint locks those rotations). Each body hangs from
the world on a ``PlanarJoint`` whose frames are the world frame and the body frame (at the
centre of mass), so the joint's positions *are* the body's pose (x, y [m], theta [rad],
counterclockwise positive, continuous) and its velocities (vx, vy, omega): nothing can leave
the plane, and phi needs no conversion.

Contacts (``contact_model``):

* ``"point"`` (default): compliant point contact between small spheres (radius
  ``corner_radius``) at the box corners that carry the rocking (a column pivots on its base
  corners; the beam on the columns' top corners) and the boxes they rest on (the ground, the
  step, the beam). Point contact between two faces would collapse to one point that jumps
  between steps; corner spheres give the two pivots their own contact each, as Drake's own
  examples do. A sphere's centre sits ``corner_radius`` inside the face it touches, level with
  the box's side, so the box rests exactly on its faces. Stiffness and dissipation are those of
  the *pair*: every geometry gets twice ``stiffness`` (Drake combines stiffnesses in series) and
  ``dissipation`` (combined as a stiffness-weighted mean, so equal values stay).
* ``"hydroelastic"``: compliant-hydroelastic boxes (modulus ``hydroelastic_modulus``) on rigid
  foundation boxes, the beam compliant too (measured in ``docs/engines/drake.md``).

Friction (static = dynamic): Drake combines two coefficients as 2 mu1 mu2 / (mu1 + mu2); the
foundation, the columns and the beam get :func:`~rockbench.engines.contacts.body_frictions`
("harmonic": mu each when one coefficient serves every pair), so that every base pair gets
exactly the base friction and the beam on its columns the beam friction
(:attr:`~rockbench.engines.base.EngineBackend.friction_pairs`: the scene's, else
``settings.friction``).

Solvers (``solver``):

* ``"sap"``, ``"similar"``, ``"lagged"``: a discrete plant (``time_step = dt``) with that
  ``DiscreteContactApproximation``; one ``_step`` is one discrete update. SAP models the
  contact's dissipation by a relaxation time (``relaxation_time``), the others by Hunt-Crossley
  dissipation (``dissipation`` [s/m]).
* ``"cenic"``: a continuous plant (``time_step = 0``) in a diagram with its SceneGraph,
  integrated by ``CenicIntegrator`` with error control at ``accuracy``; one ``_step`` advances
  the Simulator to the next multiple of ``dt``, which is then the interval at which the ground
  motion and device forces are updated (held constant across it, as in every engine) and the
  largest step CENIC may take. Its internal steps are counted in ``steps`` (cost).

Ground motion: the plant's gravity field cannot change in a Context (Drake 1.51's
``UniformGravityFieldElement`` is model data), so the ground motion enters as the generalized
force m_i u_g-inertia on each body's x dof (``gravity_x`` times the mass: exactly what a
horizontal gravity component does to a rigid body) and, with a vertical ground motion,
m_i (gravity_y + g) = -m_i u_v'' on its y dof (the plant's own gravity stays -g), through the
plant's applied generalized force input port, together with the device forces.

Devices: Drake has no tendon through four points (the scene's tendon tension acts on both its
segments), so tendons and dampers are the shared point forces of
:class:`~rockbench.engines.devices.DeviceGeometry` (damper model ``damper``), reduced to a force
and a moment about each body's centre of mass (:func:`~rockbench.engines.devices.net_wrenches`:
the planar joint's generalized forces). Fracture: the shared loop stops applying them.

See ``docs/engines/drake.md`` for the measurements behind the defaults.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import check_choice, check_range
from .base import EngineBackend, EngineSettings
from .contacts import body_frictions
from .devices import DAMPER_MODELS, PointForce, net_wrenches

__all__ = ["DrakeBackend", "DrakeSettings", "SOLVERS", "CONTACT_MODELS"]

#: settings.solver: Drake's discrete contact approximations, and the CENIC integrator.
SOLVERS = ("sap", "similar", "lagged", "cenic")
#: settings.contact_model
CONTACT_MODELS = ("point", "hydroelastic")


#: How far the beam's contact box reaches beyond each end of the beam [m] (see _build).
_BEAM_MARGIN = 0.02


@dataclass(frozen=True)
class DrakeSettings(EngineSettings):
    """Drake settings (``docs/engines/drake.md`` gives the measurements behind the defaults).

    solver : "cenic" (default: continuous plant, error-controlled CENIC integration at
        ``accuracy``), or a discrete plant at step ``dt`` with contact approximation "sap",
        "similar" or "lagged".
    accuracy : CENIC's target accuracy [-] (Drake's ``SimulatorConfig.accuracy``: the relative
        local error it keeps per step), in [1e-8, 1e-1]; used only by "cenic".
    dt : discrete step [s]; with "cenic", the interval at which ground motion and device forces
        are updated and the largest step CENIC takes.
    friction : (inherited) Coulomb coefficient of every contact pair when the scene gives no
        friction (default 1); a scene's ``[contact]`` friction replaces it
        (``docs/engines/README.md``).
    contact_model : "point" (corner spheres, default) or "hydroelastic".
    stiffness : point-contact stiffness of a contact pair [N/m], in [1e5, 1e13] (Drake's
        default 1e6 sinks a tonnes-heavy column by centimetres).
    dissipation : Hunt-Crossley dissipation of a pair [s/m], in [0, 1e3] ("similar", "lagged",
        "cenic" and hydroelastic contact); 50 s/m makes an impact effectively inelastic.
    relaxation_time : SAP's dissipation time scale [s], in [0, 1] ("sap" only).
    corner_radius : radius of the corner spheres [m], in [1e-6, 1e-2] (default 1e-5: a rounded
        corner lifts by r (1 - cos phi) as it rolls, which hides the contact's penetration from
        the shared contact probe when r is 1 mm).
    hydroelastic_modulus : of the compliant boxes [Pa], in [1e6, 1e14] ("hydroelastic" only).
    damper : how the shared damper forces reach the bodies (one of
        :data:`~rockbench.engines.devices.DAMPER_MODELS`; default "distributed").
    """

    solver: str = "cenic"
    accuracy: float = 1e-6
    contact_model: str = "point"
    stiffness: float = 1e12
    dissipation: float = 50.0
    relaxation_time: float = 1e-3
    corner_radius: float = 1e-5
    hydroelastic_modulus: float = 1e11
    damper: str = "distributed"

    def __post_init__(self) -> None:
        super().__post_init__()
        check_choice("solver", self.solver, SOLVERS)
        check_choice("contact_model", self.contact_model, CONTACT_MODELS)
        check_range("accuracy", self.accuracy, 1e-8, 1e-1)
        check_range("stiffness", self.stiffness, 1e5, 1e13)
        check_range("dissipation", self.dissipation, 0.0, 1e3)
        check_range("relaxation_time", self.relaxation_time, 0.0, 1.0)
        check_range("corner_radius", self.corner_radius, 1e-6, 1e-2)
        check_range("hydroelastic_modulus", self.hydroelastic_modulus, 1e6, 1e14)
        check_choice("damper", self.damper, DAMPER_MODELS)
        for name in ("accuracy", "stiffness", "dissipation", "relaxation_time", "corner_radius",
                     "hydroelastic_modulus"):
            object.__setattr__(self, name, float(getattr(self, name)))


class DrakeBackend(EngineBackend):
    """The scene in Drake (planar joints, corner-sphere point contact or hydroelastic boxes;
    discrete SAP / similar / lagged, or error-controlled CENIC)."""

    name: ClassVar[str] = "drake"
    package: ClassVar[str] = "drake"
    Settings: ClassVar[type] = DrakeSettings
    #: The contact settings a search may try (rockbench advise --full; engines/base.py).
    contact_variants: ClassVar[tuple] = (
        {"stiffness": 1e11}, {"stiffness": 1e13}, {"dissipation": 10.0}, {"dissipation": 200.0},
        {"relaxation_time": 1e-4})

    #: The work-precision curves (:func:`rockbench.studies.tradeoff.precision_sweeps`): CENIC's
    #: ``accuracy`` (its knob, not dt), coarse to fine, and a fixed-step solver's ``dt`` over
    #: the sweep's time steps.
    precision_sweeps: ClassVar[tuple] = (
        ("accuracy", (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7), {}),
        ("dt", None, {"solver": "similar"}),
    )

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        try:
            import pydrake  # noqa: F401
            from pydrake.multibody.cenic import CenicIntegrator  # noqa: F401
        except Exception as e:  # pragma: no cover - depends on the machine
            return False, f"pydrake does not import: {e}"
        try:
            from importlib.metadata import version
            v = version("drake")
        except Exception:  # pragma: no cover - metadata missing
            v = "unknown"
        return True, f"drake {v}"

    # --- building -----------------------------------------------------------------------------
    def _build(self) -> None:
        from pydrake.geometry import (AddCompliantHydroelasticProperties,
                                      AddContactMaterial, AddRigidHydroelasticProperties, Box,
                                      ProximityProperties, Sphere)
        from pydrake.math import RigidTransform
        from pydrake.multibody.plant import (AddMultibodyPlant, CoulombFriction,
                                             MultibodyPlantConfig)
        from pydrake.multibody.tree import PlanarJoint, SpatialInertia, UnitInertia
        from pydrake.systems.analysis import (ApplySimulatorConfig, Simulator,
                                              SimulatorConfig)
        from pydrake.systems.framework import DiagramBuilder

        cfg = self.settings
        cenic = cfg.solver == "cenic"
        hydro = cfg.contact_model == "hydroelastic"
        builder = DiagramBuilder()
        plant, _ = AddMultibodyPlant(MultibodyPlantConfig(
            time_step=0.0 if cenic else cfg.dt,
            discrete_contact_approximation="" if cenic else cfg.solver,
            contact_model="hydroelastic" if hydro else "point",
            adjacent_bodies_collision_filters=False), builder)
        plant.mutable_gravity_field().set_gravity_vector([0.0, -G, 0.0])
        # the bodies' coefficients: foundation, columns, beam (Drake combines them harmonically)
        mus = body_frictions(*self.friction_pairs, "harmonic")

        def props(compliant_box: float | None = None, rigid: bool = False, part: int = 1):
            p = ProximityProperties()
            # the pair's values: stiffnesses combine in series, dissipations as their mean
            AddContactMaterial(dissipation=cfg.dissipation, point_stiffness=2.0 * cfg.stiffness,
                               friction=CoulombFriction(mus[part], mus[part]), properties=p)
            if cfg.solver == "sap":
                p.AddProperty("material", "relaxation_time", cfg.relaxation_time)
            if hydro and rigid:
                AddRigidHydroelasticProperties(properties=p)
            elif hydro and compliant_box is not None:
                AddCompliantHydroelasticProperties(resolution_hint=compliant_box,
                                                   hydroelastic_modulus=cfg.hydroelastic_modulus,
                                                   properties=p)
            return p

        # foundation: static boxes whose tops are the ground (y = 0) and the step
        fd = self.foundation
        depth = max(sp.depth for sp in self.specs)
        thick = 1.0
        boxes = [(0.5 * (fd.x_min + fd.x_max), fd.x_max - fd.x_min, 0.0)]
        if fd.step_x0 is not None:
            boxes.append((0.5 * (fd.step_x0 + fd.step_x1), fd.step_x1 - fd.step_x0,
                          fd.step_height))
        world = plant.world_body()
        for i, (xc, width, top) in enumerate(boxes):
            plant.RegisterCollisionGeometry(
                world, RigidTransform([xc, top - 0.5 * thick, 0.0]),
                Box(width, thick, 2.0 * depth), f"foundation{i}", props(rigid=True, part=0))

        r = cfg.corner_radius
        frame = len(self.specs) == 3
        self._bodies, self._joints = [], []
        for j, sp in enumerate(self.specs):
            part = 2 if frame and j == 1 else 1
            i_unit = sp.inertia / sp.mass
            body = plant.AddRigidBody(sp.name, SpatialInertia(
                sp.mass, [0.0, 0.0, 0.0], UnitInertia(i_unit, i_unit, i_unit)))
            hw, hh = sp.half_width, sp.half_height
            is_beam = frame and j == 1
            if hydro:
                plant.RegisterCollisionGeometry(
                    body, RigidTransform(), Box(2 * hw, 2 * hh, sp.depth), f"{sp.name}_box",
                    props(compliant_box=min(hw, hh), part=part))
            elif is_beam:
                # the beam's contact box overhangs its body by _BEAM_MARGIN at each end (its
                # mass and inertia are the body's): Drake resolves a sphere against a box poorly
                # within a few mm of the box's edge, and a beam that ends flush with the columns
                # (beam_width = span + column_width, the smallest the scene allows) puts the
                # column's top corner exactly there (0.13 m of penetration; 0.09 mm with a 1 cm
                # overhang, measured on a squat frame)
                plant.RegisterCollisionGeometry(
                    body, RigidTransform(), Box(2 * hw + 2 * _BEAM_MARGIN, 2 * hh, sp.depth),
                    f"{sp.name}_box", props(part=2))
            if not hydro and not is_beam:
                ys = [-hh + r] + ([hh - r] if frame else [])
                for y in ys:
                    for x in (-hw, hw):
                        plant.RegisterCollisionGeometry(
                            body, RigidTransform([x, y, 0.0]), Sphere(r),
                            f"{sp.name}_{'top' if y > 0 else 'base'}_{'r' if x > 0 else 'l'}",
                            props())
            joint = plant.AddJoint(PlanarJoint(f"{sp.name}_planar", plant.world_frame(),
                                               body.body_frame()))
            self._bodies.append(body)
            self._joints.append(joint)
        plant.Finalize()
        self._diagram = builder.Build()
        self._sim = Simulator(self._diagram)
        self._plant = plant
        ctx = self._sim.get_mutable_context()
        self._ctx = plant.GetMyMutableContextFromRoot(ctx)
        nv = plant.num_velocities()
        # index maps: state row (x, y, theta) of each body from q and v
        self._qi = np.array([[jt.position_start() + k for k in range(3)] for jt in self._joints])
        self._vi = np.array([[jt.velocity_start() + k for k in range(3)] for jt in self._joints])
        self._mass = np.array([sp.mass for sp in self.specs])
        self._nq = plant.num_positions()
        q = np.zeros(self._nq)
        for i, pose in enumerate(self.poses0):
            q[self._qi[i]] = pose
        plant.SetPositions(self._ctx, q)
        plant.SetVelocities(self._ctx, np.zeros(nv))
        self._tau = np.zeros(nv)
        self._fixed = plant.get_applied_generalized_force_input_port().FixValue(
            self._ctx, self._tau)
        self._k = 0
        if cenic:
            ApplySimulatorConfig(SimulatorConfig(
                integration_scheme="cenic", accuracy=cfg.accuracy, use_error_control=True,
                max_step_size=cfg.dt, publish_every_time_step=False), self._sim)
            self._sim.Initialize()
            self._integrator = self._sim.get_integrator()
            self._internal = 0
        else:
            # a discrete plant advances by one (unrestricted) update per period dt
            self._sim.Initialize()
            self._integrator = None

    # --- stepping -----------------------------------------------------------------------------
    def _step(self, gravity_x: float, forces: list[PointForce], gravity_y: float = -G) -> None:
        tau = self._tau
        tau[:] = 0.0
        vi = self._vi
        if gravity_x != 0.0:
            tau[vi[:, 0]] = self._mass * gravity_x
        if gravity_y != -G:             # the vertical ground motion, beyond the plant's -g
            tau[vi[:, 1]] = self._mass * (gravity_y + G)
        if forces:
            w = net_wrenches(forces, self._state())
            tau[vi] += w
        self._fixed.GetMutableData().get_mutable_value().SetFromVector(tau)
        self._k += 1
        self._sim.AdvanceTo(self._k * self.settings.dt)
        if self._integrator is not None:
            n = self._integrator.get_num_steps_taken()
            # the loop counts one step per call (``steps``, the cost): count CENIC's internal
            # steps instead
            self.steps = getattr(self, "steps", 0) + n - self._internal - 1
            self._internal = n

    def _state(self) -> np.ndarray:
        x = self._plant.GetPositionsAndVelocities(self._ctx)
        out = np.empty((len(self._bodies), 6))
        out[:, 0:3] = x[self._qi]
        out[:, 3:6] = x[self._nq + self._vi]
        return out

    def _close(self) -> None:
        self._sim = self._diagram = self._plant = self._ctx = self._fixed = None
        self._integrator = None

"""MuJoCo backend: the planar scene in a 3-D engine, kept in the plane by joints.

Model (generated MJCF, from the scene alone)
--------------------------------------------
rockbench's plane x-y (y up) is MuJoCo's x-z plane (z up). Each body of the scene is one MuJoCo
body whose frame sits at the body's rest centre of mass, with three joints: ``slide x``,
``slide z`` and a ``hinge`` about the axis (0, -1, 0). With that axis a positive hinge angle
turns +x towards +z, i.e. counterclockwise in rockbench's x-y plane, so the hinge angle *is*
rockbench's theta (phi for the left column), with no sign flip. ``qpos`` of a body is
(x - x_rest, y - y_rest, theta) and ``qvel`` is (vx, vy, omega).

Masses and inertias are set explicitly (``<inertial>``): the moment about MuJoCo's y axis is the
scene's in-plane moment (for the beam m rho^2, not the box's); the two out-of-plane moments are
the box's, raised only where MuJoCo's triangle inequality needs it. They never enter the
dynamics: the joints allow no out-of-plane motion.

Contacts are explicit ``<pair>`` elements (automatic collisions are off, so the columns never
touch each other or the step they do not stand on): block/column bases on the ground plane (the
right column on the step box of the asymmetric frame) and both column tops against the beam.
Each pair gets exactly its coefficient (explicit pairs bypass MuJoCo's max-combination rule):
base pairs the base friction, the column tops against the beam the beam friction
(:attr:`~rockbench.engines.base.EngineBackend.friction_pairs`: the scene's, else
``settings.friction``), condim 3, and the contact softness of the settings; no restitution (MuJoCo contacts bounce
only when ``solref`` is under-damped; the default is over-damped).

Devices (``devices="native"``, the default)
-------------------------------------------
Tendon j is a spatial tendon through four sites: foundation anchor F (rest position of the column
base centre) -> column base centre P -> column top centre Q -> beam anchor T (rest position of Q,
fixed to the beam), with stiffness k and spring length |PQ| = 2H: its length minus 2H is exactly
the base opening |PF| plus the top opening |QT| of the scene model. At rest the segments FP and QT
have zero length; MuJoCo's direction is then arbitrary but the tension k (L - 2H) is zero, and
the generalized forces equal the shared model's at every rotation (tested).

Dampers (``damper``): the scene model's damper dissipates C (dc_j/dt)^2, c_j the chord of the
heel of column j for its rotation about the pivot. Three ways to apply it, measured in
``docs/engines/mujoco.md``:

* ``"distributed"`` (default, the shared model's name): damping on every joint in proportion to
  the body's inertia (m, m, I) at the rate C sum_j (dc_j/dt)^2 / (2 x kinetic energy), updated
  every step. It dissipates exactly the damper's power, and because the force is proportional to
  momentum it changes no contact reaction of the rocking mechanism (a force field M a' with a'
  along the mechanism's velocity needs no constraint force). MuJoCo integrates joint damping
  implicitly.
* ``"couple"``: damping C (dc_j/dtheta_j)^2 on the column's hinge, a pure couple.
* ``"heel"``: a spatial tendon from each base corner to a world site at its rest position, the
  heel's tendon damped with C -- the literal device. It pushes the heel with C dc/dt, up to
  4 MN on closing, more than the dead load on the pivot (about 1 MN), and lifts the column.

The couple also needs pivot reactions the contacts cannot give (the columns slip 2-3 cm just
after impacts); only the distributed form reproduces the model, whose pivots are bilateral.
``devices="forces"`` uses the shared point forces of ``DeviceGeometry`` instead (the same three
damper models, applied explicitly as forces). Fracture switches every device off.

See ``docs/engines/mujoco.md`` for the measurements behind every default.
"""

from __future__ import annotations

import functools

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_choice, check_finite, check_int, check_range
from .base import EngineBackend, EngineSettings
from .devices import DAMPER_MODELS, PointForce

__all__ = ["MujocoBackend", "MujocoSettings"]

_INTEGRATORS = {"euler": "Euler", "implicitfast": "implicitfast", "implicit": "implicit",
                "rk4": "RK4"}
_CONES = ("elliptic", "pyramidal")
#: MuJoCo's constants (mjmodel.h, mjtype.h): the smallest friction coefficient, the impedance
#: range solimp is clamped to, and the smallest mass or inertia of a moving body.
MJ_MINMU, MJ_MINIMP, MJ_MAXIMP, MJ_MINVAL = 1e-5, 1e-4, 0.9999, 1e-15
#: The most solver (and noslip) iterations per step: MuJoCo's counters are C ints (1e12 was an
#: "XML Error: number is too large" reported as "diverged"), and iterations are paid while the
#: tolerance is not met: 1e5 cost 7.2 s of CPU per 0.3 s of a block's free rocking (measured).
MAX_ITERATIONS = 10_000
_DEVICE_MODES = ("native", "forces")


@dataclass(frozen=True)
class MujocoSettings(EngineSettings):
    """MuJoCo settings (``docs/engines/mujoco.md`` gives the measurements behind the defaults).

    dt : time step [s] (default 1e-3).
    contact_timeconst : contact time constant [s] (``solref[0]``, with MuJoCo's ``refsafe``
        off), or None (default) for 2 dt, the stiffest contact the step resolves; the engine then
        converges to the rigid-contact reference as dt shrinks. MuJoCo's default 0.02 s is far
        too soft for tonnes-scale rocking. Values below 2 dt are refused: at 1 dt the contacts
        diverge (centimetres of penetration or slip within a second).
    contact_dampratio : contact damping ratio [-] (``solref[1]``), in [0.1, 10] (default 2:
        over-damped; at 1, critical, a violent impact can make the beam hop off a top pivot for
        a few milliseconds and the pivots slip 3 mm; at 0.5 the contacts bounce).
    impedance : solimp dmin = dmax [-], in [mjMINIMP, mjMAXIMP] = [1e-4, 0.9999] (MuJoCo clamps
        anything outside): the share of the contact's constraint force that is not regularized
        away (MuJoCo's default 0.9-0.95 lets the pivots creep). A scene that slides needs 0.999:
        at 0.99 friction is regularized enough that a squat block (b/h = 1) on mu = 0.8 tips
        and slides 23 % short of Newmark's sliding block, 3.3 % too far on mu = 0.2; at 0.999
        within 0.4 % (``docs/engines/README.md``).
    integrator : "implicitfast" (default), "euler", "implicit" or "rk4".
    cone : friction cone, "elliptic" (default) or "pyramidal" (MuJoCo's default).
    impratio : frictional-to-normal constraint impedance ratio [-], in [0.1, 100] (default 3;
        MuJoCo's 1 lets pivots creep during impacts: peaks up to 2 % high on some pulses).
    noslip_iterations : iterations of MuJoCo's post-solve "noslip" pass (0: off), an integer
        in [0, :data:`MAX_ITERATIONS` = 1e4].
    iterations : constraint solver (Newton) iterations per step, an integer in [1, 1e4].
    tolerance : solver tolerance [-] (relative improvement at which the solver stops), in
        [0, 1e-3] (at 1e300 the solver stops at once and the energy of a free-rocking block grew
        5000 % in 2 ms, measured).
    friction : as every engine's (used when the scene gives no friction; default 1), and
        >= mjMINMU = 1e-5 (MuJoCo clamps smaller values). A scene's ``[contact]`` friction
        replaces it (``docs/engines/README.md``).
    devices : "native" (default: MuJoCo tendons and joint damping) or "forces" (the shared
        point forces computed from the poses).
    damper : damper model, "distributed" (default), "couple" or "heel" (see the module and
        :class:`rockbench.engines.devices.DeviceGeometry`).
    loop : "compiled" (default: the stepping loop runs in numba and calls ``mj_step`` in
        MuJoCo's library, :mod:`rockbench.engines.compiled_loop`, where :func:`compiled_available`
        says it can) or "python" (the plain loop it is tested against).
    """

    dt: float = 1e-3
    contact_timeconst: float | None = None
    contact_dampratio: float = 2.0
    impedance: float = 0.99
    integrator: str = "implicitfast"
    cone: str = "elliptic"
    impratio: float = 3.0
    noslip_iterations: int = 0
    iterations: int = 100
    tolerance: float = 1e-10
    devices: str = "native"
    damper: str = "distributed"
    loop: str = "compiled"

    #: the smallest contact time constant allowed, in time steps (measured: 2 is stable,
    #: 1.5 slips millimetres, 1 diverges)
    min_timeconst_steps: ClassVar[float] = 2.0

    @property
    def timeconst(self) -> float:
        """The contact time constant in use [s]."""
        if self.contact_timeconst is None:
            return self.min_timeconst_steps * self.dt
        return float(self.contact_timeconst)

    def __post_init__(self) -> None:
        super().__post_init__()
        lo = self.min_timeconst_steps * self.dt
        if self.contact_timeconst is not None:
            tc = check_finite("contact_timeconst", self.contact_timeconst)
            if not lo * (1 - 1e-9) <= tc <= 1.0:
                raise ParameterError("contact_timeconst", self.contact_timeconst,
                                     f"None or in [{self.min_timeconst_steps:g} dt = {lo:g}, 1] s",
                                     "a contact stiffer than the time step resolves diverges")
        check_range("contact_dampratio", self.contact_dampratio, 0.1, 10.0)
        # MuJoCo clamps solimp to [mjMINIMP, mjMAXIMP] and friction to >= mjMINMU silently:
        # a value outside would not be the value used
        check_range("impedance", self.impedance, MJ_MINIMP, MJ_MAXIMP)
        if self.friction < MJ_MINMU:
            raise ParameterError("friction", self.friction,
                                 f">= mjMINMU = {MJ_MINMU:g} (MuJoCo's smallest friction)")
        check_choice("integrator", self.integrator, tuple(_INTEGRATORS))
        check_choice("cone", self.cone, _CONES)
        check_range("impratio", self.impratio, 0.1, 100.0)
        check_int("noslip_iterations", self.noslip_iterations, 0, MAX_ITERATIONS)
        check_int("iterations", self.iterations, 1, MAX_ITERATIONS)
        check_range("tolerance", self.tolerance, 0.0, 1e-3)
        check_choice("devices", self.devices, _DEVICE_MODES)
        check_choice("damper", self.damper, DAMPER_MODELS)
        check_choice("loop", self.loop, ("compiled", "python"))


def _f(x: float) -> str:
    return repr(float(x))


def _vec(*xs: float) -> str:
    return " ".join(_f(x) for x in xs)


def _inertia(sp) -> tuple[float, float, float]:
    """Diagonal inertia (Ixx, Iyy, Izz) [kg m^2] of a body in MuJoCo axes: Iyy is the scene's
    in-plane moment; Ixx, Izz the box's, raised where needed for the triangle inequality."""
    m = sp.mass
    hx, hy, hz = sp.half_width, 0.5 * sp.depth, sp.half_height
    ixx = m * (hy * hy + hz * hz) / 3.0
    izz = m * (hx * hx + hy * hy) / 3.0
    iyy = sp.inertia
    if ixx + izz < iyy:
        s = iyy / (ixx + izz)
        ixx, izz = ixx * s, izz * s
    ixx = max(ixx, abs(izz - iyy))
    izz = max(izz, abs(ixx - iyy))
    return ixx, iyy, izz


class MujocoBackend(EngineBackend):
    """The scene in MuJoCo (planar joints, box contacts, native tendons and dampers)."""

    name: ClassVar[str] = "mujoco"
    Settings: ClassVar[type] = MujocoSettings
    #: The contact settings a search may try (rockbench advise --full; engines/base.py).
    contact_variants: ClassVar[tuple] = (
        {"contact_dampratio": 1.0}, {"contact_dampratio": 4.0}, {"impedance": 0.95},
        {"impedance": 0.999}, {"impratio": 1.0}, {"impratio": 10.0}, {"noslip_iterations": 10})
    batched: ClassVar[bool] = True  # mujoco.rollout: rockbench.engines.mujoco_batch
    fast: ClassVar[bool] = True     # real-time factor 51-164 (benchmarks/results/results.md)

    @classmethod
    def batch_refusal(cls, scene, settings) -> str | None:
        """Why :meth:`run_batch` cannot run ``scene`` with ``settings`` (None: it can); see
        :func:`rockbench.engines.mujoco_batch.batch_refusal`."""
        from .mujoco_batch import batch_refusal

        return batch_refusal(scene, settings)

    @classmethod
    def run_batch(cls, scene, motions, **kwargs) -> list:
        """Many ground motions of ``scene`` in ``mujoco.rollout``:
        :func:`rockbench.engines.mujoco_batch.run_batch`."""
        from .mujoco_batch import run_batch

        return run_batch(scene, motions, **kwargs)

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        try:
            import mujoco
        except Exception as e:  # pragma: no cover - depends on the machine
            return False, f"mujoco does not import: {e}"
        return True, f"mujoco {mujoco.__version__}"

    # --- the model ------------------------------------------------------------------------
    def compile(self, phi0: float = 0.0):
        """Build the model and data of the scene at rotation ``phi0`` [rad] outside a run (for
        inspection and tests); returns the ``mujoco.MjModel`` (``self.data`` is its data)."""
        self.build(phi0)
        return self.model

    def _native(self) -> bool:
        return self.scene.has_devices and self.native_devices and len(self.specs) == 3

    def mjcf(self) -> str:
        """The MJCF text of the scene (needs ``self.specs`` and ``self.foundation``, set by
        ``run`` or :meth:`compile`)."""
        cfg = self.settings
        fd = self.foundation
        specs = self.specs
        frame = len(specs) == 3
        dev = self._native()
        dv = self.scene.devices
        heel = dev and dv.has_dampers and cfg.damper == "heel"
        depth = max(sp.depth for sp in specs)
        out = ['<mujoco model="rockbench">',
               '  <compiler angle="radian" inertiafromgeom="false"/>',
               f'  <option timestep="{_f(cfg.dt)}" gravity="0 0 {_f(-G)}" '
               f'integrator="{_INTEGRATORS[cfg.integrator]}" cone="{cfg.cone}" '
               f'iterations="{int(cfg.iterations)}" tolerance="{_f(cfg.tolerance)}" '
               f'impratio="{_f(cfg.impratio)}" noslip_iterations="{int(cfg.noslip_iterations)}">',
               '    <flag refsafe="disable"/>',
               '  </option>',
               '  <default><geom contype="0" conaffinity="0"/></default>',
               '  <worldbody>',
               '    <geom name="ground" type="plane" size="0 0 1"/>']
        if fd.step_x0 is not None:
            hx, hz = 0.5 * (fd.step_x1 - fd.step_x0), 0.5 * fd.step_height
            out.append(f'    <geom name="step" type="box" size="{_vec(hx, depth, hz)}" '
                       f'pos="{_vec(0.5 * (fd.step_x0 + fd.step_x1), 0.0, hz)}"/>')
        columns = ((0, specs[0]), (1, specs[2])) if frame else ()
        for j, sp in columns if dev else ():
            base = sp.y - sp.half_height
            out.append(f'    <site name="F{j}" pos="{_vec(sp.x, 0.0, base)}"/>')
            if heel:
                for side, sx in (("l", -1.0), ("r", 1.0)):
                    out.append(f'    <site name="R{j}{side}" '
                               f'pos="{_vec(sp.x + sx * sp.half_width, 0.0, base)}"/>')
        for i, sp in enumerate(specs):
            ixx, iyy, izz = _inertia(sp)
            out += [f'    <body name="{sp.name}" pos="{_vec(sp.x, 0.0, sp.y)}">',
                    f'      <joint name="{sp.name}_x" type="slide" axis="1 0 0"/>',
                    f'      <joint name="{sp.name}_z" type="slide" axis="0 0 1"/>',
                    f'      <joint name="{sp.name}_th" type="hinge" axis="0 -1 0"/>',
                    f'      <inertial pos="0 0 0" mass="{_f(sp.mass)}" '
                    f'diaginertia="{_vec(ixx, iyy, izz)}"/>',
                    f'      <geom name="{sp.name}" type="box" '
                    f'size="{_vec(sp.half_width, 0.5 * sp.depth, sp.half_height)}"/>']
            if dev and i != 1:
                j = 0 if i == 0 else 1
                out.append(f'      <site name="P{j}" pos="{_vec(0.0, 0.0, -sp.half_height)}"/>')
                out.append(f'      <site name="Q{j}" pos="{_vec(0.0, 0.0, sp.half_height)}"/>')
                if heel:
                    for side, sx in (("l", -1.0), ("r", 1.0)):
                        out.append(f'      <site name="C{j}{side}" pos="'
                                   f'{_vec(sx * sp.half_width, 0.0, -sp.half_height)}"/>')
            if dev and i == 1:
                for j, c in columns:
                    out.append(f'      <site name="T{j}" pos="'
                               f'{_vec(c.x - sp.x, 0.0, c.y + c.half_height - sp.y)}"/>')
            out.append('    </body>')
        out.append('  </worldbody>')
        mu_base, mu_beam = self.friction_pairs
        if mu_beam < MJ_MINMU:       # (the base friction is the settings', checked there)
            raise ParameterError("contact.beam_friction", mu_beam,
                                 f">= mjMINMU = {MJ_MINMU:g} for mujoco (its smallest friction)")
        if frame:
            pairs = [("left", "ground", mu_base),
                     ("right", "step" if fd.step_x0 is not None else "ground", mu_base),
                     ("left", "beam", mu_beam), ("right", "beam", mu_beam)]
        else:
            pairs = [(specs[0].name, "ground", mu_base)]
        d = cfg.impedance
        out.append('  <contact>')
        for a, b, mu in pairs:
            out.append(f'    <pair geom1="{a}" geom2="{b}" condim="3" '
                       f'friction="{_vec(mu, mu, 0.005, 1e-4, 1e-4)}" '
                       f'solref="{_vec(cfg.timeconst, cfg.contact_dampratio)}" '
                       f'solimp="{_vec(d, d, 0.001, 0.5, 2.0)}"/>')
        out.append('  </contact>')
        if dev and (dv.has_tendons or heel):
            out.append('  <tendon>')
            for j, sp in columns:
                if dv.has_tendons:
                    out += [f'    <spatial name="tendon{j}" stiffness="{_f(dv.tendon_stiffness)}" '
                            f'springlength="{_f(2.0 * sp.half_height)}">',
                            f'      <site site="F{j}"/><site site="P{j}"/><site site="Q{j}"/>'
                            f'<site site="T{j}"/>',
                            '    </spatial>']
                if heel:
                    for side in ("l", "r"):
                        out += [f'    <spatial name="damper{j}{side}" damping="0">',
                                f'      <site site="C{j}{side}"/><site site="R{j}{side}"/>',
                                '    </spatial>']
            out.append('  </tendon>')
        out.append('</mujoco>')
        return "\n".join(out)

    def _build(self) -> None:
        import mujoco

        self._mj = mujoco
        self.model = m = mujoco.MjModel.from_xml_string(self.mjcf())
        self.data = mujoco.MjData(m)
        n = len(self.specs)
        self._rest = np.array([[sp.x, sp.y] for sp in self.specs])
        q = np.zeros(3 * n)
        for i, pose in enumerate(self.poses0):
            q[3 * i:3 * i + 3] = (pose[0] - self._rest[i, 0], pose[1] - self._rest[i, 1], pose[2])
        self.data.qpos[:] = q
        self.data.qvel[:] = 0.0
        # native devices: (tendon id, spring length), damped columns (hinge dof, b, heel ids)
        self._tendons: list[tuple[int, float]] = []
        self._damped: list[tuple[int, float, tuple[int, int] | None]] = []
        self._c = 0.0
        self._massvec = np.array([[sp.mass, sp.mass, sp.inertia] for sp in self.specs]).ravel()
        if self._native():
            dv = self.scene.devices
            tid = lambda nm: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, nm)  # noqa: E731
            for j, idx in enumerate((0, 2)):
                if dv.has_tendons:
                    t = tid(f"tendon{j}")
                    self._tendons.append((t, float(m.tendon_lengthspring[t][0])))
                if dv.has_dampers:
                    heel = (tid(f"damper{j}l"), tid(f"damper{j}r")) \
                        if self.settings.damper == "heel" else None
                    self._damped.append((3 * idx + 2, self.specs[idx].half_width, heel))
            self._c = float(dv.damping)
        mujoco.mj_forward(m, self.data)
        # views kept once (MjData's attribute access builds a new array wrapper every call)
        n = len(self.specs)
        self._q3 = self.data.qpos.reshape(n, 3)
        self._v3 = self.data.qvel.reshape(n, 3)
        self._gravity = m.opt.gravity
        if self._damped:
            self._set_dampers()

    def _set_dampers(self) -> None:
        """Set the native dampers' damping for the current state (``settings.damper``)."""
        d, m = self.data, self.model
        q, v = d.qpos, d.qvel
        if self.settings.damper == "distributed":
            power = 0.0                                       # C sum_j (dc_j/dt)^2 [W]
            for dof, b, _ in self._damped:
                rate = 2.0 * b * math.cos(0.5 * q[dof]) * v[dof]
                power += self._c * rate * rate
            ke2 = float(np.dot(self._massvec, v * v))         # 2 x kinetic energy [J]
            # [1/s]; <= C (2b)^2 / min I_column since ke2 >= sum_j I_column_j omega_j^2
            m.dof_damping[:] = (power / ke2 if ke2 > 0.0 else 0.0) * self._massvec
            return
        for dof, b, heel in self._damped:
            th = q[dof]
            if heel is None:                                   # couple: C (dc/dtheta)^2
                dcd = 2.0 * b * math.cos(0.5 * th)
                m.dof_damping[dof] = self._c * dcd * dcd
            else:                                              # heel: right corner if th >= 0
                on, off = (heel[1], heel[0]) if th >= 0.0 else (heel[0], heel[1])
                m.tendon_damping[on] = self._c
                m.tendon_damping[off] = 0.0

    def _native_device_report(self, devices, state, elongations):
        """Tension k (length - 2H) [N] of each MuJoCo tendon, which is k times the shared
        ``elongations`` (tested), and the damper force C dc/dt [N] of the scene model, in the
        sampled ``state``."""
        ten = [devices.k * e for e in elongations] if self._tendons else [0.0, 0.0]
        damp = [0.0, 0.0]
        if self._damped:
            damp = [self._c * 2.0 * b * math.cos(0.5 * state[dof // 3][2])
                    * math.copysign(1.0, state[dof // 3][2]) * state[dof // 3][5]
                    for dof, b, _ in self._damped]
        return ten, damp

    def _remove_devices(self) -> None:
        self.model.tendon_stiffness[:] = 0.0
        self.model.tendon_damping[:] = 0.0
        self.model.dof_damping[:] = 0.0
        self._damped = []
        self._tendons = []

    def _compiled_loop(self):
        if self.settings.loop != "compiled" or not compiled_available()[0]:
            return None
        from .compiled_loop import MUJOCO, empty_engine, run_kernel

        m, d = self.model, self.data
        eng = list(empty_engine())
        eng[0] = np.array([_mj_step_address()], dtype=np.uint64)
        eng[1] = np.array([m._address, d._address], dtype=np.uint64)
        eng[3], eng[4], eng[5], eng[6] = d.qpos, d.qvel, m.opt.gravity, d.qfrc_applied
        eng[7] = np.ascontiguousarray(self._rest, dtype=float)
        flags = np.zeros(4)
        if self._native():
            flags[:3] = 1.0, self._c, DAMPER_MODELS.index(self.settings.damper)
            eng[8] = np.array([[dof, b, *(heel or (-1, -1))] for dof, b, heel in self._damped],
                              dtype=float).reshape(-1, 4)
            eng[9] = self._massvec
            eng[10], eng[11] = m.tendon_stiffness.reshape(-1), m.tendon_damping.reshape(-1)
            eng[12] = m.dof_damping.reshape(-1)
        eng[13] = flags
        eng = tuple(eng)

        def loop(*args):
            return run_kernel(MUJOCO, eng, *args)
        return loop

    def _step(self, gravity_x: float, forces: list[PointForce], gravity_y: float = -G) -> None:
        m, d = self.model, self.data
        self._gravity[0] = gravity_x
        self._gravity[2] = gravity_y
        if self._damped:
            self._set_dampers()
        if not forces:
            self._mj.mj_step(m, d)
            return
        # planar generalized forces on (slide x, slide z, hinge): the hinge's anchor is the
        # centre of mass, so its generalized force is the counterclockwise moment about it
        qf, q = d.qfrc_applied, d.qpos
        qf[:] = 0.0
        for f in forces:
            i = 3 * f.body
            rx = f.px - (self._rest[f.body, 0] + q[i])
            ry = f.py - (self._rest[f.body, 1] + q[i + 1])
            qf[i] += f.fx
            qf[i + 1] += f.fy
            qf[i + 2] += rx * f.fy - ry * f.fx
        self._mj.mj_step(m, d)
        qf[:] = 0.0

    def _state(self) -> np.ndarray:
        q = self._q3
        out = np.empty((q.shape[0], 6))
        out[:, 0:2] = self._rest + q[:, 0:2]
        out[:, 2] = q[:, 2]
        out[:, 3:6] = self._v3
        return out

    def _close(self) -> None:
        self.data = None


# ------------------------------------------------------------------------------------------
# The compiled stepping loop: mj_step called by address
# ------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def _mj_step_address() -> int:
    import ctypes
    import glob
    import os

    import mujoco

    libs = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco*")))
    if not libs:
        raise FileNotFoundError("MuJoCo's shared library next to the mujoco package")
    return int(ctypes.cast(ctypes.CDLL(libs[0]).mj_step, ctypes.c_void_p).value)


@functools.lru_cache(maxsize=1)
def compiled_available() -> tuple[bool, str]:
    """(True, "") when the compiled loop can drive MuJoCo here, else (False, why): numba,
    ``mj_step`` in MuJoCo's library, and a self-test that steps a falling box 200 times both
    ways and finds every state bit for bit equal."""
    from ..analytic.kernels import NUMBA_AVAILABLE

    if not NUMBA_AVAILABLE:
        return False, "numba is not available"
    try:
        import mujoco

        from .compiled_loop import step_by_address

        xml = ('<mujoco><option timestep="0.002"/><worldbody><geom type="plane" size="5 5 .1"/>'
               '<body pos="0 0 .6" euler="0 20 0"><freejoint/><geom type="box" '
               'size=".2 .2 .5"/></body></worldbody></mujoco>')
        runs = []
        for compiled in (False, True):
            m = mujoco.MjModel.from_xml_string(xml)
            d = mujoco.MjData(m)
            if compiled:
                step_by_address(_mj_step_address(), m._address, d._address, 200)
            else:
                for _ in range(200):
                    mujoco.mj_step(m, d)
            runs.append(np.concatenate([d.qpos, d.qvel]))
        if not np.array_equal(runs[0], runs[1]):
            return False, "the self-test's states differ from mujoco.mj_step's"
    except Exception as e:  # noqa: BLE001 - any failure means: the Python loop
        return False, f"{type(e).__name__}: {e}"
    return True, ""

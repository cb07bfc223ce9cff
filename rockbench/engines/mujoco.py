"""MuJoCo backend: the planar scene in a 3-D engine, kept in the plane by joints.

Model (generated MJCF, from the scene alone)
--------------------------------------------
rockbench's plane x-y (y up) is MuJoCo's x-z plane (z up). Each body of the scene is one MuJoCo
body whose frame sits at the body's rest centre of mass, with three joints: ``slide x``,
``slide z`` and a ``hinge`` about the axis (0, -1, 0). With that axis a positive hinge angle
turns x towards +z, i.e. counterclockwise in rockbench's x-y plane, so the hinge angle *is*
rockbench's theta (phi for the left column) with no sign flip. ``qpos`` of a body is therefore
(x - x_rest, y - y_rest, theta) and ``qvel`` (vx, vy, omega).

Masses and inertias are set explicitly (``<inertial>``): the in-plane moment (about MuJoCo's y
axis) is the scene's (for the beam m rho^2, not the box's); the two out-of-plane moments are the
box's, raised only if needed to satisfy MuJoCo's triangle inequality. They never enter the
dynamics, because the joints allow no out-of-plane rotation.

Contacts are explicit ``<pair>`` elements (automatic collisions are off): block/column bases on
the ground plane (the right column on the step box of the asymmetric frame), and both column tops
against the beam. Each pair gets exactly ``settings.friction`` (no max-combination rule applies
to explicit pairs), condim 3, and the contact softness of the settings. MuJoCo contacts never
bounce: restitution comes only from an under-damped ``solref``, and the default is critically
damped.

Devices (``devices="native"``, the default): each tendon is a spatial tendon through four
sites, foundation anchor F (rest position of the column base centre) -> column base centre P ->
column top centre Q -> beam anchor T (rest position of Q on the beam), with stiffness k and
spring length 2H: its length minus 2H is exactly the base opening plus the top opening of the
scene model. Each damper is a spatial tendon from a base corner to a world site at that corner's
rest position, with damping C; as in the shared model, only the heel (the corner farther from its
rest position) is damped, by switching ``tendon_damping`` each step. ``devices="forces"`` uses
the shared point forces of :class:`rockbench.engines.base.DeviceGeometry` instead. Fracture
zeroes the tendons' stiffness and damping.

See ``docs/engines/mujoco.md`` for the measurements behind every default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import ParameterError
from .base import EngineBackend, EngineSettings, PointForce

__all__ = ["MujocoBackend", "MujocoSettings"]

_INTEGRATORS = {"euler": "Euler", "implicitfast": "implicitfast", "implicit": "implicit",
                "rk4": "RK4"}
_CONES = ("pyramidal", "elliptic")
_DEVICE_MODES = ("native", "forces")


@dataclass(frozen=True)
class MujocoSettings(EngineSettings):
    """MuJoCo settings (``docs/engines/mujoco.md`` gives the measurements behind the defaults).

    contact_timeconst : contact time constant [s] (``solref[0]``, MuJoCo's ``refsafe`` off), or
        None (default) for ``min_timeconst_steps * dt`` = 2 dt, the stiffest contact the step
        resolves (the engine then converges to the rigid-contact reference as dt shrinks).
        MuJoCo's default 0.02 s is far too soft for tonnes-scale rocking. An explicit value
        below 2 dt is refused: measured, 1 dt diverges (metres of slip or penetration).
    contact_dampratio : contact damping ratio [-] (``solref[1]``), 1 = critical (no bounce).
    impedance : solimp dmin = dmax [-] in (0, 1): the fraction of the contact's constraint force
        that is not regularized away (MuJoCo default 0.9..0.95).
    integrator : "euler" (semi-implicit, MuJoCo default), "implicitfast", "implicit" or "rk4".
    cone : friction cone, "pyramidal" (MuJoCo default) or "elliptic".
    impratio : ratio of frictional to normal constraint impedance [-] (MuJoCo default 1).
    noslip_iterations : iterations of MuJoCo's post-solve "noslip" pass (0: off).
    iterations : constraint solver (Newton) iterations per step, >= 1.
    tolerance : solver tolerance [-], >= 0.
    devices : "native" (MuJoCo spatial tendons with stiffness and damping) or "forces" (the
        shared point forces computed from the poses).
    """

    dt: float = 1e-3
    contact_timeconst: float | None = None
    contact_dampratio: float = 1.0
    impedance: float = 0.99
    integrator: str = "implicitfast"
    cone: str = "elliptic"
    impratio: float = 1.0
    noslip_iterations: int = 0
    iterations: int = 100
    tolerance: float = 1e-10
    devices: str = "native"

    #: the smallest contact time constant allowed, in time steps (measured: 2 is stable)
    min_timeconst_steps: ClassVar[float] = 2.0

    @property
    def timeconst(self) -> float:
        """The contact time constant in use [s]."""
        if self.contact_timeconst is None:
            return self.min_timeconst_steps * self.dt
        try:
            return float(self.contact_timeconst)
        except (TypeError, ValueError):
            raise ParameterError("contact_timeconst", self.contact_timeconst,
                                 "a number [s] or None") from None

    def __post_init__(self) -> None:
        super().__post_init__()
        lo = self.min_timeconst_steps * self.dt
        tc = self.timeconst
        if isinstance(self.contact_timeconst, bool) or not math.isfinite(tc) \
                or tc < lo * (1 - 1e-9) or tc > 1.0:
            raise ParameterError("contact_timeconst", self.contact_timeconst,
                                 f"in [{self.min_timeconst_steps:g} dt = {lo:g}, 1] s",
                                 "a contact stiffer than the time step can resolve diverges")
        if not (math.isfinite(self.contact_dampratio) and 0.1 <= self.contact_dampratio <= 10):
            raise ParameterError("contact_dampratio", self.contact_dampratio, "in [0.1, 10]")
        if not (math.isfinite(self.impedance) and 0.0 < self.impedance < 1.0):
            raise ParameterError("impedance", self.impedance, "in (0, 1)")
        if self.integrator not in _INTEGRATORS:
            raise ParameterError("integrator", self.integrator, f"one of {', '.join(_INTEGRATORS)}")
        if self.cone not in _CONES:
            raise ParameterError("cone", self.cone, f"one of {', '.join(_CONES)}")
        if not (math.isfinite(self.impratio) and 0.1 <= self.impratio <= 100):
            raise ParameterError("impratio", self.impratio, "in [0.1, 100]")
        if int(self.noslip_iterations) != self.noslip_iterations or self.noslip_iterations < 0:
            raise ParameterError("noslip_iterations", self.noslip_iterations, "an integer >= 0")
        if int(self.iterations) != self.iterations or self.iterations < 1:
            raise ParameterError("iterations", self.iterations, "an integer >= 1")
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0.0):
            raise ParameterError("tolerance", self.tolerance, ">= 0")
        if self.devices not in _DEVICE_MODES:
            raise ParameterError("devices", self.devices, f"one of {', '.join(_DEVICE_MODES)}")


def _f(x: float) -> str:
    return repr(float(x))


def _vec(*xs: float) -> str:
    return " ".join(_f(x) for x in xs)


def _inertia(sp) -> tuple[float, float, float]:
    """Diagonal inertia (Ixx, Iyy, Izz) [kg m^2] of a body in MuJoCo axes: Iyy is the scene's
    in-plane moment; Ixx, Izz the box's, raised if needed for the triangle inequality."""
    m = sp.mass
    hx, hy, hz = sp.half_width, 0.5 * sp.depth, sp.half_height
    ixx = m * (hy * hy + hz * hz) / 3.0
    izz = m * (hx * hx + hy * hy) / 3.0
    iyy = sp.inertia
    if ixx + izz < iyy:                 # out-of-plane values never enter the planar dynamics
        s = iyy / (ixx + izz)
        ixx, izz = ixx * s, izz * s
    ixx = max(ixx, abs(izz - iyy))
    izz = max(izz, abs(ixx - iyy))
    return ixx, iyy, izz


class MujocoBackend(EngineBackend):
    """The scene in MuJoCo (planar joints, box contacts, native tendons and dampers)."""

    name: ClassVar[str] = "mujoco"
    Settings: ClassVar[type] = MujocoSettings

    @property
    def native_devices(self) -> bool:  # type: ignore[override]
        return self.settings.devices == "native"

    @classmethod
    def available(cls) -> tuple[bool, str]:
        try:
            import mujoco
        except Exception as e:  # pragma: no cover - depends on the machine
            return False, f"mujoco does not import: {e}"
        return True, f"mujoco {mujoco.__version__}"

    # --- the model ------------------------------------------------------------------------
    def compile(self, phi0: float = 0.0):
        """Build the MuJoCo model and data of the scene at rotation ``phi0`` [rad] outside a run
        (for inspection and tests); returns the ``mujoco.MjModel``."""
        from .base import body_specs, foundation_spec, initial_poses

        self.specs = body_specs(self.scene)
        self.foundation = foundation_spec(self.scene)
        self.poses0 = initial_poses(self.scene, phi0)
        self._build()
        return self.model

    def mjcf(self) -> str:
        """The MJCF text of the scene (needs ``self.specs``, ``self.foundation`` and
        ``self.poses0``, set by ``run`` or :meth:`compile`)."""
        cfg = self.settings
        fd = self.foundation
        specs = self.specs
        depth = max(sp.depth for sp in specs)
        solref = _vec(cfg.timeconst, cfg.contact_dampratio)
        d = cfg.impedance
        solimp = f"{_f(d)} {_f(d)} 0.001 0.5 2"
        mu = cfg.friction
        frame = len(specs) == 3
        out = ['<mujoco model="rockbench">',
               f'  <option timestep="{_f(cfg.dt)}" gravity="0 0 {_f(-G)}" '
               f'integrator="{_INTEGRATORS[cfg.integrator]}" cone="{cfg.cone}" iterations="{int(cfg.iterations)}" '
               f'tolerance="{_f(cfg.tolerance)}" impratio="{_f(cfg.impratio)}" '
               f'noslip_iterations="{int(cfg.noslip_iterations)}">',
               '    <flag refsafe="disable"/>',
               '  </option>',
               '  <compiler angle="radian" inertiafromgeom="false"/>',
               '  <default><geom contype="0" conaffinity="0"/></default>',
               '  <worldbody>',
               '    <geom name="ground" type="plane" size="0 0 1" pos="0 0 0"/>']
        if fd.step_x0 is not None:
            hx = 0.5 * (fd.step_x1 - fd.step_x0)
            hz = 0.5 * fd.step_height
            out.append(f'    <geom name="step" type="box" size="{_vec(hx, depth, hz)}" '
                       f'pos="{_vec(0.5 * (fd.step_x0 + fd.step_x1), 0.0, hz)}"/>')
        dev = self.scene.has_devices and self.native_devices and frame
        if dev:
            for j, idx in enumerate((0, 2)):
                sp = specs[idx]
                out.append(f'    <site name="F{j}" pos="{_vec(sp.x, 0.0, sp.y - sp.half_height)}"/>')
                for side, sx in (("l", -1.0), ("r", 1.0)):
                    out.append(f'    <site name="R{j}{side}" '
                               f'pos="{_vec(sp.x + sx * sp.half_width, 0.0, sp.y - sp.half_height)}"/>')
        for i, (sp, pose) in enumerate(zip(specs, self.poses0)):
            ixx, iyy, izz = _inertia(sp)
            out.append(f'    <body name="{sp.name}" pos="{_vec(sp.x, 0.0, sp.y)}">')
            out.append(f'      <joint name="{sp.name}_x" type="slide" axis="1 0 0"/>')
            out.append(f'      <joint name="{sp.name}_z" type="slide" axis="0 0 1"/>')
            out.append(f'      <joint name="{sp.name}_th" type="hinge" axis="0 -1 0"/>')
            out.append(f'      <inertial pos="0 0 0" mass="{_f(sp.mass)}" '
                       f'diaginertia="{_vec(ixx, iyy, izz)}"/>')
            out.append(f'      <geom name="{sp.name}" type="box" '
                       f'size="{_vec(sp.half_width, 0.5 * sp.depth, sp.half_height)}"/>')
            if dev and sp.name in ("left", "right"):
                j = 0 if sp.name == "left" else 1
                out.append(f'      <site name="P{j}" pos="{_vec(0.0, 0.0, -sp.half_height)}"/>')
                out.append(f'      <site name="Q{j}" pos="{_vec(0.0, 0.0, sp.half_height)}"/>')
                out.append(f'      <site name="C{j}l" pos="{_vec(-sp.half_width, 0.0, -sp.half_height)}"/>')
                out.append(f'      <site name="C{j}r" pos="{_vec(sp.half_width, 0.0, -sp.half_height)}"/>')
            if dev and sp.name == "beam":
                for j, idx in enumerate((0, 2)):
                    c = specs[idx]
                    out.append(f'      <site name="T{j}" pos="'
                               f'{_vec(c.x - sp.x, 0.0, c.y + c.half_height - sp.y)}"/>')
            out.append('    </body>')
        out.append('  </worldbody>')
        pairs = []
        if frame:
            right_base = "step" if fd.step_x0 is not None else "ground"
            pairs += [("left", "ground"), ("right", right_base), ("left", "beam"),
                      ("right", "beam")]
        else:
            pairs.append((specs[0].name, "ground"))
        out.append('  <contact>')
        for a, b in pairs:
            out.append(f'    <pair geom1="{a}" geom2="{b}" condim="3" friction="{_vec(mu, mu, 0.005, 1e-4, 1e-4)}" '
                       f'solref="{solref}" solimp="{solimp}"/>')
        out.append('  </contact>')
        if dev:
            dv = self.scene.devices
            out.append('  <tendon>')
            for j, idx in enumerate((0, 2)):
                sp = specs[idx]
                if dv.has_tendons:
                    out.append(f'    <spatial name="tendon{j}" stiffness="{_f(dv.tendon_stiffness)}" '
                               f'springlength="{_f(2.0 * sp.half_height)}">')
                    out.append(f'      <site site="F{j}"/><site site="P{j}"/>'
                               f'<site site="Q{j}"/><site site="T{j}"/>')
                    out.append('    </spatial>')
                if dv.has_dampers:
                    for side in ("l", "r"):
                        out.append(f'    <spatial name="damper{j}{side}" damping="0">')
                        out.append(f'      <site site="C{j}{side}"/><site site="R{j}{side}"/>')
                        out.append('    </spatial>')
            out.append('  </tendon>')
        out.append('</mujoco>')
        return "\n".join(out)

    def _build(self) -> None:
        import mujoco

        self._mj = mujoco
        self.model = mujoco.MjModel.from_xml_string(self.mjcf())
        self.data = mujoco.MjData(self.model)
        n = len(self.specs)
        rest = np.array([[sp.x, sp.y] for sp in self.specs])
        self._rest = rest
        q = np.zeros(3 * n)
        for i, pose in enumerate(self.poses0):
            q[3 * i:3 * i + 3] = (pose[0] - rest[i, 0], pose[1] - rest[i, 1], pose[2])
        self.data.qpos[:] = q
        self.data.qvel[:] = 0.0
        mujoco.mj_forward(self.model, self.data)
        # damper tendons: ids of (left corner, right corner) per column, their rest sites
        self._dampers = []
        m = self.model
        if self.scene.has_devices and self.native_devices and n == 3 \
                and self.scene.devices.has_dampers:
            for j, idx in enumerate((0, 2)):
                tl = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, f"damper{j}l")
                tr = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, f"damper{j}r")
                self._dampers.append((tl, tr))
            self._c = float(self.scene.devices.damping)
            self._set_heels()

    def _set_heels(self) -> None:
        """Damp only the heel of each column: the base corner farther from its rest position
        (the shared model's rule), using the current tendon lengths."""
        L = self.data.ten_length
        damp = self.model.tendon_damping
        for tl, tr in self._dampers:
            if L[tl] >= L[tr]:
                damp[tl], damp[tr] = self._c, 0.0
            else:
                damp[tl], damp[tr] = 0.0, self._c

    def _remove_devices(self) -> None:
        self.model.tendon_stiffness[:] = 0.0
        self.model.tendon_damping[:] = 0.0
        self._dampers = []

    def _step(self, gravity_x: float, forces: list[PointForce]) -> None:
        m, d = self.model, self.data
        m.opt.gravity[0] = gravity_x
        if self._dampers:
            self._set_heels()
        if forces:
            mj = self._mj
            d.qfrc_applied[:] = 0.0
            for f in forces:
                body = f.body + 1
                mj.mj_applyFT(m, d, np.array([f.fx, 0.0, f.fy]), np.zeros(3),
                              np.array([f.px, 0.0, f.py]), body, d.qfrc_applied)
            self._mj.mj_step(m, d)
            d.qfrc_applied[:] = 0.0
        else:
            self._mj.mj_step(m, d)

    def _state(self) -> np.ndarray:
        n = len(self.specs)
        q = self.data.qpos.reshape(n, 3)
        v = self.data.qvel.reshape(n, 3)
        out = np.empty((n, 6))
        out[:, 0:2] = self._rest + q[:, 0:2]
        out[:, 2] = q[:, 2]
        out[:, 3:6] = v
        return out

    def _close(self) -> None:
        self.data = None

"""The backend protocol, and the machinery every physics-engine adapter shares.

Contract of a backend (in the spirit of ``scipy.integrate.OdeSolver``)
-----------------------------------------------------------------------
A backend is a subclass of :class:`Backend` registered by name in
:mod:`rockbench.engines` (one file + one registry line). It must provide

* ``name`` - the registry name (class attribute);
* ``Settings`` - a frozen dataclass of its own settings (time step, solver iterations, contact
  parameters, ...), every field with a default that ``docs/engines/<name>.md`` justifies by a
  measurement; invalid values raise :class:`rockbench.errors.ParameterError` in
  ``__post_init__``. A backend never changes the scene: engine-only parameters live here;
* ``available()`` - classmethod returning ``(True, version)`` or ``(False, why)`` without
  raising when the engine package is missing;
* ``run(motion=None, *, duration=None, phi0=0.0) -> Result`` - one simulation of the scene it
  was constructed with, returning a :class:`rockbench.result.Result` whose ``history`` has every
  column of :data:`~rockbench.result.HISTORY_COLUMNS` (and, for engines,
  :data:`~rockbench.result.CONTACT_COLUMNS`) sampled every ``settings.output_dt`` seconds, whose
  ``phi`` is the rotation of the left column's body from rest (positive counterclockwise), and
  whose failures are reported, not raised: an engine error, NaN, or an unphysical state yields
  a Result with ``summary.status == "diverged"`` and the reason.

Engines that step a rigid-body world should subclass :class:`EngineBackend`, which implements
``run`` once for all of them. An adapter then implements only four primitives:

``_build(self)``
    Create the world from ``self.specs`` (bodies: true mass, inertia about the centre of mass,
    box half sizes, initial pose) and ``self.foundation`` (ground and step), contacts with
    friction ``self.settings.friction`` and no restitution. Planar engines stay planar; 3-D
    engines keep the bodies in the x-y plane with joints (not free bodies). Create native
    tendons/dampers only if ``native_devices`` is True and ``self.scene.has_devices``.
``_step(self, gravity_x, forces)``
    Advance the world by ``settings.dt`` with gravity ``(gravity_x, -g)`` (ground motion applied
    as a time-varying gravity vector, exact for rigid bodies) and the given external
    :class:`PointForce` list (device forces, computed here from the poses) applied during the
    step.
``_state(self) -> ndarray (n_bodies, 6)``
    x, y [m], theta [rad] (rotation from rest, continuous, + counterclockwise), vx, vy [m/s],
    omega [rad/s] of each body's centre of mass, bodies in the order of ``self.specs``.
``_close(self)``
    Release engine resources (physics clients, ...).

and optionally ``_remove_devices(self)`` (native devices: switch them off at fracture) and
``_native_device_report(self, devices, state, elongations)`` (native devices: the tendon
tensions and damper forces [N] the engine applies, for the history). A ``damper`` field in the
adapter's Settings, if present and one of :data:`DAMPER_MODELS`, selects how the shared damper
forces reach the bodies (see :class:`DeviceGeometry`; otherwise "couple").

Counters and attributes the base class keeps: ``steps`` (engine steps), ``wall_s`` (seconds
spent in ``_step``, building and the Python loop excluded), ``specs``, ``foundation``,
``poses0`` (set before ``_build``).

What ``run`` does, once for every engine
----------------------------------------
* Time: ``run_window`` (start at the motion's ``t_start``, or 0 for free rocking); steps of
  ``dt`` with gravity ``(-u_g''(t + dt/2), -g)``; the initial poses place every body on the
  exact mechanism at phi0, at rest.
* Devices (frames with tendons/dampers, unless native): :class:`DeviceGeometry` point forces
  from the poses and velocities before every step (tendon elongation = base opening + top
  opening; dampers on the heel-corner chord of each column's rotation); fracture when either
  tendon's strain reaches eps_f, after which no device force acts (native ones are removed).
* Output: the state linearly interpolated between steps onto the analytic backend's grid
  (:func:`output_grid`); phi, phidot = the left column's (block's) rotation and rate; device
  columns from the sampled states by the same formulas as the forces.
* Contacts: :class:`ContactProbe` on the sampled poses: penetration, sliding of a contact
  point from its rest position while touching, and whether a contact the analytic model keeps
  closed opened (history columns and summary maxima).
* Events from the sampled motion (:func:`excursions`, :func:`measure_impacts`): uplift (an
  excursion that starts from rest, timed back to the last sample at rest in rate), impacts with
  the effective eta (energy of successive peaks for free rocking, windowed velocity fits
  otherwise), fracture, overturn (|phi| reaches the scene's fall angle; the run stops).
* Divergence (``summary.status == "diverged"`` with ``reason``, never an exception): an
  exception from the engine or the adapter, a non-finite state, penetration or sliding above
  ``max_penetration`` / ``max_sliding`` (checked every 500 samples and at the end), mechanical
  energy growing by more than ``energy_gain_tol`` without input (free rocking: every step,
  from the bodies' states; after the ground motion ends: the potential at successive peaks).
  The Result still carries the history up to the failure.
"""

from __future__ import annotations

import abc
import math
import time
from dataclasses import asdict, dataclass, fields
from typing import Any, ClassVar, NamedTuple

import numpy as np
import pandas as pd

from ..constants import G
from ..errors import ParameterError, check_positive
from ..measure import Excursion, excursions, measure_impacts  # noqa: F401
from ..result import (CONTACT_COLUMNS, HISTORY_COLUMNS, Cost, Result, Summary, events_frame,
                      output_grid)
from ..scene.scene import Scene
from ..scene.structure import Block, Frame

__all__ = ["Backend", "EngineBackend", "EngineSettings", "BodySpec", "FoundationSpec",
           "PointForce", "DeviceGeometry", "DAMPER_MODELS", "ContactProbe", "Excursion",
           "body_specs",
           "foundation_spec", "initial_poses", "device_forces", "net_wrenches",
           "contact_diagnostics", "excursions", "measure_impacts", "output_grid", "run_window"]


# =========================================================================================
# The protocol
# =========================================================================================
class Backend(abc.ABC):
    """Base class of every backend (analytic and engines). See the module docstring."""

    name: ClassVar[str]
    Settings: ClassVar[type]

    def __init__(self, scene: Scene, settings: Any = None, **overrides: Any):
        if not isinstance(scene, Scene):
            raise ParameterError("scene", type(scene).__name__, "a rockbench Scene")
        if settings is None:
            settings = _replace(self.Settings(), overrides) if overrides else self.Settings()
        elif overrides:
            settings = _replace(settings, overrides)
        if not isinstance(settings, self.Settings):
            raise ParameterError("settings", type(settings).__name__,
                                 f"a {self.Settings.__qualname__}")
        self.scene = scene
        self.settings = settings

    @classmethod
    @abc.abstractmethod
    def available(cls) -> tuple[bool, str]:
        """(True, engine version) if the backend can run here, else (False, reason)."""

    @abc.abstractmethod
    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0) -> Result:
        """Simulate the scene under ``motion`` (None: free rocking from ``phi0`` [rad])."""


def _replace(settings, overrides: dict[str, Any]):
    names = {f.name for f in fields(settings)}
    bad = set(overrides) - names
    if bad:
        raise ParameterError(sorted(bad)[0], overrides[sorted(bad)[0]],
                             f"a setting of {type(settings).__qualname__}: {sorted(names)}")
    vals = asdict(settings)
    vals.update(overrides)
    return type(settings)(**vals)


def run_window(scene: Scene, motion, duration: float | None, phi0: float) -> tuple[float, float]:
    """Validate a run's time window and initial rotation; return (t0, t_end) [s].

    Shared by every backend so that they all start and stop at the same times: from the motion's
    ``t_start`` (-3 T_g for a Ricker pulse) or 0 for free rocking, for ``duration`` seconds
    (default: the motion's length + 10 s, or 10 s of free rocking).
    """
    t0 = float(motion.t_start) if motion is not None else 0.0
    if duration is None:
        duration = (max(motion.t_end - t0, 0.0) if motion is not None else 0.0) + 10.0
    duration = check_positive("duration", duration)
    if not math.isfinite(float(phi0)):
        raise ParameterError("phi0", phi0, "a finite number [rad]")
    fall = min(scene.fall_angles.values())
    if abs(phi0) >= fall:
        raise ParameterError("phi0", phi0, f"|phi0| < fall angle {fall:.4g} rad")
    if motion is None and phi0 == 0.0:
        raise ParameterError("phi0", phi0, "non-zero for a free-rocking run (no ground motion)")
    return t0, t0 + duration


# =========================================================================================
# Scene -> bodies (one description every engine builds from)
# =========================================================================================
class BodySpec(NamedTuple):
    """A rigid box body. Sizes in m, mass kg, inertia kg m^2 (planar, about the centre of
    mass; 3-D engines may use it for the axis normal to the plane and box values for the others),
    depth m (out of plane), rest centre of mass (x, y) in m."""

    name: str
    mass: float
    inertia: float
    half_width: float
    half_height: float
    depth: float
    x: float
    y: float


class FoundationSpec(NamedTuple):
    """Static geometry: the ground surface y = 0 (extending over ``x_min``..``x_max``), and an
    optional step (a box ``step_x0``..``step_x1`` by 0..``step_height``) under the right column.
    The step is three column widths wide, centred under the right column, so that the column's
    pivots are on the step's flat top, never on its edges."""

    x_min: float
    x_max: float
    step_x0: float | None
    step_x1: float | None
    step_height: float


def body_specs(scene: Scene) -> list[BodySpec]:
    """The bodies the scene needs, in the order engines must report them: [block] or
    [left column, beam, right column]."""
    st = scene.structure
    if isinstance(st, Block):
        return [BodySpec("block", st.mass, st.inertia_cm, st.b, st.H, st.depth, 0.0, st.H)]
    f: Frame = st
    gl, gb, gr = f.com_left, f.com_beam, f.com_right
    return [
        BodySpec("left", f.mass_left, f.inertia_left, f.b, f.H, f.depth, *gl),
        BodySpec("beam", f.mass_beam, f.inertia_beam, 0.5 * f.beam_width, f.h, f.depth, *gb),
        BodySpec("right", f.mass_right, f.inertia_right, f.b, f.H1, f.depth, *gr),
    ]


def foundation_spec(scene: Scene) -> FoundationSpec:
    st = scene.structure
    if isinstance(st, Block):
        ext = 10.0 * max(st.width, st.height)
        return FoundationSpec(-ext, ext, None, None, 0.0)
    ext = 10.0 * max(st.beam_width, st.column_height_left)
    if st.step > 0.0:
        return FoundationSpec(-ext, st.L + ext, st.L - 3 * st.b, st.L + 3 * st.b, st.step)
    return FoundationSpec(-ext, st.L + ext, None, None, 0.0)


def initial_poses(scene: Scene, phi0: float) -> np.ndarray:
    """Poses (n_bodies, 3): x, y [m], theta [rad] of each body for a rotation phi0 [rad] of the
    left column, the other bodies placed by the mechanism's exact kinematics."""
    from ..scene.mechanism import mechanism  # geometry only (pure functions)

    specs = body_specs(scene)
    if phi0 == 0.0:
        return np.array([[b.x, b.y, 0.0] for b in specs])
    cfg = mechanism(scene.structure, 1 if phi0 > 0 else -1).configuration(phi0)
    return np.array([[bk.x, bk.y, bk.theta] for bk in cfg.bodies])


# =========================================================================================
# Devices from poses
# =========================================================================================
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


# =========================================================================================
# Contact diagnostics from poses
# =========================================================================================
def _corners(sp: BodySpec):
    hw, hh = sp.half_width, sp.half_height
    return {"bl": (-hw, -hh), "br": (hw, -hh), "tl": (-hw, hh), "tr": (hw, hh)}


class ContactProbe:
    """Penetration, sliding and opening of the contacts the analytic model assumes, computed
    from body poses only (so every engine is measured the same way).

    * base contacts: the two base corners of each column (block) on the foundation surface
      (y = 0, or the step's top under the right column);
    * top contacts: the two top corners of each column against the beam soffit, in the beam's
      frame.

    Penetration [m]: depth of a corner below (inside) the surface it rests on. Sliding [m]:
    tangential distance of a corner from its rest position along its surface, counted while
    the corner is in contact (gap < ``tol``), so a pivot that creeps or a beam that slides on
    the column tops shows up, but a heel that swings while lifted does not. Opened: a contact
    the analytic model keeps closed has a gap above ``open_tol``: a pivot of the current
    mechanism while the structure rocks (mode +1: bottom-left and top-right corners, mode -1:
    bottom-right and top-left), or any of them at rest (mode 0).
    """

    def __init__(self, scene: Scene, specs: list[BodySpec], tol: float = 1e-3,
                 open_tol: float = 5e-3):
        self.specs = specs
        self.tol = tol
        self.open_tol = open_tol
        self.frame = isinstance(scene.structure, Frame)
        self.cols = [0, 2] if self.frame else [0]
        self.base_y = {i: specs[i].y - specs[i].half_height for i in self.cols}
        self.rest = {}
        for i in self.cols:
            sp = specs[i]
            for name, (lx, ly) in _corners(sp).items():
                self.rest[(i, name)] = (sp.x + lx, sp.y + ly)
        self.beam = specs[1] if self.frame else None

    def measure(self, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
        """(penetration [m], sliding [m], contact opened) for one state (n_bodies, 6) and
        rocking mode (+1, -1, 0)."""
        pen, sl, op = self.measure_many(np.asarray(state, dtype=float)[None],
                                        np.array([mode]))
        return float(pen[0]), float(sl[0]), bool(op[0])

    def measure_many(self, states: np.ndarray, modes: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorized :meth:`measure` over states (n, n_bodies, 6) and modes (n,): arrays of
        penetration [m], sliding [m] and opened flags."""
        states = np.asarray(states, dtype=float)
        modes = np.asarray(modes)
        n = states.shape[0]
        pen = np.zeros(n)
        slide = np.zeros(n)
        opened = np.zeros(n, dtype=bool)
        rocking = modes != 0
        if self.frame:
            bx, by, bth = states[:, 1, 0], states[:, 1, 1], states[:, 1, 2]
            bc, bs_ = np.cos(bth), np.sin(bth)
        for i in self.cols:
            sp = self.specs[i]
            x, y, th = states[:, i, 0], states[:, i, 1], states[:, i, 2]
            c, s = np.cos(th), np.sin(th)
            for name, (lx, ly) in _corners(sp).items():
                X = x + c * lx - s * ly
                Y = y + s * lx + c * ly
                rx0, _ = self.rest[(i, name)]
                if name in ("bl", "br"):
                    gap = Y - self.base_y[i]
                    tang = X - rx0
                    pivot = modes > 0 if name == "bl" else modes < 0
                else:
                    if not self.frame:
                        continue
                    rx, ry = X - bx, Y - by
                    u = bc * rx + bs_ * ry
                    v = -bs_ * rx + bc * ry
                    gap = -(v + self.beam.half_height)      # < 0: corner inside the beam
                    tang = u - (rx0 - self.beam.x)
                    pivot = modes > 0 if name == "tr" else modes < 0
                np.maximum(pen, -gap, out=pen)
                touch = gap < self.tol
                np.maximum(slide, np.where(touch, np.abs(tang), 0.0), out=slide)
                opened |= (gap > self.open_tol) & (pivot | ~rocking)
        return pen, slide, opened


def contact_diagnostics(scene: Scene, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
    """Convenience wrapper of :class:`ContactProbe` for one state."""
    return ContactProbe(scene, body_specs(scene)).measure(state, mode)


# =========================================================================================
# The shared stepping loop
# =========================================================================================
@dataclass(frozen=True)
class EngineSettings:
    """Settings every engine has (adapters subclass this and add their own).

    dt : engine time step [s], in [1e-6, 1e-2].
    output_dt : history sampling interval [s] (>= dt), the same grid as the analytic backend.
    friction : Coulomb friction coefficient of every contact pair (the value the pair gets,
        whatever the engine's combination rule), > 0.
    uplift_tol : |phi| / alpha above which the structure counts as uplifted (engine contacts
        are never perfectly rigid) [-].
    max_penetration, max_sliding : a run whose contacts penetrate or slide more than this [m]
        is reported ``diverged``.
    energy_gain_tol : relative growth of mechanical energy without input (free rocking) that
        marks a run ``diverged`` [-].
    """

    dt: float = 1e-3
    output_dt: float = 1e-3
    friction: float = 1.0
    uplift_tol: float = 1e-3
    max_penetration: float = 0.05
    max_sliding: float = 0.05
    energy_gain_tol: float = 0.02

    def __post_init__(self) -> None:
        dt = check_positive("dt", self.dt)
        if not 1e-6 <= dt <= 1e-2:
            raise ParameterError("dt", self.dt, "in [1e-6, 1e-2] s")
        od = check_positive("output_dt", self.output_dt)
        if od < dt * (1 - 1e-9):
            raise ParameterError("output_dt", self.output_dt, f">= dt = {dt:g} s")
        check_positive("friction", self.friction)
        check_positive("uplift_tol", self.uplift_tol)
        check_positive("max_penetration", self.max_penetration)
        check_positive("max_sliding", self.max_sliding)
        check_positive("energy_gain_tol", self.energy_gain_tol)


class _Diverged(Exception):
    pass


class EngineBackend(Backend):
    """A rigid-body engine stepped from Python. Subclasses implement the four primitives of the
    module docstring; ``run`` is implemented once here."""

    Settings: ClassVar[type] = EngineSettings
    native_devices: ClassVar[bool] = False

    # --- primitives -------------------------------------------------------------------------
    @abc.abstractmethod
    def _build(self) -> None: ...

    @abc.abstractmethod
    def _step(self, gravity_x: float, forces: list[PointForce]) -> None: ...

    @abc.abstractmethod
    def _state(self) -> np.ndarray: ...

    def _close(self) -> None:
        pass

    def _remove_devices(self) -> None:
        if self.native_devices:
            raise NotImplementedError("an adapter with native devices must remove them")

    def _native_device_report(self, devices: "DeviceGeometry", state: np.ndarray,
                              elongations: list[float]) -> tuple[list[float], list[float]]:
        """Tendon tensions and damper forces [N] of native devices for the history, at one
        output sample ``state`` (n_bodies, 6) while the devices are intact, with the shared
        geometry's ``elongations`` [m] there. Default: k times the elongations, and no damper
        force; adapters report what their engine applies in that state."""
        return [devices.k * e for e in elongations], [0.0, 0.0]

    @classmethod
    def version(cls) -> str:
        ok, v = cls.available()
        return v if ok else "unavailable"

    # --- the loop ---------------------------------------------------------------------------
    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0) -> Result:
        scene, cfg = self.scene, self.settings
        t0, t_end = run_window(scene, motion, duration, phi0)
        ok, why = self.available()
        if not ok:
            from ..errors import BackendUnavailable
            raise BackendUnavailable(f"backend {self.name!r} is not available: {why}")
        self.specs = body_specs(scene)
        self.foundation = foundation_spec(scene)
        self.poses0 = initial_poses(scene, phi0)
        self.steps = 0
        self.wall_s = 0.0
        alpha = scene.alpha
        fall = scene.fall_angles
        acc = motion.acceleration if motion is not None else None
        damper = getattr(cfg, "damper", "couple")
        devices = (DeviceGeometry(scene, self.specs,
                                  damper if damper in DAMPER_MODELS else "couple")
                   if scene.has_devices else None)
        intact = devices is not None
        check_strain = devices is not None and devices.eps_f is not None
        probe = ContactProbe(scene, self.specs)
        uplift_phi = cfg.uplift_tol * alpha

        dt = cfg.dt
        grid = output_grid(t0, t_end, cfg.output_dt)
        n_out = grid.size
        n_steps = int(math.ceil((t_end - t0) / dt - 1e-9))
        t_tol = 1e-9 * dt
        samples: list[np.ndarray] = []     # body states on the output grid
        sample_intact: list[bool] = []
        native_report: list[tuple] = []    # (tensions, damper forces) of native devices
        ev: list[dict[str, Any]] = []
        status, reason = "ok", None
        overturned = fractured = False
        t_over = t_frac = None
        max_pen = max_slide = 0.0          # over samples before the structure falls
        crit = _critical(scene)
        checked = 0                        # samples already probed for penetration / sliding
        energy0 = None
        free = motion is None and devices is None
        prev_t, prev = None, None
        try:
            self._build()
            state = np.array(self._state(), dtype=float)
            t = t0
            for k in range(n_steps + 1):
                if not np.all(np.isfinite(state)):
                    raise _Diverged(f"non-finite body state at t={t:.6g} s")
                # output samples on the fixed grid (linear interpolation between steps)
                while len(samples) < n_out and grid[len(samples)] <= t + t_tol:
                    if prev is None or t == prev_t:
                        samples.append(state)
                    else:
                        w = (grid[len(samples)] - prev_t) / (t - prev_t)
                        samples.append(prev + w * (state - prev))
                    sample_intact.append(intact)
                    if self.native_devices:
                        native_report.append(
                            self._native_device_report(devices, samples[-1],
                                                       devices.elongations(samples[-1]))
                            if intact and devices is not None else ([0.0, 0.0], [0.0, 0.0]))
                if len(samples) - checked >= _PROBE_CHUNK:
                    max_pen, max_slide = self._check_contacts(
                        probe, samples, sample_intact, crit, checked, uplift_phi, max_pen,
                        max_slide)
                    checked = len(samples)
                phi = state[0, 2]
                if abs(phi) >= fall[1 if phi > 0 else -1]:
                    overturned, t_over = True, t
                    ev.append(dict(t=t, kind="overturn", phi=phi, phidot_before=state[0, 5],
                                   phidot_after=state[0, 5], direction=1 if phi > 0 else -1))
                    break
                if free:
                    e = _mech_energy(self.specs, state)
                    if energy0 is None:
                        energy0 = max(e, 1e-300)
                    elif e > energy0 * (1 + cfg.energy_gain_tol):
                        raise _Diverged(f"mechanical energy grew by "
                                        f"{100 * (e / energy0 - 1):.2f} % without input "
                                        f"(t={t:.4g} s)")
                if k == n_steps:
                    break
                forces: list[PointForce] = []
                if intact:
                    if self.native_devices:
                        el = devices.elongations(state) if check_strain else None
                    else:                      # the forces, and the elongations with them
                        forces = devices.forces(state)[0]
                        el = devices.last_elongations
                    if check_strain and max(el) / devices.l >= devices.eps_f:
                        forces = []
                        intact = False
                        fractured, t_frac = True, t
                        ev.append(dict(t=t, kind="fracture", phi=phi,
                                       phidot_before=state[0, 5], phidot_after=state[0, 5],
                                       direction=1 if phi > 0 else -1))
                        if self.native_devices:
                            self._remove_devices()
                g_x = -float(acc(t + 0.5 * dt)) if acc is not None else 0.0
                ts = time.perf_counter()
                self._step(g_x, forces)
                self.wall_s += time.perf_counter() - ts
                self.steps += 1
                prev_t, prev = t, state
                t = t0 + (k + 1) * dt
                state = np.array(self._state(), dtype=float)
            max_pen, max_slide = self._check_contacts(probe, samples, sample_intact, crit,
                                                      checked, uplift_phi, max_pen, max_slide)
        except _Diverged as e:
            status, reason = "diverged", str(e)
        except Exception as e:  # engine failure at the adapter boundary
            status, reason = "diverged", f"{type(e).__name__}: {e}"
        finally:
            try:
                self._close()
            except Exception:
                pass

        S = np.array(samples, dtype=float).reshape(len(samples), len(self.specs), 6)
        tt = grid[:len(samples)]
        ph = S[:, 0, 2]
        pd_ = S[:, 0, 5]
        modes = np.where(np.abs(ph) <= uplift_phi, 0, np.sign(ph)).astype(np.int64)
        pen, sl, op = probe.measure_many(S, modes)
        falling = _falling(ph, np.array(sample_intact, bool), crit)
        # contact violations while the structure is past its critical angle do not make a run
        # diverged if it goes on to overturn (an engine's falling bodies may slide or sink: the
        # verdict is what matters); before that, or if it never overturns, they do
        pen_pre = float(pen[~falling].max(initial=0.0))
        sl_pre = float(sl[~falling].max(initial=0.0))
        pen_all = float(pen.max(initial=0.0))
        sl_all = float(sl.max(initial=0.0))
        max_pen = max(max_pen, pen_pre if overturned else pen_all)
        max_slide = max(max_slide, sl_pre if overturned else sl_all)
        opened = bool(op.any())
        history = self._history(scene, motion, tt, S, modes, np.array(sample_intact, bool),
                                devices, native_report, pen, sl)
        # events from the sampled motion
        rest_rate = cfg.uplift_tol * alpha * scene.p
        exc = excursions(tt, ph, pd_, uplift_tol=uplift_phi, rest_rate=rest_rate)
        for x in exc:
            if not x.after_impact and not (x.i0 == 0 and phi0 != 0.0):
                # back from the first uplifted sample to the last one still at rest in rate
                j = x.i0
                while j > 0 and abs(pd_[j]) > rest_rate and abs(ph[j - 1]) <= abs(ph[j]):
                    j -= 1
                ev.append(dict(t=float(tt[j]), kind="uplift", phi=float(ph[j]),
                               phidot_before=float(pd_[j]), phidot_after=float(pd_[j]),
                               direction=x.sign))
        energy = inertia0 = None
        dyn = None
        if len(exc):
            from ..analytic.reference import reference_of  # pure physics: V(phi) and I(0)
            dyn = reference_of(scene).dyn
        if free and dyn is not None:
            energy = lambda p: dyn[1 if p > 0 else -1].energy(p, 0.0)  # noqa: E731
            inertia0 = lambda s: dyn[s].terms(0.0).inertia  # noqa: E731
        imp = measure_impacts(tt, ph, pd_, alpha=alpha, free=free, energy=energy,
                              inertia0=inertia0, uplift_tol=uplift_phi, rest_rate=rest_rate)
        if overturned:
            imp = [r for r in imp if r["t"] <= t_over]
        ev.extend(imp)
        if status == "ok":
            if max_pen > cfg.max_penetration:
                status, reason = "diverged", (f"penetration {max_pen:.3g} m > max_penetration "
                                              f"{cfg.max_penetration:g} m")
            elif max_slide > cfg.max_sliding:
                status, reason = "diverged", (f"sliding {max_slide:.3g} m > max_sliding "
                                              f"{cfg.max_sliding:g} m")
            else:
                quiet = t0 if motion is None else float(motion.t_end)
                reason = _peak_energy_growth(exc, tt, ph, history["devices_intact"].to_numpy(),
                                             dyn, quiet, cfg.energy_gain_tol, alpha)
                if reason is not None:
                    status = "diverged"
        events = events_frame(sorted(ev, key=lambda r: r["t"]))
        impacts = events[events["kind"] == "impact"]
        max_abs = float(np.max(np.abs(ph))) if ph.size else 0.0
        ups = events[events["kind"] == "uplift"]
        uplifted = bool(len(ups)) or (phi0 != 0.0 and len(history) > 0)
        t_up = float(ups["t"].iloc[0]) if len(ups) else (t0 if uplifted else None)
        summary = Summary(
            max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / alpha,
            overturned=overturned, t_overturn=t_over,
            exceeded_critical=overturned or _exceeded(ph, crit, fractured, history),
            uplifted=uplifted, t_uplift=t_up,
            n_impacts=int(len(impacts)), fractured=fractured, t_fracture=t_frac,
            status=status, reason=reason,
            eta_measured=[float(x) for x in impacts["eta"].to_numpy()],
            max_penetration=max(max_pen, pen_all), max_sliding=max(max_slide, sl_all),
            contact_opened=opened)
        sim_time = (float(tt[-1]) - t0) if tt.size else 0.0
        cost = Cost(wall_s=self.wall_s, sim_time=sim_time, steps=self.steps)
        settings = asdict(cfg)
        settings["engine_version"] = self.version()
        return Result(backend=self.name, scene=scene,
                      motion=motion.describe() if motion is not None else {"kind": "none"},
                      history=history, events=events, summary=summary, cost=cost,
                      settings=settings)

    def _check_contacts(self, probe: "ContactProbe", samples: list, intact: list, crit: dict,
                        start: int, uplift_phi: float, max_pen: float, max_slide: float
                        ) -> tuple[float, float]:
        """Probe samples[start:] (vectorized); raise _Diverged beyond the tolerances. Samples
        past the critical angle (falling) are held to 10 x the tolerances only: whether their
        violations count is decided at the end of the run (they do unless it overturns)."""
        cfg = self.settings
        if len(samples) > start:
            S = np.array(samples[start:], dtype=float)
            ph = S[:, 0, 2]
            modes = np.where(np.abs(ph) <= uplift_phi, 0, np.sign(ph))
            pen, sl, _ = probe.measure_many(S, modes)
            falling = _falling(ph, np.array(intact[start:len(samples)], bool), crit)
            max_pen = max(max_pen, float(pen[~falling].max(initial=0.0)))
            max_slide = max(max_slide, float(sl[~falling].max(initial=0.0)))
            fpen = float(pen[falling].max(initial=0.0))
            fsl = float(sl[falling].max(initial=0.0))
            if fpen > 10 * cfg.max_penetration or fsl > 10 * cfg.max_sliding:
                raise _Diverged(f"while falling: penetration {fpen:.3g} m, sliding {fsl:.3g} m "
                                f"> 10 x max_penetration / max_sliding")
        if max_pen > cfg.max_penetration:
            raise _Diverged(f"penetration {max_pen:.3g} m > max_penetration "
                            f"{cfg.max_penetration:g} m")
        if max_slide > cfg.max_sliding:
            raise _Diverged(f"sliding {max_slide:.3g} m > max_sliding {cfg.max_sliding:g} m")
        return max_pen, max_slide

    def _history(self, scene: Scene, motion, t: np.ndarray, S: np.ndarray, modes: np.ndarray,
                 intact: np.ndarray, devices: "DeviceGeometry | None", native_report: list,
                 pen: np.ndarray, sl: np.ndarray) -> pd.DataFrame:
        """The history frame (HISTORY_COLUMNS + CONTACT_COLUMNS) from the sampled states."""
        n = t.size
        frame = isinstance(scene.structure, Frame)
        nan = np.full(n, np.nan)
        zero = np.zeros(n)
        acc = (np.asarray(motion.acceleration(t), dtype=float).reshape(n)
               if motion is not None and n else zero.copy())
        cols: dict[str, Any] = {
            "t": t, "phi": S[:, 0, 2].copy(), "phidot": S[:, 0, 5].copy(), "ground_acc": acc,
            "theta_beam": S[:, 1, 2].copy() if frame else nan,
            "theta_right": S[:, 2, 2].copy() if frame else nan,
            "mode": modes.astype(np.int64), "devices_intact": intact.astype(bool)}
        el = ten = dmp = np.zeros((n, 2))
        if devices is not None and n:
            el, ten, dmp = devices.history(S)
            if self.native_devices and native_report:
                ten = np.array([r[0] for r in native_report], dtype=float).reshape(n, 2)
                dmp = np.array([r[1] for r in native_report], dtype=float).reshape(n, 2)
            on = intact[:, None]
            el, ten, dmp = (np.where(on, a, 0.0) for a in (el, ten, dmp))
        for j, side in enumerate(("left", "right")):
            cols[f"tendon_elong_{side}"] = el[:, j].copy()
            cols[f"tendon_force_{side}"] = ten[:, j].copy()
            cols[f"damper_force_{side}"] = dmp[:, j].copy()
        cols["penetration"] = pen
        cols["sliding"] = sl
        df = pd.DataFrame(cols, columns=list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS))
        for c in df.columns:
            if c not in ("mode", "devices_intact"):
                df[c] = df[c].astype(np.float64)
        return df


#: Output samples probed together (vectorized) for the penetration / sliding divergence check.
_PROBE_CHUNK = 500


def _peak_energy_growth(exc: list, t: np.ndarray, phi: np.ndarray, intact: np.ndarray, dyn,
                        t_quiet: float, tol: float, alpha: float) -> str | None:
    """Reason string if the energy of an excursion (its potential at its peak: gravity and
    intact tendons) exceeds that of the previous one by more than ``tol`` (relative) plus
    ``tol`` times the potential at |phi| = alpha / 20, for excursions after the ground motion
    ended (``t_quiet`` [s]); None otherwise. Impacts and dampers only remove energy."""
    if dyn is None or len(exc) < 2:
        return None
    floor = tol * min(dyn[s].energy(s * 0.05 * alpha, 0.0, True) for s in (1, -1))
    prev = None
    for x in exc:
        if not x.complete or t[x.i0] < t_quiet:
            prev = None
            continue
        V = dyn[x.sign].energy(x.sign * x.peak, 0.0, bool(intact[x.ipk]))
        if prev is not None and x.after_impact and V > prev[0] * (1 + tol) + floor:
            return (f"mechanical energy grew without input: peak {x.sign * x.peak:.4g} rad at "
                    f"t={t[x.ipk]:.4g} s holds {V:.4g} J, the previous peak (t={prev[1]:.4g} s) "
                    f"{prev[0]:.4g} J")
        prev = (V, float(t[x.ipk]))
    return None


def _mech_energy(specs: list[BodySpec], state: np.ndarray) -> float:
    """Kinetic + gravitational energy [J] of the bodies, relative to the rest configuration."""
    e = 0.0
    for sp, st in zip(specs, state):
        e += 0.5 * sp.mass * (st[3] ** 2 + st[4] ** 2) + 0.5 * sp.inertia * st[5] ** 2
        e += sp.mass * G * (st[1] - sp.y)
    return e


def _falling(phi: np.ndarray, intact: np.ndarray, crit: dict) -> np.ndarray:
    """Mask of samples past the critical angle of their direction and device state."""
    out = np.zeros(phi.shape, dtype=bool)
    for s in (1, -1):
        for flag in (True, False):
            c = crit[(s, flag)]
            if math.isfinite(c):
                out |= (s * phi > c) & (intact == flag)
    return out


def _critical(scene: Scene) -> dict:
    from ..analytic.reference import reference_of  # the scene's critical angles (physics)
    return reference_of(scene).critical


def _exceeded(phis: np.ndarray, crit: dict, fractured: bool, history: pd.DataFrame) -> bool:
    if not len(history):
        return False
    intact = history["devices_intact"].to_numpy()
    for s in (1, -1):
        for flag in (True, False):
            c = crit[(s, flag)]
            if not math.isfinite(c):
                continue
            m = intact == flag
            if np.any(s * phis[m] > c):
                return True
    return False

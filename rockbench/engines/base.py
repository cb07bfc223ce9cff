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
``_penetration(self) -> float`` (the engine's own largest contact depth [m]; by default it is
computed from the poses).

Counters and attributes the base class keeps: ``steps`` (engine steps), ``wall_s`` (seconds
spent stepping, building excluded).

Shared machinery here: body and foundation specifications from the scene, initial poses for a
given phi0 from the mechanism kinematics, ground motion as gravity, tendon and damper forces from
poses and velocities (the scene model's geometry: tendon elongation = base opening + top opening;
damper along the heel-corner chord), fracture, output sampling on a fixed grid, event detection
(uplift, impacts with the effective eta measured from the engine's motion, fracture, overturn),
contact diagnostics (penetration, sliding, pivots that open) from the poses, and divergence
detection.
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
from ..result import (CONTACT_COLUMNS, HISTORY_COLUMNS, Cost, Result, Summary, events_frame)
from ..scene.scene import Scene
from ..scene.structure import Block, Frame

__all__ = ["Backend", "EngineBackend", "EngineSettings", "BodySpec", "FoundationSpec",
           "PointForce", "body_specs", "foundation_spec", "initial_poses", "device_forces",
           "contact_diagnostics", "measure_impacts"]


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
            settings = self.Settings(**overrides)
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
    from ..analytic.kinematics import mechanism  # geometry only (pure functions)

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


def _world_vel(state, lx: float, ly: float) -> tuple[float, float]:
    x, y, th, vx, vy, w = state
    c, s = math.cos(th), math.sin(th)
    rx, ry = c * lx - s * ly, s * lx + c * ly
    return vx - w * ry, vy + w * rx


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

    ``damper="couple"`` (default) applies the damper's moment -C (dc_j/dt) dc_j/dtheta_j to the
    column as a pure couple (two opposite horizontal forces); ``damper="heel"`` applies the
    force -C (dc_j/dt) u at the heel corner. Both have the virtual power -C (dc_j/dt)^2 of the
    analytic model's D phi'^2 term. The couple is the default because the analytic model keeps
    every pivot closed, while the paper's dampers (25.3 MN s/m) push the heel with 2-5 MN, more
    than the 1 MN of dead load on a column's pivot: applied at the heel they lift the column
    off its pivot in an engine (measured in pymunk: pivots open, 1.5-2.5 cm of slip, peaks off
    by up to 20 %), a behaviour outside the model the engines are compared with.
    """

    def __init__(self, scene: Scene, specs: list[BodySpec], damper: str = "couple"):
        if damper not in ("couple", "heel"):
            raise ParameterError("damper", damper, "'couple' or 'heel'")
        self.damper = damper
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
        out = []
        for idx, F, p_loc, q_loc, t_loc, _ in self.columns:
            P = _world(state[idx], *p_loc)
            Q = _world(state[idx], *q_loc)
            T = _world(state[1], *t_loc)
            out.append(math.hypot(P[0] - F[0], P[1] - F[1]) + math.hypot(T[0] - Q[0], T[1] - Q[1]))
        return out

    def forces(self, state: np.ndarray) -> tuple[list[PointForce], list[float], list[float]]:
        """Point forces of tendons and dampers, with tendon tensions [N] and damper forces [N]."""
        out: list[PointForce] = []
        tensions, dampers = [], []
        for idx, F, p_loc, q_loc, t_loc, corners in self.columns:
            st = state[idx]
            P = _world(st, *p_loc)
            Q = _world(st, *q_loc)
            T = _world(state[1], *t_loc)
            dbx, dby = F[0] - P[0], F[1] - P[1]
            dtx, dty = T[0] - Q[0], T[1] - Q[1]
            db, dt_ = math.hypot(dbx, dby), math.hypot(dtx, dty)
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
                th, w = float(st[2]), float(st[5])
                sg = 1.0 if th >= 0.0 else -1.0
                half = 0.5 * th
                dchord = 2.0 * self.b[idx] * math.cos(half) * sg   # dc/dtheta [m/rad]
                fd = self.c * dchord * w                            # C dc/dt [N]
                if self.damper == "heel":
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
        return out, tensions, dampers


def device_forces(scene: Scene, state: np.ndarray) -> list[PointForce]:
    """Tendon and damper point forces for the bodies' ``state`` (n_bodies, 6)."""
    if not scene.has_devices:
        return []
    return DeviceGeometry(scene, body_specs(scene)).forces(state)[0]


# =========================================================================================
# Contact diagnostics from poses
# =========================================================================================
def _corners(sp: BodySpec):
    hw, hh = sp.half_width, sp.half_height
    return {"bl": (-hw, -hh), "br": (hw, -hh), "tl": (-hw, hh), "tr": (hw, hh)}


class ContactProbe:
    """Penetration, sliding and opening of the contacts the analytic model assumes, computed
    from body poses only (so every engine is measured the same way).

    * base contacts: the two base corners of each column (block) on the foundation surface;
    * top contacts: the two top corners of each column against the beam soffit.

    Penetration: depth of a corner below the surface it rests on [m]. Sliding: tangential
    displacement [m] of a pivot corner along its surface from its rest position, recorded while
    the corner is in contact (gap < ``tol``). Opened: a pivot of the current mechanism has a gap
    larger than ``open_tol`` while the structure rocks.
    """

    def __init__(self, scene: Scene, specs: list[BodySpec], tol: float = 1e-3,
                 open_tol: float = 5e-3):
        self.specs = specs
        self.tol = tol
        self.open_tol = open_tol
        self.frame = isinstance(scene.structure, Frame)
        self.cols = [0, 2] if self.frame else [0]
        self.base_y = {}
        for i in self.cols:
            sp = specs[i]
            self.base_y[i] = sp.y - sp.half_height
        self.rest = {}
        for i in self.cols:
            sp = specs[i]
            for name, (lx, ly) in _corners(sp).items():
                self.rest[(i, name)] = (sp.x + lx, sp.y + ly)
        self.beam = specs[1] if self.frame else None

    def measure(self, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
        """(penetration [m], sliding [m], pivot opened) for one state and rocking mode."""
        pen = 0.0
        slide = 0.0
        opened = False
        for i in self.cols:
            sp = self.specs[i]
            for name in ("bl", "br"):
                lx, ly = _corners(sp)[name]
                X = _world(state[i], lx, ly)
                gap = X[1] - self.base_y[i]
                pen = max(pen, -gap)
                if gap < self.tol:
                    slide = max(slide, abs(X[0] - self.rest[(i, name)][0]))
                pivot = (name == "bl") if mode > 0 else (name == "br")
                if mode != 0 and pivot and gap > self.open_tol:
                    opened = True
            if self.frame:
                bs = self.beam
                for name in ("tl", "tr"):
                    lx, ly = _corners(sp)[name]
                    X = _world(state[i], lx, ly)
                    # corner in the beam's frame, relative to the beam soffit
                    bx, by, bth = state[1][0], state[1][1], state[1][2]
                    c, s = math.cos(bth), math.sin(bth)
                    rx, ry = X[0] - bx, X[1] - by
                    u, v = c * rx + s * ry, -s * rx + c * ry
                    depth = v + bs.half_height   # > 0: corner inside the beam
                    pen = max(pen, depth)
                    u0 = self.rest[(i, name)][0] - bs.x
                    if -depth < self.tol:
                        slide = max(slide, abs(u - u0))
                    pivot = (name == "tr") if mode > 0 else (name == "tl")
                    if mode != 0 and pivot and -depth > self.open_tol:
                        opened = True
        return pen, slide, opened


def contact_diagnostics(scene: Scene, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
    """Convenience wrapper of :class:`ContactProbe` for one state."""
    return ContactProbe(scene, body_specs(scene)).measure(state, mode)


# =========================================================================================
# Events and the effective coefficient of restitution from sampled motion
# =========================================================================================
def measure_impacts(t: np.ndarray, phi: np.ndarray, phidot: np.ndarray, *, alpha: float,
                    free: bool, energy=None, inertia0=None, uplift_tol: float,
                    guard: float = 0.01, window: float = 0.05) -> list[dict[str, Any]]:
    """Impacts (zero crossings of phi between uplifted excursions) and their effective eta.

    Two robust estimates, as recommended by ``shared notes/engines.md``:

    * ``free`` rocking (no ground motion, no devices): energy of successive peaks. With V_s(phi)
      the potential of mechanism s at rest velocity and I_s(0) its generalized inertia at rest,
      eta = sqrt(V_post(peak after) I_pre(0) / (V_pre(peak before) I_post(0))). ``energy(phi)``
      must return V [J] and ``inertia0(s)`` I_s(0) [kg m^2].
    * otherwise: phi' just before and after the crossing, each extrapolated to the crossing time
      by a quadratic fit of phi(t) on a ``window`` [s] that ends (starts) ``guard`` [s] before
      (after) it, so that a soft contact lasting a few milliseconds does not bias the ratio.
    """
    rows: list[dict[str, Any]] = []
    up = np.abs(phi) > uplift_tol
    if not up.any():
        return rows
    sgn = np.sign(phi)
    # crossing indices: sign change between two uplifted excursions
    idx = np.nonzero(up)[0]
    last_i = idx[0]
    last_s = sgn[last_i]
    peaks = []  # (time, |phi| max) of each excursion
    cur_max, cur_t = abs(phi[last_i]), t[last_i]
    for i in idx[1:]:
        if sgn[i] != last_s:
            # zero crossing between last_i and i
            j = last_i + int(np.argmax(np.sign(phi[last_i:i + 1]) != last_s))
            j0 = max(j - 1, 0)
            p0, p1 = phi[j0], phi[j]
            tc = t[j0] + (t[j] - t[j0]) * (p0 / (p0 - p1) if p0 != p1 else 0.0)
            peaks.append((cur_t, cur_max * last_s))
            rows.append(dict(t=float(tc), kind="impact", phi=0.0, direction=int(sgn[i]),
                             _pre=int(last_s)))
            last_s = sgn[i]
            cur_max, cur_t = abs(phi[i]), t[i]
        elif abs(phi[i]) > cur_max:
            cur_max, cur_t = abs(phi[i]), t[i]
        last_i = i
    peaks.append((cur_t, cur_max * last_s))
    for k, r in enumerate(rows):
        pre, post = r.pop("_pre"), r["direction"]
        tc = r["t"]
        vb = _fit_rate(t, phi, tc - guard - window, tc - guard, tc)
        va = _fit_rate(t, phi, tc + guard, tc + guard + window, tc)
        r["phidot_before"], r["phidot_after"] = vb, va
        e = math.nan
        if free and energy is not None:
            pb, pa = peaks[k][1], peaks[k + 1][1]
            Vb, Va = energy(pb), energy(pa)
            if Vb > 0 and Va > 0:
                e = math.sqrt(Va * inertia0(pre) / (Vb * inertia0(post)))
        elif math.isfinite(vb) and math.isfinite(va) and vb != 0.0:
            e = va / vb
        r["eta"] = e
    return rows


def _fit_rate(t, phi, ta, tb, tc) -> float:
    m = (t >= ta) & (t <= tb)
    if m.sum() < 4:
        return math.nan
    c = np.polyfit(t[m] - tc, phi[m], 2)
    return float(c[1])


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
        acc = motion.acceleration if motion is not None else (lambda t: 0.0)
        devices = DeviceGeometry(scene, self.specs) if scene.has_devices else None
        intact = devices is not None
        probe = ContactProbe(scene, self.specs)
        uplift_phi = cfg.uplift_tol * alpha

        dt, odt = cfg.dt, cfg.output_dt
        n_steps = int(math.ceil((t_end - t0) / dt - 1e-9))
        rows_out: list[tuple] = []
        ev: list[dict[str, Any]] = []
        status, reason = "ok", None
        overturned = fractured = False
        t_over = t_frac = None
        max_pen = max_slide = 0.0
        opened = False
        energy0 = None
        free = motion is None and devices is None
        dyn = None
        if free:
            from ..analytic.dynamics import Dynamics  # pure physics: V(phi) and I(0)
            dyn = {s: Dynamics(scene.structure, s) for s in (1, -1)}
        next_out = t0
        prev = None
        try:
            self._build()
            state = np.asarray(self._state(), dtype=float)
            t = t0
            tensions = [0.0, 0.0]
            damp_f = [0.0, 0.0]
            for k in range(n_steps + 1):
                if not np.all(np.isfinite(state)):
                    raise _Diverged(f"non-finite body state at t={t:.6g} s")
                phi = state[0][2]
                # output samples (linear interpolation between steps)
                while next_out <= t + 1e-12 and next_out <= t_end + 1e-12:
                    if prev is None or t == prev[0]:
                        s_out = state
                    else:
                        w = (next_out - prev[0]) / (t - prev[0])
                        s_out = prev[1] + w * (state - prev[1])
                    mode = 0 if abs(s_out[0][2]) <= uplift_phi else (1 if s_out[0][2] > 0 else -1)
                    pen, sl, op = probe.measure(s_out, mode)
                    max_pen, max_slide = max(max_pen, pen), max(max_slide, sl)
                    opened = opened or op
                    el = devices.elongations(s_out) if devices is not None else [0.0, 0.0]
                    rows_out.append((next_out, s_out, mode, intact, el, tensions, damp_f,
                                     float(acc(next_out)), pen, sl))
                    next_out = t0 + len(rows_out) * odt
                if abs(phi) >= fall[1 if phi > 0 else -1]:
                    overturned, t_over = True, t
                    ev.append(dict(t=t, kind="overturn", phi=phi, phidot_before=state[0][5],
                                   phidot_after=state[0][5], direction=1 if phi > 0 else -1))
                    break
                if max_pen > cfg.max_penetration:
                    raise _Diverged(f"penetration {max_pen:.3g} m > max_penetration "
                                    f"{cfg.max_penetration:g} m")
                if max_slide > cfg.max_sliding:
                    raise _Diverged(f"sliding {max_slide:.3g} m > max_sliding "
                                    f"{cfg.max_sliding:g} m")
                if free and dyn is not None:
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
                    el = devices.elongations(state)
                    if devices.eps_f is not None and max(el) / devices.l >= devices.eps_f:
                        intact = False
                        fractured, t_frac = True, t
                        ev.append(dict(t=t, kind="fracture", phi=phi,
                                       phidot_before=state[0][5], phidot_after=state[0][5],
                                       direction=1 if phi > 0 else -1))
                        tensions, damp_f = [0.0, 0.0], [0.0, 0.0]
                        if self.native_devices:
                            self._remove_devices()
                    elif not self.native_devices:
                        forces, tensions, damp_f = devices.forces(state)
                    else:
                        tensions = [devices.k * e for e in el]
                ts = time.perf_counter()
                self._step(-float(acc(t + 0.5 * dt)), forces)
                self.wall_s += time.perf_counter() - ts
                self.steps += 1
                prev = (t, state)
                t = t0 + (k + 1) * dt
                state = np.asarray(self._state(), dtype=float)
        except _Diverged as e:
            status, reason = "diverged", str(e)
        except Exception as e:  # engine failure at the adapter boundary
            status, reason = "diverged", f"{type(e).__name__}: {e}"
        finally:
            try:
                self._close()
            except Exception:
                pass

        history = self._history(rows_out, scene)
        # events from the sampled motion
        if len(history):
            tt = history["t"].to_numpy()
            ph = history["phi"].to_numpy()
            pd_ = history["phidot"].to_numpy()
            up = np.nonzero(np.abs(ph) > uplift_phi)[0]
            if up.size:
                i = int(up[0])
                ev.append(dict(t=float(tt[i]), kind="uplift", phi=float(ph[i]),
                               phidot_before=float(pd_[i]), phidot_after=float(pd_[i]),
                               direction=1 if ph[i] > 0 else -1))
            energy = inertia0 = None
            if free:
                energy = lambda p: dyn[1 if p > 0 else -1].energy(p, 0.0)  # noqa: E731
                inertia0 = lambda s: dyn[s].terms(0.0).inertia  # noqa: E731
            imp = measure_impacts(tt, ph, pd_, alpha=alpha, free=free, energy=energy,
                                  inertia0=inertia0, uplift_tol=uplift_phi)
            if overturned and imp and imp[-1]["t"] > t_over:
                imp = [r for r in imp if r["t"] <= t_over]
            ev.extend(imp)
        events = events_frame(sorted(ev, key=lambda r: r["t"]))
        impacts = events[events["kind"] == "impact"]
        phis = history["phi"].to_numpy() if len(history) else np.zeros(1)
        max_abs = float(np.max(np.abs(phis)))
        ups = events[events["kind"] == "uplift"]
        crit = _critical(scene)
        summary = Summary(
            max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / alpha,
            overturned=overturned, t_overturn=t_over,
            exceeded_critical=overturned or _exceeded(phis, crit, fractured, history),
            uplifted=bool(len(ups)), t_uplift=float(ups["t"].iloc[0]) if len(ups) else None,
            n_impacts=int(len(impacts)), fractured=fractured, t_fracture=t_frac,
            status=status, reason=reason,
            eta_measured=[float(x) for x in impacts["eta"].to_numpy()],
            max_penetration=max_pen, max_sliding=max_slide, contact_opened=opened)
        sim_time = (float(history["t"].iloc[-1]) - t0) if len(history) else 0.0
        cost = Cost(wall_s=self.wall_s, sim_time=sim_time, steps=self.steps)
        settings = asdict(cfg)
        settings["engine_version"] = self.version()
        return Result(backend=self.name, scene=scene,
                      motion=motion.describe() if motion is not None else {"kind": "none"},
                      history=history, events=events, summary=summary, cost=cost,
                      settings=settings)

    def _history(self, rows, scene: Scene) -> pd.DataFrame:
        frame = isinstance(scene.structure, Frame)
        cols: dict[str, list] = {c: [] for c in list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS)}
        for (t, st, mode, intact, el, ten, dmp, a, pen, sl) in rows:
            cols["t"].append(t)
            cols["phi"].append(st[0][2])
            cols["phidot"].append(st[0][5])
            cols["ground_acc"].append(a)
            cols["theta_beam"].append(st[1][2] if frame else math.nan)
            cols["theta_right"].append(st[2][2] if frame else math.nan)
            cols["mode"].append(mode)
            cols["devices_intact"].append(intact)
            on = scene.has_devices and intact
            cols["tendon_elong_left"].append(el[0] if on else 0.0)
            cols["tendon_elong_right"].append(el[1] if on else 0.0)
            cols["tendon_force_left"].append(ten[0] if on else 0.0)
            cols["tendon_force_right"].append(ten[1] if on else 0.0)
            cols["damper_force_left"].append(dmp[0] if on else 0.0)
            cols["damper_force_right"].append(dmp[1] if on else 0.0)
            cols["penetration"].append(pen)
            cols["sliding"].append(sl)
        df = pd.DataFrame(cols)
        df["mode"] = df["mode"].astype("int64")
        df["devices_intact"] = df["devices_intact"].astype(bool)
        return df


def _mech_energy(specs: list[BodySpec], state: np.ndarray) -> float:
    """Kinetic + gravitational energy [J] of the bodies, relative to the rest configuration."""
    e = 0.0
    for sp, st in zip(specs, state):
        e += 0.5 * sp.mass * (st[3] ** 2 + st[4] ** 2) + 0.5 * sp.inertia * st[5] ** 2
        e += sp.mass * G * (st[1] - sp.y)
    return e


def _critical(scene: Scene) -> dict:
    from ..analytic.reference import Reference  # the scene's critical angles (physics library)
    return Reference(scene).critical


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

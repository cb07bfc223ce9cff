"""The shared engine run: stepping (:func:`step_run`) and the turning of sampled body states
into a :class:`~rockbench.result.Result` (:func:`finish`).

:func:`finish` knows nothing of stepping: a batched backend (many cases of one scene in one
engine call) that produces body states on the output grid calls it once per case and gets the
same Result, events, contact diagnostics and divergence verdicts as a stepped run.

What a run does, once for every engine (``docs/architecture.md``):

* time: :func:`~rockbench.engines.base.run_window`; steps of ``dt`` with gravity
  ``(-u_g''(t + dt/2), -(g + u_v''(t + dt/2)))`` (:func:`ground_gravity`; u_v'' the motion's
  vertical component, positive up, 0 without one); output samples on :func:`~rockbench.result.output_grid`,
  linearly interpolated between engine steps;
* devices (frames with tendons/dampers, unless native): :class:`DeviceGeometry` point forces
  from the poses before every step; fracture when a tendon's strain reaches eps_f, after which
  no device force acts (native devices are removed by the adapter);
* overturn: |phi| reaches the scene's fall angle (the run stops);
* online divergence: a non-finite state, energy growth in free rocking (every step), contact
  violations (probed every :data:`PROBE_CHUNK` samples; sliding counts only when the scene
  gives no friction: with a scene friction it is the physics modelled), an exception from the
  engine;
* :func:`finish`: contact diagnostics (:class:`ContactProbe`), events from the sampled motion
  (:mod:`rockbench.measure`), post-run divergence checks, the verdict rules of
  :mod:`rockbench.engines.verdicts` (collapse, a run that stopped early, a run that did not
  move), summary and cost.

Units: SI and radians.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..analytic.closure import closure_function
from ..analytic.reference import reference_of
from ..constants import G
from ..errors import ParameterError, RockbenchError
from ..measure import excursions, measure_impacts
from ..result import (CONTACT_COLUMNS, HISTORY_COLUMNS, Cost, Result, Summary, events_frame,
                      output_grid)
from ..scene.scene import Scene
from ..scene.structure import Frame
from ..verdict import past_critical
from .bodies import BodySpec
from .checks import Diverged, SampleChecks, falling_or_none
from .contacts import ContactProbe
from .devices import DAMPER_MODELS, DeviceGeometry
from .verdicts import (_collapse, _energy_floor, _frozen, _judge_stopped,
                       _peak_energy_growth)

__all__ = ["Stepped", "Outcome", "step_run", "finish", "SampleChecks", "device_geometry",
           "impact_arguments", "ground_gravity", "PROBE_CHUNK", "DRIVE_CHUNKS"]

#: Output samples probed together (vectorized) for the penetration / sliding divergence check.
PROBE_CHUNK = 500

#: The compiled loop returns to Python every DRIVE_CHUNKS x PROBE_CHUNK samples (:func:`_drive`);
#: the checks run on the PROBE_CHUNK chunks of the Python loop all the same.
DRIVE_CHUNKS = 8


@dataclass
class Stepped:
    """What stepping produced, on the output grid (the input of :func:`finish`).

    grid : every output time of the run window [s] (the run may stop before its end);
    states : (n, n_bodies, 6) body states (x, y, theta, vx, vy, omega) at ``grid[:n]``;
    intact : (n,) devices intact at each sample;
    native_report : per sample (tendon tensions [N], damper forces [N]) of native devices, or
        None when the shared formulas apply;
    events : overturn and fracture events found while stepping (dicts of EVENT_COLUMNS);
    status, reason : "ok" or "diverged" and why (online checks, engine exceptions);
    max_penetration, max_sliding : online contact maxima [m] before the structure falls;
    contact : (penetration, sliding, opened) per sample as the checks measured them, when they
        measured every sample (else None: :func:`finish` measures them);
    steps, wall_s : engine steps and seconds spent inside the engine's step call.
    """

    grid: np.ndarray
    states: np.ndarray
    intact: np.ndarray
    native_report: list | None = None
    contact: tuple | None = None
    events: list[dict[str, Any]] = field(default_factory=list)
    status: str = "ok"
    reason: str | None = None
    overturned: bool = False
    t_overturn: float | None = None
    fractured: bool = False
    t_fracture: float | None = None
    max_penetration: float = 0.0
    max_sliding: float = 0.0
    steps: int = 0
    wall_s: float = 0.0


@dataclass
class Outcome:
    """What a map keeps of an engine run (:func:`finish` with ``keep="summary"``): the
    :class:`~rockbench.result.Summary` a full Result would hold - every field but
    ``eta_measured``, which stays empty (a map does not measure the impacts' eta) - its
    :class:`~rockbench.result.Cost`, the backend's name and settings (with
    ``engine_version``); no history, no events frame, no impact rows (``impacts`` is empty:
    kept so that a sweep row reads an Outcome as a Result, its eta means NaN)."""

    backend: str
    summary: Summary
    cost: Cost
    impacts: list[dict[str, Any]]
    settings: dict[str, Any]

    @property
    def status(self) -> str:
        return self.summary.status


def _eta(row: dict[str, Any]) -> float:
    """An impact row's eta as the events frame holds it (missing -> NaN)."""
    e = row.get("eta")
    return math.nan if e is None else float(e)


def device_geometry(backend) -> DeviceGeometry | None:
    """The shared device geometry of the backend's scene (None without devices), with the
    damper model of the backend's settings (``damper``, default "couple")."""
    scene = backend.scene
    if not scene.has_devices:
        return None
    damper = getattr(backend.settings, "damper", "couple")
    return DeviceGeometry(scene, backend.specs, damper if damper in DAMPER_MODELS else "couple")


def ground_gravity(motion, t_mid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The gravity (gravity_x, gravity_y) [m/s^2] of the engine steps at their midpoints
    ``t_mid`` [s]: (-u_g''(t), -(g + u_v''(t))), the ground motion as the inertial force of the
    foundation's frame, exact for rigid bodies (poses relative to the moving ground). u_v'':
    ``motion.vertical``'s acceleration (positive up), else 0 (gravity_y exactly -g)."""
    n = t_mid.size
    if motion is None or not n:
        return np.zeros(n), np.full(n, -G)
    gx = -np.asarray(motion.acceleration(t_mid), dtype=float).reshape(n)
    vertical = getattr(motion, "vertical", None)
    if vertical is None:
        return gx, np.full(n, -G)
    av = np.asarray(vertical.acceleration(t_mid), dtype=float).reshape(n)
    return gx, -(G + av)


def step_run(backend, motion, t0: float, t_end: float, phi0: float) -> Stepped:
    """Step ``backend`` (an :class:`~rockbench.engines.base.EngineBackend` whose ``specs``,
    ``foundation`` and ``poses0`` are set) from ``t0`` to ``t_end`` [s] under ``motion`` (None:
    free rocking from ``phi0`` [rad]); never raises for an engine failure (status "diverged").

    Per step the loop does only what the scene requires: the ground motion's gravity
    (precomputed for every step), device forces and the fracture check only while a scene's
    devices are intact, the overturn check, the engine step and the state read. Samples go into
    a preallocated array; the checks that need no per-step resolution (non-finite state,
    energy growth in free rocking, contact violations) run on the samples, in chunks of
    :data:`PROBE_CHUNK` (vectorized), and report the first offending sample.
    """
    scene, cfg = backend.scene, backend.settings
    specs = backend.specs
    nb = len(specs)
    fall_p, fall_n = scene.fall_angles[1], scene.fall_angles[-1]
    devices = device_geometry(backend)
    native = bool(backend.native_devices)
    intact = devices is not None
    check_strain = devices is not None and devices.eps_f is not None
    probe = ContactProbe(scene, specs)
    uplift_phi = cfg.uplift_tol * scene.alpha
    crit = reference_of(scene).critical

    dt = cfg.dt
    grid = output_grid(t0, t_end, cfg.output_dt)
    n_out = grid.size
    n_steps = int(math.ceil((t_end - t0) / dt - 1e-9))
    t_tol = 1e-9 * dt
    # the time of every step's start, as the loop has always computed it (t0 + k dt), and the
    # ground motion's gravity at the step's midpoint, in one vectorized call
    t_steps = t0 + np.arange(1, n_steps + 1) * dt
    t_mid = np.concatenate(([t0], t_steps[:-1]))[:n_steps] + 0.5 * dt
    gx, gy = ground_gravity(motion, t_mid)
    vertical = getattr(motion, "vertical", None) is not None
    states = np.empty((n_out, nb, 6))
    sample_intact = np.zeros(n_out, dtype=bool)
    native_report: list[tuple] = []
    out = Stepped(grid=grid, states=states[:0], intact=sample_intact[:0])
    checker = SampleChecks(cfg, specs, probe, crit, uplift_phi,
                            free=motion is None and devices is None,
                            energy_floor=_energy_floor(reference_of(scene)),
                            sliding=scene.contact.given)
    n = 0                              # samples written
    no_forces: tuple = ()
    backend.steps = 0
    backend.wall_s = 0.0
    step = backend._step
    read = backend._state
    clock = time.perf_counter
    try:
        _build(backend)
        state = np.array(read(), dtype=float)
        kernel = backend._compiled_loop()
        if kernel is not None:
            n = _drive(kernel, state=state, gx=gx, gy=gy, t_steps=t_steps, grid=grid, t0=t0,
                       t_tol=t_tol, states=states, sample_intact=sample_intact,
                       intact=intact, fall=(fall_p, fall_n), devices=devices,
                       check_strain=check_strain, checker=checker, out=out, backend=backend)
            raise _Done
        gx, gy, t_steps = gx.tolist(), gy.tolist(), t_steps.tolist()  # Python floats
        gridl = grid.tolist()
        prev_t, prev = None, None
        t = t0
        for k in range(n_steps + 1):
            phi = state[0, 2]
            if phi != phi:
                raise Diverged(f"non-finite body state at t={t:.6g} s")
            # output samples on the fixed grid (linear interpolation between steps)
            while n < n_out and gridl[n] <= t + t_tol:
                if prev is None or t == prev_t or gridl[n] == t:
                    states[n] = state
                else:
                    w = (gridl[n] - prev_t) / (t - prev_t)
                    states[n] = prev + w * (state - prev)
                sample_intact[n] = intact
                if native:
                    native_report.append(
                        backend._native_device_report(devices, states[n],
                                                      devices.elongations(states[n]))
                        if intact else ([0.0, 0.0], [0.0, 0.0]))
                n += 1
                if n - checker.checked >= PROBE_CHUNK:
                    checker.check(states, sample_intact, grid, n, out)
            if phi >= fall_p or -phi >= fall_n:
                out.overturned, out.t_overturn = True, t
                out.events.append(dict(t=t, kind="overturn", phi=phi,
                                       phidot_before=state[0, 5], phidot_after=state[0, 5],
                                       direction=1 if phi > 0 else -1))
                break
            if k == n_steps:
                break
            forces = no_forces
            if intact:
                if native:
                    el = devices.elongations(state) if check_strain else None
                else:                      # the forces, and the elongations with them
                    forces = devices.forces(state)[0]
                    el = devices.last_elongations
                if check_strain and max(el) / devices.l >= devices.eps_f:
                    forces = no_forces
                    intact = False
                    out.fractured, out.t_fracture = True, t
                    out.events.append(dict(t=t, kind="fracture", phi=phi,
                                           phidot_before=state[0, 5],
                                           phidot_after=state[0, 5],
                                           direction=1 if phi > 0 else -1))
                    if native:
                        backend._remove_devices()
            ts = clock()
            step(gx[k], forces, gy[k]) if vertical else step(gx[k], forces)  # default: -g
            backend.wall_s += clock() - ts
            backend.steps += 1
            prev_t, prev = t, state
            t = t_steps[k]
            state = np.asarray(read(), dtype=float)      # a new array every step (contract)
        checker.check(states, sample_intact, grid, n, out)
    except _Done:
        pass
    except Diverged as e:
        n = getattr(e, "samples", n)
        out.status, out.reason = "diverged", str(e)
    except RockbenchError:            # bad input found at the boundary: not physics
        raise
    except Exception as e:  # engine failure at the adapter boundary
        out.status, out.reason = "diverged", f"{type(e).__name__}: {e}"
    finally:
        try:
            backend._close()
        except Exception:
            pass
    if out.status != "ok" and checker.stop_at is not None:
        n = min(n, checker.stop_at)     # the history ends at the first offending sample
    out.states = states[:n]
    out.intact = sample_intact[:n]
    out.native_report = native_report[:n] if native else None
    out.max_penetration, out.max_sliding = checker.max_pen, checker.max_slide
    if checker.checked >= n and checker.contact is not None:
        out.contact = tuple(a[:n] for a in checker.contact)
    out.steps, out.wall_s = backend.steps, backend.wall_s
    return out


class _Done(Exception):
    """A compiled loop finished the run (leaves the Python loop)."""


def _build(backend) -> None:
    """``backend._build()``, with the engine's refusals translated at the adapter boundary:
    an engine that cannot build the scene with these settings (MuJoCo's "mass and inertia of
    moving bodies must be larger than mjMINVAL", an XML number too large, a C integer
    overflow) was given an impossible input - a :class:`ParameterError` naming the settings
    and the engine's words (exit 2 on the command line), not a run that "diverged"."""
    try:
        backend._build()
    except RockbenchError:
        raise
    except Exception as e:
        detail = " ".join(f"{type(e).__name__}: {e}".split())
        raise ParameterError("scene", backend.scene.name,
                             f"a scene {backend.name} can build with these settings",
                             f"{backend.name} refused it: {detail[:300]}") from None


def _drive(kernel, *, state, gx, gy, t_steps, grid, t0, t_tol, states, sample_intact, intact,
           fall, devices, check_strain, checker, out, backend) -> int:
    """Run a compiled stepping loop (``backend._compiled_loop()``, the protocol of
    :func:`rockbench.engines.compiled_loop.run_kernel`) to the end of the run, with the sample
    checks of the Python loop; return the samples written. Raises :class:`Diverged` as the
    Python loop does.

    The kernel returns to Python every :data:`DRIVE_CHUNKS` x :data:`PROBE_CHUNK` samples
    (a return costs ~56 us of numba dispatch, the price of ~15 engine steps); the checks then
    run on the same chunks, in the same order, as the Python loop's (:func:`_boundaries`). A
    chunk that fails ends the run where the Python loop ends it - its samples, steps and
    events (a fracture or an overturn the kernel found after that chunk's end is not
    recorded), so the run is the same; the kernel only stepped further in a run that
    diverged (``tests/engines/test_map_path.py``)."""
    from .compiled_loop import LoopState as L
    from .device_kernel import device_params

    ls = np.zeros(L.SIZE)
    ls[L.INTACT], ls[L.T] = 1.0 if intact else 0.0, t0
    prev = np.zeros_like(state)
    dev = device_params(devices) if devices is not None else np.zeros(0)
    clock = time.perf_counter
    # the time of every step's end (index k: after k steps) plus the loop's tolerance
    t_tolled = np.concatenate(([t0], t_steps)) + t_tol
    n = 0

    def fracture(before: float = math.inf) -> None:   # the event, as the Python loop has it
        if ls[L.FRAC] and not out.fractured and ls[L.T_FRAC] < before:
            t, phi, pd_ = ls[L.T_FRAC], ls[L.PHI_FRAC], ls[L.PD_FRAC]
            out.fractured, out.t_fracture = True, float(t)
            out.events.append(dict(t=float(t), kind="fracture", phi=float(phi),
                                   phidot_before=float(pd_), phidot_after=float(pd_),
                                   direction=1 if phi > 0 else -1))

    def check_chunks(n: int) -> None:  # the Python loop's chunk checks up to sample n
        for end, k in _boundaries(grid, t_tolled, checker.checked, n):
            try:
                checker.check(states, sample_intact, grid, end, out)
            except Diverged as e:   # the Python loop stopped here: after k steps, end samples
                backend.steps = k
                fracture(before=t_steps[k - 1] if k else t0)
                e.samples = end
                raise
    try:
        while True:
            ts = clock()
            code = kernel(gx, gy, t_steps, grid, t_tol, states, sample_intact, state, prev, ls,
                          fall[0], fall[1], backend.settings.dt, dev, bool(check_strain),
                          checker.checked + DRIVE_CHUNKS * PROBE_CHUNK)
            backend.wall_s += clock() - ts
            backend.steps = int(ls[L.STEPS])
            n = int(ls[L.N])
            check_chunks(n)
            if code != 1:
                break
        fracture()
        if code == 3:
            raise Diverged(f"non-finite body state at t={ls[L.T]:.6g} s")
        if code == 2:
            t, phi, pd_ = ls[L.T_OVER], ls[L.PHI_OVER], ls[L.PD_OVER]
            out.overturned, out.t_overturn = True, float(t)
            out.events.append(dict(t=float(t), kind="overturn", phi=float(phi),
                                   phidot_before=float(pd_), phidot_after=float(pd_),
                                   direction=1 if phi > 0 else -1))
        checker.check(states, sample_intact, grid, n, out)
    except Diverged as e:
        if not hasattr(e, "samples"):
            e.samples = n
        raise
    return n


def _boundaries(grid: np.ndarray, t_tolled: np.ndarray, start: int, n: int):
    """The (samples written, steps taken) at which the Python loop checks samples
    ``start`` ... ``n`` - 1: its first return after ``PROBE_CHUNK`` more samples, from where
    the last check ended, for every such return within the ``n`` samples written.
    ``t_tolled[k]``: the time after k steps plus the loop's tolerance (a sample at grid time
    tg is written once tg <= t + tol)."""
    while start + PROBE_CHUNK <= n:
        k = int(np.searchsorted(t_tolled, grid[start + PROBE_CHUNK - 1], "left"))
        end = int(np.searchsorted(grid, t_tolled[k], "right"))
        if end > n:
            return
        yield end, k
        start = end


def finish(scene: Scene, motion, settings, specs: list[BodySpec], stepped: Stepped, *,
           phi0: float, t0: float, backend_name: str, engine_version: str,
           devices: DeviceGeometry | None, keep: str = "all") -> Result | Outcome:
    """The Result of an engine run from its samples on the output grid (see :class:`Stepped`):
    history with contact diagnostics, events (uplift, impacts with the effective eta, fracture,
    overturn), post-run divergence checks (penetration, sliding, energy gained between peaks
    after the ground motion), summary and cost. ``settings`` is the backend's Settings
    (``uplift_tol``, ``max_penetration``, ``max_sliding``, ``energy_gain_tol``); the sliding
    tolerance applies only when the scene gives no friction (with one, sliding is physics).

    ``keep="summary"`` (what a map keeps: status and reason, verdict, peak, impacts, fracture,
    contact maxima): returns an :class:`Outcome` whose summary equals the full Result's field
    by field except ``eta_measured`` (empty), without the history and events frames and
    without measuring every impact's eta (``tests/engines/test_map_path.py``). Its impacts are
    counted from the excursions (:func:`~rockbench.measure.measure_impacts` measures one per
    excursion that begins with an impact); they are measured only where a verdict needs them:
    every impact of a run that overturned (those after the overturn do not count), and, for
    the rule "two impacts and not one measurable eta: invalid" (:func:`_unmeasured`), the
    first impact (on the history up to the end of the excursion after it, which is all its
    measurement reads), then all of them if its eta is not finite."""
    if keep not in ("all", "summary"):
        raise ParameterError("keep", keep, "'all' (the Result) or 'summary' (an Outcome)")
    cfg = settings
    alpha = scene.alpha
    ref = reference_of(scene)
    crit = ref.critical
    uplift_phi = cfg.uplift_tol * alpha
    S = stepped.states
    n = S.shape[0]
    tt = stepped.grid[:n]
    ph = S[:, 0, 2]
    pd_ = S[:, 0, 5]
    intact = stepped.intact
    status, reason = stepped.status, stepped.reason
    overturned, t_over = stepped.overturned, stepped.t_overturn
    collapse = None
    if not overturned and n:
        quiet = t0 if motion is None else float(motion.t_end)
        collapse = _collapse(tt, ph, intact, crit, quiet)
        if collapse is not None:
            overturned, t_over = True, float(tt[collapse])
    modes = np.where(np.abs(ph) <= uplift_phi, 0, np.sign(ph)).astype(np.int64)
    if stepped.contact is not None and len(stepped.contact[0]) == n:
        pen, sl, op = stepped.contact
    else:
        pen, sl, op = ContactProbe(scene, specs).measure_many(S, modes)
    falling = falling_or_none(ph, intact, crit)
    if falling is None:
        falling = np.zeros(n, dtype=bool)
    # contact violations while the structure is past its critical angle do not make a run
    # diverged if it goes on to overturn (an engine's falling bodies may slide or sink: the
    # verdict is what matters); before that, or if it never overturns, they do
    pen_pre = float(pen[~falling].max(initial=0.0))
    sl_pre = float(sl[~falling].max(initial=0.0))
    pen_all = float(pen.max(initial=0.0))
    sl_all = float(sl.max(initial=0.0))
    max_pen = max(stepped.max_penetration, pen_pre if overturned else pen_all)
    max_slide = max(stepped.max_sliding, sl_pre if overturned else sl_all)
    opened = bool(op.any())
    history = (_history(scene, motion, tt, S, modes, intact, devices, stepped.native_report,
                        pen, sl) if keep == "all" else None)
    intact_b = intact.astype(bool)
    ev = list(stepped.events)
    if collapse is not None:
        ev.append(dict(t=t_over, kind="overturn", phi=float(ph[collapse]),
                       phidot_before=float(pd_[collapse]), phidot_after=float(pd_[collapse]),
                       direction=1 if ph[collapse] > 0 else -1))
    # events from the sampled motion
    free = motion is None and devices is None
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
    dyn = ref.dyn if len(exc) else None
    measure = impact_arguments(scene, motion, cfg, free)
    counted = keep == "summary" and not overturned     # a map's impacts, counted (docstring)
    if counted:
        imp = None
        n_imp = sum(x.after_impact for x in exc)
    else:
        imp = measure_impacts(tt, ph, pd_, intact=intact, **measure)
        if overturned:
            imp = [r for r in imp if r["t"] <= t_over]
        n_imp = len(imp)
        if keep == "all":
            ev.extend(imp)
    if status == "ok":
        if max_pen > cfg.max_penetration:
            status, reason = "diverged", (f"penetration {max_pen:.3g} m > max_penetration "
                                          f"{cfg.max_penetration:g} m")
        elif max_slide > cfg.max_sliding and not scene.contact.given:
            status, reason = "diverged", (f"sliding {max_slide:.3g} m > max_sliding "
                                          f"{cfg.max_sliding:g} m")
        else:
            quiet = t0 if motion is None else float(motion.t_end)
            reason = _peak_energy_growth(exc, tt, ph, intact_b, dyn, quiet,
                                         cfg.energy_gain_tol, alpha)
            if reason is not None:
                status = "diverged"
            elif imp is not None:
                status, reason = _unmeasured(imp, cfg)
            elif n_imp >= 2 and not _first_eta_finite(tt, ph, pd_, intact, exc, measure):
                imp = measure_impacts(tt, ph, pd_, intact=intact, **measure)
                status, reason = _unmeasured(imp, cfg)
        if status == "ok":
            reason = _frozen(scene, motion, ref, tt, ph, intact.astype(bool), phi0, t0,
                             uplift_phi, slid=sl_all if scene.contact.given else 0.0)
            if reason is not None:
                status = "invalid"
    elif status == "diverged" and n and not overturned:
        over, t_o, note = _judge_stopped(scene, motion, ref, tt, ph, pd_, intact.astype(bool),
                                         t0)
        if over:                      # the fall the analytic model finished from the last state
            overturned, t_over = True, t_o
            ev.append(dict(t=t_o, kind="overturn", phi=float(ph[-1]),
                           phidot_before=float(pd_[-1]), phidot_after=float(pd_[-1]),
                           direction=1 if ph[-1] > 0 else -1))
        reason = f"{reason}; {note}" if note else reason
    rows = sorted(ev, key=lambda r: r["t"])
    impacts = [r for r in rows if r["kind"] == "impact"]
    max_abs = float(np.max(np.abs(ph))) if ph.size else 0.0
    ups = [r for r in rows if r["kind"] == "uplift"]
    uplifted = bool(len(ups)) or (phi0 != 0.0 and n > 0)
    t_up = float(ups[0]["t"]) if len(ups) else (t0 if uplifted else None)
    summary = Summary(
        max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / alpha,
        overturned=overturned, t_overturn=t_over,
        exceeded_critical=overturned or bool(past_critical(ph, intact_b, crit).any()),
        uplifted=uplifted, t_uplift=t_up,
        n_impacts=n_imp, fractured=stepped.fractured,
        t_fracture=stepped.t_fracture, status=status, reason=reason,
        eta_measured=[_eta(r) for r in impacts],
        max_penetration=max(max_pen, pen_all), max_sliding=max(max_slide, sl_all),
        contact_opened=opened)
    sim_time = (float(tt[-1]) - t0) if tt.size else 0.0
    cost = Cost(wall_s=stepped.wall_s, sim_time=sim_time, steps=stepped.steps)
    out_settings = asdict(cfg)
    out_settings["engine_version"] = engine_version
    if keep == "summary":
        return Outcome(backend=backend_name, summary=summary, cost=cost, impacts=[],
                       settings=out_settings)
    events = events_frame(rows)
    return Result(backend=backend_name, scene=scene,
                  motion=motion.describe() if motion is not None else {"kind": "none"},
                  history=history, events=events, summary=summary, cost=cost,
                  settings=out_settings)


def impact_arguments(scene: Scene, motion, settings, free: bool) -> dict[str, Any]:
    """The keyword arguments (but ``intact``) of :func:`~rockbench.measure.measure_impacts`
    for an engine run of ``scene`` under ``motion`` (None: free rocking) with ``settings``
    (``uplift_tol``); ``free``: no ground motion and no devices. Impacts: the energy of
    successive peaks in free rocking; otherwise the mechanism's own equation of motion (device
    forces, ground motion) integrated from either side of each impact to phi = 0
    (``docs/metrics.md``)."""
    alpha = scene.alpha
    dyn = reference_of(scene).dyn
    energy = inertia0 = None
    if free:
        energy = lambda p: dyn[1 if p > 0 else -1].energy(p, 0.0)  # noqa: E731
        inertia0 = lambda s: dyn[s].terms(0.0).inertia  # noqa: E731
    return dict(alpha=alpha, free=free, energy=energy, inertia0=inertia0,
                uplift_tol=settings.uplift_tol * alpha,
                rest_rate=settings.uplift_tol * alpha * scene.p, dynamics=dyn,
                ground_acc=motion.acceleration if motion is not None else None,
                closure=closure_function(scene, motion))


def _first_eta_finite(t, phi, phidot, intact, exc: list, measure: dict) -> bool:
    """Whether the run's first impact has a finite eta, measured by
    :func:`~rockbench.measure.measure_impacts` (arguments ``measure``) on the samples up to
    the last of the excursion it begins: an impact's measurement reads only the samples of the
    two excursions around it, so this is the full history's first impact bit for bit
    (``tests/engines/test_map_path.py``)."""
    first = next((x for x in exc if x.after_impact), None)
    if first is None:
        return False
    m = first.i1 + 1
    rows = measure_impacts(t[:m], phi[:m], phidot[:m], intact=intact[:m], **measure)
    return len(rows) == 1 and math.isfinite(_eta(rows[0]))


def _unmeasured(impacts: list, cfg) -> tuple[str, str | None]:
    """("invalid", why) for a run that finished without an engine failure but whose result
    cannot be read as rocking, else ("ok", None):

    * two or more impacts and not one measurable eta (e.g. ``output_dt`` of 10 ms is too coarse
      for the velocity fits around an impact under a ground motion): the run's impacts are
      unmeasured, not good.

    Slip while an overturning structure falls stays allowed here (``tests/engines/
    test_falling.py``: the verdict is what matters); ``rockbench stress`` flags it against the
    reference instead.
    """
    etas = [r.get("eta") for r in impacts if r.get("kind") == "impact"]
    if len(etas) >= 2 and not any(e is not None and math.isfinite(e) for e in etas):
        return "invalid", (f"none of the {len(etas)} impacts has a measurable eta (output_dt = "
                           f"{cfg.output_dt:g} s is too coarse to measure an impact; use "
                           "output_dt <= 2e-3 s)")
    return "ok", None


def _history(scene: Scene, motion, t: np.ndarray, S: np.ndarray, modes: np.ndarray,
             intact: np.ndarray, devices: DeviceGeometry | None, native_report: list | None,
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
        if native_report:
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


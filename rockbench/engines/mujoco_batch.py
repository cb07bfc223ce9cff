"""MuJoCo's batched path: many ground motions of one scene in ``mujoco.rollout`` (the whole run
in C), each case stopped at its overturn verdict.

:class:`~rockbench.engines.mujoco.MujocoBackend` declares ``batched = True`` and reaches this
module through its ``run_batch`` / ``batch_refusal`` classmethods (what sweeps call, through the
registry); the adapter itself (the MJCF model, the Python and compiled stepping loops) is
:mod:`rockbench.engines.mujoco`, as :mod:`rockbench.engines.chipmunk` holds pymunk's C entry
points beside :mod:`rockbench.engines.pymunk`.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..constants import G
from ..errors import ParameterError
from .loop import Diverged, SampleChecks, Stepped, device_geometry, finish, ground_gravity
from .mujoco import MujocoBackend, MujocoSettings

__all__ = ["run_batch", "batch_refusal", "VERDICT_CHUNK"]


def batch_refusal(scene, settings: MujocoSettings) -> str | None:
    """Why the batched path cannot run ``scene`` with ``settings`` (None: it can). Between two
    steps it can change nothing, so it refuses what needs Python there: dampers (their
    coefficients follow the state), fracture (devices removed mid-run) and devices applied as
    shared point forces."""
    if scene.has_devices:
        dv = scene.devices
        if settings.devices != "native":
            return "devices='forces' are computed from the poses between steps"
        if dv.has_dampers:
            return "the dampers' coefficients are updated from the state between steps"
        if dv.fracture_strain is not None:
            return "fracture removes the tendons between steps"
    return None


#: Steps of one ``mujoco.rollout`` call of a case on the single-thread batched path, between
#: which the overturn verdict is checked (a case that overturned is not simulated further).
VERDICT_CHUNK = 1000


def run_batch(scene, motions, *, duration: float | None = None, settings=None,
              nthread: int | None = None, keep: str = "all", **overrides) -> list:
    """Run ``scene`` under each ground motion of ``motions`` (from rest, phi0 = 0) in MuJoCo,
    with the whole run of every case inside ``mujoco.rollout`` (threads: ``nthread``, default
    one per core), and return one :class:`~rockbench.result.Result` per motion - the same
    Result the plain path (``rb.run(scene, m, engine="mujoco")``) gives, to within floating
    point: the ground motion enters as the open-loop generalized force m_i * (-u_g''(t +
    dt/2)) on every body's slide-x joint (``qfrc_applied``) instead of a horizontal gravity,
    and a vertical component's m_i * (-u_v''(t + dt/2)) on its slide-z joint, which are the
    same forces summed in another order (tested against the plain path).

    Raises ParameterError naming the reason when :func:`batch_refusal` refuses the scene
    (callers fall back to the plain path). ``duration`` [s] as in ``run`` (None: each motion's
    length + 10 s). ``keep``: as in ``run`` ("summary": an Outcome per motion).

    With one thread (``nthread=1``, what sweeps use: one process per core), each case is rolled
    out in calls of :data:`VERDICT_CHUNK` steps, its solver warm start carried from one call to
    the next (bit for bit the states of one long call), and stops at the first call in which it
    overturned: steps after the verdict are not paid. With several threads the cases run to
    their end in one call (threads share the cases, not a case's steps)."""
    import time

    import mujoco
    from mujoco import rollout

    from .base import check_vertical, run_window

    cpu = time.process_time()
    backend = MujocoBackend(scene, settings, **overrides)
    cfg = backend.settings
    why = batch_refusal(scene, cfg)
    if why is not None:
        raise ParameterError("scene", scene.name, "a scene the batched MuJoCo path can run", why)
    ok, version = MujocoBackend.available()
    if not ok:
        from ..errors import BackendUnavailable
        raise BackendUnavailable(f"backend 'mujoco' is not available: {version}")
    motions = list(motions)
    backend.build(0.0)
    m, d = backend.model, backend.data
    nb, nq, nv = len(backend.specs), m.nq, m.nv
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, state0, spec)
    masses = np.array([sp.mass for sp in backend.specs])
    dt = cfg.dt
    windows, groups = [], {}
    for i, mo in enumerate(motions):
        t0, t_end = run_window(scene, mo, duration, 0.0)
        check_vertical(MujocoBackend, mo)
        n_steps = int(math.ceil((t_end - t0) / dt - 1e-9))
        windows.append((t0, t_end, n_steps))
        groups.setdefault(n_steps, []).append(i)
    nthread = nthread or os.cpu_count() or 1
    datas = [mujoco.MjData(m) for _ in range(max(1, nthread))]
    runner = rollout.Rollout(nthread=nthread if nthread > 1 else None)
    results: list = [None] * len(motions)
    for n_steps, idx in groups.items():
        ctrl = np.zeros((len(idx), n_steps, nv))
        for j, i in enumerate(idx):
            t0 = windows[i][0]
            t_steps = t0 + np.arange(1, n_steps + 1) * dt
            t_mid = np.concatenate(([t0], t_steps[:-1])) + 0.5 * dt
            gx, gy = ground_gravity(motions[i], t_mid)
            ctrl[j][:, 0:3 * nb:3] = gx[:, None] * masses[None, :]
            if getattr(motions[i], "vertical", None) is not None:   # beyond the model's -g
                ctrl[j][:, 1:3 * nb:3] = (gy + G)[:, None] * masses[None, :]
        if nthread == 1:
            for j, i in enumerate(idx):
                wall = time.perf_counter()
                states = _rollout_to_verdict(runner, m, datas[0], state0, ctrl[j], n_steps,
                                             scene.fall_angles)
                wall = time.perf_counter() - wall
                q = np.concatenate((state0[None, 1:1 + nq], states[:, 1:1 + nq]))
                v = np.concatenate((state0[None, 1 + nq:1 + nq + nv],
                                    states[:, 1 + nq:1 + nq + nv]))
                results[i] = _finish_batch(backend, motions[i], windows[i], q, v, wall,
                                           version, keep)
            continue
        init = np.repeat(state0[None, :], len(idx), axis=0)
        wall = time.perf_counter()
        state, _ = runner.rollout([m] * len(idx), datas, init, ctrl,
                                  control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED,
                                  nstep=n_steps)
        wall = (time.perf_counter() - wall) / len(idx)
        for j, i in enumerate(idx):
            q = np.concatenate((state0[None, 1:1 + nq], state[j, :, 1:1 + nq]))
            v = np.concatenate((state0[None, 1 + nq:1 + nq + nv],
                                state[j, :, 1 + nq:1 + nq + nv]))
            results[i] = _finish_batch(backend, motions[i], windows[i], q, v, wall, version,
                                       keep)
    share = (time.process_time() - cpu) / max(len(motions), 1)
    for r in results:
        r.cost.cpu_s = share          # the batch's process CPU time, shared equally
    return results


def _rollout_to_verdict(runner, m, d, state0: np.ndarray, ctrl: np.ndarray, n_steps: int,
                        fall: dict) -> np.ndarray:
    """The rollout states (k, nstate) of one case from ``state0`` under ``ctrl`` (n_steps,
    nv), in calls of :data:`VERDICT_CHUNK` steps on the data ``d``, carrying the solver's warm
    start, until the call in which phi (qpos[2], the first body's rotation) reached a fall angle
    of ``fall`` (k < n_steps) or the end (k = n_steps)."""
    import mujoco

    spec = mujoco.mjtState.mjSTATE_QFRC_APPLIED
    out = np.empty((n_steps, state0.size))
    init, warm, k = state0[None, :], None, 0
    while k < n_steps:
        n = min(VERDICT_CHUNK, n_steps - k)
        st, _ = runner.rollout([m], [d], init, ctrl[None, k:k + n], control_spec=spec,
                               nstep=n, initial_warmstart=warm)
        out[k:k + n] = st[0]
        k += n
        phi = st[0, :, 1 + 2]
        if np.any((phi >= fall[1]) | (-phi >= fall[-1])):
            break
        init, warm = st[:, -1], d.qacc_warmstart.copy()[None, :]
    return out[:k]


def _finish_batch(backend, motion, window, q, v, wall: float, version: str,
                  keep: str = "all"):
    """Step states (k + 1, nq), (.., nv) of one batched case (k <= n_steps steps: a case
    stopped at its verdict has fewer) -> its Result (``keep="summary"``: Outcome), through the
    loop's sampling rules (overturn stop, samples on the output grid, sample checks); ``wall``
    [s]: the rollout's time for the k steps."""
    from ..analytic.reference import reference_of
    from ..result import output_grid
    from .contacts import ContactProbe

    scene, cfg = backend.scene, backend.settings
    t0, t_end, n_steps = window
    nb = len(backend.specs)
    n_done = q.shape[0] - 1                    # steps simulated
    S = np.empty((n_done + 1, nb, 6))
    q3, v3 = q.reshape(-1, nb, 3), v.reshape(-1, nb, 3)
    S[:, :, 0:2] = backend._rest[None] + q3[:, :, 0:2]
    S[:, :, 2] = q3[:, :, 2]
    S[:, :, 3:6] = v3
    times = np.concatenate(([t0], t0 + np.arange(1, n_done + 1) * cfg.dt))
    phi = S[:, 0, 2]
    fall_p, fall_n = scene.fall_angles[1], scene.fall_angles[-1]
    over = np.flatnonzero((phi >= fall_p) | (-phi >= fall_n))
    out = Stepped(grid=output_grid(t0, t_end, cfg.output_dt), states=S[:0],
                  intact=np.zeros(0, bool))
    last = n_done
    if over.size:
        last = int(over[0])
        out.overturned, out.t_overturn = True, float(times[last])
        out.events.append(dict(t=float(times[last]), kind="overturn", phi=float(phi[last]),
                               phidot_before=float(S[last, 0, 5]),
                               phidot_after=float(S[last, 0, 5]),
                               direction=1 if phi[last] > 0 else -1))
    # samples: the first step at or after each grid time (within the loop's tolerance),
    # interpolated from the step before unless the times coincide
    grid = out.grid
    tol = 1e-9 * cfg.dt
    k = np.searchsorted(times[:last + 1], grid - tol, side="left")
    inside = k <= last
    grid_k, k = grid[inside], k[inside]
    exact = (k == 0) | (times[k] == grid_k)
    km = np.maximum(k - 1, 0)
    w = np.where(exact, 1.0, (grid_k - times[km]) / np.where(exact, 1.0, times[k] - times[km]))
    samples = np.where(exact[:, None, None], S[k],
                       S[km] + w[:, None, None] * (S[k] - S[km]))
    out.states = samples
    out.intact = np.full(len(samples), scene.has_devices)
    out.steps, out.wall_s = last, wall * last / max(n_done, 1)
    checker = SampleChecks(cfg, backend.specs, ContactProbe(scene, backend.specs),
                            reference_of(scene).critical, cfg.uplift_tol * scene.alpha,
                            free=False, sliding=scene.contact.given)
    try:
        checker.check(samples, out.intact, grid, len(samples), out)
    except Diverged as e:
        out.status, out.reason = "diverged", str(e)
        if checker.stop_at is not None:
            out.states, out.intact = samples[:checker.stop_at], out.intact[:checker.stop_at]
    out.max_penetration, out.max_sliding = checker.max_pen, checker.max_slide
    devices = device_geometry(backend)
    if devices is not None:                     # native tendons: k x the shared elongations
        el = devices.history(out.states)[0]
        out.native_report = [(list(devices.k * e), [0.0, 0.0]) for e in el]
    return finish(scene, motion, cfg, backend.specs, out, phi0=0.0, t0=t0,
                  backend_name="mujoco", engine_version=version,
                  devices=devices, keep=keep)

"""The stepping loop of :func:`rockbench.engines.loop.step_run` in compiled code, for engines
whose C step function can be called directly (pymunk's Chipmunk, MuJoCo).

Through Python, one step of a three-body frame costs about 1 microsecond inside Chipmunk and
several more in the calls around it, so a run spends most of its time in rockbench's loop.
:func:`run_kernel` is that loop in numba - ground-motion gravity (horizontal and vertical), device forces and the
fracture check, the overturn check, the engine's step, the state read, the output samples with
their linear interpolation - calling the engine's exported C functions by address (found with
``ctypes`` in the engine's own library) on the world the adapter built. It returns to Python
every ``DRIVE_CHUNKS`` x :data:`~rockbench.engines.loop.PROBE_CHUNK` samples; the driver
:func:`rockbench.engines.loop._drive` runs the divergence checks on the Python loop's chunks
(a failed one ends the run where the Python loop ends it) and turns the kernel's events into
the same :class:`~rockbench.engines.loop.Stepped`.

One kernel serves every engine (``kind``): engine-specific data travel in the tuple ``eng``
(:func:`chipmunk_engine`, :func:`rockbench.engines.mujoco.MujocoBackend._compiled_loop`), so
it is compiled once and cached. Agreement with the Python loop, tested in
``tests/engines/test_fast_paths.py``: bit for bit without devices; with devices the tendon
lengths come from the C library's ``hypot`` (CPython's differs by one ulp in about 0.5 % of
calls) and MuJoCo's distributed damper sums its kinetic energy in a loop (numpy's ``dot``
in another order).
"""

from __future__ import annotations

import numpy as np

from ..analytic.kernels import NUMBA_AVAILABLE, njit
from .device_kernel import _device_wrench

__all__ = ["LoopState", "run_kernel", "CHIPMUNK", "MUJOCO", "empty_engine", "step_by_address"]

#: Engine kinds of :func:`run_kernel`.
CHIPMUNK, MUJOCO = 0, 1

if NUMBA_AVAILABLE:  # pragma: no branch - numba is a dependency
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils  # noqa: F401 - kept for the intrinsics' users
    from numba.extending import intrinsic

    _D = ir.DoubleType()
    _P = ir.IntType(64)

    def _by_address(args: str, returns: str = "void"):
        """An intrinsic ``call(address, ...)`` of a C function at ``address`` (uint64) with
        arguments ``args`` ("p": a pointer passed as uint64, "d": a double; a cpVect by value is
        "dd", the C calling convention for a struct of two doubles on x86-64 and arm64) and
        ``returns`` "void", "d" or "vec" (a struct of two doubles, as a 2-tuple)."""
        ret_ir = {"void": ir.VoidType(), "d": _D, "vec": ir.LiteralStructType([_D, _D])}[returns]
        ret_nb = {"void": types.void, "d": types.float64,
                  "vec": types.UniTuple(types.float64, 2)}[returns]
        arg_ir = [_P if a == "p" else _D for a in args]
        arg_nb = [types.uint64 if a == "p" else types.float64 for a in args]
        fnty = ir.FunctionType(ret_ir, arg_ir)
        sig = ret_nb(types.uint64, *arg_nb)

        def codegen(context, builder, signature, llargs):
            fn = builder.inttoptr(llargs[0], fnty.as_pointer())
            r = builder.call(fn, llargs[1:])
            if returns == "vec":
                return context.make_tuple(builder, signature.return_type,
                                          [builder.extract_value(r, 0),
                                           builder.extract_value(r, 1)])
            if returns == "void":
                return context.get_dummy_value()
            return r

        n = len(args)
        if n == 1:
            def call(typingctx, address, a):
                return sig, codegen
        elif n == 2:
            def call(typingctx, address, a, b):
                return sig, codegen
        else:
            def call(typingctx, address, a, b, c):
                return sig, codegen
        return intrinsic(call)

    _call_p_vec = _by_address("p", "vec")
    _call_p_d = _by_address("p", "d")
    _call_pd = _by_address("pd")
    _call_pdd = _by_address("pdd")
    _call_pp = _by_address("pp")

#: Function addresses of the Chipmunk entry points, in this order (``eng[0]``).
CHIPMUNK_FUNCTIONS = ("cpSpaceSetGravity", "cpSpaceStep", "cpBodyGetPosition",
                      "cpBodyGetVelocity", "cpBodyGetAngle", "cpBodyGetAngularVelocity",
                      "cpBodySetForce", "cpBodySetTorque")


class LoopState:
    """Indices of the loop's resumable state (a float array): step, samples written, devices
    intact, previous step's time, whether there is one, current time, resume phase, fracture
    (flag, t, phi, phidot), overturn (flag, t, phi, phidot), steps taken."""

    K, N, INTACT, PREV_T, HAS_PREV, T, PHASE = range(7)
    FRAC, T_FRAC, PHI_FRAC, PD_FRAC = range(7, 11)
    OVER, T_OVER, PHI_OVER, PD_OVER = range(11, 15)
    STEPS = 15
    SIZE = 16


def empty_engine() -> tuple:
    """The ``eng`` tuple with every field empty (each engine fills its own)."""
    e1, e2 = np.zeros(0), np.zeros((0, 0))
    u = np.zeros(0, dtype=np.uint64)
    # fp, handles, bodies | qpos, qvel, gravity, qfrc, rest, damped, massvec, tendon
    # stiffness, tendon damping, dof damping, flags
    return (u, u, u, e1, e1, e1, e1, e2, e2, e1, e1, e1, e1, e1)


@njit(cache=True, inline="always")
def _read(kind, eng, state):
    if kind == 0:
        fp, bodies = eng[0], eng[2]
        for j in range(bodies.shape[0]):
            b = bodies[j]
            px, py = _call_p_vec(fp[2], b)
            vx, vy = _call_p_vec(fp[3], b)
            state[j, 0] = px
            state[j, 1] = py
            state[j, 2] = _call_p_d(fp[4], b)
            state[j, 3] = vx
            state[j, 4] = vy
            state[j, 5] = _call_p_d(fp[5], b)
    else:
        qpos, qvel, rest = eng[3], eng[4], eng[7]
        for j in range(state.shape[0]):
            state[j, 0] = rest[j, 0] + qpos[3 * j]
            state[j, 1] = rest[j, 1] + qpos[3 * j + 1]
            state[j, 2] = qpos[3 * j + 2]
            state[j, 3] = qvel[3 * j]
            state[j, 4] = qvel[3 * j + 1]
            state[j, 5] = qvel[3 * j + 2]


@njit(cache=True, inline="always")
def _mujoco_dampers(eng):
    """MujocoBackend._set_dampers: the native dampers' coefficients for the current state."""
    qpos, qvel, damped, massvec = eng[3], eng[4], eng[8], eng[9]
    tdamp, dofdamp, flags = eng[11], eng[12], eng[13]
    c, model = flags[1], int(flags[2])
    if model == 2:                                   # distributed
        power = 0.0
        for r in range(damped.shape[0]):
            dof = int(damped[r, 0])
            rate = 2.0 * damped[r, 1] * np.cos(0.5 * qpos[dof]) * qvel[dof]
            power += c * rate * rate
        ke2 = 0.0
        for i in range(massvec.shape[0]):
            ke2 += massvec[i] * (qvel[i] * qvel[i])
        lam = power / ke2 if ke2 > 0.0 else 0.0
        for i in range(massvec.shape[0]):
            dofdamp[i] = lam * massvec[i]
        return
    for r in range(damped.shape[0]):
        dof = int(damped[r, 0])
        th = qpos[dof]
        if model == 0:                               # couple
            dcd = 2.0 * damped[r, 1] * np.cos(0.5 * th)
            dofdamp[dof] = c * dcd * dcd
        else:                                        # heel
            on, off = (int(damped[r, 3]), int(damped[r, 2])) if th >= 0.0 else \
                (int(damped[r, 2]), int(damped[r, 3]))
            tdamp[on] = c
            tdamp[off] = 0.0


@njit(cache=True)
def run_kernel(kind, eng, gx, gy, t_steps, grid, t_tol, states, sample_intact, state, prev, ls,
               fall_p, fall_n, dt, dev, check_strain, n_stop):
    """Run the loop of :func:`rockbench.engines.loop.step_run` for engine ``kind``
    (:data:`CHIPMUNK`, :data:`MUJOCO`; its data in ``eng``) from the state saved in ``ls``
    (:class:`LoopState`), ``state`` and ``prev`` (n_bodies, 6) until the run ends (returns 0),
    ``n_stop`` samples are written (1: the caller checks them and calls again), the structure
    overturns (2) or the state is not finite (3). ``dev``: :func:`~rockbench.engines.
    device_kernel.device_params` (empty without device forces to apply); MuJoCo's native
    devices are ``eng[13][0]`` = 1. ``gx``, ``gy``: the gravity of every step [m/s^2]
    (:func:`~rockbench.engines.loop.ground_gravity`: the horizontal and vertical ground motion)."""
    nb = state.shape[0]
    W = np.zeros((nb, 3))
    n_steps = gx.shape[0]
    n_out = grid.shape[0]
    k, n = int(ls[0]), int(ls[1])
    intact = ls[2] != 0.0
    prev_t, has_prev, t = ls[3], ls[4] != 0.0, ls[5]
    phase = int(ls[6])
    native = kind == 1 and eng[13][0] != 0.0
    code = 0
    while True:
        if phase == 0:
            phi = state[0, 2]
            if phi != phi:
                code = 3
                break
            while n < n_out and grid[n] <= t + t_tol:
                if not has_prev or t == prev_t or grid[n] == t:
                    states[n, :, :] = state
                else:
                    w = (grid[n] - prev_t) / (t - prev_t)
                    for i in range(nb):
                        for c in range(6):
                            states[n, i, c] = prev[i, c] + w * (state[i, c] - prev[i, c])
                sample_intact[n] = intact
                n += 1
            if n >= n_stop:
                phase = 1
                code = 1
                break
        phase = 0
        phi = state[0, 2]
        if phi >= fall_p or -phi >= fall_n:
            ls[11], ls[12], ls[13], ls[14] = 1.0, t, phi, state[0, 5]
            code = 2
            break
        if k == n_steps:
            code = 0
            break
        apply = False
        if intact and dev.shape[0] > 0:
            max_el = _device_wrench(state, dev, W)
            apply = not native
            if check_strain and max_el / dev[2] >= dev[3]:
                apply = False
                intact = False
                ls[7], ls[8], ls[9], ls[10] = 1.0, t, phi, state[0, 5]
                if native:                           # MujocoBackend._remove_devices
                    eng[10][:] = 0.0
                    eng[11][:] = 0.0
                    eng[12][:] = 0.0
        if kind == 0:
            fp, space, bodies = eng[0], eng[1][0], eng[2]
            if apply:
                for j in range(nb):
                    fx, fy, tau = W[j, 0], W[j, 1], W[j, 2]
                    if fx != 0.0 or fy != 0.0 or tau != 0.0:
                        _call_pdd(fp[6], bodies[j], fx, fy)
                        _call_pd(fp[7], bodies[j], tau)
            _call_pdd(fp[0], space, gx[k], gy[k])
            _call_pd(fp[1], space, dt)
        else:
            eng[5][0] = gx[k]
            eng[5][2] = gy[k]
            if native and intact and eng[8].shape[0] > 0:
                _mujoco_dampers(eng)
            qfrc = eng[6]
            if apply:
                for j in range(nb):
                    qfrc[3 * j] = W[j, 0]
                    qfrc[3 * j + 1] = W[j, 1]
                    qfrc[3 * j + 2] = W[j, 2]
            _call_pp(eng[0][0], eng[1][0], eng[1][1])
            if apply:
                qfrc[:] = 0.0
        ls[15] += 1.0
        prev[:, :] = state
        prev_t = t
        has_prev = True
        t = t_steps[k]
        _read(kind, eng, state)
        k += 1
    ls[0], ls[1], ls[2] = k, n, 1.0 if intact else 0.0
    ls[3], ls[4], ls[5], ls[6] = prev_t, 1.0 if has_prev else 0.0, t, phase
    return code


@njit(cache=True)
def step_by_address(mj_step, model, data, n):
    """Call ``mj_step(model, data)`` ``n`` times by address (the MuJoCo self-test)."""
    for _ in range(n):
        _call_pp(mj_step, model, data)

"""pymunk's stepping loop in compiled code: Chipmunk's C functions called from numba.

Through Python, one pymunk step of a three-body frame costs about 1 microsecond inside
Chipmunk and several more in the calls around it (gravity, step, twelve state reads, device
forces); a run spent most of its time in rockbench's loop (issue 12). Here the whole loop of
:func:`rockbench.engines.loop.step_run` - ground-motion gravity, device forces and the
fracture check, the overturn check, the step, the state read, the output samples with their
linear interpolation - runs in one numba function that calls Chipmunk's exported C functions
(``cpSpaceStep``, ``cpBodyGetPosition``, ...) in pymunk's own library, on the same
``cpSpace`` that pymunk built. It returns to Python every :data:`~rockbench.engines.loop.
PROBE_CHUNK` samples for the divergence checks, exactly where the Python loop runs them.

Chipmunk passes and returns its 2-D vectors (``cpVect``, two doubles) by value; the kernel
declares them as two doubles, which is the C calling convention for such a struct on x86-64
(System V) and arm64. :func:`available` therefore enables the path only on those platforms,
and only after a self-test has stepped a small scene both ways and found every state bit for
bit equal; otherwise pymunk runs through the Python loop, which gives the same numbers.

Agreement with the Python loop (``tests/engines/test_fast_paths.py``): bit for bit on
free-standing scenes; on scenes with devices the tendon lengths come from the C library's
``hypot``, which differs from CPython's by one ulp in about 0.5 % of calls.
"""

from __future__ import annotations

import functools
import platform
import sys

import numpy as np

from ..analytic.kernels import NUMBA_AVAILABLE, njit
from .device_kernel import _device_wrench

__all__ = ["available", "LoopState", "run_kernel"]

_PLATFORMS = {("linux", "x86_64"), ("linux", "aarch64"), ("darwin", "x86_64"),
              ("darwin", "arm64")}

if NUMBA_AVAILABLE:  # pragma: no branch - numba is a dependency
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    def _c_function(name: str, n_vec_args: int = 0, n_f64_args: int = 0,
                    returns: str = "void"):
        """An intrinsic calling Chipmunk's ``name`` with a pointer (as uint64), then
        ``n_vec_args`` cpVect arguments (two doubles each) and ``n_f64_args`` doubles;
        ``returns`` "void", "f64" or "vec" (a 2-tuple of doubles)."""
        d = ir.DoubleType()
        ret_ir = {"void": ir.VoidType(), "f64": d, "vec": ir.LiteralStructType([d, d])}[returns]
        ret_nb = {"void": types.void, "f64": types.float64,
                  "vec": types.UniTuple(types.float64, 2)}[returns]
        n_args = 2 * n_vec_args + n_f64_args
        fnty = ir.FunctionType(ret_ir, [ir.IntType(64)] + [d] * n_args)

        def codegen(context, builder, signature, llargs):
            fn = cgutils.get_or_insert_function(builder.module, fnty, name)
            r = builder.call(fn, llargs)
            if returns == "vec":
                return context.make_tuple(builder, signature.return_type,
                                          [builder.extract_value(r, 0),
                                           builder.extract_value(r, 1)])
            if returns == "void":
                return context.get_dummy_value()
            return r

        sig = ret_nb(types.uint64, *([types.float64] * n_args))
        if n_args == 0:
            def call(typingctx, ptr):
                return sig, codegen
        elif n_args == 1:
            def call(typingctx, ptr, a):
                return sig, codegen
        else:
            def call(typingctx, ptr, a, b):
                return sig, codegen
        return intrinsic(call)

    _set_gravity = _c_function("cpSpaceSetGravity", n_vec_args=1)
    _space_step = _c_function("cpSpaceStep", n_f64_args=1)
    _get_position = _c_function("cpBodyGetPosition", returns="vec")
    _get_velocity = _c_function("cpBodyGetVelocity", returns="vec")
    _get_angle = _c_function("cpBodyGetAngle", returns="f64")
    _get_omega = _c_function("cpBodyGetAngularVelocity", returns="f64")
    _set_force = _c_function("cpBodySetForce", n_vec_args=1)
    _set_torque = _c_function("cpBodySetTorque", n_f64_args=1)


class LoopState:
    """Indices of the loop's resumable state (a float array): step, samples written, devices
    intact, previous step's time, whether there is one, current time, resume phase, fracture
    (flag, t, phi, phidot), overturn (flag, t, phi, phidot), steps taken."""

    K, N, INTACT, PREV_T, HAS_PREV, T, PHASE = range(7)
    FRAC, T_FRAC, PHI_FRAC, PD_FRAC = range(7, 11)
    OVER, T_OVER, PHI_OVER, PD_OVER = range(11, 15)
    STEPS = 15
    SIZE = 16


@njit(cache=True, inline="always")
def _read(bodies, state):
    for j in range(bodies.shape[0]):
        b = bodies[j]
        px, py = _get_position(b)
        vx, vy = _get_velocity(b)
        state[j, 0] = px
        state[j, 1] = py
        state[j, 2] = _get_angle(b)
        state[j, 3] = vx
        state[j, 4] = vy
        state[j, 5] = _get_omega(b)


@njit(cache=True)
def run_kernel(space, bodies, gx, t_steps, grid, t_tol, states, sample_intact, state, prev,
               ls, fall_p, fall_n, g, dt, dev, check_strain, n_stop):
    """Run the loop of :func:`rockbench.engines.loop.step_run` from the state saved in ``ls``
    (:class:`LoopState`), ``state`` and ``prev`` (n_bodies, 6) until the run ends (returns 0),
    ``n_stop`` samples are written (1: the caller checks them and calls again), the structure
    overturns (2) or the state is not finite (3). ``dev``: :func:`~rockbench.engines.
    device_kernel.device_params` (empty without devices)."""
    nb = bodies.shape[0]
    W = np.zeros((nb, 3))
    n_steps = gx.shape[0]
    n_out = grid.shape[0]
    k, n = int(ls[0]), int(ls[1])
    intact = ls[2] != 0.0
    prev_t, has_prev, t = ls[3], ls[4] != 0.0, ls[5]
    phase = int(ls[6])
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
        if intact and dev.shape[0] > 0:
            max_el = _device_wrench(state, dev, W)
            apply = True
            if check_strain and max_el / dev[2] >= dev[3]:
                apply = False
                intact = False
                ls[7], ls[8], ls[9], ls[10] = 1.0, t, phi, state[0, 5]
            if apply:
                for j in range(nb):
                    fx, fy, tau = W[j, 0], W[j, 1], W[j, 2]
                    if fx != 0.0 or fy != 0.0 or tau != 0.0:
                        _set_force(bodies[j], fx, fy)
                        _set_torque(bodies[j], tau)
        _set_gravity(space, gx[k], -g)
        _space_step(space, dt)
        ls[15] += 1.0
        prev[:, :] = state
        prev_t = t
        has_prev = True
        t = t_steps[k]
        _read(bodies, state)
        k += 1
    ls[0], ls[1], ls[2] = k, n, 1.0 if intact else 0.0
    ls[3], ls[4], ls[5], ls[6] = prev_t, 1.0 if has_prev else 0.0, t, phase
    return code


@functools.lru_cache(maxsize=1)
def available() -> tuple[bool, str]:
    """(True, "") when the compiled pymunk loop can run here, else (False, why): numba, a
    platform whose C calling convention passes a cpVect as two doubles, Chipmunk's symbols,
    and a self-test that steps a falling, sliding box both ways and compares every state."""
    if not NUMBA_AVAILABLE:
        return False, "numba is not available"
    key = (sys.platform, platform.machine())
    if key not in _PLATFORMS:
        return False, f"not enabled on {key[0]} {key[1]}"
    try:
        import llvmlite.binding as llvm
        import pymunk
        import pymunk._chipmunk as native
        from pymunk._chipmunk_cffi import ffi, lib

        llvm.load_library_permanently(native.__file__)
        ref, fast = [], []
        for out in (ref, fast):
            space = pymunk.Space()
            space.gravity = (0.0, -9.81)
            ground = pymunk.Segment(space.static_body, (-5.0, 0.0), (5.0, 0.0), 0.0)
            body = pymunk.Body(2.0, 0.7)
            body.position, body.angle = (0.1, 0.6), 0.3
            box = pymunk.Poly.create_box(body, (0.4, 1.0))
            ground.friction = box.friction = 0.3
            space.add(body, box, ground)
            gx = np.sin(np.arange(300) * 0.05) * 4.0
            if out is ref:
                for k, gxk in enumerate(gx):
                    if k % 7 == 0:
                        body.force, body.torque = (1.5, -2.0), 0.25
                    lib.cpSpaceSetGravity(space._space, (gxk, -9.81))
                    lib.cpSpaceStep(space._space, 2e-3)
                    p, v = lib.cpBodyGetPosition(body._body), lib.cpBodyGetVelocity(body._body)
                    out.append((p.x, p.y, lib.cpBodyGetAngle(body._body), v.x, v.y,
                                lib.cpBodyGetAngularVelocity(body._body)))
            else:
                fast.extend(_self_test(np.uint64(int(ffi.cast("uintptr_t", space._space))),
                                       np.uint64(int(ffi.cast("uintptr_t", body._body))),
                                       gx).tolist())
        if not np.array_equal(np.array(ref), np.array(fast)):
            return False, "the self-test's states differ from pymunk's own stepping"
    except Exception as e:  # noqa: BLE001 - any failure means: the Python loop
        return False, f"{type(e).__name__}: {e}"
    return True, ""


@njit(cache=True)
def _self_test(space, body, gx):
    out = np.empty((gx.shape[0], 6))
    bodies = np.empty(1, dtype=np.uint64)
    bodies[0] = body
    st = np.empty((1, 6))
    for k in range(gx.shape[0]):
        if k % 7 == 0:
            _set_force(body, 1.5, -2.0)
            _set_torque(body, 0.25)
        _set_gravity(space, gx[k], -9.81)
        _space_step(space, 2e-3)
        _read(bodies, st)
        out[k, :] = st[0, :]
    return out

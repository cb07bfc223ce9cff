"""pymunk's stepping loop in compiled code (:mod:`rockbench.engines.compiled_loop`): the
addresses of Chipmunk's C functions in pymunk's own library, and the self-test that decides
whether the compiled loop may run here.

Chipmunk passes and returns its 2-D vectors (``cpVect``, two doubles) by value; the kernel
declares them as two doubles, which is the C calling convention for such a struct on x86-64
(System V) and arm64. :func:`available` therefore enables the path only on those platforms,
and only after a self-test has stepped a small scene (pushed, sliding and tipping) both ways
and found every state bit for bit equal; otherwise pymunk runs through the Python loop, which
gives the same numbers.
"""

from __future__ import annotations

import ctypes
import functools
import platform
import sys

import numpy as np

from ..analytic.kernels import NUMBA_AVAILABLE, njit
from .compiled_loop import CHIPMUNK_FUNCTIONS, empty_engine

if NUMBA_AVAILABLE:  # pragma: no branch - numba is a dependency
    from .compiled_loop import _call_p_d, _call_p_vec, _call_pd, _call_pdd

__all__ = ["available", "engine"]

_PLATFORMS = {("linux", "x86_64"), ("linux", "aarch64"), ("darwin", "x86_64"),
              ("darwin", "arm64")}


@functools.lru_cache(maxsize=1)
def _addresses() -> np.ndarray:
    """Addresses of :data:`~rockbench.engines.compiled_loop.CHIPMUNK_FUNCTIONS` in pymunk's
    library."""
    import pymunk._chipmunk as native

    lib = ctypes.CDLL(native.__file__)
    return np.array([ctypes.cast(getattr(lib, f), ctypes.c_void_p).value
                     for f in CHIPMUNK_FUNCTIONS], dtype=np.uint64)


def engine(cspace, cbodies) -> tuple:
    """The ``eng`` tuple of :func:`~rockbench.engines.compiled_loop.run_kernel` for pymunk's
    cffi handles of a space and its bodies."""
    from pymunk._chipmunk_cffi import ffi

    e = list(empty_engine())
    e[0] = _addresses()
    e[1] = np.array([int(ffi.cast("uintptr_t", cspace))], dtype=np.uint64)
    e[2] = np.array([int(ffi.cast("uintptr_t", b)) for b in cbodies], dtype=np.uint64)
    return tuple(e)


@functools.lru_cache(maxsize=1)
def available() -> tuple[bool, str]:
    """(True, "") when the compiled pymunk loop can run here, else (False, why): numba, a
    platform whose C calling convention passes a cpVect as two doubles, Chipmunk's symbols,
    and a self-test that steps a pushed, sliding, tipping box both ways and compares every
    state bit for bit."""
    if not NUMBA_AVAILABLE:
        return False, "numba is not available"
    key = (sys.platform, platform.machine())
    if key not in _PLATFORMS:
        return False, f"not enabled on {key[0]} {key[1]}"
    try:
        import pymunk
        from pymunk._chipmunk_cffi import lib

        gx = np.sin(np.arange(300) * 0.05) * 4.0
        runs = []
        for compiled in (False, True):
            space = pymunk.Space()
            space.gravity = (0.0, -9.81)
            ground = pymunk.Segment(space.static_body, (-5.0, 0.0), (5.0, 0.0), 0.0)
            body = pymunk.Body(2.0, 0.7)
            body.position, body.angle = (0.1, 0.6), 0.3
            box = pymunk.Poly.create_box(body, (0.4, 1.0))
            ground.friction = box.friction = 0.3
            space.add(body, box, ground)
            if compiled:
                eng = engine(space._space, [body._body])
                runs.append(_self_test(eng[0], eng[1][0], eng[2], gx))
                continue
            out = []
            for k, gxk in enumerate(gx):
                if k % 7 == 0:
                    body.force, body.torque = (1.5, -2.0), 0.25
                lib.cpSpaceSetGravity(space._space, (gxk, -9.81))
                lib.cpSpaceStep(space._space, 2e-3)
                p, v = lib.cpBodyGetPosition(body._body), lib.cpBodyGetVelocity(body._body)
                out.append((p.x, p.y, lib.cpBodyGetAngle(body._body), v.x, v.y,
                            lib.cpBodyGetAngularVelocity(body._body)))
            runs.append(np.array(out))
        if not np.array_equal(runs[0], runs[1]):
            return False, "the self-test's states differ from pymunk's own stepping"
    except Exception as e:  # noqa: BLE001 - any failure means: the Python loop
        return False, f"{type(e).__name__}: {e}"
    return True, ""


@njit(cache=True)
def _self_test(fp, space, bodies, gx):
    out = np.empty((gx.shape[0], 6))
    b = bodies[0]
    for k in range(gx.shape[0]):
        if k % 7 == 0:
            _call_pdd(fp[6], b, 1.5, -2.0)
            _call_pd(fp[7], b, 0.25)
        _call_pdd(fp[0], space, gx[k], -9.81)
        _call_pd(fp[1], space, 2e-3)
        px, py = _call_p_vec(fp[2], b)
        vx, vy = _call_p_vec(fp[3], b)
        out[k, 0], out[k, 1], out[k, 2] = px, py, _call_p_d(fp[4], b)
        out[k, 3], out[k, 4], out[k, 5] = vx, vy, _call_p_d(fp[5], b)
    return out

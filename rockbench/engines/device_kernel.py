"""The shared tendon and damper forces (:class:`~rockbench.engines.devices.DeviceGeometry`)
as a numba kernel, for the compiled stepping loops (:mod:`rockbench.engines.chipmunk`).

:func:`device_params` packs a DeviceGeometry into a plain array; :func:`_device_wrench`
computes, from the bodies' state, the resultant force and moment on every body of the point
forces that :meth:`DeviceGeometry.forces` returns, summed in the same order as
:func:`~rockbench.engines.devices.net_wrenches`. The arithmetic is the same, except that
numba's ``math.hypot`` (the C library's) and CPython's differ by one ulp in about 0.5 % of
calls: a tendon elongation can differ by 1e-16 relative from the Python path.

Forces in N, moments in N m, lengths in m.
"""

from __future__ import annotations

import math

import numpy as np

from ..analytic.kernels import njit
from .devices import DAMPER_MODELS, DeviceGeometry

__all__ = ["device_params"]

_COL = 11          # start of the first column's block
_NCOL = 16         # entries per column


def device_params(devices: DeviceGeometry) -> np.ndarray:
    """The plain array of ``devices`` read by :func:`_device_wrench`."""
    p = np.zeros(_COL + 2 * _NCOL)
    p[0], p[1], p[2] = devices.k, devices.c, devices.l
    p[3] = math.inf if devices.eps_f is None else devices.eps_f
    p[4] = DAMPER_MODELS.index(devices.damper)
    p[5:8] = devices.mass
    p[8:11] = devices.inertia
    for j, (idx, F, p_loc, q_loc, t_loc, corners) in enumerate(devices.columns):
        o = _COL + j * _NCOL
        p[o:o + 15] = (idx, F[0], F[1], *p_loc, *q_loc, *t_loc, *corners[0][0], *corners[1][0],
                       devices.b[idx], devices.arm[idx])
    return p


@njit(cache=True, inline="always")
def _world(st, i, lx, ly):
    c, s = math.cos(st[i, 2]), math.sin(st[i, 2])
    return st[i, 0] + c * lx - s * ly, st[i, 1] + s * lx + c * ly


@njit(cache=True, inline="always")
def _add(W, st, b, px, py, fx, fy):
    W[b, 0] += fx
    W[b, 1] += fy
    W[b, 2] += (px - st[b, 0]) * fy - (py - st[b, 1]) * fx


@njit(cache=True)
def _device_wrench(st, p, W):
    """Fill W (n_bodies, 3) with fx, fy [N] and the moment about each body's centre [N m] of
    the device forces for the state ``st`` (n_bodies, 6); return the larger tendon
    elongation [m]."""
    W[:, :] = 0.0
    k, c, model = p[0], p[1], int(p[4])
    power = 0.0
    max_el = -math.inf
    for j in range(2):
        o = 11 + j * 16
        idx = int(p[o])
        Px, Py = _world(st, idx, p[o + 3], p[o + 4])
        Qx, Qy = _world(st, idx, p[o + 5], p[o + 6])
        Tx, Ty = _world(st, 1, p[o + 7], p[o + 8])
        dbx, dby = p[o + 1] - Px, p[o + 2] - Py
        dtx, dty = Tx - Qx, Ty - Qy
        db, dt_ = math.hypot(dbx, dby), math.hypot(dtx, dty)
        el = db + dt_
        if el > max_el:
            max_el = el
        tension = k * (db + dt_)
        if tension > 0.0:
            if db > 1e-12:
                _add(W, st, idx, Px, Py, tension * dbx / db, tension * dby / db)
            if dt_ > 1e-12:
                fx, fy = tension * dtx / dt_, tension * dty / dt_
                _add(W, st, idx, Qx, Qy, fx, fy)
                _add(W, st, 1, Tx, Ty, -fx, -fy)
        if c > 0.0:
            th, w = st[idx, 2], st[idx, 5]
            sg = 1.0 if th >= 0.0 else -1.0
            half = 0.5 * th
            dchord = 2.0 * p[o + 13] * math.cos(half) * sg
            fd = c * dchord * w
            if model == 2:                       # distributed
                power += fd * dchord * w
            elif model == 1:                     # heel
                if sg > 0:
                    Xx, Xy = _world(st, idx, p[o + 11], p[o + 12])
                else:
                    Xx, Xy = _world(st, idx, p[o + 9], p[o + 10])
                _add(W, st, idx, Xx, Xy, fd * math.sin(half), -fd * math.cos(half))
            else:                                # couple
                tau = -fd * dchord
                d = p[o + 14]
                _add(W, st, idx, st[idx, 0], st[idx, 1] + d, -0.5 * tau / d, 0.0)
                _add(W, st, idx, st[idx, 0], st[idx, 1] - d, 0.5 * tau / d, 0.0)
    if power > 0.0:
        two_t = 0.0
        for b in range(st.shape[0]):
            m, i = p[5 + b], p[8 + b]
            two_t += m * (st[b, 3] * st[b, 3] + st[b, 4] * st[b, 4]) + i * st[b, 5] * st[b, 5]
        if two_t > 0.0:
            lam = power / two_t
            for b in range(st.shape[0]):
                m, i = p[5 + b], p[8 + b]
                _add(W, st, b, st[b, 0], st[b, 1], -lam * m * st[b, 3], -lam * m * st[b, 4])
                tau = -lam * i * st[b, 5]
                if tau != 0.0:
                    _add(W, st, b, st[b, 0], st[b, 1] + 1.0, -0.5 * tau, 0.0)
                    _add(W, st, b, st[b, 0], st[b, 1] - 1.0, 0.5 * tau, 0.0)
    return max_el

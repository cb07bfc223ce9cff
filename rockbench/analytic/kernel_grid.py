"""numba kernels of the compiled analytic path over map cells: a Ricker pulse built in the
kernel per cell and the serial and parallel loops that run :func:`~rockbench.analytic.kernel_run._run`
on each. See :mod:`rockbench.analytic.compiled`."""

from __future__ import annotations

import math

import numpy as np

from ..constants import FREE_TAIL, G
from .kernel_run import _run
from .kernels import _NOUT, _acc, njit, prange


# --- pulses built in the kernel (map cells) ------------------------------------------------------
@njit(cache=True)
def _pulse_setup(shape, sign, A, W, alpha, p, sym_ext, anti_ext, beta, xfac, mp, ext, extsuf):
    """RickerPulse.dimensionless in compiled code: fills mp (scale, period, t_start, t_end,
    xfac; mp[5] = mp[6] = 0: no vertical part), the extrema and their suffix maxima; returns
    the number of extrema."""
    amp = A * G * math.tan(alpha)
    per = 2.0 * math.pi / (W * p)
    if shape == 1:
        mp[0] = sign * amp
        taus = sym_ext
    else:
        mp[0] = sign * amp / beta
        taus = anti_ext
    mp[1] = per
    mp[2] = -3.0 * per
    mp[3] = 3.0 * per
    mp[4] = xfac
    n = taus.shape[0]
    hint = np.zeros(1, dtype=np.int64)
    dummy = np.zeros(1)
    for i in range(n):
        ext[i] = per * taus[i]
    m = 0.0
    for i in range(n - 1, -1, -1):
        v = abs(_acc(ext[i], shape, mp, dummy, dummy, hint))
        if v > m:
            m = v
        extsuf[i] = m
    return n


@njit(cache=True)
def _grid_cell(i, geo, sc, shapes, signs, As, Ws, duration, rtol, atol, v_rest, thr_p, thr_n,
               rp, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res):
    mp = np.zeros(7)
    shape = shapes[i]
    n_ext = 3 if shape == 1 else 4
    ext = np.zeros(n_ext)
    extsuf = np.zeros(n_ext)
    _pulse_setup(shape, float(signs[i]), As[i], Ws[i], sc[12], sc[13], sym_ext, anti_ext, beta,
                 xfac, mp, ext, extsuf)
    t0 = mp[2]
    dur = duration if duration > 0.0 else (mp[3] - mp[2]) + FREE_TAIL
    dummy = np.zeros(1)
    evf = np.zeros((1, 5))
    evi = np.zeros((1, 2), dtype=np.int64)
    tg = np.zeros(1)
    hist = np.zeros((1, 2))
    hmode = np.zeros((1, 2), dtype=np.int64)
    out = np.zeros(_NOUT)
    # max_abs_after short cut: no uplift possible at all -> the run is at rest throughout
    _run(geo, sc, shape, mp, dummy, dummy, ext, extsuf, dummy, t0, t0 + dur, 0.0, 0.0, rtol,
         atol, v_rest, thr_p, thr_n, mp[3], rp[0], rp[1], rp[2], int(rp[3]), int(rp[4]),
         A, B, C, E3, E5, Dd, ns, False, evf, evi, False, tg, hist, hmode, out)
    for k in range(_NOUT):
        res[i, k] = out[k]


@njit(cache=True)
def _grid_serial(geo, sc, shapes, signs, As, Ws, duration, rtol, atol, v_rest, thr_p, thr_n,
                 rp, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res):
    for i in range(shapes.shape[0]):
        _grid_cell(i, geo, sc, shapes, signs, As, Ws, duration, rtol, atol, v_rest, thr_p,
                   thr_n, rp, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res)


@njit(cache=True, parallel=True)
def _grid_parallel(geo, sc, shapes, signs, As, Ws, duration, rtol, atol, v_rest, thr_p, thr_n,
                   rp, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res):
    for i in prange(shapes.shape[0]):
        _grid_cell(i, geo, sc, shapes, signs, As, Ws, duration, rtol, atol, v_rest, thr_p,
                   thr_n, rp, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res)

"""The equation-of-motion impact estimator's extrapolation (:func:`rockbench.measure.
extrapolate_to_closure`) compiled with numba, for many samples in one call.

:func:`rockbench.measure.measure_impacts` integrates the mechanism's Eq. 17 from a few sampled
states on either side of every impact to phi = 0 (classical Runge-Kutta, steps of
:data:`rockbench.measure.EOM_STEP`, Newton on the last sub-step). In Python that costs about
as much as stepping pymunk through the whole run; this kernel does the same
arithmetic on the compiled path's mechanism (:func:`rockbench.analytic.kernels._phidd`) and
ground motions (:func:`~rockbench.analytic.kernels._acc`). It agrees with the Python function
to rounding (``tests/engines/test_fast_paths.py``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .kernels import NUMBA_AVAILABLE, _acc_hv, _phidd, njit

__all__ = ["closure_function"]


@njit(cache=True)
def _rk4(tt, y0, y1, h, g, intact, mk, mp, rt, ra, hint, kin):
    ag0, av0 = _acc_hv(tt, mk, mp, rt, ra, hint)
    a1 = _phidd(y0, y1, ag0, 9.81 + av0, g, intact, kin)
    k1p, k1v = y1, a1
    tm = tt + h / 2
    agm, avm = _acc_hv(tm, mk, mp, rt, ra, hint)
    k2p = y1 + h / 2 * k1v
    k2v = _phidd(y0 + h / 2 * k1p, y1 + h / 2 * k1v, agm, 9.81 + avm, g, intact, kin)
    k3p = y1 + h / 2 * k2v
    k3v = _phidd(y0 + h / 2 * k2p, y1 + h / 2 * k2v, agm, 9.81 + avm, g, intact, kin)
    k4p = y1 + h * k3v
    ag1, av1 = _acc_hv(tt + h, mk, mp, rt, ra, hint)
    k4v = _phidd(y0 + h * k3p, y1 + h * k3v, ag1, 9.81 + av1, g, intact, kin)
    return (y0 + h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p),
            y1 + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v))


@njit(cache=True)
def _closure_many(phi0, pd0, t0, intact, direction, max_time, step, g, mk, mp, rt, ra,
                  out_t, out_v):
    """For every sample i: (time [s], phi' [rad/s]) at phi = 0, integrated from (t0[i],
    phi0[i], pd0[i]) forward (direction +1) or backward (-1); NaN if phi does not close within
    max_time[i] [s]. ``g``: the mechanism's row of :func:`~rockbench.analytic.compiled.
    scene_arrays` for the sample's rocking direction."""
    kin = np.zeros((3, 7))
    hint = np.zeros(1, dtype=np.int64)
    for i in range(phi0.shape[0]):
        p0 = phi0[i]
        if p0 == 0.0:
            out_t[i], out_v[i] = t0[i], pd0[i]
            continue
        sgn = 1.0 if p0 > 0 else -1.0
        tt, y0, y1 = t0[i], p0, pd0[i]
        h = direction[i] * step
        ok = intact[i]
        out_t[i], out_v[i] = np.nan, np.nan
        while abs(tt - t0[i]) < max_time[i]:
            n0, n1 = _rk4(tt, y0, y1, h, g, ok, mk, mp, rt, ra, hint, kin)
            if sgn * n0 <= 0.0:
                tau = h * y0 / (y0 - n0)
                for _ in range(8):
                    m0, m1 = _rk4(tt, y0, y1, tau, g, ok, mk, mp, rt, ra, hint, kin)
                    if m1 == 0.0:
                        break
                    d = m0 / m1
                    tau -= d
                    if abs(d) < 1e-15:
                        break
                out_t[i] = tt + tau
                out_v[i] = _rk4(tt, y0, y1, tau, g, ok, mk, mp, rt, ra, hint, kin)[1]
                break
            tt, y0, y1 = tt + h, n0, n1


def closure_function(scene, motion) -> Callable | None:
    """A function ``(phi0, phidot0, t0, intact, direction, max_time, sign) -> (t, phidot)``
    over arrays of samples (``sign``: the rocking direction +1/-1 of all of them) that does
    what :func:`rockbench.measure.extrapolate_to_closure` does for each, compiled; None when
    numba or the motion's compiled form (Ricker pulse, record, none) is not available."""
    if not NUMBA_AVAILABLE:
        return None
    from ..measure import EOM_STEP
    from .compiled import _motion_arrays, scene_arrays

    try:
        mk, mp, rt, ra, *_ = _motion_arrays(motion)
    except Exception:  # noqa: BLE001 - another GroundMotion: the Python path
        return None
    geo, _ = scene_arrays(scene)

    def closure(phi0, pd0, t0, intact, direction, max_time, sign):
        n = len(phi0)
        out_t, out_v = np.empty(n), np.empty(n)
        f = lambda a, dt=float: np.ascontiguousarray(a, dtype=dt)  # noqa: E731
        _closure_many(f(phi0), f(pd0), f(t0), f(intact, np.bool_), f(direction), f(max_time),
                      float(EOM_STEP), geo[0 if sign > 0 else 1], mk, mp, rt, ra, out_t, out_v)
        return out_t, out_v
    return closure

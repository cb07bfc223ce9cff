"""Compiled fast path of the analytic backend: the SDOF rocking model integrated event by event in
numba-compiled code, a drop-in for :func:`rockbench.analytic.solver.simulate` and a batch entry
point for overturning maps (:func:`run_pulse_grid`).

Design (measured choices, see ``benchmarks/results/compiled_analytic.md``):

* Kinematics and Eq. 17 terms are *evaluated*, not tabulated: the exact closed-form four-bar
  solution of :mod:`rockbench.scene.mechanism` and the terms of :mod:`rockbench.analytic.dynamics`
  (with tendon elongation = base + top opening and damper chord rates) are ported line by line to
  compiled code that reads plain parameter arrays extracted once per scene (:func:`scene_arrays`).
  One evaluation of phi'' costs a few trigonometric calls, so there is no interpolation error to
  budget for and the right-hand side agrees with ``Dynamics.acceleration`` to round-off.
* The integrator is the same explicit Runge-Kutta method of order 8 with a 7th-order error
  estimate and 7th-order dense output (Dormand-Prince 8(5,3), "DOP853") that the reference path
  uses through ``scipy.integrate.solve_ivp``, with the same step-size controller, the same initial
  step selection and the same tolerances (``AnalyticSettings.rtol``/``atol``, 1e-10 / 1e-12 by
  default). The Butcher tableau is read at import time from scipy's own coefficient table, so
  both paths integrate the same scheme and the fast path tracks the plain one step for step.
* Events are located as ``solve_ivp`` does: a sign change of the event function between two
  accepted steps (with the event's direction), then Brent's method on the dense output to
  4 machine epsilons; events after the first terminal one in a step are dropped.

Event rules mirrored from :mod:`rockbench.analytic.rules` and :mod:`rockbench.analytic.solver`
(the reference): uplift from rest when u_g'' > lambda g (1 + UPLIFT_RTOL) (direction +1) or
u_g'' < lambda_cw g (1 + UPLIFT_RTOL) (direction -1), found on the motion's knots (pulses:
T_g/400 and the extrema, then Brent to 1e-13 s; records: exact crossing of the linear
interpolation), stepped just past the root; impact at phi = 0 with eta of the post-impact
direction, rest when |phi'+| <= rest_ratio p alpha (or eta <= 0), chatter (two successive
post-impact |phi'| <= CHATTER_VELOCITY_RATIO p alpha at most CHATTER_INTERVAL / p apart settle
the structure); fracture (all devices removed) at the fracture angle of the direction; overturn
at the scene's fall angle (terminal); critical angle exceedance (also, with a "critical" event,
when a segment starts at or beyond the critical angle of its potential); peaks at phi' = 0
(impact and peak event functions are taken as positive at a segment's first instant); at rest,
the run ends at max(t, motion end) once the motion cannot uplift the structure any more before
the end of the run; the progress guarantee (PROGRESS_WINDOW iterations must advance time by
PROGRESS_MIN_ADVANCE / p, at most MAX_EVENT_ITERATIONS iterations; an integrator failure) ends
the run as ``status == "invalid"`` with the reason, never with an exception. The constants are
read from :mod:`rockbench.analytic.rules` when a run starts, as the reference does.

If numba cannot be imported, :data:`NUMBA_AVAILABLE` is False, :data:`NUMBA_ERROR` says why,
and every entry point raises :class:`rockbench.errors.BackendUnavailable` so that callers can
fall back to :func:`rockbench.analytic.solver.simulate`.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import asdict
from typing import Any, Iterable

import numpy as np
import pandas as pd

from ..constants import G
from ..errors import BackendUnavailable, ParameterError, check_positive
from ..result import (CONTACT_COLUMNS, HISTORY_COLUMNS, Cost, Result, Summary, events_frame,
                      output_grid)
from ..scene.motion import Record, RickerPulse, antisymmetric_beta
from ..scene.scene import Scene
from ..scene.structure import Frame
from . import rules
from .reference import Reference, reference_of

__all__ = ["NUMBA_AVAILABLE", "NUMBA_ERROR", "simulate_compiled", "run_pulse_grid",
           "scene_arrays", "MAP_COLUMNS"]

try:  # pragma: no cover - exercised by the environment, not by a test
    import numba
    from numba import njit, prange
    NUMBA_AVAILABLE = True
    NUMBA_ERROR: str | None = None
except Exception as exc:  # noqa: BLE001 - any import failure means "no fast path"
    NUMBA_AVAILABLE = False
    NUMBA_ERROR = f"numba could not be imported ({type(exc).__name__}: {exc})"

    def njit(*args, **kwargs):  # type: ignore[no-redef]
        if args and callable(args[0]):
            return args[0]
        return lambda f: f

    prange = range  # type: ignore[assignment]

#: Columns of the frame returned by :func:`run_pulse_grid`, in order.
MAP_COLUMNS = ("amplitude", "frequency", "pulse", "sign", "overturned", "exceeded_critical",
               "max_abs_phi_over_alpha", "n_impacts", "fractured", "uplifted", "t_overturn",
               "status", "reason", "cpu_s")


def _require_numba() -> None:
    if not NUMBA_AVAILABLE:
        raise BackendUnavailable(
            f"the compiled analytic path needs numba: {NUMBA_ERROR}; install it "
            "(pip install numba) or use rockbench.analytic.solver.simulate")


# --- the DOP853 tableau (scipy's coefficient table, the scheme the reference path uses) ----------
def _tableau():
    from scipy.integrate._ivp import dop853_coefficients as c
    n = c.N_STAGES
    return (np.ascontiguousarray(c.A, dtype=np.float64), np.ascontiguousarray(c.B, np.float64),
            np.ascontiguousarray(c.C, np.float64), np.ascontiguousarray(c.E3, np.float64),
            np.ascontiguousarray(c.E5, np.float64), np.ascontiguousarray(c.D, np.float64), n)


_A, _B, _C, _E3, _E5, _D, _NS = _tableau()
_NSE = _A.shape[0]          # stages incl. the three extra ones of the dense output (16)
_NI = _D.shape[0] + 3       # interpolator power (7)

# kinds of ground motion understood by the kernel
_M_NONE, _M_SYM, _M_ANTI, _M_REC = 0, 1, 2, 3
# event kinds (codes in the kernel's event buffer)
_EV_NAMES = ("uplift", "impact", "peak", "critical", "fracture", "overturn", "rest")
_EV_UPLIFT, _EV_IMPACT, _EV_PEAK, _EV_CRIT, _EV_FRAC, _EV_OVER, _EV_REST = range(7)
# failure reasons
_REASONS = {1: "integrator step size fell below 10 ulp (solver could not advance)",
            2: "event loop made no progress",
            3: "event buffer full",
            4: "event loop exceeded the maximum number of iterations"}
# layout of the per-direction geometry rows (see scene_arrays)
_NGEO = 32
# layout of the summary vector returned by the kernel
(_O_STATUS, _O_T, _O_MAXABS, _O_OVER, _O_TOVER, _O_EXC, _O_UPL, _O_TUPL, _O_NIMP, _O_FRAC,
 _O_TFRAC, _O_STEPS, _O_NFEV, _O_NEV, _O_PHI, _O_PHID, _O_MODE, _O_INTACT, _O_ADV) = range(19)
_NOUT = 19

_PI = math.pi
_SYM_EXT = np.array([-math.sqrt(1.5) / math.pi, 0.0, math.sqrt(1.5) / math.pi])
_xs = np.sqrt([3.0 - math.sqrt(6.0), 3.0 + math.sqrt(6.0)])
_taus = math.sqrt(3.0) * _xs / (2.0 * math.pi)
_ANTI_EXT = np.concatenate([-_taus[::-1], _taus])
_BETA = antisymmetric_beta()
_XFAC = 2.0 * math.pi / math.sqrt(3.0)


# ================================================================================================
# Scene -> plain arrays
# ================================================================================================
@functools.lru_cache(maxsize=64)
def scene_arrays(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Plain parameter arrays of ``scene`` for the compiled kernel, computed once per scene.

    Returns ``geo`` (2 x 32: one row per direction, index 0 for +1 and 1 for -1: mechanism
    geometry, masses, inertias, b, k, C) and ``sc`` (scalars: lambda, eta, fall, fracture and
    critical angles, alpha, p, devices flag), all from :func:`reference_of`.
    """
    ref = reference_of(scene)
    st = scene.structure
    geo = np.zeros((2, _NGEO))
    for i, s in enumerate((1, -1)):
        dyn = ref.dyn[s]
        row = geo[i]
        m, Ic = list(dyn._m) + [0.0] * (3 - len(dyn._m)), list(dyn._I) + [0.0] * (3 - len(dyn._I))
        row[20:23] = m
        row[23:26] = Ic
        row[26] = st.b
        row[27] = dyn._k
        row[28] = dyn._c
        mech = dyn.mechanism
        if isinstance(st, Frame):
            row[0] = 1.0
            row[1:3] = mech._A
            row[3:5] = mech._D
            row[5], row[6], row[7] = mech._rho0, mech._rho1, mech._L
            row[8], row[9], row[10] = mech._phiAB0, mech._phiCD0, mech._phiBC0
            row[11:13] = mech._rl
            row[13:15] = mech._rb
            row[15:17] = mech._rr
            row[17] = mech._branch
        else:
            row[0] = 0.0
            px, py = mech.pivot
            row[1], row[2] = px, py
            row[3], row[4] = -px, st.H
    sc = np.array([ref.lam[1], ref.lam[-1], ref.eta[1], ref.eta[-1], ref.fall[1], ref.fall[-1],
                   ref.fracture_angle[1], ref.fracture_angle[-1],
                   ref.critical[(1, True)], ref.critical[(-1, True)],
                   ref.critical[(1, False)], ref.critical[(-1, False)],
                   ref.alpha, ref.p, 1.0 if scene.has_devices else 0.0])
    geo.setflags(write=False)
    sc.setflags(write=False)
    return geo, sc


# ================================================================================================
# Compiled kernel
# ================================================================================================
@njit(cache=True, inline="always")
def _body(ox, oy, dox, doy, ddox, ddoy, rx, ry, th, dth, ddth, out, j):
    """dx, dy, ddx, ddy of the centre of mass of a body rotating by th(phi) about a point O
    (mechanism._body_about), written to out[j, :]."""
    c = math.cos(th)
    s = math.sin(th)
    qx = c * rx - s * ry
    qy = s * rx + c * ry
    out[j, 0] = dox - dth * qy
    out[j, 1] = doy + dth * qx
    out[j, 2] = ddox - ddth * qy - dth * dth * qx
    out[j, 3] = ddoy + ddth * qx - dth * dth * qy
    out[j, 4] = th
    out[j, 5] = dth
    out[j, 6] = ddth


@njit(cache=True)
def _kinematics(phi, g, kin):
    """Fill kin[body] = (dx, dy, ddx, ddy, theta, dtheta, ddtheta) of every body at ``phi``
    (mechanism.FrameMechanism.configuration / BlockMechanism.configuration). Returns the number of
    bodies, or -1 beyond the reach of the four-bar linkage."""
    if g[0] == 0.0:
        _body(g[1], g[2], 0.0, 0.0, 0.0, 0.0, g[3], g[4], phi, 1.0, 0.0, kin, 0)
        return 1
    Ax, Ay, Dx, Dy = g[1], g[2], g[3], g[4]
    r0, r1, L = g[5], g[6], g[7]
    pab = g[8] + phi
    cab = math.cos(pab)
    sab = math.sin(pab)
    Bx = Ax + r0 * cab
    By = Ay + r0 * sab
    ux = Bx - Dx
    uy = By - Dy
    d2 = ux * ux + uy * uy
    d = math.sqrt(d2)
    ap = (d2 + r1 * r1 - L * L) / (2.0 * d)
    h2 = r1 * r1 - ap * ap
    if h2 < 0.0:
        return -1
    hh = g[17] * math.sqrt(h2)
    Cx = Dx + (ap * ux - hh * uy) / d
    Cy = Dy + (ap * uy + hh * ux) / d
    pbc = math.atan2(Cy - By, Cx - Bx)
    pcd = math.atan2(Cy - Dy, Cx - Dx)
    sbc = math.sin(pbc)
    cbc = math.cos(pbc)
    scd = math.sin(pcd)
    ccd = math.cos(pcd)
    m11 = -L * sbc
    m12 = r1 * scd
    m21 = L * cbc
    m22 = -r1 * ccd
    det = m11 * m22 - m12 * m21
    f1 = r0 * sab
    f2 = -r0 * cab
    dbc = (f1 * m22 - m12 * f2) / det
    dcd = (m11 * f2 - f1 * m21) / det
    g1 = r0 * cab + L * cbc * dbc * dbc - r1 * ccd * dcd * dcd
    g2 = r0 * sab + L * sbc * dbc * dbc - r1 * scd * dcd * dcd
    ddbc = (g1 * m22 - m12 * g2) / det
    ddcd = (m11 * g2 - g1 * m21) / det
    bx = Bx - Ax
    by = By - Ay
    _body(Ax, Ay, 0.0, 0.0, 0.0, 0.0, g[11], g[12], phi, 1.0, 0.0, kin, 0)
    _body(Bx, By, -by, bx, -bx, -by, g[13], g[14], pbc - g[10], dbc, ddbc, kin, 1)
    _body(Dx, Dy, 0.0, 0.0, 0.0, 0.0, g[15], g[16], pcd - g[9], dcd, ddcd, kin, 2)
    return 3


@njit(cache=True, inline="always")
def _opening(b, x, dx):
    ax = abs(x)
    sgn = 1.0 if x >= 0.0 else -1.0
    return 2.0 * b * math.sin(0.5 * ax), b * math.cos(0.5 * ax) * sgn * dx


@njit(cache=True)
def _devices(kin, b):
    """(elong_l, elong_r, delong_l, delong_r, dchord_l, dchord_r) (Dynamics.device_state)."""
    eb, deb = _opening(b, kin[0, 4], kin[0, 5])
    et, det = _opening(b, kin[0, 4] - kin[1, 4], kin[0, 5] - kin[1, 5])
    el, dl, cl = eb + et, deb + det, 2.0 * deb
    eb, deb = _opening(b, kin[2, 4], kin[2, 5])
    et, det = _opening(b, kin[2, 4] - kin[1, 4], kin[2, 5] - kin[1, 5])
    er, dr, cr = eb + et, deb + det, 2.0 * deb
    return el, er, dl, dr, cl, cr


@njit(cache=True)
def _phidd(phi, pd, ag, g, intact, kin):
    """phi'' [rad/s^2] of Eq. 17 (Dynamics.acceleration)."""
    nb = _kinematics(phi, g, kin)
    if nb < 0:
        return np.nan
    In = 0.0
    J = 0.0
    Gm = 0.0
    Bm = 0.0
    for i in range(nb):
        m = g[20 + i]
        Ic = g[23 + i]
        dx, dy, ddx, ddy = kin[i, 0], kin[i, 1], kin[i, 2], kin[i, 3]
        dth, ddth = kin[i, 5], kin[i, 6]
        In += m * (dx * dx + dy * dy) + Ic * dth * dth
        J += m * (dx * ddx + dy * ddy) + Ic * dth * ddth
        Gm += m * dy
        Bm -= m * dx
    K = 0.0
    D = 0.0
    k = g[27]
    c = g[28]
    if intact and (k > 0.0 or c > 0.0):
        el, er, dl, dr, cl, cr = _devices(kin, g[26])
        K = k * (el * dl + er * dr)
        D = c * (cl * cl + cr * cr)
    return (Bm * ag - J * pd * pd - Gm * 9.81 - K - D * pd) / In


@njit(cache=True)
def _acc(t, mk, mp, rt, ra, hint):
    """Ground acceleration [m/s^2] (RickerPulse.acceleration / Record.acceleration)."""
    if mk == 1:
        tau = t / mp[1]
        u = 9.869604401089358 * tau * tau
        return mp[0] * ((1.0 - 2.0 * u) * math.exp(-u))
    if mk == 2:
        x = mp[4] * (t / mp[1])
        return mp[0] * ((x * x - 3.0) * x * math.exp(-0.5 * x * x))
    if mk == 3:
        n = rt.shape[0]
        if not (rt[0] <= t <= rt[n - 1]):
            return 0.0
        i = hint[0]
        if i < 0 or i >= n - 1 or not (rt[i] <= t < rt[i + 1]):
            if 0 <= i < n - 2 and rt[i + 1] <= t < rt[i + 2]:
                i = i + 1
            else:
                i = np.searchsorted(rt, t, side="right") - 1
            if i >= n - 1:
                return ra[n - 1]
            hint[0] = i
        w = (t - rt[i]) / (rt[i + 1] - rt[i])
        return (1.0 - w) * ra[i] + w * ra[i + 1]
    return 0.0


@njit(cache=True)
def _max_abs_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint):
    """sup |u_g''| over [t, inf) (GroundMotion.max_abs_after)."""
    a = abs(_acc(t, mk, mp, rt, ra, hint))
    later = 0.0
    if mk == 1 or mk == 2:
        i = np.searchsorted(ext, t, side="left")
        if i < ext.shape[0]:
            later = extsuf[i]
    elif mk == 3:
        i = np.searchsorted(rt, t, side="right")
        if i < rsuf.shape[0]:
            later = rsuf[i]
    return max(later, a)


@njit(cache=True)
def _updir(a, thr_p, thr_n):
    if a > thr_p:
        return 1
    if a < thr_n:
        return -1
    return 0


@njit(cache=True)
def _brent_acc(lo, hi, thr, mk, mp, rt, ra, hint, xtol, rtol):
    """Root of acc(t) - thr in [lo, hi] (sign change assumed) by Brent's method."""
    a, b = lo, hi
    fa = _acc(a, mk, mp, rt, ra, hint) - thr
    fb = _acc(b, mk, mp, rt, ra, hint) - thr
    return _brent_core(a, b, fa, fb, xtol, rtol, 0, mk, mp, rt, ra, hint,
                       np.zeros((1, 1)), 0.0, 1.0, np.zeros(2), 0, thr, 1.0)


@njit(cache=True)
def _dense_eval(F, yold, t_old, h, t, comp):
    """Component ``comp`` of the DOP853 dense output at t (Dop853DenseOutput)."""
    x = (t - t_old) / h
    y = 0.0
    n = F.shape[0]
    for i in range(n):
        y += F[n - 1 - i, comp]
        if i % 2 == 0:
            y *= x
        else:
            y *= 1.0 - x
    return y + yold[comp]


@njit(cache=True)
def _fval(kind, t, mk, mp, rt, ra, hint, F, t_old, h, yold, comp, shift, mul):
    if kind == 0:
        return _acc(t, mk, mp, rt, ra, hint) - shift
    return mul * _dense_eval(F, yold, t_old, h, t, comp) - shift


@njit(cache=True)
def _brent_core(xa, xb, fa, fb, xtol, rtol, kind, mk, mp, rt, ra, hint, F, t_old, h, yold,
                comp, shift, mul):
    """Brent's method (inverse quadratic interpolation / secant / bisection) on [xa, xb]."""
    if fa == 0.0:
        return xa
    if fb == 0.0:
        return xb
    xpre, xcur = xa, xb
    fpre, fcur = fa, fb
    xblk = 0.0
    fblk = 0.0
    spre = 0.0
    scur = 0.0
    for _ in range(200):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk = xpre
            fblk = fpre
            spre = xcur - xpre
            scur = spre
        if abs(fblk) < abs(fcur):
            xpre = xcur
            xcur = xblk
            xblk = xpre
            fpre = fcur
            fcur = fblk
            fblk = fpre
        delta = 0.5 * (xtol + rtol * abs(xcur))
        sbis = 0.5 * (xblk - xcur)
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre = scur
                scur = stry
            else:
                spre = sbis
                scur = sbis
        else:
            spre = sbis
            scur = sbis
        xpre = xcur
        fpre = fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = _fval(kind, xcur, mk, mp, rt, ra, hint, F, t_old, h, yold, comp, shift, mul)
    return xcur


@njit(cache=True)
def _next_uplift(ta, tb, mk, mp, rt, ra, hint, ext, thr_p, thr_n):
    """First uplift time in [ta, tb] and its direction, (nan, 0) if none (solver.next_uplift)."""
    s = _updir(_acc(ta, mk, mp, rt, ra, hint), thr_p, thr_n)
    if s != 0:
        return ta, s
    if mk == 0 or tb <= ta:
        return np.nan, 0
    lo = ta
    hi = ta
    found = 0
    if mk == 3:
        n = rt.shape[0]
        i = np.searchsorted(rt, ta, side="right")
        while True:
            if i < n and rt[i] < tb:
                hi = rt[i]
            else:
                hi = tb
            a = _acc(hi, mk, mp, rt, ra, hint)
            d = _updir(a, thr_p, thr_n)
            if d != 0:
                found = d
                break
            if hi >= tb:
                break
            lo = hi
            i += 1
    else:
        per = mp[1]
        nk = max(1, int(math.ceil((tb - ta) * 400.0 / per)))
        step = (tb - ta) / nk
        j = 1
        e = np.searchsorted(ext, ta, side="right")
        ne = ext.shape[0]
        while True:
            tg = tb if j >= nk else ta + j * step
            if e < ne and ext[e] < tb and ext[e] < tg:
                hi = ext[e]
                e += 1
            else:
                hi = tg
                if e < ne and ext[e] == tg:
                    e += 1
                j += 1
            a = _acc(hi, mk, mp, rt, ra, hint)
            d = _updir(a, thr_p, thr_n)
            if d != 0:
                found = d
                break
            if hi >= tb:
                break
            lo = hi
    if found == 0:
        return np.nan, 0
    thr = thr_p if found == 1 else thr_n
    if mk == 3:
        alo = _acc(lo, mk, mp, rt, ra, hint)
        ahi = _acc(hi, mk, mp, rt, ra, hint)
        tu = lo + (thr - alo) * (hi - lo) / (ahi - alo)
        tu = min(max(tu, lo), hi)
    else:
        tu = _brent_acc(lo, hi, thr, mk, mp, rt, ra, hint, 1e-13, 1e-14)
    # step just past the root so that the excess is strictly positive (doubling steps)
    step = 1e-13 * max(1.0, abs(tu))
    while tu < hi and not (found * (_acc(tu, mk, mp, rt, ra, hint) - thr) > 0.0):
        tu = min(hi, tu + step)
        step *= 2.0
    return tu, found


@njit(cache=True)
def _rms2(a0, a1, s0, s1):
    x0 = a0 / s0
    x1 = a1 / s1
    return math.sqrt(0.5 * (x0 * x0 + x1 * x1))


@njit(cache=True)
def _push_event(evf, evi, nev, t, kind, phi, pb, pa, eta, d):
    cap = evf.shape[0]
    if nev < cap:
        evf[nev, 0] = t
        evf[nev, 1] = phi
        evf[nev, 2] = pb
        evf[nev, 3] = pa
        evf[nev, 4] = eta
        evi[nev, 0] = kind
        evi[nev, 1] = d
    return nev + 1


@njit(cache=True)
def _fill_hist(tg, hist, hmode, hint_, ta, tb, F, yold, t_old, h, mode, intact, rest):
    """Write the history samples tg in [ta, tb] from the dense output (or rest)."""
    n = tg.shape[0]
    i = np.searchsorted(tg, ta, side="left")
    while i < n and tg[i] <= tb:
        if rest:
            hist[i, 0] = 0.0
            hist[i, 1] = 0.0
        else:
            hist[i, 0] = _dense_eval(F, yold, t_old, h, tg[i], 0)
            hist[i, 1] = _dense_eval(F, yold, t_old, h, tg[i], 1)
        hmode[i, 0] = mode
        hmode[i, 1] = intact
        i += 1


@njit(cache=True)
def _run(geo, sc, mk, mp, rt, ra, ext, extsuf, rsuf, t0, t_end, phi0, phid0, rtol, atol,
         v_rest, thr_p, thr_n, motion_end, v_chat, dt_chat, min_adv, window, max_iter,
         A, B, C, E3, E5, Dd, ns, want_ev, evf, evi, want_hist, tg, hist, hmode, out):
    """One event-driven run of the SDOF model (solver.simulate's loop). Results go to ``out``
    (layout _O_*), events to evf/evi, history samples to hist/hmode."""
    hint = np.zeros(1, dtype=np.int64)
    kin = np.zeros((3, 7))
    K = np.zeros((A.shape[0], 2))
    F = np.zeros((Dd.shape[0] + 3, 2))
    yold = np.zeros(2)
    ynew = np.zeros(2)
    ytmp = np.zeros(2)
    g_old = np.zeros(5)
    g_new = np.zeros(5)
    roots = np.zeros(5)
    order = np.zeros(5, dtype=np.int64)
    ntab = A.shape[0]
    nint = Dd.shape[0] + 3
    err_exp = -1.0 / 8.0
    intact = sc[14] != 0.0
    status = 0
    overturned = False
    t_over = np.nan
    fractured = False
    t_frac = np.nan
    exceeded = False
    max_abs = abs(phi0)
    nimp = 0
    nev = 0
    steps = 0
    nfev = 0
    t_upl = np.nan
    if phi0 != 0.0:
        mode = 1 if phi0 > 0.0 else -1
    elif phid0 != 0.0:
        mode = 1 if phid0 > 0.0 else -1
    else:
        mode = 0
    t = t0
    phi = phi0
    phid = phid0
    n_iter = 0
    recent = np.zeros(max(1, window))
    has_last = False       # last impact of the current rocking episode (chatter rule)
    last_t = 0.0
    last_v = 0.0
    adv = 0.0
    while t < t_end and not overturned:
        n_iter += 1
        recent[(n_iter - 1) % window] = t
        if n_iter >= window:
            adv = t - recent[n_iter % window]
            if adv < min_adv:
                status = 2
                break
        if n_iter > max_iter:
            status = 4
            break
        if mode == 0:
            # the motion can no longer exceed either threshold: same outcome as a scan that
            # finds no uplift before t_end (GroundMotion.max_abs_after), at no cost
            if _max_abs_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint) <= min(thr_p, -thr_n):
                tu, s = np.nan, 0
            else:
                tu, s = _next_uplift(t, t_end, mk, mp, rt, ra, hint, ext, thr_p, thr_n)
            if s == 0:
                t_stop = min(t_end, max(t, motion_end))
                if want_hist:
                    _fill_hist(tg, hist, hmode, hint, t, t_stop, F, yold, 0.0, 1.0, 0,
                               intact, True)
                t = t_stop
                t_end = t_stop
                break
            if want_hist:
                _fill_hist(tg, hist, hmode, hint, t, tu, F, yold, 0.0, 1.0, 0, intact, True)
            if want_ev:
                nev = _push_event(evf, evi, nev, tu, 0, 0.0, 0.0, 0.0, np.nan, s)
            if np.isnan(t_upl):
                t_upl = tu
            t = tu
            phi = 0.0
            phid = 0.0
            mode = s
            has_last = False
            continue

        s = mode
        gi = 0 if s == 1 else 1
        g = geo[gi]
        fall = sc[4 + gi]
        frac = sc[6 + gi] if intact else np.inf
        crit = sc[8 + gi] if intact else sc[10 + gi]
        # a segment that starts at or beyond the critical angle of its potential exceeds it
        if crit < np.inf and s * phi >= crit:
            exceeded = True
            if want_ev:
                nev = _push_event(evf, evi, nev, t, 3, phi, phid, phid, np.nan, s)
        nev_seg = nev
        max_seg = max_abs
        exc_seg = exceeded
        # --- solve_ivp(DOP853) from (t, phi, phid) to t_end with the five events -------------
        ya0 = phi
        ya1 = phid
        ag = _acc(t, mk, mp, rt, ra, hint)
        f0 = ya1
        f1 = _phidd(ya0, ya1, ag, g, intact, kin)
        nfev += 1
        # initial step (common.select_initial_step, order 7)
        interval = abs(t_end - t)
        s0 = atol + abs(ya0) * rtol
        s1 = atol + abs(ya1) * rtol
        d0 = _rms2(ya0, ya1, s0, s1)
        d1 = _rms2(f0, f1, s0, s1)
        if d0 < 1e-5 or d1 < 1e-5:
            h0 = 1e-6
        else:
            h0 = 0.01 * d0 / d1
        h0 = min(h0, interval)
        y1a = ya0 + h0 * f0
        y1b = ya1 + h0 * f1
        fb0 = y1b
        fb1 = _phidd(y1a, y1b, _acc(t + h0, mk, mp, rt, ra, hint), g, intact, kin)
        nfev += 1
        d2 = _rms2(fb0 - f0, fb1 - f1, s0, s1) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
        h_abs = min(100.0 * h0, h1, interval)
        # events at the start: impact, overturn, fracture, critical, peak
        # impact (s phi falls to 0) and peak (s phi' falls to 0) are taken as positive at the
        # segment's first instant, so that a root is never the start itself (solver.py)
        g_old[0] = 1.0
        g_old[1] = s * ya0 - fall
        g_old[2] = s * ya0 - frac
        g_old[3] = s * ya0 - crit
        g_old[4] = 1.0
        term_kind = -1
        t_seg0 = t
        while True:
            # ---- one accepted step (RungeKutta._step_impl) ----
            min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
            if h_abs < min_step:
                h_abs = min_step
            rejected = False
            ok = False
            while True:
                if h_abs < min_step:
                    break
                h = h_abs
                t_new = t + h
                if t_new - t_end > 0.0:
                    t_new = t_end
                h = t_new - t
                h_abs = abs(h)
                K[0, 0] = f0
                K[0, 1] = f1
                for st in range(1, ns):
                    dy0 = 0.0
                    dy1 = 0.0
                    for j in range(st):
                        dy0 += K[j, 0] * A[st, j]
                        dy1 += K[j, 1] * A[st, j]
                    ytmp[0] = ya0 + dy0 * h
                    ytmp[1] = ya1 + dy1 * h
                    tt = t + C[st] * h
                    K[st, 0] = ytmp[1]
                    K[st, 1] = _phidd(ytmp[0], ytmp[1], _acc(tt, mk, mp, rt, ra, hint), g,
                                      intact, kin)
                s0b = 0.0
                s1b = 0.0
                for j in range(ns):
                    s0b += K[j, 0] * B[j]
                    s1b += K[j, 1] * B[j]
                ynew[0] = ya0 + h * s0b
                ynew[1] = ya1 + h * s1b
                fn0 = ynew[1]
                fn1 = _phidd(ynew[0], ynew[1], _acc(t + h, mk, mp, rt, ra, hint), g, intact,
                             kin)
                K[ns, 0] = fn0
                K[ns, 1] = fn1
                nfev += ns
                sc0 = atol + max(abs(ya0), abs(ynew[0])) * rtol
                sc1 = atol + max(abs(ya1), abs(ynew[1])) * rtol
                e50 = 0.0
                e51 = 0.0
                e30 = 0.0
                e31 = 0.0
                for j in range(ns + 1):
                    e50 += K[j, 0] * E5[j]
                    e51 += K[j, 1] * E5[j]
                    e30 += K[j, 0] * E3[j]
                    e31 += K[j, 1] * E3[j]
                e50 /= sc0
                e51 /= sc1
                e30 /= sc0
                e31 /= sc1
                n5 = e50 * e50 + e51 * e51
                n3 = e30 * e30 + e31 * e31
                if n5 == 0.0 and n3 == 0.0:
                    err = 0.0
                else:
                    err = abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * 2.0)
                if not (err == err):  # NaN: beyond the mechanism's reach
                    h_abs *= 0.2
                    rejected = True
                    continue
                if err < 1.0:
                    if err == 0.0:
                        factor = 10.0
                    else:
                        factor = min(10.0, 0.9 * err ** err_exp)
                    if rejected:
                        factor = min(1.0, factor)
                    h_abs *= factor
                    ok = True
                    break
                h_abs *= max(0.2, 0.9 * err ** err_exp)
                rejected = True
            if not ok:
                status = 1
                break
            steps += 1
            t_old = t
            yold[0] = ya0
            yold[1] = ya1
            # ---- events ----
            g_new[0] = s * ynew[0]
            g_new[1] = s * ynew[0] - fall
            g_new[2] = s * ynew[0] - frac
            g_new[3] = s * ynew[0] - crit
            g_new[4] = s * ynew[1]
            nact = 0
            for e in range(5):
                d = -1 if (e == 0 or e == 4) else 1
                up = g_old[e] <= 0.0 and g_new[e] >= 0.0
                down = g_old[e] >= 0.0 and g_new[e] <= 0.0
                if (up and d > 0) or (down and d < 0):
                    order[nact] = e
                    nact += 1
            have_dense = False
            need_h = False
            if want_hist:
                ih = np.searchsorted(tg, t_old, side="left")
                need_h = ih < tg.shape[0] and tg[ih] <= t_new
            if nact > 0 or need_h:
                # dense output (DOP853._dense_output_impl): three extra stages
                for st in range(ns + 1, ntab):
                    dy0 = 0.0
                    dy1 = 0.0
                    for j in range(st):
                        dy0 += K[j, 0] * A[st, j]
                        dy1 += K[j, 1] * A[st, j]
                    ytmp[0] = ya0 + dy0 * h
                    ytmp[1] = ya1 + dy1 * h
                    tt = t_old + C[st] * h
                    K[st, 0] = ytmp[1]
                    K[st, 1] = _phidd(ytmp[0], ytmp[1], _acc(tt, mk, mp, rt, ra, hint), g,
                                      intact, kin)
                nfev += ntab - ns - 1
                for c in range(2):
                    dlt = ynew[c] - yold[c]
                    fo = K[0, c]
                    fnew = fn0 if c == 0 else fn1
                    F[0, c] = dlt
                    F[1, c] = h * fo - dlt
                    F[2, c] = 2.0 * dlt - h * (fnew + fo)
                    for r in range(nint - 3):
                        acc_ = 0.0
                        for j in range(ntab):
                            acc_ += Dd[r, j] * K[j, c]
                        F[3 + r, c] = h * acc_
                have_dense = True
            t_stop = t_new
            terminated = False
            if nact > 0:
                for q in range(nact):
                    e = order[q]
                    comp = 1 if e == 4 else 0
                    if e == 0 or e == 4:
                        mul = float(s)
                        shift = 0.0
                    else:
                        mul = float(s)
                        shift = fall if e == 1 else (frac if e == 2 else crit)
                    # solve_ivp: brentq on the dense output, xtol = rtol = 4 machine epsilons
                    roots[q] = _brent_core(t_old, t_new, g_old[e], g_new[e], 8.881784197001252e-16,
                                           8.881784197001252e-16, 1, mk, mp, rt, ra, hint, F,
                                           t_old, h, yold, comp, shift, mul)
                # sort active events by root time (insertion sort, stable)
                for q in range(1, nact):
                    rq = roots[q]
                    eq = order[q]
                    p = q - 1
                    while p >= 0 and roots[p] > rq:
                        roots[p + 1] = roots[p]
                        order[p + 1] = order[p]
                        p -= 1
                    roots[p + 1] = rq
                    order[p + 1] = eq
                last = nact
                for q in range(nact):
                    if order[q] <= 2:
                        last = q + 1
                        terminated = True
                        break
                for q in range(last):
                    e = order[q]
                    te = roots[q]
                    if e == 3 or e == 4:
                        pe = _dense_eval(F, yold, t_old, h, te, 0)
                        pde = _dense_eval(F, yold, t_old, h, te, 1)
                        if e == 4:
                            if abs(pe) > max_abs:
                                max_abs = abs(pe)
                            if want_ev:
                                nev = _push_event(evf, evi, nev, te, 2, pe, pde, pde, np.nan, s)
                        else:
                            exceeded = True
                            if want_ev:
                                nev = _push_event(evf, evi, nev, te, 3, pe, pde, pde, np.nan, s)
                if terminated:
                    term_kind = order[last - 1]
                    t_stop = roots[last - 1]
                    ynew[0] = _dense_eval(F, yold, t_old, h, t_stop, 0)
                    ynew[1] = _dense_eval(F, yold, t_old, h, t_stop, 1)
            if want_hist and have_dense:
                _fill_hist(tg, hist, hmode, hint, t_old, t_stop, F, yold, t_old, h, s,
                           intact, False)
            if abs(ynew[0]) > max_abs:
                max_abs = abs(ynew[0])
            for e in range(5):
                g_old[e] = g_new[e]
            t = t_stop
            ya0 = ynew[0]
            ya1 = ynew[1]
            f0 = fn0
            f1 = fn1
            if terminated or t >= t_end:
                break
        if status != 0:
            # as the reference: the failed segment is not kept, the run ends at its start
            t = t_seg0
            nev = nev_seg
            max_abs = max_seg
            exceeded = exc_seg
            break
        phi = ya0
        phid = ya1
        if term_kind < 0:      # reached t_end
            break
        if term_kind == 0:     # impact
            phi = 0.0
            post = -s
            eta = sc[2] if post == 1 else sc[3]
            after = eta * phid
            settles = eta <= 0.0 or abs(after) <= v_rest
            # chatter (rules.py): two successive small post-impact velocities, close in time
            if (not settles and has_last and abs(after) <= v_chat and last_v <= v_chat
                    and t - last_t <= dt_chat):
                settles = True
            new_mode = 0 if settles else post
            nimp += 1
            if want_ev:
                nev = _push_event(evf, evi, nev, t, 1, 0.0, phid, after, eta, new_mode)
            if new_mode == 0:
                if want_ev:
                    nev = _push_event(evf, evi, nev, t, 6, 0.0, phid * eta, 0.0, np.nan, 0)
                after = 0.0
                has_last = False
            else:
                has_last = True
                last_t = t
                last_v = abs(after)
            phid = after
            mode = new_mode
        elif term_kind == 1:   # overturn
            overturned = True
            t_over = t
            if want_ev:
                nev = _push_event(evf, evi, nev, t, 5, phi, phid, phid, np.nan, s)
        else:                  # fracture
            intact = False
            fractured = True
            t_frac = t
            if want_ev:
                nev = _push_event(evf, evi, nev, t, 4, phi, phid, phid, np.nan, s)
    if want_ev and nev > evf.shape[0]:
        status = 3
    out[_O_STATUS] = status
    out[_O_T] = t
    out[_O_MAXABS] = max_abs
    out[_O_OVER] = 1.0 if overturned else 0.0
    out[_O_TOVER] = t_over
    out[_O_EXC] = 1.0 if (exceeded or overturned) else 0.0
    out[_O_UPL] = 1.0 if (not np.isnan(t_upl) or phi0 != 0.0 or phid0 != 0.0) else 0.0
    out[_O_TUPL] = t_upl
    out[_O_NIMP] = nimp
    out[_O_FRAC] = 1.0 if fractured else 0.0
    out[_O_TFRAC] = t_frac
    out[_O_STEPS] = steps
    out[_O_NFEV] = nfev
    out[_O_NEV] = nev
    out[_O_PHI] = phi
    out[_O_PHID] = phid
    out[_O_MODE] = mode
    out[_O_INTACT] = 1.0 if intact else 0.0
    out[_O_ADV] = adv


# --- pulses built in the kernel (map cells) ------------------------------------------------------
@njit(cache=True)
def _pulse_setup(shape, sign, A, W, alpha, p, sym_ext, anti_ext, beta, xfac, mp, ext, extsuf):
    """RickerPulse.dimensionless in compiled code: fills mp (scale, period, t_start, t_end,
    xfac), the extrema and their suffix maxima; returns the number of extrema."""
    amp = A * 9.81 * math.tan(alpha)
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
    mp = np.zeros(5)
    shape = shapes[i]
    n_ext = 3 if shape == 1 else 4
    ext = np.zeros(n_ext)
    extsuf = np.zeros(n_ext)
    _pulse_setup(shape, float(signs[i]), As[i], Ws[i], sc[12], sc[13], sym_ext, anti_ext, beta,
                 xfac, mp, ext, extsuf)
    t0 = mp[2]
    dur = duration if duration > 0.0 else (mp[3] - mp[2]) + 10.0
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


@njit(cache=True)
def _device_history(geo, sc, phi, mode, out):
    """theta_beam, theta_right, elongations and damper chord rates per history sample."""
    kin = np.zeros((3, 7))
    for i in range(phi.shape[0]):
        if mode[i] == 0:
            continue
        g = geo[0] if mode[i] == 1 else geo[1]
        if _kinematics(phi[i], g, kin) < 3:
            continue
        el, er, dl, dr, cl, cr = _devices(kin, g[26])
        out[i, 0] = kin[1, 4]
        out[i, 1] = kin[2, 4]
        out[i, 2] = el
        out[i, 3] = er
        out[i, 4] = cl
        out[i, 5] = cr


# ================================================================================================
# Python entry points
# ================================================================================================
def _thresholds(sc: np.ndarray) -> tuple[float, float]:
    f = 1.0 + rules.UPLIFT_RTOL
    return sc[0] * G * f, sc[1] * G * f


def _rule_params(sc: np.ndarray) -> np.ndarray:
    """The rules' constants, read when a run starts (rockbench.analytic.rules): chatter velocity
    [rad/s] and interval [s], least advance [s], progress window and most iterations."""
    p, alpha = sc[13], sc[12]
    return np.array([rules.CHATTER_VELOCITY_RATIO * p * alpha, rules.CHATTER_INTERVAL / p,
                     rules.PROGRESS_MIN_ADVANCE / p, max(1, int(rules.PROGRESS_WINDOW)),
                     int(rules.MAX_EVENT_ITERATIONS)], dtype=float)


def _reason(code: int, out: np.ndarray, rp: np.ndarray, t_end: float) -> str | None:
    """The reason of a run that is not ok (worded as the reference's)."""
    t = out[_O_T]
    if code == 0:
        return None
    if code == 1:
        return (f"compiled DOP853 failed at t = {t:.9g} s: required step size is less than "
                "spacing between numbers")
    if code == 2:
        return (f"analytic event loop made no progress: {int(rp[3])} iterations advanced time by "
                f"{out[_O_ADV]:.3g} s < {rp[2]:.3g} s at t = {t:.9g} s (mode {int(out[_O_MODE])})")
    if code == 4:
        return (f"analytic event loop exceeded {int(rp[4])} iterations at t = {t:.9g} s "
                f"of {t_end:.9g} s")
    return _REASONS.get(code, str(code))


def _motion_arrays(mot) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                 np.ndarray, np.ndarray]:
    """(kind, mp, record t, record a, extrema, extrema suffix max, record suffix max)."""
    empty = np.zeros(1)
    mp = np.zeros(5)
    mp[4] = _XFAC
    if mot is None:
        return _M_NONE, mp, empty, empty, empty[:0], empty[:0], empty
    if isinstance(mot, RickerPulse):
        kind = _M_SYM if mot.shape == "symmetric" else _M_ANTI
        mp[0], mp[1] = mot._scale, mot.period
        mp[2], mp[3] = mot.t_start, mot.t_end
        ext = np.ascontiguousarray(mot._extrema, dtype=float)
        suf = np.ascontiguousarray(mot._extrema_sufmax, dtype=float)
        return kind, mp, empty, empty, ext, suf, empty
    if isinstance(mot, Record):
        rt = np.array(mot.time, dtype=float)          # writable copies: one compiled type
        ra = np.array(mot.samples, dtype=float)
        mp[2], mp[3] = mot.t_start, mot.t_end
        return _M_REC, mp, rt, ra, empty[:0], empty[:0], np.array(mot._sufmax, dtype=float)
    raise ParameterError("motion", type(mot).__name__,
                         "a RickerPulse, a Record or None for the compiled analytic path")


def simulate_compiled(scene: Scene, motion=None, *, duration: float | None = None,
                      phi0: float = 0.0, phidot0: float = 0.0, settings=None,
                      reference: Reference | None = None) -> Result:
    """Run the analytic SDOF model of ``scene`` under ``motion`` with the compiled kernel.

    Same signature, arguments and :class:`rockbench.result.Result` schema as
    :func:`rockbench.analytic.solver.simulate` (see its docstring; ``settings`` is an
    ``AnalyticSettings``: rtol, atol, output_dt, rest_ratio and history are honoured; method must
    be "DOP853" (the scheme compiled here) or "compiled"). ``motion`` may be a RickerPulse, a
    Record or None (free rocking). ``cost.wall_s`` counts the compiled integration only;
    ``cost.steps`` counts accepted steps and ``cost.rhs_calls`` evaluations of phi''.
    """
    _require_numba()
    from .solver import AnalyticSettings
    settings = settings or AnalyticSettings()
    if settings.method not in ("DOP853", "compiled"):
        raise ParameterError("settings.method", settings.method,
                             "'DOP853' or 'compiled' (the compiled path integrates DOP853 only; "
                             "use rockbench.analytic.solver.simulate for other methods)")
    ref = reference if reference is not None and reference.scene == scene else reference_of(scene)
    geo, sc = scene_arrays(scene)
    mk, mp, rt, ra, ext, suf, rsuf = _motion_arrays(motion)
    t0 = float(motion.t_start) if motion is not None else 0.0
    m_end = float(motion.t_end) if motion is not None else 0.0
    if duration is None:
        duration = max(m_end - t0, 0.0) + 10.0
    duration = check_positive("duration", duration)
    phi0, phidot0 = float(phi0), float(phidot0)
    for name, v in (("phi0", phi0), ("phidot0", phidot0)):
        if not math.isfinite(v):
            raise ParameterError(name, v, "a finite number")
    if abs(phi0) >= min(ref.fall.values()):
        raise ParameterError("phi0", phi0, f"|phi0| < fall angle {min(ref.fall.values()):.4g} rad")
    if motion is None and phi0 == 0.0 and phidot0 == 0.0:
        raise ParameterError("phi0", phi0, "non-zero for a free-rocking run (no ground motion)")
    t_end = t0 + duration
    v_rest = settings.rest_ratio * ref.p * ref.alpha
    thr_p, thr_n = _thresholds(sc)
    rp = _rule_params(sc)
    tg_full = output_grid(t0, t_end, settings.output_dt)
    hist = np.zeros((tg_full.size, 2))
    hmode = np.zeros((tg_full.size, 2), dtype=np.int64)
    hmode[:, 1] = 1 if scene.has_devices else 0
    cap = 4096
    while True:
        evf = np.zeros((cap, 5))
        evi = np.zeros((cap, 2), dtype=np.int64)
        out = np.zeros(_NOUT)
        w0 = time.perf_counter()
        _run(geo, sc, mk, mp, rt, ra, ext, suf, rsuf, t0, t_end, phi0, phidot0,
             float(settings.rtol), float(settings.atol), v_rest, thr_p, thr_n, m_end,
             rp[0], rp[1], rp[2], int(rp[3]), int(rp[4]), _A, _B, _C, _E3, _E5, _D, _NS,
             True, evf, evi, True, tg_full, hist, hmode, out)
        wall = time.perf_counter() - w0
        if int(out[_O_STATUS]) == 3:
            cap = int(out[_O_NEV]) + 16
            continue
        break
    status = int(out[_O_STATUS])
    reason = _reason(status, out, rp, t_end)
    t_fin = float(out[_O_T])
    tg = output_grid(t0, t_fin, settings.output_dt)
    n = tg.size
    phi = hist[:n, 0].copy()
    phid = hist[:n, 1].copy()
    mode = hmode[:n, 0].astype(np.int64)
    intact = hmode[:n, 1].astype(bool)
    if tg[-1] != tg_full[n - 1]:
        # the run ended between two grid points (overturn, early end at rest): the appended
        # last sample is the final state
        phi[-1], phid[-1] = out[_O_PHI], out[_O_PHID]
        mode[-1] = int(out[_O_MODE])
        intact[-1] = bool(out[_O_INTACT])
    history = _history(scene, geo, sc, motion, tg, phi, phid, mode, intact, settings)
    nev = int(out[_O_NEV])
    rows = [dict(t=float(evf[i, 0]), kind=_EV_NAMES[int(evi[i, 0])], phi=float(evf[i, 1]),
                 phidot_before=float(evf[i, 2]), phidot_after=float(evf[i, 3]),
                 eta=float(evf[i, 4]), direction=int(evi[i, 1])) for i in range(nev)]
    events = events_frame(sorted(rows, key=lambda r: r["t"]))
    overturned = bool(out[_O_OVER])
    t_upl = float(out[_O_TUPL])
    uplifted = bool(out[_O_UPL])
    max_abs = float(out[_O_MAXABS])
    summary = Summary(
        max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / ref.alpha, overturned=overturned,
        t_overturn=float(out[_O_TOVER]) if overturned else None,
        exceeded_critical=bool(out[_O_EXC]), uplifted=uplifted,
        t_uplift=t_upl if math.isfinite(t_upl) else (t0 if uplifted else None),
        n_impacts=int(out[_O_NIMP]), fractured=bool(out[_O_FRAC]),
        t_fracture=float(out[_O_TFRAC]) if out[_O_FRAC] else None,
        status="ok" if status == 0 else "invalid", reason=reason)
    cost = Cost(wall_s=wall, sim_time=t_fin - t0, steps=int(out[_O_STEPS]),
                rhs_calls=int(out[_O_NFEV]))
    sdict = asdict(settings)
    sdict["path"] = "compiled"
    mot_desc = motion.describe() if motion is not None else {"kind": "none"}
    return Result(backend="analytic", scene=scene, motion=mot_desc, history=history,
                  events=events, summary=summary, cost=cost, settings=sdict)


def _history(scene, geo, sc, mot, tg, phi, phid, mode, intact, settings) -> pd.DataFrame:
    """The history frame (solver._history's columns), derived columns in compiled code."""
    acc = np.asarray(mot.acceleration(tg), dtype=float) if mot is not None else np.zeros_like(tg)
    cols: dict[str, Any] = {"t": tg, "phi": phi, "phidot": phid, "ground_acc": acc,
                            "mode": mode, "devices_intact": intact}
    nan = np.full(tg.size, np.nan)
    st = scene.structure
    full = settings.history == "full"
    if st.kind == "frame" and full:
        d = np.zeros((tg.size, 6))
        _device_history(geo, sc, np.ascontiguousarray(phi), np.ascontiguousarray(mode), d)
        cols.update(theta_beam=d[:, 0], theta_right=d[:, 1])
        dev = scene.devices if scene.has_devices else None
        k = dev.tendon_stiffness if dev else 0.0
        c = dev.damping if dev else 0.0
        el, er, dl, dr = d[:, 2], d[:, 3], d[:, 4] * phid, d[:, 5] * phid
        cols.update(tendon_elong_left=np.where(intact, el, 0.0) if dev else np.zeros_like(tg),
                    tendon_elong_right=np.where(intact, er, 0.0) if dev else np.zeros_like(tg),
                    tendon_force_left=np.where(intact, k * el, 0.0),
                    tendon_force_right=np.where(intact, k * er, 0.0),
                    damper_force_left=np.where(intact, c * dl, 0.0),
                    damper_force_right=np.where(intact, c * dr, 0.0))
    else:
        for c in ("theta_beam", "theta_right", "tendon_elong_left", "tendon_elong_right",
                  "tendon_force_left", "tendon_force_right", "damper_force_left",
                  "damper_force_right"):
            cols[c] = nan if (st.kind == "frame" or c.startswith("theta")) else np.zeros_like(tg)
    for c in CONTACT_COLUMNS:
        cols[c] = nan
    return pd.DataFrame(cols, columns=list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS))


def run_pulse_grid(scene: Scene, cells: Iterable, *, duration: float | None = None,
                   rest_ratio: float | None = None, rtol: float = 1e-10,
                   atol: float = 1e-12, parallel: bool = False) -> pd.DataFrame:
    """Overturning-map cells of ``scene`` under Ricker pulses, without building Results.

    Parameters
    ----------
    cells : iterable of (shape, sign, A, W)
        shape "symmetric"/"antisymmetric" (or 1/2), sign +1/-1, A = a_g / (g tan alpha) > 0,
        W = omega_g / p > 0 (alpha, p of the scene's taller column).
    duration : float, optional
        Simulated time [s] from the pulse's start (-3 T_g); default 6 T_g + 10 s (as simulate).
    rest_ratio, rtol, atol : as :class:`AnalyticSettings` (defaults identical; rest_ratio None
        means :data:`rockbench.analytic.rules.REST_RATIO`, read at the call).
    parallel : bool
        Loop over cells with ``numba.prange`` (threads) instead of serially.

    Returns a frame with :data:`MAP_COLUMNS`, one row per cell in the order given. ``status`` is
    "ok" or "invalid" (``reason`` says why the kernel could not advance); ``cpu_s`` is the
    process CPU time of the whole call divided by the number of cells (an amortized share: with
    ``parallel=True`` it adds the CPU time of every thread).
    """
    _require_numba()
    rows = list(cells)
    n = len(rows)
    shapes = np.empty(n, dtype=np.int64)
    signs = np.empty(n, dtype=np.int64)
    As = np.empty(n)
    Ws = np.empty(n)
    for i, (shape, sign, A, W) in enumerate(rows):
        if shape in ("symmetric", 1):
            shapes[i] = 1
        elif shape in ("antisymmetric", 2):
            shapes[i] = 2
        else:
            raise ParameterError("shape", shape, "'symmetric' or 'antisymmetric'")
        if sign not in (1, -1):
            raise ParameterError("sign", sign, "+1 or -1")
        signs[i] = int(sign)
        As[i] = check_positive("A", A)
        Ws[i] = check_positive("W", W)
    dur = -1.0 if duration is None else check_positive("duration", duration)
    geo, sc = scene_arrays(scene)
    thr_p, thr_n = _thresholds(sc)
    if rest_ratio is None:
        rest_ratio = rules.REST_RATIO
    v_rest = check_positive("rest_ratio", rest_ratio) * sc[13] * sc[12]
    rp = _rule_params(sc)
    res = np.zeros((n, _NOUT))
    c0 = time.process_time()
    args = (geo, sc, shapes, signs, As, Ws, dur, float(rtol), float(atol), v_rest, thr_p, thr_n,
            rp, _A, _B, _C, _E3, _E5, _D, _NS, _SYM_EXT, _ANTI_EXT, _BETA, _XFAC, res)
    if n and parallel:
        # cells differ in cost by orders of magnitude (at rest vs. long rocking): hand them out
        # in small chunks rather than one contiguous block per thread
        with numba.parallel_chunksize(8):
            _grid_parallel(*args)
    elif n:
        _grid_serial(*args)
    cpu = (time.process_time() - c0) / max(n, 1)
    st = res[:, _O_STATUS].astype(int)
    over = res[:, _O_OVER] != 0.0
    return pd.DataFrame({
        "amplitude": As, "frequency": Ws,
        "pulse": np.where(shapes == 1, "symmetric", "antisymmetric"),
        "sign": signs, "overturned": over, "exceeded_critical": res[:, _O_EXC] != 0.0,
        "max_abs_phi_over_alpha": res[:, _O_MAXABS] / sc[12],
        "n_impacts": res[:, _O_NIMP].astype(np.int64), "fractured": res[:, _O_FRAC] != 0.0,
        "uplifted": res[:, _O_UPL] != 0.0,
        "t_overturn": np.where(over, res[:, _O_TOVER], np.nan),
        "status": np.where(st == 0, "ok", "invalid"),
        "reason": [_reason(int(c), res[i], rp, float("nan")) for i, c in enumerate(st)],
        "cpu_s": np.full(n, cpu),
    }, columns=list(MAP_COLUMNS))

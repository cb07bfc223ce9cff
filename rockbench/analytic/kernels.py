"""numba kernels of the compiled analytic path (:mod:`rockbench.analytic.compiled`): the
DOP853 tableau, the mechanism and Eq. 17 terms, ground motions, event location (Brent on the
dense output), uplift search. Plain arrays in, plain arrays out; no Python objects."""

from __future__ import annotations

import math

import numpy as np

from ..scene.motion import antisymmetric_beta
from .tableau import dop853_tableau

try:  # pragma: no cover - exercised by the environment, not by a test
    import numba  # noqa: F401 - re-exported (parallel_chunksize)
    from .._jit import njit, prange   # numba's, cached once per installation (_jit.py)
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

# --- the DOP853 tableau (scipy's coefficient table, the scheme the reference path uses) ----------
_A, _B, _C, _E3, _E5, _D, _NS = dop853_tableau()
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
_NGEO = 44       # fixed part of a geometry row; tables (kind 3) follow from _TAB0
_TAB0 = 50
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

@njit(cache=True, inline="always")
def _body(ox, oy, dox, doy, ddox, ddoy, rx, ry, th, dth, ddth, out, j):
    """dx, dy, ddx, ddy of the centre of mass of a body rotating by th(phi) about a point O
    (mechanism._body_about), written to out[j, :]."""
    _body_cs(ox, oy, dox, doy, ddox, ddoy, rx, ry, math.cos(th), math.sin(th), th, dth, ddth,
             out, j)


@njit(cache=True, inline="always")
def _body_cs(ox, oy, dox, doy, ddox, ddoy, rx, ry, c, s, th, dth, ddth, out, j):
    """:func:`_body` with c = cos(th), s = sin(th) given (computed once for several bodies, or
    from the linkage's vectors without a trigonometric call)."""
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
def _kinematics(phi, g, kin, need_theta):
    """Fill kin[body] = (dx, dy, ddx, ddy, theta, dtheta, ddtheta) of every body at ``phi``
    (mechanism.FrameMechanism.configuration / BlockMechanism.configuration). Returns the number of
    bodies, or -1 beyond the reach of the four-bar linkage.

    Three forms, chosen per scene by ``g[0]`` (compiled.scene_arrays): 0 a block; 2 a frame whose
    linkage is a parallelogram (equal columns: the beam translates and both columns turn by phi,
    one sin and one cos of phi for every body); 1 any other frame, the exact loop closure with
    the link directions taken from the linkage's vectors (one sin and cos, four square roots; no
    atan2 and no further trigonometric call). The beam's and right column's rotations (theta,
    used only by the devices) are computed with atan2 only when ``need_theta`` (0 otherwise).
    All three agree with the general closed form
    of :mod:`rockbench.scene.mechanism` to round-off (tests/analytic/test_dynamics.py)."""
    if g[0] == 0.0:
        _body(g[1], g[2], 0.0, 0.0, 0.0, 0.0, g[3], g[4], phi, 1.0, 0.0, kin, 0)
        return 1
    Ax, Ay, Dx, Dy = g[1], g[2], g[3], g[4]
    if g[0] == 2.0:
        c = math.cos(phi)
        s = math.sin(phi)
        bx = c * g[32] - s * g[33]          # B - A = Rot(phi) (B0 - A)
        by = s * g[32] + c * g[33]
        _body_cs(Ax, Ay, 0.0, 0.0, 0.0, 0.0, g[11], g[12], c, s, phi, 1.0, 0.0, kin, 0)
        _body_cs(Ax + bx, Ay + by, -by, bx, -bx, -by, g[13], g[14], 1.0, 0.0, 0.0, 0.0, 0.0,
                 kin, 1)
        _body_cs(Dx, Dy, 0.0, 0.0, 0.0, 0.0, g[15], g[16], c, s, phi, 1.0, 0.0, kin, 2)
        return 3
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
    # link directions: (cos, sin) of atan2 of the link vectors, by normalising the vectors
    vbx = Cx - Bx
    vby = Cy - By
    cbc = vbx / L
    sbc = vby / L
    vdx = Cx - Dx
    vdy = Cy - Dy
    ccd = vdx / r1
    scd = vdy / r1
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
    # body rotations: phi (left), phi_BC - phi_BC0 (beam), phi_CD - phi_CD0 (right), by the
    # angle-difference formulas with cos/sin of the rest angles (g[34:40])
    cl = cab * g[34] + sab * g[35]
    sl = sab * g[34] - cab * g[35]
    cb = cbc * g[36] + sbc * g[37]
    sb = sbc * g[36] - cbc * g[37]
    cr = ccd * g[38] + scd * g[39]
    sr = scd * g[38] - ccd * g[39]
    thb = 0.0
    thr = 0.0
    if need_theta:
        thb = math.atan2(vby, vbx) - g[10]
        thr = math.atan2(vdy, vdx) - g[9]
    _body_cs(Ax, Ay, 0.0, 0.0, 0.0, 0.0, g[11], g[12], cl, sl, phi, 1.0, 0.0, kin, 0)
    _body_cs(Bx, By, -by, bx, -bx, -by, g[13], g[14], cb, sb, thb, dbc, ddbc, kin, 1)
    _body_cs(Dx, Dy, 0.0, 0.0, 0.0, 0.0, g[15], g[16], cr, sr, thr, dcd, ddcd, kin, 2)
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


@njit(cache=True, inline="always")
def _estrin11(g, b, x, x2, x4, x8):
    """The polynomial of degree 11 with coefficients g[b..b + 11] (highest degree first) at x,
    by Estrin's scheme (x2, x4, x8 = x^2, x^4, x^8)."""
    p0 = g[b + 11] + g[b + 10] * x
    p1 = g[b + 9] + g[b + 8] * x
    p2 = g[b + 7] + g[b + 6] * x
    p3 = g[b + 5] + g[b + 4] * x
    p4 = g[b + 3] + g[b + 2] * x
    p5 = g[b + 1] + g[b] * x
    q0 = p0 + p1 * x2
    q1 = p2 + p3 * x2
    q2 = p4 + p5 * x2
    return (q0 + q1 * x4) + q2 * x8


@njit(cache=True, inline="always")
def _tabulated(u, pd, ag, ge, g, dev):
    """phi'' from the tabulated terms of a frame (``g[0] == 3``, compiled.scene_arrays):
    u = s phi in [g[45], g[46]] split into g[48] equal intervals of width g[47] (g[43] =
    1 / g[47]), each with polynomials of degree 11 (g[49]) in the interval's local coordinate
    x in [-1, 1] for I, J, G, B, sum e de/dphi and sum (dc/dphi)^2 (coefficients from g[_TAB0],
    highest degree first). ``ge`` = g + a_v [m/s^2]."""
    du = g[47]
    n = int(g[48])
    i = int((u - g[45]) * g[43])          # g[43] = 1 / du: no division on the way to x
    if i >= n:
        i = n - 1
    x = 2.0 * (u - g[45] - i * du) * g[43] - 1.0
    base = _TAB0 + i * 72                 # 6 polynomials of 12 coefficients
    K = 0.0
    D = 0.0
    # Estrin's scheme (pairs, then pairs of pairs): four short dependency chains instead of
    # Horner's eleven, 1.1 x faster per step of a tabulated frame (degree 11 only:
    # compiled._tabulate checks TABLE_DEGREE)
    x2 = x * x
    x4 = x2 * x2
    x8 = x4 * x4
    vI = _estrin11(g, base, x, x2, x4, x8)
    vJ = _estrin11(g, base + 12, x, x2, x4, x8)
    vG = _estrin11(g, base + 24, x, x2, x4, x8)
    vB = _estrin11(g, base + 36, x, x2, x4, x8)
    if dev:
        K = g[27] * _estrin11(g, base + 48, x, x2, x4, x8)
        D = g[28] * _estrin11(g, base + 60, x, x2, x4, x8)
    return (vB * ag - vJ * pd * pd - vG * ge - K - D * pd) / vI


@njit(cache=True, inline="always")
def _phidd(phi, pd, ag, ge, g, intact, kin):
    """phi'' [rad/s^2] of Eq. 17 (Dynamics.acceleration) for the ground accelerations ``ag``
    [m/s^2] and ``ge`` = g + a_v [m/s^2] (9.81 + 0.0 = 9.81 exactly without vertical motion).

    A parallelogram frame (``g[0] == 2``) is a Housner block exactly: I is constant (g[42]),
    J = 0, G(phi) = P cos(phi) - Q sin(phi) and B(phi) = Q cos(phi) + P sin(phi) with P = sum
    m_i r_ix, Q = sum m_i r_iy over the bodies' rest offsets (g[40], g[41]: scene_arrays): one
    sin and one cos of phi per evaluation; the devices see both columns turned by phi and the
    beam not at all."""
    dev = intact and (g[27] > 0.0 or g[28] > 0.0)
    if g[0] == 2.0:
        c = math.cos(phi)
        s = math.sin(phi)
        P = g[40]
        Q = g[41]
        K = 0.0
        D = 0.0
        if dev:
            kin[0, 4] = phi
            kin[0, 5] = 1.0
            kin[1, 4] = 0.0
            kin[1, 5] = 0.0
            kin[2, 4] = phi
            kin[2, 5] = 1.0
            el, er, dl, dr, cl, cr = _devices(kin, g[26])
            K = g[27] * (el * dl + er * dr)
            D = g[28] * (cl * cl + cr * cr)
        return ((Q * c + P * s) * ag - (P * c - Q * s) * ge - K - D * pd) / g[42]
    if g[0] == 3.0:
        u = g[44] * phi
        if g[45] <= u <= g[46]:
            return _tabulated(u, pd, ag, ge, g, dev)
    nb = _kinematics(phi, g, kin, dev)
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
    if dev:
        el, er, dl, dr, cl, cr = _devices(kin, g[26])
        K = k * (el * dl + er * dr)
        D = c * (cl * cl + cr * cr)
    return (Bm * ag - J * pd * pd - Gm * ge - K - D * pd) / In


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def _acc_hv(t, mk, mp, rt, ra, hint):
    """(u_g'', a_v) [m/s^2] at t: the horizontal acceleration as :func:`_acc` (the same
    operations, the same bits) and the vertical one by ``mp[5]``: 0 none (0.0), 1 a pulse's
    vertical part, the wavelet times mp[6] (RickerPulse.vertical: its own scale), 2 a record's
    vertical channel, ``ra[n:2n]`` on the times ``rt`` (n = rt.shape[0]; compiled._motion_arrays)."""
    vk = mp[5]
    if vk == 0.0:
        return _acc(t, mk, mp, rt, ra, hint), 0.0
    if mk == 1:
        tau = t / mp[1]
        u = 9.869604401089358 * tau * tau
        w = (1.0 - 2.0 * u) * math.exp(-u)
        return mp[0] * w, mp[6] * w
    if mk == 2:
        x = mp[4] * (t / mp[1])
        w = (x * x - 3.0) * x * math.exp(-0.5 * x * x)
        return mp[0] * w, mp[6] * w
    if mk == 3:
        n = rt.shape[0]
        if not (rt[0] <= t <= rt[n - 1]):
            return 0.0, 0.0
        a = _acc(t, mk, mp, rt, ra, hint)       # leaves the interval's index in hint[0]
        i = hint[0]
        if not (0 <= i < n - 1 and rt[i] <= t <= rt[i + 1]):
            i = np.searchsorted(rt, t, side="right") - 1
        if i >= n - 1:
            return a, ra[2 * n - 1]
        w = (t - rt[i]) / (rt[i + 1] - rt[i])
        return a, (1.0 - w) * ra[n + i] + w * ra[n + i + 1]
    return 0.0, 0.0


@njit(cache=True)
def _max_abs_v_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint):
    """sup |a_v| over [t, inf) [m/s^2] (0 without vertical motion): a pulse's vertical part is
    |mp[6] / mp[0]| times its horizontal one; a record's channel has its suffix maxima in
    ``rsuf[n:2n]``."""
    vk = mp[5]
    if vk == 0.0:
        return 0.0
    if vk == 1.0:
        return abs(mp[6] / mp[0]) * _max_abs_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint)
    n = rt.shape[0]
    a = abs(_acc_hv(t, mk, mp, rt, ra, hint)[1])
    i = np.searchsorted(rt, t, side="right")
    later = rsuf[n + i] if i < n else 0.0
    return max(later, a)


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
        if i < rt.shape[0]:          # rsuf[n:] holds a vertical channel's (_max_abs_v_after)
            later = rsuf[i]
    return max(later, a)


@njit(cache=True)
def _updir(a, thr_p, thr_n):
    if a > thr_p:
        return 1
    if a < thr_n:
        return -1
    return 0


@njit(cache=True, inline="always")
def _excess(t, thr, mk, mp, rt, ra, hint):
    """u_g''(t) - thr (1 + a_v(t) / g) [m/s^2]: the uplift condition's excess over a threshold
    ``thr`` = lambda g (1 + UPLIFT_RTOL) (exactly u_g'' - thr without vertical motion)."""
    a, v = _acc_hv(t, mk, mp, rt, ra, hint)
    return a - thr * (1.0 + v / 9.81)


@njit(cache=True)
def _brent_acc(lo, hi, thr, mk, mp, rt, ra, hint, xtol, rtol):
    """Root of :func:`_excess` in [lo, hi] (sign change assumed) by Brent's method."""
    a, b = lo, hi
    fa = _excess(a, thr, mk, mp, rt, ra, hint)
    fb = _excess(b, thr, mk, mp, rt, ra, hint)
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
        return _excess(t, shift, mk, mp, rt, ra, hint)
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
def _updir_at(t, mk, mp, rt, ra, hint, thr_p, thr_n):
    """:func:`_updir` at time t with the thresholds times (g + a_v) / g."""
    a, v = _acc_hv(t, mk, mp, rt, ra, hint)
    f = 1.0 + v / 9.81
    return _updir(a, thr_p * f, thr_n * f)


@njit(cache=True)
def _next_uplift(ta, tb, mk, mp, rt, ra, hint, ext, thr_p, thr_n):
    """First uplift time in [ta, tb] and its direction, (nan, 0) if none (solver.next_uplift);
    the thresholds scale with (g + a_v) / g (vertical motion)."""
    s = _updir_at(ta, mk, mp, rt, ra, hint, thr_p, thr_n)
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
            d = _updir_at(hi, mk, mp, rt, ra, hint, thr_p, thr_n)
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
            d = _updir_at(hi, mk, mp, rt, ra, hint, thr_p, thr_n)
            if d != 0:
                found = d
                break
            if hi >= tb:
                break
            lo = hi
    if found == 0:
        return np.nan, 0
    thr = thr_p if found == 1 else thr_n
    if mk == 3 and mp[5] == 0.0:
        alo = _acc(lo, mk, mp, rt, ra, hint)
        ahi = _acc(hi, mk, mp, rt, ra, hint)
        tu = lo + (thr - alo) * (hi - lo) / (ahi - alo)
        tu = min(max(tu, lo), hi)
    elif mk == 3:
        # with a vertical channel on the same samples the excess is linear between them too
        elo = _excess(lo, thr, mk, mp, rt, ra, hint)
        ehi = _excess(hi, thr, mk, mp, rt, ra, hint)
        tu = lo - elo * (hi - lo) / (ehi - elo)
        tu = min(max(tu, lo), hi)
    else:
        tu = _brent_acc(lo, hi, thr, mk, mp, rt, ra, hint, 1e-13, 1e-14)
    # step just past the root so that the excess is strictly positive (doubling steps)
    step = 1e-13 * max(1.0, abs(tu))
    while tu < hi and not (found * _excess(tu, thr, mk, mp, rt, ra, hint) > 0.0):
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



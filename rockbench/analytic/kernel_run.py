"""numba kernels of the compiled analytic path: the event-driven run of one case (:func:`_run`);
the loops over map cells are in :mod:`rockbench.analytic.kernel_grid`. See
:mod:`rockbench.analytic.compiled`."""

from __future__ import annotations

import math

import numpy as np

from .kernels import numba, njit, prange  # noqa: F401
from .kernels import (_O_ADV, _O_EXC, _O_FRAC, _O_INTACT, _O_MAXABS, _O_MODE, _O_NEV, _O_NFEV, _O_NIMP, _O_OVER, _O_PHI, _O_PHID, _O_STATUS, _O_STEPS, _O_T, _O_TFRAC, _O_TOVER, _O_TUPL, _O_UPL, _acc_hv, _brent_core, _dense_eval, _fill_hist, _max_abs_after, _max_abs_v_after, _next_uplift, _phidd, _push_event, _rms2, _tabulated)


@njit(cache=True)
def _f_general(t, y0, y1, mk, mp, rt, ra, hint, g, intact, kin):
    """kernels._phidd of kernels._acc_hv (g + a_v with vertical motion): any mechanism, any
    motion (a call, not inlined, so that the step loop of a block under a pulse stays small)."""
    ag, av = _acc_hv(t, mk, mp, rt, ra, hint)
    return _phidd(y0, y1, ag, 9.81 + av, g, intact, kin)


@njit(cache=True, inline="always")
def _f(t, y0, y1, form, P, Q, I0, mk, scale, vscale, per, xfac, g, intact, dev, kin, mp, rt,
       ra, hint):
    """phi'' at (t, phi = y0, phi' = y1): kernels._phidd of kernels._acc, in one of three forms
    chosen per segment (:func:`_form`). 2: a parallelogram frame without devices acting, under a
    Ricker pulse (``mk`` 1 or 2), in its block form with P, Q, I0 = g[40], g[41], g[42];
    3: a tabulated frame under a Ricker pulse, from its table, NaN beyond the table (the caller
    then redoes the step with form 0); 0: anything, by a call of :func:`_f_general`. The pulse
    is evaluated with scale, per, xfac = mp[0], mp[1], mp[4], its vertical part with vscale =
    mp[6] (0 without one: g + a_v = 9.81 exactly). Forms 2 and 3 do the operations of _phidd
    and _acc_hv in the same order: the same numbers to the last bit."""
    if form == 2 or form == 3:
        if mk == 1:
            tau = t / per
            u = 9.869604401089358 * tau * tau
            w = (1.0 - 2.0 * u) * math.exp(-u)
        else:
            x = xfac * (t / per)
            w = (x * x - 3.0) * x * math.exp(-0.5 * x * x)
        ag = scale * w
        ge = 9.81 + vscale * w
        if form == 2:
            c = math.cos(y0)
            s = math.sin(y0)
            return ((Q * c + P * s) * ag - (P * c - Q * s) * ge) / I0
        u = g[44] * y0
        if g[45] <= u <= g[46]:
            return _tabulated(u, y1, ag, ge, g, dev)
        return np.nan
    return _f_general(t, y0, y1, mk, mp, rt, ra, hint, g, intact, kin)


@njit(cache=True)
def _form(g, intact, mk):
    """The form of phi'' for a segment on mechanism row ``g`` (see :func:`_f`)."""
    if mk != 1 and mk != 2:
        return 0
    if g[0] == 2.0 and not (intact and (g[27] > 0.0 or g[28] > 0.0)):
        return 2
    if g[0] == 3.0:
        return 3
    return 0


@njit(cache=True, inline="always")
def _attempt(form, t, h, ya0, ya1, f0, f1, K, A, B, C, E3, E5, rtol, atol, mk, g, intact, dev,
             kin, mp, rt, ra, hint):
    """One DOP853 step attempt of size h from (t, ya0, ya1) (RungeKutta._step_impl): fills the
    stages K[0..ns], returns (err, phi, phi', phi'' at t + h); err is NaN when phi'' is
    (beyond the mechanism's reach, or beyond the table with form 3). Inlined once per form, so
    that the block's and the table's stage loops hold no call."""
    ns = B.shape[0]
    P = g[40]
    Q = g[41]
    I0 = g[42]
    scale = mp[0]
    vscale = mp[6]
    per = mp[1]
    xfac = mp[4]
    K[0, 0] = f0
    K[0, 1] = f1
    for st in range(1, ns):
        dy0 = 0.0
        dy1 = 0.0
        for j in range(st):
            dy0 += K[j, 0] * A[st, j]
            dy1 += K[j, 1] * A[st, j]
        q1 = ya1 + dy1 * h
        K[st, 0] = q1
        K[st, 1] = _f(t + C[st] * h, ya0 + dy0 * h, q1, form, P, Q, I0, mk, scale, vscale, per,
                      xfac, g, intact, dev, kin, mp, rt, ra, hint)
    s0b = 0.0
    s1b = 0.0
    for j in range(ns):
        s0b += K[j, 0] * B[j]
        s1b += K[j, 1] * B[j]
    n0 = ya0 + h * s0b
    n1 = ya1 + h * s1b
    fn1 = _f(t + h, n0, n1, form, P, Q, I0, mk, scale, vscale, per, xfac, g, intact, dev, kin,
             mp, rt, ra, hint)
    K[ns, 0] = n1
    K[ns, 1] = fn1
    sc0 = atol + max(abs(ya0), abs(n0)) * rtol
    sc1 = atol + max(abs(ya1), abs(n1)) * rtol
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
    return err, n0, n1, fn1


@njit(cache=True, inline="always")
def _extra_stages(form, t, h, ya0, ya1, K, A, C, ns, mk, g, intact, dev, kin, mp, rt, ra,
                  hint):
    """The three extra stages of DOP853's dense output, K[ns + 1..], after a step of size h
    from (t, ya0, ya1), in form ``form`` of :func:`_f`. Returns False when a stage is NaN (with
    form 3: beyond the table; the caller then computes them with form 0)."""
    P = g[40]
    Q = g[41]
    I0 = g[42]
    scale = mp[0]
    vscale = mp[6]
    per = mp[1]
    xfac = mp[4]
    ok = True
    for st in range(ns + 1, A.shape[0]):
        dy0 = 0.0
        dy1 = 0.0
        for j in range(st):
            dy0 += K[j, 0] * A[st, j]
            dy1 += K[j, 1] * A[st, j]
        q1 = ya1 + dy1 * h
        K[st, 0] = q1
        K[st, 1] = _f(t + C[st] * h, ya0 + dy0 * h, q1, form, P, Q, I0, mk, scale, vscale, per,
                      xfac, g, intact, dev, kin, mp, rt, ra, hint)
        if not (K[st, 1] == K[st, 1]):
            ok = False
    return ok


@njit(cache=True)
def _initial_step(t, ya0, ya1, f0, f1, interval, rtol, atol, mk, mp, rt, ra, hint, g, intact,
                  kin):
    """scipy's common.select_initial_step for DOP853 (order 7): one more phi'' evaluation."""
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
    agh, avh = _acc_hv(t + h0, mk, mp, rt, ra, hint)
    fb1 = _phidd(y1a, y1b, agh, 9.81 + avh, g, intact, kin)
    d2 = _rms2(fb0 - f0, fb1 - f1, s0, s1) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval)


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
    if intact and mode != 0 and mode * phi0 >= sc[6 + (0 if mode == 1 else 1)]:
        # released beyond the fracture angle of its direction: the tendons have failed before
        # the motion starts (the solve_ivp reference's rule)
        intact = False
        fractured = True
        t_frac = t0
        if want_ev:
            nev = _push_event(evf, evi, nev, t0, 4, phi0, phid0, phid0, np.nan, mode)
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
            # (vertical motion: |u_g''| <= |lambda| g (1 - sup |a_v| / g) everywhere later)
            vfac = 1.0 - _max_abs_v_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint) / 9.81
            if _max_abs_after(t, mk, mp, rt, ra, ext, extsuf, rsuf, hint) <= \
                    min(thr_p, -thr_n) * vfac:
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
        # the form of phi'' (_f): the stage loops of a block or a table under a pulse are
        # inlined without a call (1.3 x faster per step than with the general form's call)
        dev = intact and (g[27] > 0.0 or g[28] > 0.0)
        form = _form(g, intact, mk)
        f0 = ya1
        f1 = _f_general(t, ya0, ya1, mk, mp, rt, ra, hint, g, intact, kin)
        nfev += 1
        interval = abs(t_end - t)
        # every segment (after an impact or a fracture too) starts as solve_ivp's does, from
        # scipy's initial-step selection. A step kept across the impact (capped at
        # |phi' / phi''|) was 1.2 x cheaper but stepped over short excursions where the forcing
        # turns phi'' within the step: two impacts missed and the peak 2.7 % low on
        # paper-asymmetric-hybrid-eps1, antisymmetric -, A = 4.54, W = 5.62 (the slow 40 x 40
        # test; tests/analytic/test_compiled.py keeps that cell)
        h_abs = _initial_step(t, ya0, ya1, f0, f1, interval, rtol, atol, mk, mp, rt, ra,
                              hint, g, intact, kin)
        nfev += 1
        # events at the start: impact, overturn, fracture, critical, peak
        # impact (s phi falls to 0) and peak (s phi' falls to 0) are taken as positive at the
        # segment's first instant, so that a root is never the start itself (solver.py)
        go0 = 1.0
        go1 = s * ya0 - fall
        go2 = s * ya0 - frac
        go3 = s * ya0 - crit
        go4 = 1.0
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
                err = 0.0
                if form == 2:
                    err, n0, n1, fn1 = _attempt(2, t, h, ya0, ya1, f0, f1, K, A, B, C, E3, E5,
                                                rtol, atol, mk, g, intact, dev, kin, mp, rt,
                                                ra, hint)
                elif form == 3:
                    err, n0, n1, fn1 = _attempt(3, t, h, ya0, ya1, f0, f1, K, A, B, C, E3, E5,
                                                rtol, atol, mk, g, intact, dev, kin, mp, rt,
                                                ra, hint)
                # the general form; with form 3, when a stage lay beyond the table (NaN): the
                # exact closure
                if form == 0 or not (err == err):
                    err, n0, n1, fn1 = _attempt(0, t, h, ya0, ya1, f0, f1, K, A, B, C, E3, E5,
                                                rtol, atol, mk, g, intact, dev, kin, mp, rt,
                                                ra, hint)
                fn0 = n1
                nfev += ns
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
            # ---- events: impact and peak when s phi, s phi' fall through 0; overturn,
            # fracture, critical when s phi rises through their angles ----
            gn0 = s * n0
            gn1 = gn0 - fall
            gn2 = gn0 - frac
            gn3 = gn0 - crit
            gn4 = s * n1
            nact = 0
            if go0 >= 0.0 and gn0 <= 0.0:
                order[nact] = 0
                nact += 1
            if go1 <= 0.0 and gn1 >= 0.0:
                order[nact] = 1
                nact += 1
            if go2 <= 0.0 and gn2 >= 0.0:
                order[nact] = 2
                nact += 1
            if go3 <= 0.0 and gn3 >= 0.0:
                order[nact] = 3
                nact += 1
            if go4 >= 0.0 and gn4 <= 0.0:
                order[nact] = 4
                nact += 1
            have_dense = False
            need_h = False
            if want_hist:
                ih = np.searchsorted(tg, t_old, side="left")
                need_h = ih < tg.shape[0] and tg[ih] <= t_new
            if nact > 0 or need_h:
                yold[0] = ya0
                yold[1] = ya1
                # dense output (DOP853._dense_output_impl): three extra stages
                ok_x = False
                if form == 2:
                    ok_x = _extra_stages(2, t_old, h, ya0, ya1, K, A, C, ns, mk, g, intact, dev,
                                         kin, mp, rt, ra, hint)
                elif form == 3:
                    ok_x = _extra_stages(3, t_old, h, ya0, ya1, K, A, C, ns, mk, g, intact, dev,
                                         kin, mp, rt, ra, hint)
                if not ok_x:
                    _extra_stages(0, t_old, h, ya0, ya1, K, A, C, ns, mk, g, intact, dev, kin,
                                  mp, rt, ra, hint)
                nfev += ntab - ns - 1
                for c in range(2):
                    dlt = (n0 - ya0) if c == 0 else (n1 - ya1)
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
                    if e == 0:
                        ga, gb = go0, gn0
                    elif e == 1:
                        ga, gb = go1, gn1
                    elif e == 2:
                        ga, gb = go2, gn2
                    elif e == 3:
                        ga, gb = go3, gn3
                    else:
                        ga, gb = go4, gn4
                    roots[q] = _brent_core(t_old, t_new, ga, gb, 8.881784197001252e-16,
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
                    n0 = _dense_eval(F, yold, t_old, h, t_stop, 0)
                    n1 = _dense_eval(F, yold, t_old, h, t_stop, 1)
            if want_hist and have_dense:
                _fill_hist(tg, hist, hmode, hint, t_old, t_stop, F, yold, t_old, h, s,
                           intact, False)
            if abs(n0) > max_abs:
                max_abs = abs(n0)
            go0 = gn0
            go1 = gn1
            go2 = gn2
            go3 = gn3
            go4 = gn4
            t = t_stop
            ya0 = n0
            ya1 = n1
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

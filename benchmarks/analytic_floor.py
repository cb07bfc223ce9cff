"""The compiled analytic path against a floor: a minimal compiled solver of the same map cells.

    python benchmarks/analytic_floor.py [--quick] [--cells N] [--repeat R] [--out DIR]

The symmetric frame (``paper-symmetric``: equal columns) rocks as a parallelogram: the beam
translates, both columns turn by phi, so I(phi) is constant, J = 0 and G(phi), B(phi) are
combinations of cos(phi) and sin(phi): it is exactly a Housner block,

    I phi'' = (B_c cos phi + B_s sin phi) u_g'' - (G_c cos phi + G_s sin phi) g,

with per-direction constants read off the package's own ``Dynamics`` (and checked against it at
50 rotations to 1e-12 before anything is timed). The floor integrates that equation with scipy's
DOP853 tableau and step-size controller (rtol 1e-10, atol 1e-12), the step size kept across
impacts (the first step after one at most |phi' / phi''|, short of the excursion's peak),
events on the dense output (impact at phi = 0, overturn at the fall angle, peaks at phi' = 0,
Brent to 4 eps), and the package's rules (uplift beyond lambda g (1 + UPLIFT_RTOL), rest
below REST_RATIO p alpha, chatter, restitution eta of the post-impact direction), in one small
numba function: what a map cell costs when nothing but the physics is computed.

Measured side by side in one run, in process CPU time: ``run_pulse_grid(paper-symmetric, cells)``
(the package's map path) against the floor on the same cells, repeats interleaved, medians and
spread; the floor validated against the package on every cell (identical verdicts; max |phi| /
alpha within 1e-8). Writes ``analytic_floor.md``.
"""

from __future__ import annotations

import argparse
import functools
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from rockbench.analytic import rules  # noqa: E402
from rockbench.analytic.compiled import run_pulse_grid  # noqa: E402
from rockbench.analytic.kernels import _ANTI_EXT, _BETA, _SYM_EXT, _XFAC  # noqa: E402
from rockbench.analytic.kernels import _brent_core, _dense_eval, _next_uplift  # noqa: E402
from rockbench.analytic.kernel_grid import _pulse_setup  # noqa: E402
from rockbench.analytic.kernels import _max_abs_after  # noqa: E402
from rockbench.analytic.reference import reference_of  # noqa: E402
from rockbench.constants import G  # noqa: E402
from rockbench.scene.scene import load_scene  # noqa: E402
from scipy.integrate._ivp import dop853_coefficients as _c  # noqa: E402

NS = _c.N_STAGES
A_ = np.ascontiguousarray(_c.A, dtype=np.float64)
B_ = np.ascontiguousarray(_c.B, dtype=np.float64)
C_ = np.ascontiguousarray(_c.C, dtype=np.float64)
E3_ = np.ascontiguousarray(_c.E3, dtype=np.float64)
E5_ = np.ascontiguousarray(_c.E5, dtype=np.float64)
D_ = np.ascontiguousarray(_c.D, dtype=np.float64)


# --- the block form of a parallelogram frame, from the package's own dynamics --------------------
@functools.lru_cache(maxsize=8)
def block_constants(scene) -> np.ndarray:
    """Per direction (row 0: +1, row 1: -1): I, G_c, G_s, B_c, B_s, eta after an impact into the
    direction, fall angle; checked against ``Dynamics.terms`` at 50 rotations up to 0.8 x the fall
    angle (beyond, near the linkage's toggle, the general four-bar evaluation loses digits).
    Computed once per scene, as the package's ``scene_arrays``: a timed call of the floor pays
    only its compiled loop and its arrays."""
    ref = reference_of(scene)
    out = np.zeros((2, 7))
    for i, s in enumerate((1, -1)):
        dyn = ref.dyn[s]
        x1, x2 = 0.1 * s, 0.3 * s
        t1, t2 = dyn.terms(x1, False), dyn.terms(x2, False)
        M = np.array([[math.cos(x1), math.sin(x1)], [math.cos(x2), math.sin(x2)]])
        gc, gs = np.linalg.solve(M, [t1.gravity, t2.gravity])
        bc, bs = np.linalg.solve(M, [t1.ground, t2.ground])
        out[i] = (t1.inertia, gc, gs, bc, bs, ref.eta[s], ref.fall[s])
        for x in np.linspace(0.0, 0.8 * ref.fall[s], 50):
            t = dyn.terms(float(x), False)
            c, sn = math.cos(x), math.sin(x)
            for got, want in ((t.inertia, out[i, 0]), (t.gravity, gc * c + gs * sn),
                              (t.ground, bc * c + bs * sn)):
                if abs(got - want) > 1e-12 * max(abs(gc), abs(bc), abs(want)):
                    raise ValueError(f"{scene.name} is not a block (phi = {x}: {got} != {want})")
            if abs(t.velocity) > 1e-12 * abs(t.inertia):
                raise ValueError(f"{scene.name} is not a block: J({x}) = {t.velocity}")
    return out


# --- the floor ------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _ricker(t, shape, scale, per):
    if shape == 1:
        tau = t / per
        u = 9.869604401089358 * tau * tau
        return scale * ((1.0 - 2.0 * u) * math.exp(-u))
    x = 2.0 * math.pi / math.sqrt(3.0) * (t / per)
    return scale * ((x * x - 3.0) * x * math.exp(-0.5 * x * x))


@njit(cache=True, inline="always")
def _f(t, phi, shape, scale, per, I, gc, gs, bc, bs):
    c = math.cos(phi)
    s = math.sin(phi)
    return ((bc * c + bs * s) * _ricker(t, shape, scale, per) - (gc * c + gs * s) * 9.81) / I


@njit(cache=True)
def floor_cell(shape, sign, Amp, W, k, alpha, p, thr_p, thr_n, v_rest, v_chat, dt_chat, rtol,
               atol, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, out):
    """One map cell: out = (overturned, max |phi|, impacts, steps)."""
    mp = np.zeros(7)
    n_ext = 3 if shape == 1 else 4
    ext = np.zeros(n_ext)
    extsuf = np.zeros(n_ext)
    _pulse_setup(shape, float(sign), Amp, W, alpha, p, sym_ext, anti_ext, beta, xfac, mp, ext,
                 extsuf)
    scale, per, t, t_end = mp[0], mp[1], mp[2], mp[3] + 10.0
    dummy = np.zeros(1)
    hint = np.zeros(1, dtype=np.int64)
    K = np.zeros((A.shape[0], 2))
    F = np.zeros((Dd.shape[0] + 3, 2))
    yold = np.zeros(2)
    ntab = A.shape[0]
    nint = Dd.shape[0] + 3
    mode = 0
    phi = 0.0
    phid = 0.0
    max_abs = 0.0
    nimp = 0
    steps = 0
    over = False
    h_abs = -1.0
    has_last = False
    last_t = 0.0
    last_v = 0.0
    while t < t_end and not over:
        if mode == 0:
            if _max_abs_after(t, shape, mp, dummy, dummy, ext, extsuf, dummy, hint) <= \
                    min(thr_p, -thr_n):
                break
            tu, s = _next_uplift(t, t_end, shape, mp, dummy, dummy, hint, ext, thr_p, thr_n)
            if s == 0:
                break
            t, phi, phid, mode, has_last = tu, 0.0, 0.0, s, False
            continue
        s = mode
        i = 0 if s == 1 else 1
        I, gc, gs, bc, bs, fall = k[i, 0], k[i, 1], k[i, 2], k[i, 3], k[i, 4], k[i, 6]
        y0, y1 = phi, phid
        f0 = y1
        f1 = _f(t, y0, shape, scale, per, I, gc, gs, bc, bs)
        if h_abs < 0.0:        # the first segment only: scipy's select_initial_step
            s0 = atol + abs(y0) * rtol
            s1 = atol + abs(y1) * rtol
            d0 = math.sqrt(0.5 * ((y0 / s0) ** 2 + (y1 / s1) ** 2))
            d1 = math.sqrt(0.5 * ((f0 / s0) ** 2 + (f1 / s1) ** 2))
            h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
            h0 = min(h0, t_end - t)
            g1 = _f(t + h0, y0 + h0 * f0, shape, scale, per, I, gc, gs, bc, bs)
            d2 = math.sqrt(0.5 * (((y1 + h0 * f1 - f0) / s0) ** 2 + ((g1 - f1) / s1) ** 2)) / h0
            h1 = max(1e-6, h0 * 1e-3) if (d1 <= 1e-15 and d2 <= 1e-15) else \
                (0.01 / max(d1, d2)) ** 0.125
            h_abs = min(100.0 * h0, h1, t_end - t)
        elif s * f1 < 0.0 and y1 != 0.0:
            # the step is kept across impacts, but the first one stops short of the excursion's
            # peak, |phi' / phi''|, so that it cannot step over the return to phi = 0
            h_abs = min(h_abs, abs(y1 / f1))
        g_imp = 1.0       # s phi, positive at the segment's start
        g_pk = 1.0        # s phi'
        event = 0         # 0 none, 1 impact, 2 overturn
        while True:
            rejected = False
            while True:
                min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
                if h_abs < min_step:
                    h_abs = min_step
                h = min(h_abs, t_end - t)
                K[0, 0] = f0
                K[0, 1] = f1
                for st in range(1, ns):
                    a0 = 0.0
                    a1 = 0.0
                    for j in range(st):
                        a0 += K[j, 0] * A[st, j]
                        a1 += K[j, 1] * A[st, j]
                    q1 = y1 + a1 * h
                    K[st, 0] = q1
                    K[st, 1] = _f(t + C[st] * h, y0 + a0 * h, shape, scale, per, I, gc, gs,
                                  bc, bs)
                b0 = 0.0
                b1 = 0.0
                for j in range(ns):
                    b0 += K[j, 0] * B[j]
                    b1 += K[j, 1] * B[j]
                n0 = y0 + h * b0
                n1 = y1 + h * b1
                fn1 = _f(t + h, n0, shape, scale, per, I, gc, gs, bc, bs)
                K[ns, 0] = n1
                K[ns, 1] = fn1
                sc0 = atol + max(abs(y0), abs(n0)) * rtol
                sc1 = atol + max(abs(y1), abs(n1)) * rtol
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
                q5 = e50 * e50 + e51 * e51
                q3 = e30 * e30 + e31 * e31
                err = 0.0 if (q5 == 0.0 and q3 == 0.0) else \
                    h * q5 / math.sqrt((q5 + 0.01 * q3) * 2.0)
                if err < 1.0:
                    fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** -0.125)
                    if rejected:
                        fac = min(1.0, fac)
                    h_abs = h * fac
                    break
                h_abs = h * max(0.2, 0.9 * err ** -0.125)
                rejected = True
            steps += 1
            t_new = t + h
            gi = s * n0
            gp = s * n1
            hit_imp = g_imp >= 0.0 and gi <= 0.0
            hit_pk = g_pk >= 0.0 and gp <= 0.0
            hit_over = gi >= fall
            if hit_imp or hit_pk or hit_over:
                for st in range(ns + 1, ntab):
                    a0 = 0.0
                    a1 = 0.0
                    for j in range(st):
                        a0 += K[j, 0] * A[st, j]
                        a1 += K[j, 1] * A[st, j]
                    K[st, 0] = y1 + a1 * h
                    K[st, 1] = _f(t + C[st] * h, y0 + a0 * h, shape, scale, per, I, gc, gs,
                                  bc, bs)
                yold[0] = y0
                yold[1] = y1
                for c in range(2):
                    dlt = (n0 - y0) if c == 0 else (n1 - y1)
                    fo = K[0, c]
                    fnew = n1 if c == 0 else fn1
                    F[0, c] = dlt
                    F[1, c] = h * fo - dlt
                    F[2, c] = 2.0 * dlt - h * (fnew + fo)
                    for r in range(nint - 3):
                        acc = 0.0
                        for j in range(ntab):
                            acc += Dd[r, j] * K[j, c]
                        F[3 + r, c] = h * acc
                t_imp = t_new + 1.0
                t_ov = t_new + 1.0
                if hit_imp:
                    t_imp = _brent_core(t, t_new, g_imp, gi, 8.881784197001252e-16,
                                        8.881784197001252e-16, 1, 0, dummy, dummy, dummy, hint,
                                        F, t, h, yold, 0, 0.0, float(s))
                if hit_over:
                    t_ov = _brent_core(t, t_new, s * y0 - fall, gi - fall,
                                       8.881784197001252e-16, 8.881784197001252e-16, 1, 0,
                                       dummy, dummy, dummy, hint, F, t, h, yold, 0, fall,
                                       float(s))
                t_stop = min(t_imp, t_ov)
                if hit_pk:
                    tp = _brent_core(t, t_new, g_pk, gp, 8.881784197001252e-16,
                                     8.881784197001252e-16, 1, 0, dummy, dummy, dummy, hint, F,
                                     t, h, yold, 1, 0.0, float(s))
                    if tp <= t_stop:
                        pe = abs(_dense_eval(F, yold, t, h, tp, 0))
                        if pe > max_abs:
                            max_abs = pe
                if t_stop <= t_new:
                    event = 1 if t_imp <= t_ov else 2
                    n0 = _dense_eval(F, yold, t, h, t_stop, 0)
                    n1 = _dense_eval(F, yold, t, h, t_stop, 1)
                    t_new = t_stop
            if abs(n0) > max_abs:
                max_abs = abs(n0)
            t = t_new
            y0, y1 = n0, n1
            f0 = n1
            f1 = fn1
            g_imp = gi
            g_pk = gp
            if event != 0 or t >= t_end:
                break
        phi, phid = y0, y1
        if event == 2:
            over = True
        elif event == 1:
            post = -s
            eta = k[0, 5] if post == 1 else k[1, 5]
            after = eta * phid
            nimp += 1
            settles = eta <= 0.0 or abs(after) <= v_rest
            if (not settles and has_last and abs(after) <= v_chat and last_v <= v_chat
                    and t - last_t <= dt_chat):
                settles = True
            if settles:
                mode, phid, has_last = 0, 0.0, False
            else:
                mode, phid = post, after
                has_last, last_t, last_v = True, t, abs(after)
            phi = 0.0
        else:
            break
    out[0] = 1.0 if over else 0.0
    out[1] = max_abs
    out[2] = nimp
    out[3] = steps


@njit(cache=True)
def floor_grid(shapes, signs, As, Ws, k, alpha, p, thr_p, thr_n, v_rest, v_chat, dt_chat, rtol,
               atol, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac, res):
    for i in range(shapes.shape[0]):
        floor_cell(shapes[i], signs[i], As[i], Ws[i], k, alpha, p, thr_p, thr_n, v_rest, v_chat,
                   dt_chat, rtol, atol, A, B, C, E3, E5, Dd, ns, sym_ext, anti_ext, beta, xfac,
                   res[i])


def run_floor(scene, cells, rtol=1e-10, atol=1e-12) -> np.ndarray:
    """(overturned, max |phi| / alpha, impacts, steps) of every cell, with the floor."""
    ref = reference_of(scene)
    k = block_constants(scene)
    shapes = np.array([1 if c[0] == "symmetric" else 2 for c in cells], dtype=np.int64)
    signs = np.array([c[1] for c in cells], dtype=np.int64)
    As = np.array([c[2] for c in cells], dtype=float)
    Ws = np.array([c[3] for c in cells], dtype=float)
    f = 1.0 + rules.UPLIFT_RTOL
    res = np.zeros((len(cells), 4))
    floor_grid(shapes, signs, As, Ws, k, ref.alpha, ref.p, ref.lam[1] * G * f,
               ref.lam[-1] * G * f, rules.REST_RATIO * ref.p * ref.alpha,
               rules.CHATTER_VELOCITY_RATIO * ref.p * ref.alpha, rules.CHATTER_INTERVAL / ref.p,
               rtol, atol, A_, B_, C_, E3_, E5_, D_, NS, _SYM_EXT, _ANTI_EXT, _BETA, _XFAC, res)
    res[:, 1] /= ref.alpha
    return res


# --- measurement ----------------------------------------------------------------------------------
def map_cells(n: int):
    return [(shape, sign, float(A), float(W)) for shape in ("symmetric", "antisymmetric")
            for sign in (1, -1) for A in np.linspace(0.5, 8.0, n)
            for W in np.linspace(0.5, 10.0, n)]


def validate(scene, cells) -> dict:
    fl = run_floor(scene, cells)
    pk = run_pulse_grid(scene, cells)
    ref = reference_of(scene)
    over_same = (fl[:, 0] != 0) == pk["overturned"].to_numpy()
    crit = min(ref.critical[(1, True)], ref.critical[(-1, True)]) / ref.alpha
    dpeak = np.abs(fl[:, 1] - pk["max_abs_phi_over_alpha"].to_numpy())
    surv = ~pk["overturned"].to_numpy()
    return {"cells": len(cells), "verdicts_differ": int((~over_same).sum()),
            "max_dpeak_survivors": float(dpeak[surv].max()) if surv.any() else 0.0,
            "max_dpeak_all": float(dpeak.max()), "overturned": int(pk["overturned"].sum()),
            "impacts_differ": int((fl[:, 2] != pk["n_impacts"].to_numpy()).sum()),
            "crit": crit}


def package_steps(scene, cells) -> float:
    """Accepted steps of the package's kernel over ``cells`` (an untimed run of its map loop)."""
    from rockbench.analytic import compiled as C
    from rockbench.analytic.kernel_run import _grid_serial
    from rockbench.analytic.kernels import _NOUT, _O_STEPS

    geo, sc = C.scene_arrays(scene)
    thr_p, thr_n = C._thresholds(sc)
    res = np.zeros((len(cells), _NOUT))
    _grid_serial(geo, sc, np.array([1 if c[0] == "symmetric" else 2 for c in cells]),
                 np.array([c[1] for c in cells]), np.array([c[2] for c in cells], dtype=float),
                 np.array([c[3] for c in cells], dtype=float), -1.0, 1e-10, 1e-12,
                 rules.REST_RATIO * sc[13] * sc[12], thr_p, thr_n, C._rule_params(sc), C._A,
                 C._B, C._C, C._E3, C._E5, C._D, C._NS, C._SYM_EXT, C._ANTI_EXT, C._BETA,
                 C._XFAC, res)
    return float(res[:, _O_STEPS].sum())


def timed(fn, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        out.append(time.process_time() - c)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--cells", type=int, default=400, help="cells drawn from the 100x100x4 grid")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    from compiled_analytic import machine

    n_cells = 80 if args.quick else args.cells
    repeat = 3 if args.quick else args.repeat
    rng = np.random.default_rng(7)
    grid = map_cells(100)
    cells = [grid[i] for i in rng.choice(len(grid), n_cells, replace=False)]
    lines = ["# The compiled analytic path against the floor", "",
             "Measured side by side in one run of `benchmarks/analytic_floor.py`"
             + (" (--quick)" if args.quick else "") + ": the package's map path "
             "(`run_pulse_grid`) and a minimal compiled solver of the same cells (the floor, "
             "see the script's docstring), process CPU time (`time.process_time()`), repeats "
             "interleaved, median (min-max, n).", ""]
    c0 = time.perf_counter()
    for name in ("paper-symmetric", "paper-asymmetric"):
        run_pulse_grid(load_scene(name), cells[:2])
    run_floor(load_scene("paper-symmetric"), cells[:2])
    warm = time.perf_counter() - c0
    lines += ["## Machine", ""] + [f"- {k}: {v}" for k, v in machine().items()] + [
        f"- compilation or cache load (excluded): {warm:.1f} s wall",
        "- the 2 cores are shared with other sessions: CPU times, not wall times; ratios are "
        "measured with interleaved repeats", ""]
    sym, asym = load_scene("paper-symmetric"), load_scene("paper-asymmetric")
    v = validate(sym, cells)
    times = {"floor (paper-symmetric as a block)": [], "package, paper-symmetric": [],
             "package, paper-asymmetric": []}
    for _ in range(repeat):
        times["floor (paper-symmetric as a block)"] += timed(lambda: run_floor(sym, cells), 1)
        times["package, paper-symmetric"] += timed(lambda: run_pulse_grid(sym, cells), 1)
        times["package, paper-asymmetric"] += timed(lambda: run_pulse_grid(asym, cells), 1)
    floor = statistics.median(times["floor (paper-symmetric as a block)"])
    lines += [f"## {n_cells} cells drawn (seed 7) from the 100 x 100 x 4 map grid", "",
              "A = a_g/(g tan alpha) in 0.5..8, W = omega_g/p in 0.5..10, both pulse shapes and "
              "signs, pulse + 10 s, rtol 1e-10, atol 1e-12, one process.", "",
              "| solver | us per cell | ratio to the floor (median; min-max over repeats) | "
              "accepted steps per cell | ns per step | per-step ratio to the floor |",
              "|:--|--:|--:|--:|--:|--:|"]
    fl_all = times["floor (paper-symmetric as a block)"]
    steps = {"floor (paper-symmetric as a block)": float(run_floor(sym, cells)[:, 3].sum()),
             "package, paper-symmetric": package_steps(sym, cells),
             "package, paper-asymmetric": package_steps(asym, cells)}
    floor_step = floor / steps["floor (paper-symmetric as a block)"]
    for name, xs in times.items():
        ratios = sorted(x / f for x, f in zip(xs, fl_all))
        per_step = statistics.median(xs) / steps[name]
        lines.append(f"| {name} | {1e6 * statistics.median(xs) / n_cells:.0f} "
                     f"({1e6 * min(xs) / n_cells:.0f}-{1e6 * max(xs) / n_cells:.0f}, "
                     f"n={len(xs)}) | {statistics.median(xs) / floor:.2f} "
                     f"({ratios[0]:.2f}-{ratios[-1]:.2f}) | {steps[name] / n_cells:.1f} | "
                     f"{1e9 * per_step:.0f} | {per_step / floor_step:.2f} |")
    lines += ["", "The floor solves the symmetric frame only (the block it exactly is); the "
              "asymmetric frame's cells rock longer, so its fair comparison is per accepted "
              "step. The floor keeps its step size across impacts (the first step after one at "
              "most |phi'/phi''|), which can step over a short excursion (impact counts below); "
              "the package starts every segment from scipy's initial step as `solve_ivp` does "
              "(`rockbench/analytic/kernel_run.py`), hence its extra steps per cell: the ratio "
              "per step is the cost of the machinery, the ratio per cell includes that safety."]
    lines += ["", "## Validation of the floor against the package (paper-symmetric, same cells)",
              "", f"- cells: {v['cells']}, overturned: {v['overturned']}",
              f"- verdicts (overturned) that differ: {v['verdicts_differ']}",
              f"- max |difference of max |phi| / alpha|: {v['max_dpeak_survivors']:.2e} over "
              f"the surviving cells, {v['max_dpeak_all']:.2e} over all (an overturning cell's "
              "peak is the fall angle, reached at an event)",
              f"- impact counts that differ: {v['impacts_differ']} (not a verdict: the floor "
              "keeps its step size across impacts)", ""]
    # the map tolerance: which rtol keeps every verdict of the default one
    n_tol = 24 if args.quick else 100
    full = map_cells(n_tol)
    lines += [f"## The map tolerance: the {n_tol} x {n_tol} x 4 map of paper-asymmetric at "
              "three rtol", "",
              "Verdicts (overturned, exceeded critical) compared with rtol 1e-10 (the default); "
              "atol 1e-12; CPU of one run.", "",
              "| rtol | CPU s | ratio to rtol 1e-10 | verdicts that differ | max \\|d max "
              "\\|phi\\|/alpha\\| |", "|--:|--:|--:|--:|--:|"]
    base = None
    for rtol in (1e-10, 1e-9, 1e-8):
        c = time.process_time()
        df = run_pulse_grid(asym, full, rtol=rtol)
        cpu = time.process_time() - c
        if base is None:
            base, base_cpu = df, cpu
        diff = int(((df["overturned"] != base["overturned"])
                    | (df["exceeded_critical"] != base["exceeded_critical"])).sum())
        dpk = float((df["max_abs_phi_over_alpha"] - base["max_abs_phi_over_alpha"]).abs().max())
        lines.append(f"| {rtol:g} | {cpu:.2f} | {cpu / base_cpu:.2f} | {diff} of {len(df)} | "
                     f"{dpk:.1e} |")
    lines.append("")
    out = Path(args.out) / "analytic_floor.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Why the compiled and ``solve_ivp`` analytic paths part on a long record, measured in one run
(the evidence behind docs/reproducibility.md).

    python benchmarks/analytic_divergence.py [--out benchmarks/results]

On El Centro 1940 (``IV1940_ElCentro_180``, 40 s) and ``paper-asymmetric`` (the free-standing
frame), with the default settings (DOP853, rtol 1e-10, atol 1e-12):

1. the first rocking segment step by step: the first accepted step at which the two paths'
   states differ, and the first at which their step *sequences* part, with the error norms both
   step-size controllers computed there (the compiled kernel's Python source is run with a step
   log; scipy's ``DOP853._estimate_error_norm`` is wrapped);
2. per 1-s window: the response amplitude max |phi| / alpha, |phi_compiled - phi_reference| /
   alpha, |phi_compiled - phi_compiled'| / alpha where ' is the record's samples times
   (1 + 2^-52) (one ulp), and the impacts of each run in the window;
3. the whole record's impact count and peak under perturbations nobody controls: one-ulp changes
   of the record, 1e-12 relative changes of rtol and atol, each of OpenBLAS's CPU kernels for the
   reference (``OPENBLAS_CORETYPE``, what numpy's dot products run on), glibc's libm without its
   FMA variants for the compiled path (``GLIBC_TUNABLES``), numba's target CPU (``host`` or
   ``generic``). Items run in subprocesses with the environment variable set.

Writes ``analytic_divergence.md``. CPU: about 1.5 minutes (the reference costs ~10 s a run).
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from compiled_analytic import RECORD, machine  # noqa: E402

SCENE = "paper-asymmetric"
ULP = 2.0 ** -52


def _load(scale: float = 1.0):
    from rockbench.scene.motion import Record
    from rockbench.scene.records import load_record

    rec = load_record(RECORD)
    if scale == 1.0:
        return rec
    return Record(rec.time, np.asarray(rec.samples) * scale, name=f"{rec.name} x {scale!r}")


def one_run(path: str, scale: float = 1.0, rtol: float = 1e-10, atol: float = 1e-12) -> dict:
    """One run of the whole record; its count, peak and phi on the output grid."""
    from rockbench.analytic.compiled import simulate_compiled
    from rockbench.analytic.solver import AnalyticSettings, simulate
    from rockbench.scene.scene import load_scene

    scene = load_scene(SCENE)
    st = AnalyticSettings(history="minimal", rtol=rtol, atol=atol)
    c = time.process_time()
    r = (simulate_compiled if path == "compiled" else simulate)(scene, _load(scale), settings=st)
    imp = r.events.loc[r.events["kind"] == "impact", "t"].to_numpy()
    return {"n_impacts": int(r.summary.n_impacts), "peak": r.summary.max_abs_phi_over_alpha,
            "impacts": imp.tolist(), "phi": r.history["phi"].to_numpy().tolist(),
            "t": r.history["t"].to_numpy().tolist(), "alpha": scene.alpha,
            "cpu_s": time.process_time() - c}


def _subprocess(path: str, env: dict) -> dict:
    code = (f"import sys, json; sys.path.insert(0, {str(HERE)!r}); "
            f"from analytic_divergence import one_run; r = one_run({path!r}); "
            "print(json.dumps({k: r[k] for k in ('n_impacts', 'peak', 'cpu_s')}))")
    out = subprocess.run([sys.executable, "-c", code], env={**os.environ, **env},
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


# --- 1. the first segment, step by step -----------------------------------------------------------
def step_trace(t_end: float = 1.70) -> list[str]:
    import rockbench.analytic.kernel_run as kr
    from rockbench.analytic import compiled, solver
    from rockbench.analytic.reference import reference_of
    from rockbench.analytic.solver import AnalyticSettings
    from rockbench.scene.scene import load_scene
    from scipy.integrate._ivp import rk

    src = inspect.getsource(kr._run.py_func).replace("@njit(cache=True)\n", "")
    hooks = (("                if not (err == err):",
              "                _ERR.append((t, h, err))\n                if not (err == err):"),
             ("            steps += 1\n",
              "            steps += 1\n            _LOG.append((t_new, ynew[0], ynew[1]))\n"))
    for a, b in hooks:
        if a not in src:
            return [f"(step trace skipped: the kernel's source changed; no `{a.strip()}`)"]
        src = src.replace(a, b, 1)
    ns = dict(vars(kr))
    ns["_LOG"], ns["_ERR"] = clog, cerr = [], []
    exec(src, ns)  # noqa: S102 - the package's own kernel, as plain Python, with a step log
    scene = load_scene(SCENE)
    rec = _load()
    geo, sc = compiled.scene_arrays(scene)
    mk, mp_, rt, ra, ext, suf, rsuf = compiled._motion_arrays(rec)
    thr_p, thr_n = compiled._thresholds(sc)
    rp = compiled._rule_params(sc)
    ref = reference_of(scene)
    out = np.zeros(compiled._NOUT)
    ns["_run"](geo, sc, mk, mp_, rt, ra, ext, suf, rsuf, 0.0, t_end, 0.0, 0.0, 1e-10, 1e-12,
               1e-4 * ref.p * ref.alpha, thr_p, thr_n, rec.t_end, rp[0], rp[1], rp[2],
               int(rp[3]), int(rp[4]), compiled._A, compiled._B, compiled._C, compiled._E3,
               compiled._E5, compiled._D, compiled._NS, True, np.zeros((4096, 5)),
               np.zeros((4096, 2), dtype=np.int64), False, np.zeros(1), np.zeros((1, 2)),
               np.zeros((1, 2), dtype=np.int64), out)
    sols, rerr = [], []
    orig_ivp, orig_est = solver.solve_ivp, rk.DOP853._estimate_error_norm

    def keep(*a, **k):
        s = orig_ivp(*a, **k)
        sols.append(s)
        return s

    def est(self, K, h, scale):
        e = orig_est(self, K, h, scale)
        rerr.append((self.t, h, e))
        return e
    solver.solve_ivp, rk.DOP853._estimate_error_norm = keep, est
    try:
        solver.simulate(scene, rec, duration=t_end, settings=AnalyticSettings(history="minimal"))
    finally:
        solver.solve_ivp, rk.DOP853._estimate_error_norm = orig_ivp, orig_est
    rt_ = np.concatenate([s.t[1:] for s in sols])
    ry = np.concatenate([s.y[:, 1:] for s in sols], axis=1)
    ct = np.array([x[0] for x in clog])
    cy = np.array([[x[1], x[2]] for x in clog]).T
    n = min(ct.size, rt_.size)
    state = next((i for i in range(n) if cy[0, i] != ry[0, i] or cy[1, i] != ry[1, i]), None)
    seq = next((i for i in range(n) if ct[i] != rt_[i]), None)
    lines = [f"Uplift at t = {sols[0].t[0]:.15g} s (the same in both paths). Accepted steps up "
             f"to t = {t_end} s: compiled {ct.size}, reference {rt_.size}."]
    if state is not None:
        lines.append(f"* first accepted step whose state differs: step {state + 1}, t = "
                     f"{ct[state]:.15g} s, phi = {ry[0, state]:.3g} rad, difference "
                     f"{cy[0, state] - ry[0, state]:.3g} rad (round-off).")
    if seq is not None:
        rel = (cy[0] - ry[0]) / ry[0]
        lines.append("* step times, phi and its relative difference around the step at which "
                     "the step sequences part:")
        lines += ["", "| step | t compiled [s] | t reference [s] | phi reference [rad] | "
                  "(phi_c - phi_r) / phi_r |", "|--:|--:|--:|--:|--:|"]
        for j in range(max(0, seq - 2), min(n, seq + 3)):
            lines.append(f"| {j + 1} | {ct[j]:.16g} | {rt_[j]:.16g} | {ry[0, j]:.4g} | "
                         f"{rel[j]:.2g} |")
        lines.append("")
    m = min(len(cerr), len(rerr))
    acc = [(i, cerr[i], rerr[i]) for i in range(m) if cerr[i][2] < 1.0 and rerr[i][2] < 1.0
           and cerr[i][1] == rerr[i][1] and cerr[i][2] != rerr[i][2]]
    if acc:
        lines.append("* error norms of the same accepted trial steps (same t and h) in both "
                     "controllers (DOP853's err = |h| |E5 K|^2 / sqrt(...)): the estimate of a "
                     "smooth step is a sum that cancels to round-off, so the two summation "
                     "orders disagree in its leading digits:")
        lines += ["", "| trial | t [s] | h [s] | err compiled | err reference |",
                  "|--:|--:|--:|--:|--:|"]
        for i, a, b in acc[:6]:
            lines.append(f"| {i + 1} | {a[0]:.12g} | {a[1]:.6g} | {a[2]:.6g} | {b[2]:.6g} |")
        lines.append("")
    return lines


# --- 2. per-second windows ----------------------------------------------------------------------
def windows(c: dict, r: dict, cp: dict) -> list[str]:
    t = np.asarray(r["t"])
    a = c["alpha"]
    pc, pr, pp = (np.asarray(x["phi"]) for x in (c, r, cp))
    m = min(pc.size, pr.size, pp.size)
    t, pc, pr, pp = t[:m], pc[:m], pr[:m], pp[:m]
    ic, ir, ip = (np.asarray(x["impacts"]) for x in (c, r, cp))
    lines = ["| window [s] | amplitude max \\|phi\\|/alpha | \\|compiled - reference\\|/alpha | "
             "\\|compiled - compiled (1 ulp)\\|/alpha | impacts compiled / reference / 1 ulp |",
             "|:--|--:|--:|--:|--:|"]
    for w in range(0, int(t[-1]) + 1):
        k = (t >= w) & (t < w + 1)
        if not k.any():
            continue
        cnt = "/".join(str(int(((x >= w) & (x < w + 1)).sum())) for x in (ic, ir, ip))
        lines.append(f"| {w}-{w + 1} | {np.abs(pr[k]).max() / a:.2e} | "
                     f"{np.abs(pc[k] - pr[k]).max() / a:.2e} | "
                     f"{np.abs(pc[k] - pp[k]).max() / a:.2e} | {cnt} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    cpu0 = time.process_time()
    base_c = one_run("compiled")
    base_r = one_run("reference")
    ulp_c = one_run("compiled", scale=1 + ULP)
    trace = step_trace()
    rows = [("compiled", "none (this machine's default)", base_c),
            ("reference", "none (this machine's default)", base_r),
            ("compiled", "record samples x (1 + 2^-52)", ulp_c),
            ("compiled", "record samples x (1 - 2^-53)", one_run("compiled", scale=1 - ULP / 2)),
            ("reference", "record samples x (1 + 2^-52)", one_run("reference", scale=1 + ULP)),
            ("compiled", "rtol x (1 + 1e-12)", one_run("compiled", rtol=1e-10 * (1 + 1e-12))),
            ("compiled", "atol x (1 + 1e-12)", one_run("compiled", atol=1e-12 * (1 + 1e-12)))]
    for core in ("Haswell", "Zen", "SkylakeX", "Sandybridge"):
        rows.append(("reference", f"OPENBLAS_CORETYPE={core}",
                     _subprocess("reference", {"OPENBLAS_CORETYPE": core})))
    rows.append(("compiled", "GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F (libm without "
                 "its FMA variants)",
                 _subprocess("compiled", {"GLIBC_TUNABLES":
                                          "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F"})))
    rows.append(("compiled", "NUMBA_CPU_NAME=generic (no AVX code generation)",
                 _subprocess("compiled", {"NUMBA_CPU_NAME": "generic",
                                          "ROCKBENCH_CACHE_DIR": "/tmp/rockbench-generic-jit"})))
    lines = ["# Why the two analytic paths part on a long record", "",
             "Measured in one run of `benchmarks/analytic_divergence.py` (explained in "
             "[docs/reproducibility.md](../../docs/reproducibility.md)): El Centro 1940 "
             f"(`{RECORD.stem}`, 40 s), `{SCENE}`, default settings (DOP853, rtol 1e-10, atol "
             "1e-12); phi in units of the scene's alpha.", "", "## Machine", ""]
    lines += [f"- {k}: {v}" for k, v in machine().items()]
    lines += ["- the 2 cores are shared with other sessions (no timing is reported here)", "",
              "## 1. The first rocking segment, step by step", ""] + trace
    lines += ["", "## 2. How the difference grows", "",
              "Per 1-s window. The two paths differ from each other by as much as the compiled "
              "path differs from itself when the record's samples change by one ulp.", ""]
    lines += windows(base_c, base_r, ulp_c)
    lines += ["", "## 3. The whole record's impact count and peak", "",
              "| path | change | impacts | max \\|phi\\|/alpha |", "|:--|:--|--:|--:|"]
    lines += [f"| {p} | {what} | {r['n_impacts']} | {r['peak']:.12f} |" for p, what, r in rows]
    lines += ["", f"CPU time of the whole script: {time.process_time() - cpu0:.0f} s in this "
              "process, plus the subprocesses."]
    out = Path(args.out) / "analytic_divergence.md"
    out.write_text("\n".join(lines) + "\n")
    print(out.read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The cross-engine bars of issue 3, measured for one or more settings of an engine backend.

Runs every case of ``tests/engines/cases.py`` (free rocking of three scenes from 0.5 alpha; the
16 Ricker pulses the analytic frame survives; the 16 that overturn it), each as the case
defines it (``case.load()``, ``case.kwargs()``), against the analytic backend, and prints one
Markdown row per setting:

* eta: largest |eta_engine / eta_analytic - 1| [%] over the impacts of each free-rocking run,
  for impacts after which the structure rocks counterclockwise / clockwise;
* nrmse: largest RMS of (phi_engine - phi_analytic) / alpha over the first 2 s [-];
* peak: largest |max|phi|_engine / max|phi|_analytic - 1| [%] over the surviving pulses of the
  bare asymmetric frame / of the hybrid frame (eps_f = 1 %);
* OT: overturning pulses that overturned in the engine / all;
* pen, slide: largest penetration / sliding [mm] over every run;
* rtf: median real-time factor of the stepping (simulated s per wall s), and the wall time of
  the whole evaluation [s] (stepping, Python loop and analysis). Timings on a loaded machine
  are noisy.

Usage::

    python benchmarks/pymunk_settings.py                          # pymunk at its defaults
    python benchmarks/pymunk_settings.py "dt=5e-4" "iterations=10"  # one row per setting
    python benchmarks/pymunk_settings.py --sweep         # the sweep of docs/engines/pymunk.md
    python benchmarks/pymunk_settings.py --engine mujoco ""        # another engine
    python benchmarks/pymunk_settings.py --cases "dt=2e-3"         # every case's numbers
    python benchmarks/pymunk_settings.py --speed "" "dt=5e-4"       # real-time factors
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
import math
import time
from pathlib import Path

import numpy as np

import rockbench as rb
from rockbench.analytic.reference import Reference

_CASES = Path(__file__).resolve().parents[1] / "tests" / "engines" / "cases.py"

#: One-factor-at-a-time sweep around the defaults (docs/engines/pymunk.md).
SWEEP = ["", "dt=2e-3,output_dt=2e-3", "dt=5e-4", "dt=2.5e-4",
         "iterations=10", "iterations=20", "iterations=50", "iterations=100",
         "friction=0.5", "friction=0.7", "friction=1", "friction=10",
         "collision_slop=0.0", "collision_slop=1e-5", "collision_slop=1e-4",
         "collision_slop=1e-3", "collision_bias=0.1**60", "collision_bias=0.99**60",
         "damper='couple'", "damper='heel'"]


def _load_cases():
    spec = importlib.util.spec_from_file_location("_rockbench_cases", _CASES)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


cases = _load_cases()


@functools.lru_cache(maxsize=None)
def _reference(case):
    scene = case.load()
    return rb.run(scene, engine="analytic", **case.kwargs(scene))


def rms_error(res, ref, alpha: float, window: float) -> float:
    """RMS of (phi - phi_ref) / alpha over the first ``window`` seconds [-], on the reference's
    grid (the engine's history interpolated linearly when its output_dt differs)."""
    h, hr = res.history, ref.history
    tr = hr.t.to_numpy()
    m = tr - tr[0] <= window + 1e-9
    phi = np.interp(tr[m], h.t.to_numpy(), h.phi.to_numpy())
    d = (phi - hr.phi.to_numpy()[m]) / alpha
    return float(np.sqrt(np.mean(d ** 2))) if m.any() else math.inf


def evaluate(engine: str = "pymunk", **settings) -> dict:
    """Every metric of one setting; ``out["cases"]`` holds one row per run."""
    out = dict(eta={}, rms={}, peak={}, ot=0, n_ot=0, pen=0.0, slide=0.0, rtf=[],
               diverged=[], cases=[])
    t_start = time.perf_counter()

    def run(case):
        scene = case.load()
        r = rb.run(scene, engine=engine, **case.kwargs(scene), **settings)
        s = r.summary
        out["pen"] = max(out["pen"], s.max_penetration or 0.0)
        out["slide"] = max(out["slide"], s.max_sliding or 0.0)
        if r.cost.wall_s > 0:
            out["rtf"].append(r.cost.real_time_factor)
        if not r.ok:
            out["diverged"].append(f"{case.id}: {s.reason}")
        return scene, r

    for case in cases.FREE_CASES:
        scene, r = run(case)
        eta = Reference(scene).eta
        errs = {1: [], -1: []}
        for _, e in r.impacts().iterrows():
            errs[int(e.direction)].append(e.eta / eta[int(e.direction)] - 1)
        out["eta"][case.scene] = {d: (max(v, key=abs) if v else math.nan)
                                  for d, v in errs.items()}
        out["rms"][case.scene] = rms_error(r, _reference(case), scene.alpha,
                                           cases.NRMSE_WINDOW)
        out["cases"].append((case.id, out["eta"][case.scene], out["rms"][case.scene],
                             r.summary.max_penetration, r.summary.max_sliding, r.status))
    for case in cases.SURVIVE_CASES:
        _, r = run(case)
        ref = _reference(case)
        e = (r.summary.max_abs_phi_over_alpha / ref.summary.max_abs_phi_over_alpha - 1
             if not r.summary.overturned else math.inf)
        out["peak"][case.scene] = max(out["peak"].get(case.scene, 0.0), abs(e))
        out["cases"].append((case.id, ref.summary.max_abs_phi_over_alpha, e,
                             r.summary.max_penetration, r.summary.max_sliding, r.status))
    for case in cases.OVERTURN_CASES:
        _, r = run(case)
        out["n_ot"] += 1
        out["ot"] += int(r.summary.overturned)
        out["cases"].append((case.id, "overturned" if r.summary.overturned else "SURVIVED",
                             r.summary.t_overturn, r.summary.max_penetration,
                             r.summary.max_sliding, r.status))
    out["rtf"] = float(np.median(out["rtf"])) if out["rtf"] else math.nan
    out["wall"] = time.perf_counter() - t_start
    return out


def speed(engine: str = "pymunk", repeat: int = 3, **settings) -> list[tuple]:
    """Real-time factors [-] of three representative runs (best of ``repeat``): the stepping
    only (``Result.cost``) and the whole ``run`` call (stepping, Python loop, analysis)."""
    rows = []
    runs = [("housner-block, free rocking 10 s", "housner-block", None, 10.0),
            ("paper-asymmetric, free rocking 10 s", "paper-asymmetric", None, 10.0),
            ("paper-asymmetric-hybrid-eps1, pulse A=7 W=3", "paper-asymmetric-hybrid-eps1",
             (7.0, 3.0), None)]
    for label, name, aw, dur in runs:
        scene = rb.load_scene(name)
        kw = dict(duration=dur, phi0=0.5 * scene.alpha)
        if aw is not None:
            p = rb.RickerPulse.dimensionless(*aw, scene.structure)
            kw = dict(motion=p, duration=cases.SURVIVE_END - p.t_start)
        best = None
        for _ in range(repeat):
            t = time.perf_counter()
            r = rb.run(scene, engine=engine, **kw, **settings)
            wall = time.perf_counter() - t
            cand = (r.cost.real_time_factor, r.cost.sim_time / wall, r.cost.steps)
            best = cand if best is None or cand[1] > best[1] else best
        rows.append((label,) + best)
    return rows


def header() -> str:
    names = " | ".join(f"eta err % {c.scene} ccw / cw" for c in cases.FREE_CASES)
    return (f"| setting | {names} | nrmse | peak err % bare / hybrid | OT | pen mm | slide mm "
            f"| rtf | wall s | status |\n" + "|---" * (9 + len(cases.FREE_CASES)) + "|")


def row(label: str, m: dict) -> str:
    eta = " | ".join(f"{100 * m['eta'][c.scene][1]:+.2f} / {100 * m['eta'][c.scene][-1]:+.2f}"
                     for c in cases.FREE_CASES)
    peak = " / ".join(f"{100 * v:.2f}" for v in m["peak"].values())
    st = "ok" if not m["diverged"] else f"{len(m['diverged'])} diverged"
    return (f"| {label} | {eta} | {max(m['rms'].values()):.5f} | {peak} | {m['ot']}/{m['n_ot']} "
            f"| {1e3 * m['pen']:.2f} | {1e3 * m['slide']:.2f} | {m['rtf']:.0f} "
            f"| {m['wall']:.0f} | {st} |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("settings", nargs="*", default=[""],
                    help="comma-separated overrides, e.g. \"dt=5e-4,iterations=20\"")
    ap.add_argument("--engine", default="pymunk")
    ap.add_argument("--sweep", action="store_true", help="run the settings of SWEEP")
    ap.add_argument("--cases", action="store_true", help="print every run")
    ap.add_argument("--speed", action="store_true",
                    help="real-time factors of three runs per setting instead of the bars")
    a = ap.parse_args(argv)
    if a.speed:
        print("| setting | run | rtf stepping | rtf whole run | steps |\n|---|---|---|---|---|")
        for s in (SWEEP if a.sweep else a.settings):
            for label, rtf, rtf_all, steps in speed(a.engine, **eval(f"dict({s})")):  # noqa: S307
                print(f"| {s or 'defaults'} | {label} | {rtf:.0f} | {rtf_all:.0f} | {steps} |",
                      flush=True)
        return
    print(header(), flush=True)
    for s in (SWEEP if a.sweep else a.settings):
        kw = eval(f"dict({s})")  # noqa: S307 - a benchmark script's command line
        m = evaluate(a.engine, **kw)
        print(row(s or "defaults", m), flush=True)
        if a.cases:
            for c in m["cases"]:
                print("    ", c)
            for d in m["diverged"]:
                print("     diverged:", d)


if __name__ == "__main__":
    main()

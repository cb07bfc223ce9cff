"""Accuracy and speed of the MuJoCo backend against the analytic reference, per setting.

Runs the cross-engine checks of issue 3 (free rocking of three scenes from phi0 = 0.5 alpha;
Ricker pulses that the analytic frame survives; pulses that overturn it) for one or more
settings of :class:`rockbench.engines.mujoco.MujocoSettings` (or of any engine), and prints one
Markdown table row per setting:

* eta: largest |eta_engine / eta_analytic - 1| [%] over the impacts of the free-rocking runs
  that start in the first ``FREE_WINDOW`` seconds (the last, possibly unfinished, excursion is
  left out), per scene;
* rms: largest RMS of (phi_engine - phi_analytic) / alpha over the first 2 s [-];
* peak: largest |max|phi|_engine / max|phi|_analytic - 1| [%] over the surviving pulses;
* OT: overturning pulses that overturned in the engine / all;
* pen, slide: largest penetration / sliding [mm] of all runs; rtf: simulated seconds per wall
  second of stepping (median over runs; noisy on a loaded machine).

Usage::

    python benchmarks/mujoco_settings.py                              # defaults
    python benchmarks/mujoco_settings.py "dt=5e-4" "cone='pyramidal'"  # one row per setting
    python benchmarks/mujoco_settings.py --engine pymunk ""            # another engine
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
import time

import numpy as np

import rockbench as rb
from rockbench.analytic.reference import Reference

FREE = ("housner-block", "paper-symmetric", "paper-asymmetric")
FREE_DURATION = 8.0      # s
FREE_WINDOW = 6.0        # s: impacts after this are left out (their next peak may be cut)
RMS_WINDOW = 2.0         # s
#: (scene, A, W, shapes): pulses the analytic frame survives with max|phi|/alpha in 0.3..0.8
SURVIVE = (("paper-asymmetric", 6.0, 6.0, ("symmetric", "antisymmetric")),
           ("paper-asymmetric", 10.0, 6.0, ("symmetric", "antisymmetric")),
           ("paper-asymmetric-hybrid-eps1", 8.0, 3.0, ("symmetric", "antisymmetric")),
           ("paper-asymmetric-hybrid-eps1", 10.0, 4.0, ("symmetric", "antisymmetric")))
#: pulses that overturn the analytic frame (A well above its threshold)
OVERTURN = (("paper-asymmetric", 5.0, 3.0, ("symmetric", "antisymmetric")),
            ("paper-asymmetric-hybrid-eps1", 12.0, 3.0, ("symmetric", "antisymmetric")))
AFTER = 5.0              # s simulated after the pulse


def pulses(table):
    for name, A, W, shapes in table:
        sc = rb.load_scene(name)
        for shape in shapes:
            for sign in (1, -1):
                yield (name, A, W, shape, sign), sc, \
                    rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)


@functools.lru_cache(maxsize=None)
def _reference_free(name):
    sc = rb.load_scene(name)
    return rb.run(sc, None, engine="analytic", phi0=0.5 * sc.alpha, duration=FREE_DURATION)


@functools.lru_cache(maxsize=None)
def _reference_pulse(name, A, W, shape, sign):
    sc = rb.load_scene(name)
    p = rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)
    return rb.run(sc, p, engine="analytic", duration=p.t_end - p.t_start + AFTER)


def free_metrics(name, engine, **kw):
    """(eta errors {direction: max |rel err|}, rms, result) of one free-rocking run."""
    sc = rb.load_scene(name)
    ref = _reference_free(name)
    r = rb.run(sc, None, engine=engine, phi0=0.5 * sc.alpha, duration=FREE_DURATION, **kw)
    eta = Reference(sc).eta
    errs = {1: 0.0, -1: 0.0}
    imp = r.events[(r.events.kind == "impact") & (r.events.t <= FREE_WINDOW)]
    for _, e in imp.iterrows():
        d = int(e.direction)
        err = abs(e.eta / eta[d] - 1) if math.isfinite(e.eta) else math.inf
        errs[d] = max(errs[d], err)
    if len(imp) == 0:
        errs = {1: math.inf, -1: math.inf}
    h, hr = r.history, ref.history
    n = min(len(h), len(hr))
    m = h.t.to_numpy()[:n] <= RMS_WINDOW + 1e-9
    dphi = (h.phi.to_numpy()[:n] - hr.phi.to_numpy()[:n]) / sc.alpha
    rms = float(np.sqrt(np.mean(dphi[m] ** 2))) if m.any() else math.inf
    return errs, rms, r


def evaluate(engine="mujoco", hybrid=True, **kw):
    """All metrics of one setting (dict); ``hybrid=False`` leaves out the hybrid frame."""
    out = dict(eta={}, rms=0.0, peak=0.0, peak_rows=[], ot=0, n_ot=0, pen=0.0, slide=0.0,
               slide_ot=0.0, rtf=[], status=[])

    def track(r, ot=False):
        s = r.summary
        out["pen"] = max(out["pen"], s.max_penetration)
        key = "slide_ot" if ot else "slide"
        out[key] = max(out[key], s.max_sliding)
        if r.cost.wall_s > 0:
            out["rtf"].append(r.cost.sim_time / r.cost.wall_s)
        if s.status != "ok":
            out["status"].append(f"{r.scene.name}: {s.reason}")

    for name in FREE:
        errs, rms, r = free_metrics(name, engine, **kw)
        out["eta"][name] = errs
        out["rms"] = max(out["rms"], rms)
        track(r)
    keep = (lambda t: t) if hybrid else (lambda t: [c for c in t if "hybrid" not in c[0]])
    for key, sc, p in pulses(keep(SURVIVE)):
        ref = _reference_pulse(*key)
        r = rb.run(sc, p, engine=engine, duration=p.t_end - p.t_start + AFTER, **kw)
        e = r.summary.max_abs_phi_over_alpha / ref.summary.max_abs_phi_over_alpha - 1
        if r.summary.overturned:
            e = math.inf
        out["peak"] = max(out["peak"], abs(e))
        out["peak_rows"].append((*key, ref.summary.max_abs_phi_over_alpha, e))
        track(r)
    for _, sc, p in pulses(keep(OVERTURN)):
        r = rb.run(sc, p, engine=engine, duration=p.t_end - p.t_start + AFTER, **kw)
        out["n_ot"] += 1
        out["ot"] += int(r.summary.overturned)
        track(r, ot=True)
    out["rtf"] = float(np.median(out["rtf"])) if out["rtf"] else math.nan
    return out


def row(label, m):
    eta = " | ".join(f"{100 * m['eta'][n][1]:.2f} / {100 * m['eta'][n][-1]:.2f}" for n in FREE)
    st = "ok" if not m["status"] else f"{len(m['status'])} diverged"
    return (f"| {label} | {eta} | {m['rms']:.5f} | {100 * m['peak']:.2f} | {m['ot']}/{m['n_ot']} "
            f"| {1e3 * m['pen']:.3f} | {1e3 * m['slide']:.3f} / {1e3 * m['slide_ot']:.1f} "
            f"| {m['rtf']:.0f} | {st} |")


HEADER = ("| setting | eta err % block (ccw / cw) | symmetric | asymmetric | rms phi/alpha "
          "| peak err % | OT | pen mm | slide mm (overturning runs) | rtf | status |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("settings", nargs="*", default=[""],
                    help="comma-separated overrides, e.g. \"dt=5e-4,cone='elliptic'\"")
    ap.add_argument("--engine", default="mujoco")
    ap.add_argument("--verbose", action="store_true")
    ap.add_argument("--bare", action="store_true", help="leave out the hybrid frame")
    a = ap.parse_args(argv)
    print(HEADER)
    for s in a.settings:
        kw = eval(f"dict({s})")  # noqa: S307 - a benchmark script's command line
        t = time.perf_counter()
        m = evaluate(a.engine, hybrid=not a.bare, **kw)
        print(row(s or "defaults", m), flush=True)
        if a.verbose:
            for r in m["peak_rows"]:
                print(f"    {r[0]} A={r[1]:g} W={r[2]:g} {r[3]} {r[4]:+d}: analytic "
                      f"{r[5]:.3f} alpha, err {100 * r[6]:+.2f} %")
            for r in m["status"]:
                print("    diverged:", r)
            print(f"    ({time.perf_counter() - t:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()

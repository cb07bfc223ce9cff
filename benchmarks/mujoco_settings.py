"""Accuracy and speed of an engine backend against the analytic reference, per setting.

Runs the cross-engine cases of issue 3 exactly as ``tests/engines/cases.py`` defines them (free
rocking of three scenes from phi0 = 0.5 alpha; Ricker pulses the analytic frame survives; pulses
that overturn it) for one or more settings of the engine (MuJoCo by default), and prints one
Markdown table row per setting:

* eta: largest |eta_engine / eta_analytic - 1| [%] over the impacts of each free-rocking run,
  for impacts after which the structure rocks counterclockwise / clockwise;
* nrmse: largest RMS of (phi_engine - phi_analytic) / alpha over the first 2 s [-];
* peak: largest |max|phi|_engine / max|phi|_analytic - 1| [%] over the surviving pulses, per
  scene (bare asymmetric frame / hybrid eps1);
* OT: overturning pulses that overturned in the engine / all;
* pen, slide: largest penetration / sliding [mm] over the free and surviving runs, and (after the
  slash) over the overturning runs; rtf: simulated seconds per wall second of stepping (median
  over runs). Timings on a loaded machine are noisy.

Usage::

    python benchmarks/mujoco_settings.py                               # defaults
    python benchmarks/mujoco_settings.py "dt=5e-4" "cone='pyramidal'"   # one row per setting
    python benchmarks/mujoco_settings.py --engine pymunk ""             # another engine
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


def _load_cases():
    spec = importlib.util.spec_from_file_location("_rockbench_cases", _CASES)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


cases = _load_cases()


@functools.lru_cache(maxsize=None)
def _scene(case):
    return case.load()     # the case's scene (overturn runs stop at the case's fall angle)


@functools.lru_cache(maxsize=None)
def _reference(case):
    sc = _scene(case)
    return rb.run(sc, engine="analytic", **case.kwargs(sc))


def _rms(res, ref, alpha, window):
    h, hr = res.history, ref.history
    t = h.t.to_numpy()
    m = t - t[0] <= window + 1e-9
    ref_phi = np.interp(t[m], hr.t.to_numpy(), hr.phi.to_numpy())   # same grid if same output_dt
    d = (h.phi.to_numpy()[m] - ref_phi) / alpha
    return float(np.sqrt(np.mean(d ** 2))) if m.any() else math.inf


def evaluate(engine="mujoco", **kw):
    """All metrics of one setting (dict)."""
    out = dict(eta={}, rms=0.0, peak={}, rows=[], ot=0, n_ot=0, pen=0.0, slide=0.0,
               pen_ot=0.0, slide_ot=0.0, rtf=[], status=[])

    def track(r, ot=False):
        s = r.summary
        sfx = "_ot" if ot else ""
        out["pen" + sfx] = max(out["pen" + sfx], s.max_penetration)
        out["slide" + sfx] = max(out["slide" + sfx], s.max_sliding)
        if r.cost.wall_s > 0:
            out["rtf"].append(r.cost.sim_time / r.cost.wall_s)
        if s.status != "ok":
            out["status"].append(f"{r.scene.name}: {s.reason}")

    for case in cases.FREE_CASES:
        sc = _scene(case)
        r = rb.run(sc, engine=engine, **case.kwargs(sc), **kw)
        eta = Reference(sc).eta
        errs = {1: math.nan, -1: math.nan}
        for _, e in r.events[r.events.kind == "impact"].iterrows():
            d = int(e.direction)
            err = abs(e.eta / eta[d] - 1) if math.isfinite(e.eta) else math.inf
            errs[d] = err if math.isnan(errs[d]) else max(errs[d], err)
        out["eta"][case.scene] = errs
        out["rms"] = max(out["rms"], _rms(r, _reference(case), sc.alpha, cases.NRMSE_WINDOW))
        track(r)
    for case in cases.SURVIVE_CASES:
        sc = _scene(case)
        ref = _reference(case)
        r = rb.run(sc, engine=engine, **case.kwargs(sc), **kw)
        e = r.summary.max_abs_phi_over_alpha / ref.summary.max_abs_phi_over_alpha - 1
        if r.summary.overturned:
            e = math.inf
        out["peak"][case.scene] = max(out["peak"].get(case.scene, 0.0), abs(e))
        out["rows"].append((case.id, ref.summary.max_abs_phi_over_alpha, e,
                            r.summary.max_sliding))
        track(r)
    for case in cases.OVERTURN_CASES:
        sc = _scene(case)
        r = rb.run(sc, engine=engine, **case.kwargs(sc), **kw)
        out["n_ot"] += 1
        out["ot"] += int(r.summary.overturned)
        track(r, ot=True)
    out["rtf"] = float(np.median(out["rtf"])) if out["rtf"] else math.nan
    return out


def row(label, m):
    eta = " | ".join(f"{100 * m['eta'][c.scene][1]:.2f} / {100 * m['eta'][c.scene][-1]:.2f}"
                     for c in cases.FREE_CASES)
    peak = " / ".join(f"{100 * v:.2f}" for v in m["peak"].values())
    st = "ok" if not m["status"] else f"{len(m['status'])} diverged"
    return (f"| {label} | {eta} | {m['rms']:.5f} | {peak} | {m['ot']}/{m['n_ot']} "
            f"| {1e3 * m['pen']:.2f} / {1e3 * m['pen_ot']:.2f} "
            f"| {1e3 * m['slide']:.2f} / {1e3 * m['slide_ot']:.1f} | {m['rtf']:.0f} | {st} |")


def header():
    names = " | ".join(f"eta err % {c.scene} (ccw / cw)" for c in cases.FREE_CASES)
    peaks = " / ".join(sorted({c.scene for c in cases.SURVIVE_CASES}))
    return (f"| setting | {names} | nrmse | peak err % ({peaks}) | overturned "
            f"| pen mm (overturn runs) | slide mm (overturn runs) | rtf | status |\n"
            + "|---" * 10 + "|")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("settings", nargs="*", default=[""],
                    help="comma-separated overrides, e.g. \"dt=5e-4,cone='elliptic'\"")
    ap.add_argument("--engine", default="mujoco")
    ap.add_argument("--verbose", action="store_true", help="print every surviving pulse")
    a = ap.parse_args(argv)
    print(header())
    for s in a.settings:
        kw = eval(f"dict({s})")  # noqa: S307 - a benchmark script's command line
        t = time.perf_counter()
        m = evaluate(a.engine, **kw)
        print(row(s or "defaults", m), flush=True)
        if a.verbose:
            for cid, ref, e, sl in m["rows"]:
                print(f"    {cid}: analytic {ref:.3f} alpha, peak err {100 * e:+.2f} %, "
                      f"slide {1e3 * sl:.2f} mm")
            for r in m["status"]:
                print("    diverged:", r)
            print(f"    ({time.perf_counter() - t:.0f} s wall)")


if __name__ == "__main__":
    main()

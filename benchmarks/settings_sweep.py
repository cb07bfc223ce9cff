"""The cross-engine bars of issue 3, measured for one or more settings of an engine backend.

    python benchmarks/settings_sweep.py ENGINE [SETTING ...] [--sweep [NAME ...]]
                                        [--suite free|pulses|all] [--cases] [--speed]
                                        [--csv PATH]

Runs the cross-engine cases of rockbench's case catalogue (``rockbench/scenarios/cases.toml``,
:func:`rockbench.sweep.cases.catalogue`): free rocking of three scenes from 0.5 alpha; (with
``--suite pulses`` or ``all``, the default) the 16 Ricker pulses the analytic frame survives
and the 16 that overturn it, each as the case defines it (``case.load()``, ``case.kwargs()``),
against the analytic backend, and prints one Markdown row per setting:

* eta err %: per free-rocking scene, the largest |eta_engine / eta_analytic - 1| [%] (signed)
  over the impacts after which the structure rocks counterclockwise / clockwise; and the
  largest absolute one over every scene;
* nrmse: largest RMS of (phi_engine - phi_analytic) / alpha over the first 2 s [-]
  (``rockbench.comparison.history_error``, on the reference's time grid);
* peak err %: largest |max|phi|_engine / max|phi|_analytic - 1| over the surviving pulses of
  each scene (bare asymmetric frame / hybrid eps_f = 1 %), and over both;
* OT: overturning pulses that overturned in the engine / all;
* pen, slide: largest penetration / sliding [mm] over the free and surviving runs / over the
  overturning runs;
* rtf: median real-time factor of the stepping (simulated s per wall s) and the aggregate one
  (summed simulated s / summed wall s); wall: seconds of the whole evaluation (stepping,
  Python loop and analysis); status: ``ok`` or how many runs did not finish cleanly (the
  first one's reason with ``--cases``). Timings on a loaded machine are noisy.

SETTING is a comma-separated list of overrides, e.g. ``"dt=5e-4,iterations=20"`` (``""``: the
defaults). ``--sweep`` runs the named groups of :data:`SWEEPS` for ENGINE (no name: all of
them): the one-factor-at-a-time sweeps of ``docs/engines/<engine>.md``. A pybullet setting
whose key starts with ``_`` is a "trap": a Bullet default the backend overrides, restored on
purpose (``_damping``, ``_raw_friction``). ``--speed`` prints the real-time factors of three
representative runs per setting instead of the bars.
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
import time

import numpy as np
import pandas as pd

import rockbench as rb
from rockbench.comparison import history_error
from rockbench.sweep.cases import catalogue

CASES = catalogue()


def _dt(v: float) -> dict:
    return {"dt": v, "output_dt": max(v, 1e-3)}


def _parse(*texts: str) -> list[tuple[str, dict]]:
    """(text, overrides) of command-line style settings, e.g. "dt=5e-4,iterations=20"."""
    return [(t or "defaults", eval(f"dict({t})")) for t in texts]  # noqa: S307 - our own text


#: engine -> sweep name -> [(label, settings overrides)]: the one-factor-at-a-time sweeps of
#: ``docs/engines/<engine>.md`` (keys starting with "_" are pybullet traps).
SWEEPS: dict[str, dict[str, list[tuple[str, dict]]]] = {
    # pymunk: one setting changed at a time from the defaults (docs/engines/pymunk.md)
    "pymunk": {"default": [("defaults", {})]} | {
        name: _parse(*texts) for name, texts in (
            ("dt", ("dt=2e-3,output_dt=2e-3", "dt=5e-4", "dt=2.5e-4")),
            ("iterations", ("iterations=10", "iterations=20", "iterations=50",
                            "iterations=100")),
            ("friction", ("friction=0.5", "friction=0.7", "friction=1", "friction=10")),
            ("collision_slop", ("collision_slop=0.0", "collision_slop=1e-5",
                                "collision_slop=1e-4", "collision_slop=1e-3")),
            ("collision_bias", ("collision_bias=0.1**60", "collision_bias=0.99**60")),
            ("damper", ("damper='couple'", "damper='heel'")))},
    "mujoco": {"default": [("defaults", {})]},
    "pybullet": {
        "default": [("defaults", {})],
        "dt": [(f"dt={v:g}", _dt(v)) for v in (4e-3, 2e-3, 1e-3, 5e-4, 2e-4)],
        "dt_iterations": [(f"dt={d:g}, solver_iterations={n}",
                           {"dt": d, "output_dt": 1e-3, "solver_iterations": n})
                          for d in (1e-3, 5e-4, 2e-4) for n in (50, 100, 200)],
        "iterations": [(f"solver_iterations={v}", {"solver_iterations": v})
                       for v in (5, 10, 20, 50, 100)],
        "erp": [(f"contact_erp={v:g}", {"contact_erp": v})
                for v in (0.02, 0.05, 0.08, 0.1, 0.2, 0.5, 0.8)],
        "breaking": [(f"contact_breaking_threshold={v:g}", {"contact_breaking_threshold": v})
                     for v in (0.02, 5e-3, 1e-3, 1e-4)],
        "anchor": [(f"friction_anchor={v}", {"friction_anchor": v}) for v in (True, False)],
        "stiffness": [(f"contact_stiffness={k:g}, damping={c:g}",
                       {"contact_stiffness": k, "contact_damping": c})
                      for k, c in ((1e7, 1e5), (1e8, 1e6), (1e9, 1e7), (1e10, 1e8))],
        "solver": [("solver=si", {"solver": "si"}),
                   ("solver=dantzig (rejected)", {"solver": "dantzig"}),
                   ("solver=pgs (trap)", {"solver": "pgs"})],
        "damper": [(f"damper={v}", {"damper": v}) for v in ("distributed", "couple", "heel")],
        "friction": [(f"friction={v:g}", {"friction": v}) for v in (0.6, 1.0, 2.0)],
        "traps": [("Bullet multibody damping 0.04 (trap)", {"_damping": 0.04}),
                  ("friction=0.6 not square-rooted: pair 0.36 (trap)",
                   {"friction": 0.6, "_raw_friction": True})],
    },
}


# ------------------------------------------------------------------------------------------
# Running one case
# ------------------------------------------------------------------------------------------
def _trap_backend(trap: dict):
    """The pybullet backend with Bullet defaults restored (``trap``), to measure what
    overriding them buys."""
    from rockbench.engines import pybullet as pbmod

    pbmod._SOLVERS.setdefault("dantzig", "CONSTRAINT_SOLVER_LCP_DANTZIG")   # rejected solvers,
    pbmod._SOLVERS.setdefault("pgs", "CONSTRAINT_SOLVER_LCP_PGS")           # on purpose

    class Trap(pbmod.PybulletBackend):
        def _build(self) -> None:
            super()._build()
            pb, cid = self._pb, self._cid
            if "_damping" in trap:
                d = float(trap["_damping"])
                for bid in self._bodies:
                    pb.changeDynamics(bid, -1, linearDamping=d, angularDamping=d,
                                      physicsClientId=cid)
            if trap.get("_raw_friction"):
                mu = float(self.settings.friction)   # each body mu: the pair gets mu^2
                for bid in self._bodies:
                    pb.changeDynamics(bid, 2, lateralFriction=mu, physicsClientId=cid)
                for bid in self._static:
                    pb.changeDynamics(bid, -1, lateralFriction=mu, physicsClientId=cid)

    return Trap


def _run(case, engine: str, settings: dict):
    scene = case.load()
    kw = case.kwargs(scene)
    trap = {k: v for k, v in settings.items() if k.startswith("_")}
    over = {k: v for k, v in settings.items() if not k.startswith("_")}
    if engine == "pybullet" and (trap or over.get("solver") in ("dantzig", "pgs")):
        motion = kw.pop("motion")
        return _trap_backend(trap)(scene, **over).run(motion, **kw)
    return rb.run(scene, engine=engine, **kw, **over)


@functools.lru_cache(maxsize=None)
def _reference(case):
    scene = case.load()
    return rb.run(scene, engine="analytic", **case.kwargs(scene))


def _nrmse(res, ref) -> float:
    t, d = history_error(res, ref)
    m = t <= t[0] + CASES.nrmse_window + 1e-9 if len(t) else t
    return float(np.sqrt(np.mean(d[m] ** 2))) if len(t) and m.any() else math.inf


# ------------------------------------------------------------------------------------------
# The bars of one setting
# ------------------------------------------------------------------------------------------
def evaluate(engine: str, settings: dict, suite: str = "all") -> dict:
    """Every metric of one setting (module docstring); ``out["cases"]`` holds one line per run."""
    out = dict(eta={}, rms={}, peak={}, ot=0, n_ot=0, pen=0.0, slide=0.0, pen_ot=0.0,
               slide_ot=0.0, rtf=[], sim=0.0, wall_s=0.0, diverged=[], cases=[])
    t_start = time.perf_counter()

    def track(case, r, ot: bool = False) -> None:
        s, sfx = r.summary, "_ot" if ot else ""
        if not r.ok:
            out["diverged"].append(f"{case.id}: {r.status}: {s.reason}")
            return
        out["pen" + sfx] = max(out["pen" + sfx], float(s.max_penetration or 0.0))
        out["slide" + sfx] = max(out["slide" + sfx], float(s.max_sliding or 0.0))
        if r.cost.wall_s > 0:
            out["rtf"].append(r.cost.real_time_factor)
        out["sim"] += r.cost.sim_time
        out["wall_s"] += r.cost.wall_s

    for case in CASES.free_cases:
        r, ref = _run(case, engine, settings), _reference(case)
        track(case, r)
        info = rb.info(ref.scene)
        eta = {1: info["eta_ccw"], -1: info["eta_cw"]}
        errs = {1: [], -1: []}
        if r.ok:
            for _, e in r.impacts().iterrows():
                errs[int(e.direction)].append(e.eta / eta[int(e.direction)] - 1)
        out["eta"][case.scene] = {d: (max(v, key=abs) if v else math.nan)
                                  for d, v in errs.items()}
        out["rms"][case.scene] = _nrmse(r, ref) if r.ok else math.inf
        out["cases"].append((case.id, out["eta"][case.scene], out["rms"][case.scene],
                             r.summary.max_penetration, r.summary.max_sliding, r.status))
    if suite in ("pulses", "all"):
        for case in CASES.survive_cases:
            r, ref = _run(case, engine, settings), _reference(case)
            track(case, r)
            e = (r.summary.max_abs_phi_over_alpha / ref.summary.max_abs_phi_over_alpha - 1
                 if r.ok and not r.summary.overturned else math.inf)
            out["peak"][case.scene] = max(out["peak"].get(case.scene, 0.0), abs(e))
            out["cases"].append((case.id, ref.summary.max_abs_phi_over_alpha, e,
                                 r.summary.max_penetration, r.summary.max_sliding, r.status))
        for case in CASES.overturn_cases:
            r = _run(case, engine, settings)
            track(case, r, ot=True)
            out["n_ot"] += 1
            out["ot"] += int(r.ok and bool(r.summary.overturned))
            out["cases"].append((case.id, "overturned" if r.summary.overturned else "SURVIVED",
                                 r.summary.t_overturn, r.summary.max_penetration,
                                 r.summary.max_sliding, r.status))
    out["rtf_total"] = out["sim"] / out["wall_s"] if out["wall_s"] > 0 else math.nan
    out["rtf"] = float(np.median(out["rtf"])) if out["rtf"] else math.nan
    out["wall"] = time.perf_counter() - t_start
    return out


def header() -> str:
    names = " | ".join(f"eta err % {c.scene} ccw / cw" for c in CASES.free_cases)
    peaks = " / ".join(CASES.survive_points)
    return (f"| setting | {names} | eta err max % | nrmse | peak err % {peaks} | peak err max % "
            f"| OT | pen mm (overturn runs) | slide mm (overturn runs) | rtf median / total "
            f"| wall s | status |\n" + "|---" * (11 + len(CASES.free_cases)) + "|")


def row(label: str, m: dict) -> str:
    eta = " | ".join(f"{100 * m['eta'][c.scene][1]:+.2f} / {100 * m['eta'][c.scene][-1]:+.2f}"
                     for c in CASES.free_cases)
    eta_max = max((abs(v) for e in m["eta"].values() for v in e.values() if not math.isnan(v)),
                  default=math.nan)
    peak = " / ".join(f"{100 * m['peak'][s]:.2f}" if s in m["peak"] else "-"
                      for s in CASES.survive_points)
    peak_max = f"{100 * max(m['peak'].values()):.2f}" if m["peak"] else "-"
    ot = f"{m['ot']}/{m['n_ot']}" if m["n_ot"] else "-"
    st = "ok" if not m["diverged"] else f"{len(m['diverged'])} diverged"
    return (f"| {label} | {eta} | {100 * eta_max:.3f} | {max(m['rms'].values()):.5f} | {peak} "
            f"| {peak_max} | {ot} | {1e3 * m['pen']:.2f} / {1e3 * m['pen_ot']:.2f} "
            f"| {1e3 * m['slide']:.2f} / {1e3 * m['slide_ot']:.2f} "
            f"| {m['rtf']:.0f} / {m['rtf_total']:.0f} | {m['wall']:.0f} | {st} |")


# ------------------------------------------------------------------------------------------
# Speed
# ------------------------------------------------------------------------------------------
def speed(engine: str, settings: dict, repeat: int = 3) -> list[tuple]:
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
            kw = dict(motion=p, duration=CASES.survive_end - p.t_start)
        best = None
        for _ in range(repeat):
            t = time.perf_counter()
            r = rb.run(scene, engine=engine, **kw, **settings)
            wall = time.perf_counter() - t
            cand = (r.cost.real_time_factor, r.cost.sim_time / wall, r.cost.steps)
            best = cand if best is None or cand[1] > best[1] else best
        rows.append((label,) + best)
    return rows


# ------------------------------------------------------------------------------------------
def _variants(a) -> list[tuple[str, str, dict]]:
    """(sweep, label, settings) of every row asked for."""
    if a.sweep is None:
        return [("", label, kw) for label, kw in _parse(*a.settings)]
    groups = SWEEPS.get(a.engine, {"default": [("defaults", {})]})
    names = a.sweep or list(groups)
    bad = [n for n in names if n not in groups]
    if bad:
        raise SystemExit(f"unknown sweep {bad[0]!r} for {a.engine}: one of {', '.join(groups)}")
    return [(n, label, dict(over)) for n in names for label, over in groups[n]]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("engine", help="a backend name, e.g. pymunk, mujoco, pybullet")
    ap.add_argument("settings", nargs="*", default=[""],
                    help="comma-separated overrides, e.g. \"dt=5e-4,iterations=20\"")
    ap.add_argument("--sweep", nargs="*", default=None, metavar="NAME",
                    help="run the named sweeps of SWEEPS[ENGINE] (no name: all of them)")
    ap.add_argument("--suite", default="all", choices=("free", "pulses", "all"))
    ap.add_argument("--cases", action="store_true", help="print every run")
    ap.add_argument("--speed", action="store_true",
                    help="real-time factors of three runs per setting instead of the bars")
    ap.add_argument("--csv", default=None, help="also write the table to this CSV file")
    a = ap.parse_args(argv)
    variants = _variants(a)
    if a.speed:
        print("| setting | run | rtf stepping | rtf whole run | steps |\n|---|---|---|---|---|")
        for _, label, kw in variants:
            for run_label, rtf, rtf_all, steps in speed(a.engine, kw):
                print(f"| {label} | {run_label} | {rtf:.0f} | {rtf_all:.0f} | {steps} |",
                      flush=True)
        return 0
    print(header(), flush=True)
    rows = []
    for sweep, label, kw in variants:
        try:
            m = evaluate(a.engine, kw, a.suite)
        except Exception as e:  # a bad variant is a row, not a crash
            print(f"| {label} | error: {type(e).__name__}: {e} |", flush=True)
            rows.append({"sweep": sweep, "variant": label, "status": f"error: {e}"})
            continue
        print(row(label, m), flush=True)
        rows.append({"sweep": sweep, "variant": label, "nrmse_max": max(m["rms"].values()),
                     "peak_err_max": max(m["peak"].values()) if m["peak"] else math.nan,
                     "overturned": f"{m['ot']}/{m['n_ot']}", "pen_max": max(m["pen"], m["pen_ot"]),
                     "slide_max": max(m["slide"], m["slide_ot"]), "rtf": m["rtf"],
                     "rtf_total": m["rtf_total"], "wall_s": m["wall"],
                     "status": "ok" if not m["diverged"] else m["diverged"][0],
                     **{f"eta_err[{s}][{d:+d}]": v for s, e in m["eta"].items()
                        for d, v in e.items()},
                     **{f"nrmse[{s}]": v for s, v in m["rms"].items()}})
        if a.cases:
            for c in m["cases"]:
                print("    ", c)
            for d in m["diverged"]:
                print("     diverged:", d)
    if a.csv:
        pd.DataFrame(rows).to_csv(a.csv, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Speed and accuracy benchmark of every available backend, measured side by side in one run.

    python benchmarks/run.py [--quick] [--out benchmarks/results]

Writes ``results.md`` (tables + the machine it ran on) and ``results.csv``. Commit both with
any change to a solver or an engine adapter. Each timing is the median of ``--repeat`` runs;
``wall_s`` counts the integration/stepping only (model building excluded), ``total_s`` the whole
``rb.run`` call. Ratios are taken against the analytic backend on the same case in this run.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import pandas as pd

import rockbench as rb
from rockbench.comparison import metrics
from rockbench.scene.motion import motion_from_spec
from rockbench.sweep.cases import catalogue


def cpu_name() -> str:
    """The processor's model name, for the benchmarks' machine lines (one reader:
    :func:`rockbench.machine.cpu_name`)."""
    from rockbench.machine import cpu_name as name

    return name()


def machine() -> dict:
    return {"date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "cpu": cpu_name(), "cores": os.cpu_count(), "python": sys.version.split()[0],
            "platform": platform.platform(), "rockbench": rb.__version__,
            "engines": "; ".join(f"{r['name']}: {r.get('version', r.get('reason'))}"
                                 for r in rb.engine_info())}


def machine_section(load0: float) -> str:
    """The ``## Machine`` section of a result file: :func:`machine` and the load average
    (1 min) ``load0`` before the measurement and now, after it."""
    mc = machine()
    mc["load average (1 min) before / after"] = f"{load0:.2f} / {os.getloadavg()[0]:.2f}"
    return "## Machine\n\n" + "\n".join(f"- {k}: {v}" for k, v in mc.items())


def cases(quick: bool):
    """(label, scene, motion, phi0 [rad], duration [s]) of the benchmark cases (rockbench's
    case catalogue, ``[benchmarks]`` of ``rockbench/scenarios/cases.toml``)."""
    b = catalogue().benchmarks
    out = []
    for c in b["cases"]:
        scene = rb.load_scene(c["scene"])
        out.append((c["label"], scene, motion_from_spec(c.get("motion"), scene.structure),
                    c.get("phi0", 0.0) * scene.alpha, c.get("duration")))
    return out[:b["quick"]] if quick else out


def timed(scene, motion, engine, phi0, duration, repeat, **settings):
    runs, totals = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        r = rb.run(scene, motion, engine=engine, phi0=phi0, duration=duration, **settings)
        totals.append(time.perf_counter() - t)
        runs.append(r)
    i = sorted(range(repeat), key=lambda k: runs[k].cost.wall_s)[repeat // 2]
    return runs[i], statistics.median(totals)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    engines = rb.available_backends()
    rows = []
    for label, scene, motion, phi0, duration in cases(args.quick):
        ref, ref_total = timed(scene, motion, "analytic", phi0, duration, args.repeat)
        for eng in engines:
            r, total = (ref, ref_total) if eng == "analytic" else timed(
                scene, motion, eng, phi0, duration, args.repeat)
            m = metrics(r, ref)
            rows.append({"case": label, "backend": eng, "dt": r.settings.get("dt"),
                         "status": r.summary.status, "sim_s": r.cost.sim_time,
                         "wall_s": r.cost.wall_s, "total_s": total,
                         "real_time_factor": r.cost.real_time_factor,
                         "total_vs_analytic": total / ref_total,
                         "peak_rel_error": m["peak_rel_error"], "nrmse": m["nrmse"],
                         "eta_max_rel_error": m["eta_max_rel_error"]})
            print(f"{label:45s} {eng:9s} total {total:7.3f} s  rtf {rows[-1]['real_time_factor']:9.1f}",
                  flush=True)
    # accuracy vs cost: dt sweep on the pulse case
    sweep = []
    if not args.quick:
        label, scene, motion, phi0, duration = cases(False)[catalogue().benchmarks["dt_case"]]
        ref, _ = timed(scene, motion, "analytic", phi0, duration, 1)
        for eng in engines:
            if eng == "analytic":
                continue
            for dt in catalogue().benchmarks["dt_sweep"]:
                try:
                    r, total = timed(scene, motion, eng, phi0, duration, 1, dt=dt,
                                     output_dt=max(dt, 1e-3))
                except rb.ParameterError as e:
                    sweep.append({"backend": eng, "dt": dt, "status": f"refused: {e}"})
                    continue
                m = metrics(r, ref)
                sweep.append({"backend": eng, "dt": dt, "status": r.summary.status,
                              "wall_s": r.cost.wall_s, "real_time_factor": r.cost.real_time_factor,
                              "peak_rel_error": m["peak_rel_error"], "nrmse": m["nrmse"]})
                print(f"dt sweep {eng:9s} dt={dt:g}  {sweep[-1]['status']}", flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    df = pd.DataFrame(rows)
    df.to_csv(out / "results.csv", index=False)
    sw = pd.DataFrame(sweep)
    if len(sw):
        sw.to_csv(out / "dt_sweep.csv", index=False)
    mc = machine()
    with open(out / "results.md", "w") as f:
        f.write("# Benchmark results\n\nMeasured side by side in one run of `benchmarks/run.py`"
                f"{' --quick' if args.quick else ''} (median of {args.repeat}).\n\n")
        f.write("## Machine\n\n" + "\n".join(f"- {k}: {v}" for k, v in mc.items()) + "\n\n")
        f.write("## Cost and accuracy at default settings\n\n"
                "`wall_s`: stepping/integration only; `total_s`: the whole `rb.run` call "
                "(model building included); `total_vs_analytic`: ratio to the analytic backend "
                "on the same case; errors against the analytic reference (see docs/metrics.md)."
                "\n\n")
        f.write(df.to_markdown(index=False, floatfmt=".4g") if _has_tabulate()
                else df.to_string(index=False))
        if len(sw):
            f.write("\n\n## Accuracy vs cost: time-step sweep (asym frame, sym. Ricker A=2 W=3)"
                    "\n\n")
            f.write(sw.to_markdown(index=False, floatfmt=".4g") if _has_tabulate()
                    else sw.to_string(index=False))
        f.write("\n")
    print(f"wrote {out / 'results.md'}")
    return 0


def _has_tabulate() -> bool:
    try:
        import tabulate  # noqa: F401
        return True
    except ImportError:
        return False


if __name__ == "__main__":
    raise SystemExit(main())

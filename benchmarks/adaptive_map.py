"""An adaptive map against the full grid (issue 27 section 2), side by side in one run.

    python benchmarks/adaptive_map.py [--grid 100] [--repeat 3] [--axes engine]
                                      [--engine analytic] [--scenes a,b] [--out DIR]

For each scene (default: the paper's five frames) the map of ``--grid`` x ``--grid`` x 4 cells
is run in full and adaptively (``run_map(..., adaptive=True)``, ``rockbench.sweep.adaptive``),
with no store, one local worker, repeats interleaved (full, adaptive, full, ...). Reported: the
cells simulated by the adaptive map (and its coarse stride), the verdicts (``overturned``) equal
to the full grid's, and the process CPU time of each (the parent and its worker processes,
``resource.getrusage``), median (min-max) over ``--repeat`` passes after one untimed pass of
each (compilation, imports). ``--axes``: ``engine`` (the report's engine cells: A 1-8, W 1-10,
pulse window + 3 s), ``paper`` (A 0.5-8, W 0.5-10, + 10 s) or ``both``. ``--engine``: the
backend (an engine map costs 0.05-1.6 CPU s a cell: use a small ``--grid``).
Writes ``adaptive_map.md`` (``adaptive_map[_ENGINE][_GRID].md`` for another engine or grid)
with the machine and its load average.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import resource
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from rockbench.studies.maps import run_map  # noqa: E402
from rockbench.sweep.adaptive import coarse_stride  # noqa: E402
from run import machine_section  # noqa: E402

SCENES = ["paper-symmetric", "paper-asymmetric", "paper-asymmetric-hybrid",
          "paper-asymmetric-hybrid-eps2", "paper-asymmetric-hybrid-eps1"]
AXES = {"engine": dict(amplitude="1:8", frequency="1:10", tail=3.0),
        "paper": dict(amplitude="0.5:8", frequency="0.5:10")}
KEY = ["pulse", "sign", "amplitude", "frequency"]


def cpu() -> float:
    """Process CPU seconds of this process and its finished children (reaped first, so that a
    worker's time is not counted in the next pass)."""
    for p in multiprocessing.active_children():    # the pool shuts down without waiting
        p.join(timeout=30)
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def timed(fn):
    c = cpu()
    out = fn()
    return out, cpu() - c


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--axes", choices=("engine", "paper", "both"), default="engine")
    ap.add_argument("--engine", default="analytic")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    load0 = os.getloadavg()[0]
    g = (args.grid, args.grid)
    stride = coarse_stride(*g)
    lines = ["| scene | axes | cells | simulated (adaptive) | verdicts equal to the full grid's | "
             "full: CPU s | adaptive: CPU s | adaptive / full |", "|---|---|--:|--:|--:|--:|--:|--:|"]
    for axn in (("engine", "paper") if args.axes == "both" else (args.axes,)):
        for sc in args.scenes.split(","):
            kw = dict(grid=g, progress=False, workers=1, **AXES[axn])
            full = lambda: run_map(sc, args.engine, **kw)                    # noqa: E731
            adap = lambda: run_map(sc, args.engine, adaptive=True, **kw)     # noqa: E731
            f, a = full(), adap()                                            # untimed
            tf, ta = [], []
            for _ in range(args.repeat):
                f, t = timed(full)
                tf.append(t)
                a, t = timed(adap)
                ta.append(t)
            kf = f.set_index(KEY)["overturned"].astype(bool)
            ka = a.set_index(KEY)["overturned"].astype(bool).reindex(kf.index)
            same = int((ka.to_numpy() == kf.to_numpy()).sum())
            sim = int((~a["inferred"].astype(bool)).sum())
            n = len(f)
            mf, ma = statistics.median(tf), statistics.median(ta)
            lines.append(f"| {sc} | {axn} | {n} | {sim} ({sim / n:.1%}) | "
                         f"{same / n:.2%} ({n - same} differ) | {mf:.3g} ({min(tf):.3g}-"
                         f"{max(tf):.3g}) | {ma:.3g} ({min(ta):.3g}-{max(ta):.3g}) | "
                         f"{ma / mf:.2f} |")
            print(lines[-1], flush=True)
    text = ("# An adaptive map against the full grid (issue 27 section 2)\n\n"
            f"Measured side by side in one run of `benchmarks/adaptive_map.py --grid {args.grid}"
            f" --repeat {args.repeat} --axes {args.axes} --engine {args.engine}`: "
            f"{args.grid} x {args.grid} x 4 cells, the adaptive map's coarse stride "
            f"{stride}, no store, one local worker, process CPU time of the parent and its "
            "worker (median (min-max) of the repeats, interleaved, after an untimed pass of "
            "each) on a machine shared with other processes.\n\n"
            + machine_section(load0) + "\n\n## Maps\n\n"
            + "\n".join(lines) + "\n\nThe fraction simulated is of cells, not of CPU time: "
            "the inferred cells are mostly the cheap ones (at rest, or overturned at once).\n")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = "adaptive_map" + ("" if args.engine == "analytic" else f"_{args.engine}") + (
        "" if args.grid == 100 else f"_{args.grid}") + ".md"
    (out / name).write_text(text)
    print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())

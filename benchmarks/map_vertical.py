"""What a vertical ground motion costs an analytic overturning map.

    python benchmarks/map_vertical.py [--repeat 3] [--grid 12] [--ratio 0.5] [--out DIR]

The compiled grid kernel builds horizontal Ricker pulses inside numba; a map with a vertical
part (``rockbench map --vertical RATIO``) builds each cell's pulse in Python and calls the run
kernel once per cell (``run_pulse_grid(..., vertical_ratio=r)``). Measured here, on the cells
of ``paper-asymmetric`` at GRID x GRID x 4 (the map's default axes A 0.5-8, W 0.5-10, the pulse
window + 10 s, the fall of a cell past its critical angle finished as in every map), in this
process (no worker pool, one thread), process CPU time per cell (``time.process_time``), median
and min-max of ``--repeat`` interleaved passes after an untimed one:

* ``grid kernel, horizontal``: the path of every horizontal map;
* ``run kernel per cell, vertical``: the compiled path of a vertical map;
* ``rb.run per cell, compiled, vertical``: the same integration with a whole Result per cell
  (history, events, the friction demand along the run): what the map path leaves out;
* ``rb.run per cell, solve_ivp, vertical``: the reference path (``--setting
  method=solve_ivp``), on every 8th cell.

Writes ``map_vertical.md`` with the machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from rockbench.studies.maps import _analytic_cells, map_cells  # noqa: E402
from run import machine_section  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--grid", type=int, default=12)
    ap.add_argument("--ratio", type=float, default=0.5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    load0 = os.getloadavg()[0]
    scene = rb.load_scene("paper-asymmetric")
    cells = map_cells(grid=(args.grid, args.grid))
    variants = [("grid kernel, horizontal", cells, "compiled", 0.0),
                ("run kernel per cell, vertical", cells, "compiled", args.ratio),
                ("rb.run per cell, compiled, vertical", cells, "compiled", args.ratio),
                ("rb.run per cell, solve_ivp, vertical", cells[::8], "solve_ivp", args.ratio)]

    def once(i: int):
        _, cs, method, r = variants[i]
        if i == 2:           # a whole Result per cell on the compiled path
            return _per_run(scene, cs, method, r)
        return _analytic_cells(scene, cs, method, None, vertical=r)

    frames = [once(i) for i in range(len(variants))]           # untimed: compilation, imports
    times: list[list[float]] = [[] for _ in variants]
    for _ in range(args.repeat):
        for i in range(len(variants)):
            c = time.process_time()
            frames[i] = once(i)
            times[i].append((time.process_time() - c) / len(variants[i][1]))
    base = statistics.median(times[0])
    lines = ["| path | cells | CPU s / cell, median (min-max) | x grid kernel | overturned | "
             "not ok |", "|---|---|---|---|---|---|"]
    for (label, cs, _, _), ts, df in zip(variants, times, frames):
        m = statistics.median(ts)
        lines.append(f"| {label} | {len(cs)} | {m:.4g} ({min(ts):.3g}-{max(ts):.3g}) | "
                     f"{m / base:.3g} | {int(df['overturned'].astype(bool).sum())} | "
                     f"{int((df['status'] != 'ok').sum())} |")
        print(lines[-1], flush=True)
    same = (frames[1]["overturned"].astype(bool).to_numpy()
            == frames[2]["overturned"].astype(bool).to_numpy()).mean()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = ("# What a vertical ground motion costs an analytic map\n\n"
            f"Measured by `benchmarks/map_vertical.py --repeat {args.repeat} --grid {args.grid} "
            f"--ratio {args.ratio:g}`: `paper-asymmetric`, {args.grid} x {args.grid} x 4 cells "
            "(A 0.5-8, W 0.5-10, the pulse window + 10 s), in one process, process CPU time "
            "per cell, median (min-max) of the interleaved passes after an untimed one. "
            f"The run kernel per cell and rb.run give the same verdict in {100 * same:.1f} % "
            "of the cells.\n\n"
            + machine_section(load0) + "\n\n## Results\n\n" + "\n".join(lines) + "\n")
    (out / "map_vertical.md").write_text(text)
    print(f"wrote {out / 'map_vertical.md'}")
    return 0


def _per_run(scene, cells, method, ratio):
    """Map rows of ``cells``, each one ``rb.run`` of its pulse with the vertical part ``ratio``
    (the analytic backend finishes a fall under way itself, as a map does)."""
    import pandas as pd

    from rockbench.studies.maps import MAP_COLUMNS, map_row

    rows = []
    for shape, sign, A, W in cells:
        pulse = rb.RickerPulse.dimensionless(A, W, scene.structure, shape, sign,
                                             vertical_ratio=ratio)
        rows.append(map_row((shape, sign, A, W),
                            rb.run(scene, pulse, history="minimal", method=method)))
    return pd.DataFrame(rows, columns=list(MAP_COLUMNS))


if __name__ == "__main__":
    raise SystemExit(main())

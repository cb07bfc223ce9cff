"""What a user waits for: ``rockbench map`` (the command, a fresh process) against the floor.

    python benchmarks/map_command.py [--repeat R] [--grid N] [--out DIR]

Measured side by side, repeats interleaved, in process CPU time (user + system, the command's
children included: ``resource.getrusage(RUSAGE_CHILDREN)``):

* the command ``rockbench map paper-symmetric --grid NxN --store TMP --quiet`` (every pulse, a
  fresh store each time): what a user types, start-up, imports, store and all;
* the floor: a minimal compiled solver of the same N x N x 4 cells
  (``benchmarks/analytic_floor.py``: the symmetric frame is exactly a Housner block), in this
  process, compiled before anything is timed.

The ratio command / floor is the price of everything around the physics. Writes
``map_command.md``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def command_cpu(grid: int, workers: int | None = None) -> float:
    """Process CPU [s] of one ``rockbench map`` command (a fresh process and store)."""
    with tempfile.TemporaryDirectory() as tmp:
        argv = [sys.executable, "-m", "rockbench", "map", "paper-symmetric", "--grid",
                f"{grid}x{grid}", "--store", str(Path(tmp) / "m.parquet"), "--quiet"]
        if workers is not None:
            argv += ["--workers", str(workers)]
        c0 = _children_cpu()
        subprocess.run(argv, check=True, capture_output=True, cwd=tmp,
                       env=dict(os.environ, ROCKBENCH_REQUIRE_ENGINES=""))
        return _children_cpu() - c0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--grid", type=int, default=100)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    from analytic_floor import map_cells, run_floor
    from compiled_analytic import machine

    from rockbench.scene.scene import load_scene

    sym = load_scene("paper-symmetric")
    cells = map_cells(args.grid)
    run_floor(sym, cells[:2])                     # compile the floor before timing it
    command_cpu(4)                                # the command's kernels in the JIT cache
    half = [c for c in cells if c[1] == 1]        # what the command computes (mirror_twins)
    floor, floor_half, cmd, cmd1 = [], [], [], []
    for _ in range(args.repeat):
        c0 = time.process_time()
        run_floor(sym, cells)
        floor.append(time.process_time() - c0)
        c0 = time.process_time()
        run_floor(sym, half)
        floor_half.append(time.process_time() - c0)
        cmd.append(command_cpu(args.grid))
        cmd1.append(command_cpu(args.grid, workers=1))
    f = statistics.median(floor)

    def row(name, xs):
        rs = sorted(x / y for x, y in zip(xs, floor))
        return (f"| {name} | {statistics.median(xs):.2f} ({min(xs):.2f}-{max(xs):.2f}, "
                f"n={len(xs)}) | {1e6 * statistics.median(xs) / len(cells):.0f} | "
                f"{statistics.median(xs) / f:.2f} ({rs[0]:.2f}-{rs[-1]:.2f}) |")
    lines = ["# `rockbench map` against the floor", "",
             "Measured side by side in one run of `benchmarks/map_command.py`: process CPU "
             "time (user + system, children included), repeats interleaved, median (min-max, "
             "n).", "", "## Machine", ""] + [f"- {k}: {v}" for k, v in machine().items()] + [
             "", f"## paper-symmetric, {args.grid} x {args.grid} x 4 = {len(cells)} cells", "",
             "| what | CPU s | us per cell | ratio to the floor |", "|:--|--:|--:|--:|",
             row("floor (a minimal compiled solver, in-process)", floor),
             row("floor, the +1 half only (the cells the command computes)", floor_half),
             row("`rockbench map` (default: numba threads on every core)", cmd),
             row("`rockbench map --workers 1`", cmd1), "",
             "The command's CPU includes the interpreter's start-up, the imports, loading the "
             "compiled kernels from the cache, the analytic reference of the scene, the "
             "fall of every cell past its critical angle finished (run longer), and the "
             "Parquet store; the floor is the physics alone. The symmetric frame is its own "
             "mirror image: the command computes the +1 cells and writes each -1 cell as its "
             "mirror (`rockbench.studies.map_cells.mirror_twins`, tested against running both); "
             f"against the floor of that half alone it costs "
             f"{statistics.median(cmd) / statistics.median(floor_half):.2f}x, the price of "
             "the path around the kernel (start-up, imports, kernels' cache, store)."]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "map_command.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""How long the longest allowed run takes (issue 22 §4: the docs' estimate must be measured).

    python benchmarks/longest_run.py [--steps 2e5] [--full-engine pymunk] [--out benchmarks/results]

A run is bounded by ``max_steps`` = 2e7 engine steps and ``max_samples`` = 2e6 history samples
(``rockbench/limits.py``): the longest runs are 2e7 steps of dt = 1e-4 s (2000 s simulated,
samples at 1 ms) or 2e6 steps at the default dt = 1e-3 s (2000 s). For each engine this
measures the process CPU time of one run of ``--steps`` steps at dt = 1e-4 s (free rocking of
``paper-asymmetric`` from 0.3 alpha: the engines step at full cost whether the frame rocks or
rests) and extrapolates to 2e7 steps (stepping is linear in the steps; ``--full-engine``
checks it by running that engine for the whole 2e7 steps); and the analytic reference over
1999 s of a Ricker pulse (``rockbench compare --duration 1999``), which costs what its events
cost, not its length. Writes ``longest_run.md``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import time
from pathlib import Path

import rockbench as rb

ROOT = Path(__file__).resolve().parents[1]


from run import cpu_name  # noqa: E402  (benchmarks/ is on sys.path when run)

_cpu_name = cpu_name   # one reader of the processor's name: benchmarks/run.py


def engine_run(scene, engine: str, steps: int, dt: float = 1e-4) -> tuple[float, rb.Result]:
    """CPU seconds of one free-rocking run of ``steps`` steps of ``dt`` (after a warm-up run
    that pays the one-off costs: imports, JIT)."""
    rb.run(scene, None, engine=engine, phi0=0.3 * scene.alpha, duration=0.05, dt=dt)
    c0 = time.process_time()
    r = rb.run(scene, None, engine=engine, phi0=0.3 * scene.alpha, duration=steps * dt, dt=dt)
    return time.process_time() - c0, r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=float, default=2e5)
    ap.add_argument("--full-engine", default=None, help="also run this engine for 2e7 steps")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args()
    steps = int(args.steps)
    scene = rb.load_scene("paper-asymmetric")
    rows = []
    for engine in [e for e in rb.available_backends() if e != "analytic"]:
        cpu, r = engine_run(scene, engine, steps)
        per = cpu / steps          # per step of dt (an engine may sub-step: r.cost.steps)
        rows.append((engine, r.cost.steps, cpu, per, per * 2e7, r.summary.status))
        print(rows[-1], flush=True)
    full = None
    if args.full_engine:
        cpu, r = engine_run(scene, args.full_engine, int(2e7))
        full = (args.full_engine, r.cost.steps, cpu, r.summary.status)
        print(full, flush=True)
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure)
    c0 = time.process_time()
    ref = rb.run(scene, pulse, duration=1999.0)
    analytic = time.process_time() - c0

    lines = ["# The longest allowed run", "",
             f"`python benchmarks/longest_run.py --steps {args.steps:g}"
             f"{' --full-engine ' + args.full_engine if args.full_engine else ''}` on "
             f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC; {_cpu_name()}, "
             f"{os.cpu_count()} cores shared with other jobs; process CPU time, one run each "
             "(after a warm-up run).", "",
             "Free rocking of paper-asymmetric from 0.3 alpha at dt = 1e-4 s; the limit "
             "`max_steps` = 2e7 steps (2000 s at dt = 1e-4 s).", "",
             "| engine | engine steps run | CPU [s] | CPU per step of dt [us] | 2e7 steps [min] | "
             "status |",
             "|---|---|---|---|---|---|"]
    for engine, n, cpu, per, total, status in rows:
        lines.append(f"| {engine} | {n} | {cpu:.2f} | {per * 1e6:.2f} | {total / 60:.1f} | "
                     f"{status} |")
    if full:
        lines += ["", f"Measured in full: {full[0]}, {full[1]} steps: {full[2]:.1f} s CPU "
                  f"({full[2] / 60:.1f} min), status {full[3]}."]
    lines += ["", f"The analytic reference over 1999 s of a Ricker pulse (A = 3, W = 4): "
              f"{analytic:.2f} s CPU ({ref.cost.steps} integrator steps, status "
              f"{ref.summary.status})."]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "longest_run.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""What rockbench's harness costs next to the engines it measures (issue 12), side by side in one run.

    python benchmarks/loop_overhead.py [--repeat 5] [--out benchmarks/results]

For each engine and case, in process CPU time (``time.process_time``, so another process's load
does not enter) per simulated second, median of ``--repeat`` runs with min-max spread:

* ``raw``: the engine's own stepping - the adapter built once, then a bare loop over its step
  call with the ground motion's gravity precomputed (no state read, no devices, no sampling);
* ``rockbench``: the whole ``rb.run`` (building, stepping, devices, sampling, diagnostics, the
  Result);
* ``ratio`` = rockbench / raw.

Plus MuJoCo plain stepping against the batched ``mujoco.rollout`` path per map cell, and the
analytic run with full and minimal history. Writes ``loop_overhead.md`` with the machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from rockbench.engines import get_backend  # noqa: E402
from rockbench.engines.base import run_window  # noqa: E402
from run import machine  # noqa: E402


def cpu(fn, repeat: int) -> tuple[float, float, float]:
    """(median, min, max) process CPU seconds of ``fn()`` over ``repeat`` calls."""
    xs = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        xs.append(time.process_time() - c)
    return statistics.median(xs), min(xs), max(xs)


def raw_stepping(engine: str, scene, motion, duration: float):
    """A function stepping the engine bare over the run window (gravity precomputed)."""
    cls = get_backend(engine)

    def go():
        b = cls(scene)
        t0, t_end = run_window(scene, motion, duration, 0.0)
        dt = b.settings.dt
        n = int(round((t_end - t0) / dt))
        t = t0 + dt * (np.arange(n) + 0.5)
        gx = (-np.asarray(motion.acceleration(t), dtype=float)).tolist()
        b.build(0.0)
        step = b._step
        for g in gx:
            step(g, ())
        b._close()
    return go


def cases():
    asym = rb.load_scene("paper-asymmetric")
    hyb = rb.load_scene("paper-asymmetric-hybrid")
    p1 = rb.RickerPulse.dimensionless(2.0, 3.0, asym.structure, "symmetric", 1)
    p2 = rb.RickerPulse.dimensionless(4.0, 3.0, hyb.structure, "antisymmetric", -1)
    return [("free-standing frame, sym. Ricker A=2 W=3", asym, p1, p1.t_end - p1.t_start + 5.0),
            ("hybrid frame, antisym. Ricker A=4 W=3", hyb, p2, p2.t_end - p2.t_start + 5.0)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    engines = [e for e in rb.available_backends() if e != "analytic"]
    lines = ["| case | engine | raw CPU s / sim s | rockbench CPU s / sim s | ratio | raw RTF | "
             "rockbench RTF |", "|---|---|---|---|---|---|---|"]
    for label, scene, motion, duration in cases():
        for eng in engines:
            raw = cpu(raw_stepping(eng, scene, motion, duration), args.repeat)
            whole = cpu(lambda: rb.run(scene, motion, engine=eng, duration=duration),
                        args.repeat)
            r, w = raw[0] / duration, whole[0] / duration
            lines.append(f"| {label} | {eng} | {r:.4g} ({raw[1] / duration:.3g}-"
                         f"{raw[2] / duration:.3g}) | {w:.4g} ({whole[1] / duration:.3g}-"
                         f"{whole[2] / duration:.3g}) | {w / r:.3g} | {1 / r:.4g} | "
                         f"{1 / w:.4g} |")
            print(lines[-1], flush=True)
    # MuJoCo: plain stepping against the batched rollout path, per map cell
    if "mujoco" in engines:
        from rockbench.engines.mujoco import run_batch

        sc = rb.load_scene("paper-asymmetric")
        chunk = [rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)
                 for A in (2.0, 3.0, 4.0, 6.0) for W in (3.0, 5.0)
                 for shape, sign in (("symmetric", 1), ("antisymmetric", -1))]
        lines += ["", f"MuJoCo on a map chunk ({len(chunk)} cells of paper-asymmetric, pulse "
                      "window + 10 s each): process CPU s per cell and wall s per cell",
                  "", "| path | CPU s / cell | wall s / cell | speed-up (CPU) | speed-up (wall) |",
                  "|---|---|---|---|---|"]
        n = len(chunk)

        def timed(fn):
            w = time.perf_counter()
            c = cpu(fn, max(1, args.repeat // 2))
            return c, (time.perf_counter() - w) / max(1, args.repeat // 2)

        plain = timed(lambda: [rb.run(sc, m, engine="mujoco") for m in chunk])
        rows = [("plain stepping (rb.run per cell)", plain)]
        for nt in (1, 2):
            rows.append((f"batched, mujoco.rollout, {nt} thread{'s' if nt > 1 else ''}",
                         timed(lambda nt=nt: run_batch(sc, chunk, nthread=nt))))
        for name, (c, w) in rows:
            lines.append(f"| {name} | {c[0] / n:.4g} ({c[1] / n:.3g}-{c[2] / n:.3g}) | "
                         f"{w / n:.4g} | {plain[0][0] / c[0]:.3g} | {plain[1] / w:.3g} |")
            print(lines[-1], flush=True)

    # analytic: full vs minimal history
    lines += ["", "| case | analytic history | CPU s / sim s | RTF |", "|---|---|---|---|"]
    for label, scene, motion, duration in cases():
        for hist in ("full", "minimal"):
            c = cpu(lambda: rb.run(scene, motion, duration=duration, history=hist),
                    args.repeat)
            lines.append(f"| {label} | {hist} | {c[0] / duration:.4g} ({c[1] / duration:.3g}-"
                         f"{c[2] / duration:.3g}) | {duration / c[0]:.4g} |")
            print(lines[-1], flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    mc = machine()
    text = ("# Harness overhead (issue 12)\n\nMeasured side by side in one run of "
            f"`benchmarks/loop_overhead.py --repeat {args.repeat}`: process CPU time per "
            "simulated second, median (min-max) of the repeats; RTF = real-time factor "
            "(simulated s per CPU s).\n\n## Machine\n\n"
            + "\n".join(f"- {k}: {v}" for k, v in mc.items()) + "\n\n" + "\n".join(lines) + "\n")
    (out / "loop_overhead.md").write_text(text)
    print(f"wrote {out / 'loop_overhead.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

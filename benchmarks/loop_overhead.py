"""What rockbench's harness costs next to the engines it measures (issue 12), side by side in one run.

    python benchmarks/loop_overhead.py [--repeat 5] [--out benchmarks/results]

For each engine and case, in process CPU time (``time.process_time``, so another process's load
does not enter) per simulated second, median of ``--repeat`` runs with min-max spread:

* ``raw``: the engine's own stepping - the adapter built once, then a bare Python loop over its
  step call with the ground motion's gravity precomputed (no state read, no devices, no
  sampling);
* ``raw C`` (pymunk, MuJoCo): the same bare loop compiled (numba, the engine's C step function
  called by address): what the engine itself costs, without any Python per step;
* ``rockbench``: the whole ``rb.run`` (building, stepping, devices, sampling, diagnostics, the
  Result) at its defaults (pymunk and MuJoCo: the compiled loop), and ``rockbench, Python
  loop`` (``loop="python"``);
* ``ratio`` = rockbench / raw, and rockbench / raw C.

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
    """(median, min, max) process CPU seconds of ``fn()`` over ``repeat`` calls, after one
    untimed call (numba compilation or cache loading, imports)."""
    fn()
    xs = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        xs.append(time.process_time() - c)
    return statistics.median(xs), min(xs), max(xs)


def _built(engine: str, scene, motion, duration: float):
    """The engine's world built at rest and the ground motion's gravity at every step's
    midpoint over the run window (as the loop computes it)."""
    b = get_backend(engine)(scene)
    t0, t_end = run_window(scene, motion, duration, 0.0)
    dt = b.settings.dt
    n = int(round((t_end - t0) / dt))
    gx = -np.asarray(motion.acceleration(t0 + dt * (np.arange(n) + 0.5)), dtype=float)
    b.build(0.0)
    return b, gx


def raw_stepping(engine: str, scene, motion, duration: float):
    """A function stepping the engine bare over the run window (gravity precomputed)."""
    def go():
        b, gx = _built(engine, scene, motion, duration)
        step = b._step
        for g in gx.tolist():
            step(g, ())
        b._close()
    return go


def raw_c_stepping(engine: str, scene, motion, duration: float):
    """The bare loop of :func:`raw_stepping` compiled: gravity and step, by address."""
    from numba import njit

    from rockbench.engines.compiled_loop import _call_pd, _call_pdd, _call_pp

    @njit
    def chipmunk(fp, space, gx, g, dt):
        for k in range(gx.shape[0]):
            _call_pdd(fp[0], space, gx[k], -g)
            _call_pd(fp[1], space, dt)

    @njit
    def mujoco(step, model, data, gravity, gx):
        for k in range(gx.shape[0]):
            gravity[0] = gx[k]
            _call_pp(step, model, data)

    def go():
        b, gx = _built(engine, scene, motion, duration)
        dt = b.settings.dt
        if engine == "pymunk":
            from rockbench.engines.chipmunk import engine as eng_of
            eng = eng_of(b._cspace, b._cbodies)
            chipmunk(eng[0], eng[1][0], gx, 9.81, dt)
        else:
            from rockbench.engines.mujoco import _mj_step_address
            mujoco(np.uint64(_mj_step_address()), np.uint64(b.model._address),
                   np.uint64(b.data._address), b.model.opt.gravity, gx)
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
    lines = ["| case | engine | raw CPU s / sim s | raw C CPU s / sim s | rockbench CPU s / "
             "sim s | ratio to raw | ratio to raw C | rockbench, Python loop | raw RTF | "
             "rockbench RTF |", "|---|---|---|---|---|---|---|---|---|---|"]
    fmt = lambda c, d: f"{c[0] / d:.4g} ({c[1] / d:.3g}-{c[2] / d:.3g})"  # noqa: E731
    for label, scene, motion, duration in cases():
        for eng in engines:
            compiled = eng in ("pymunk", "mujoco")
            raw = cpu(raw_stepping(eng, scene, motion, duration), args.repeat)
            rawc = (cpu(raw_c_stepping(eng, scene, motion, duration), args.repeat)
                    if compiled else None)
            whole = cpu(lambda: rb.run(scene, motion, engine=eng, duration=duration),
                        args.repeat)
            plain = (cpu(lambda: rb.run(scene, motion, engine=eng, duration=duration,
                                        loop="python"), args.repeat) if compiled else None)
            r, w = raw[0] / duration, whole[0] / duration
            lines.append(
                f"| {label} | {eng} | {fmt(raw, duration)} | "
                f"{fmt(rawc, duration) if rawc else '-'} | {fmt(whole, duration)} | "
                f"{w / r:.3g} | {whole[0] / rawc[0]:.3g} | " if rawc else
                f"| {label} | {eng} | {fmt(raw, duration)} | - | {fmt(whole, duration)} | "
                f"{w / r:.3g} | - | ")
            lines[-1] += (f"{fmt(plain, duration)} | " if plain else "- | ") + \
                f"{1 / r:.4g} | {1 / w:.4g} |"
            print(lines[-1], flush=True)
    # MuJoCo: plain stepping against the batched rollout path, per map cell
    if "mujoco" in engines:
        from rockbench.engines.mujoco_batch import run_batch

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
            """((median, min, max) CPU s, median wall s) over the repeats, after a warm-up."""
            fn()
            cs, ws = [], []
            for _ in range(max(1, args.repeat // 2)):
                w, c = time.perf_counter(), time.process_time()
                fn()
                cs.append(time.process_time() - c)
                ws.append(time.perf_counter() - w)
            return (statistics.median(cs), min(cs), max(cs)), statistics.median(ws)

        plain = timed(lambda: [rb.run(sc, m, engine="mujoco", loop="python") for m in chunk])
        rows = [("plain stepping, Python loop (rb.run per cell, loop='python')", plain),
                ("plain stepping, compiled loop (rb.run per cell, the default)",
                 timed(lambda: [rb.run(sc, m, engine="mujoco") for m in chunk]))]
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

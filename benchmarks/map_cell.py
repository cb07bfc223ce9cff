"""What one engine map cell costs next to the engine's own stepping of it (issue 27 section 3),
before and after the map path, side by side in one run.

    python benchmarks/map_cell.py [--repeat 5] [--out benchmarks/results]

Cells: a chunk of map cells of ``paper-asymmetric`` (A x W x pulse, each run as a map runs it:
from rest over the pulse window + 10 s, the sweep's case, ``rockbench.sweep.run_case``). For each
engine (pymunk, MuJoCo), process CPU time (``time.process_time``) of the whole chunk, per cell,
median of ``--repeat`` passes with min-max spread, after one untimed pass:

* ``raw C``: the engine's own stepping of each cell - its world built, then its C step function
  called by address in a compiled loop (``benchmarks/loop_overhead.py``), gravity precomputed,
  for exactly the steps rockbench took in that cell (a cell that overturned stops there);
* ``before``: the path maps took before issue 27 - ``run_case`` with the full Result (history,
  events and measurement frames) and the scene loaded again for every cell; MuJoCo also
  batched in ``mujoco.rollout`` running every case to the end of its window
  (``VERDICT_CHUNK`` set beyond the window);
* ``after``: the map path - ``keep="summary"`` (``rockbench.engines.loop.finish``: no history
  or events frames; impacts counted, their eta measured only where a verdict needs it; the
  compiled loop back in Python every ``DRIVE_CHUNKS`` probe chunks), the scene loaded once per
  process; MuJoCo batched (one thread, stopped at the verdict) and plain (the compiled loop).

``ratio`` = the path's CPU time / raw C. Writes ``map_cell.md`` with the machine and its load
average (1 min) before and after the measurement.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from loop_overhead import _built  # noqa: E402
from rockbench.engines import mujoco as M  # noqa: E402
from rockbench.engines import mujoco_batch as MB  # noqa: E402
from rockbench.engines.base import run_window  # noqa: E402
from rockbench.sweep import runs  # noqa: E402
from rockbench.sweep.cases import normalize_case  # noqa: E402
from run import machine_section  # noqa: E402

SCENE = "paper-asymmetric"


def cells(engine: str) -> list[dict]:
    """Normalized sweep cases of a map chunk: A in (1.5, 3, 6), W in (3, 6), two pulses."""
    return [normalize_case({"scene": SCENE, "engine": engine, "motion": {
        "kind": "ricker", "shape": shape, "sign": sign, "A": A, "W": W}})
        for A in (1.5, 3.0, 6.0) for W in (3.0, 6.0)
        for shape, sign in (("symmetric", 1), ("antisymmetric", -1))]


def passes(fn, repeat: int) -> tuple[float, float, float]:
    """(median, min, max) process CPU seconds of ``fn()`` over ``repeat`` calls, after one
    untimed call (numba cache loading, imports)."""
    fn()
    xs = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        xs.append(time.process_time() - c)
    return statistics.median(xs), min(xs), max(xs)


def raw_c(engine: str, cases: list[dict], steps: list[int]):
    """The engine's own stepping of each cell for ``steps`` steps (compiled, by address)."""
    from numba import njit

    from rockbench.engines.compiled_loop import _call_pd, _call_pdd, _call_pp
    from rockbench.scene.motion import motion_from_spec

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

    scene = rb.load_scene(SCENE)
    motions = [motion_from_spec(c["motion"], scene.structure) for c in cases]

    def go():
        for mo, n in zip(motions, steps):
            b, gx = _built(engine, scene, mo, None)
            gx = np.ascontiguousarray(gx[:n])
            if engine == "pymunk":
                from rockbench.engines.chipmunk import engine as eng_of
                eng = eng_of(b._cspace, b._cbodies)
                chipmunk(eng[0], eng[1][0], gx, 9.81, b.settings.dt)
            else:
                mujoco(np.uint64(M._mj_step_address()), np.uint64(b.model._address),
                       np.uint64(b.data._address), b.model.opt.gravity, gx)
            b._close()
    return go


def before_plain(cases):
    def go():
        for c in cases:
            runs._SCENES.clear()              # the scene loaded for every cell, as before
            runs.run_case(c)
    return go


def after_plain(cases):
    def go():
        for c in cases:
            runs.run_case(c, keep="summary")
    return go


def batched(cases, keep: str, stop: bool):
    def go():
        saved = MB.VERDICT_CHUNK
        if not stop:                          # one rollout call to the end of the window
            MB.VERDICT_CHUNK = 10 ** 9
            runs._SCENES.clear()
        try:
            runs.run_batch_cases(cases, nthread=1, keep=keep)
        finally:
            MB.VERDICT_CHUNK = saved
    return go


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    have = rb.available_backends()
    load0 = os.getloadavg()[0]
    n = len(cells("pymunk"))
    lines = [f"{n} cells of `{SCENE}` (A in 1.5, 3, 6; W in 3, 6; symmetric+ and "
             "antisymmetric-; pulse window + 10 s): process CPU s per cell, median (min-max) "
             f"of {args.repeat} passes over the chunk.", "",
             "| engine | path | CPU s / cell | ratio to raw C |", "|---|---|---|---|"]
    checks = []
    for engine in ("pymunk", "mujoco"):
        if engine not in have:
            lines.append(f"| {engine} | not installed here | - | - |")
            continue
        cases = cells(engine)
        full = [runs.run_case(c) for c in cases]
        light = [runs.run_case(c, keep="summary") for c in cases]
        same = sum(all(a[k] == b[k] or (a[k] != a[k] and b[k] != b[k])
                       for k in ("status", "overturned", "max_abs_phi_over_alpha", "n_impacts",
                                 "fractured", "exceeded_critical")) for a, b in zip(full, light))
        steps = [int(r["steps"]) for r in full]
        window = sum(int(np.ceil(np.diff(run_window(
            rb.load_scene(SCENE), rb.RickerPulse.dimensionless(
                c["motion"]["A"], c["motion"]["W"], rb.load_scene(SCENE).structure,
                c["motion"]["shape"], c["motion"]["sign"]), None, 0.0))[0] / 1e-3 - 1e-9))
            for c in cases)
        checks.append(f"- {engine}: {same}/{n} cells with the same map fields (status, "
                      f"verdict, peak, impacts, fracture, exceeded) on both paths; "
                      f"{sum(r['overturned'] for r in full)} overturned; steps taken "
                      f"{sum(steps)} of {window} in the windows at dt = 1 ms")
        raw = passes(raw_c(engine, cases, steps), args.repeat)
        rows = [("raw C (the engine's own stepping)", raw),
                ("before: run_case, full Result, scene per cell", passes(before_plain(cases),
                                                                         args.repeat)),
                ("after: run_case, keep='summary'", passes(after_plain(cases), args.repeat))]
        if engine == "mujoco":
            rows += [("before: batched rollout to the window's end, full Result",
                      passes(batched(cases, "all", False), args.repeat)),
                     ("after: batched rollout stopped at the verdict, keep='summary'",
                      passes(batched(cases, "summary", True), args.repeat))]
        for name, (med, lo, hi) in rows:
            lines.append(f"| {engine} | {name} | {med / n:.4g} ({lo / n:.3g}-{hi / n:.3g}) | "
                         f"{med / raw[0]:.3g} |")
            print(lines[-1], flush=True)
    text = ("# A map cell against the engine's own stepping (issue 27 section 3)\n\n"
            f"Measured side by side in one run of `benchmarks/map_cell.py --repeat "
            f"{args.repeat}` on a machine shared with other processes (process CPU time, so "
            "their load enters only through caches and frequency).\n\n"
            + machine_section(load0) + "\n\n## Cells\n\n"
            + "\n".join(lines) + "\n\n## Checks\n\n" + "\n".join(checks) + "\n")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "map_cell.md").write_text(text)
    print("\n".join(checks))
    print(f"wrote {out / 'map_cell.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

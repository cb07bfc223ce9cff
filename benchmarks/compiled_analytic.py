"""The compiled analytic path against the ``solve_ivp`` reference, measured side by side in one run.

    python benchmarks/compiled_analytic.py [--quick] [--out benchmarks/results]

Measures, in process CPU time (``time.process_time()``; medians of repeats with min-max spread):

1. cells per second of both analytic paths on one chunk of the paper-asymmetric map (200 cells
   drawn with a fixed seed from the 100 x 100 x 4 grid below), reference = ``simulate`` with a
   minimal history per cell, compiled = :func:`rockbench.analytic.compiled.run_pulse_grid`;
2. the full 100 x 100 x 4 map of paper-asymmetric (A = a_g/(g tan alpha) in 0.5..8, W =
   omega_g/p in 0.5..10, symmetric and antisymmetric pulses of both signs, durations = pulse + 10
   s) with the compiled path on 1 process, on 2 processes (multiprocessing, one chunk each) and
   on 2 threads (``numba.prange``): wall time and CPU time (all processes / threads);
3. the real-time factor (simulated s / CPU s of the whole call) of both paths on El Centro 1940
   (``rockbench/records/IV1940_ElCentro_180.AT2``, else ``/work/shared/records/``) for
   paper-asymmetric and
   paper-asymmetric-hybrid-eps1.

Writes ``compiled_analytic.md`` with the machine. The numba compilation (or cache load) is timed
once and excluded from every other figure.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from rockbench.analytic.compiled import run_pulse_grid, simulate_compiled
from rockbench.analytic.solver import AnalyticSettings, simulate
from rockbench.scene.motion import RickerPulse
from rockbench.scene.scene import load_scene

_PACKAGED = (Path(__file__).resolve().parents[1] / "rockbench" / "records"
             / "IV1940_ElCentro_180.AT2")
RECORD = _PACKAGED if _PACKAGED.exists() else Path("/work/shared/records/IV1940_ElCentro_180.AT2")


def machine() -> dict:
    import llvmlite
    import numba
    import scipy

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from run import machine as common

    out = common()
    out.update({"cores available": len(os.sched_getaffinity(0)), "numpy": np.__version__,
                "scipy": scipy.__version__, "numba": numba.__version__,
                "llvmlite": llvmlite.__version__, "numba threading layer": _threading_layer(),
                "load average (1, 5, 15 min) at the end":
                    ", ".join(f"{x:.1f}" for x in os.getloadavg())})
    return out


def _threading_layer() -> str:
    try:
        import numba
        return numba.threading_layer()
    except Exception:  # noqa: BLE001 - not initialised until a parallel kernel ran
        return "not initialised"


def full_map_cells(n: int = 100):
    return [(shape, sign, float(A), float(W)) for shape in ("symmetric", "antisymmetric")
            for sign in (1, -1) for A in np.linspace(0.5, 8.0, n)
            for W in np.linspace(0.5, 10.0, n)]


def stats(xs):
    return statistics.median(xs), min(xs), max(xs)


def fmt(xs, unit="", digits=4):
    m, lo, hi = stats(xs)
    return f"{m:.{digits}g}{unit} ({lo:.{digits}g}-{hi:.{digits}g}, n={len(xs)})"


# --- 1. one chunk --------------------------------------------------------------------------------
def chunk_rate(scene, cells, repeat_ref, repeat_fast):
    minimal = AnalyticSettings(history="minimal")
    ref_rates = []
    for _ in range(repeat_ref):
        c0 = time.process_time()
        for shape, sign, A, W in cells:
            simulate(scene, RickerPulse.dimensionless(A, W, scene.structure, shape, sign),
                     settings=minimal)
        ref_rates.append(len(cells) / (time.process_time() - c0))
    fast_rates, drop_rates = [], []
    for _ in range(repeat_fast):
        c0 = time.process_time()
        run_pulse_grid(scene, cells)
        fast_rates.append(len(cells) / (time.process_time() - c0))
        c0 = time.process_time()
        for shape, sign, A, W in cells:
            simulate_compiled(scene, RickerPulse.dimensionless(A, W, scene.structure, shape, sign),
                              settings=minimal)
        drop_rates.append(len(cells) / (time.process_time() - c0))
    return ref_rates, fast_rates, drop_rates


# --- 1b. every engine on one chunk of the report's engine map -----------------------------------
def engine_chunk_lines(quick: bool) -> list[str]:
    """Cells per CPU second of each backend at its default settings on 16 cells of the
    report's engine map (paper-asymmetric, A 1..8, W 1..10, pulse window + 3 s), through the
    path maps use (:func:`rockbench.studies.maps._engine_rows`: MuJoCo batched in rollout), in this
    process; the analytic model's compiled path on the same cells for scale."""
    import rockbench as rb
    from rockbench.campaign.maps import engine_axes
    ENGINE_AXES = engine_axes()
    from rockbench.studies.maps import _engine_rows, map_cells

    cells = map_cells(grid=(12, 12), amplitude=ENGINE_AXES["amplitude"],
                      frequency=ENGINE_AXES["frequency"])
    rng = np.random.default_rng(5)
    chunk = [cells[i] for i in rng.choice(len(cells), 4 if quick else 16, replace=False)]
    out = [f"## Every backend on one chunk of the report's engine map ({len(chunk)} cells)", "",
           "paper-asymmetric, cells drawn (seed 5) from the 12 x 12 x 4 grid of the report's "
           "engine maps (A 1..8, W 1..10, pulse window + 3 s), default settings, one process, "
           "the path `rockbench map` uses (MuJoCo batched in `mujoco.rollout`); process CPU "
           "time, after one untimed pass.", "",
           "| backend | cells per CPU second | CPU s per cell |", "|:--|--:|--:|"]
    for eng in rb.available_backends():
        if eng == "analytic":
            def go():
                scene = load_scene("paper-asymmetric")
                by_w = {}
                for c in chunk:
                    by_w.setdefault(c[3], []).append(c)
                from rockbench.studies.maps import _duration
                for w, cs in by_w.items():
                    run_pulse_grid(scene, cs, duration=_duration(scene, w, ENGINE_AXES["tail"]))
        else:
            def go(eng=eng):
                _engine_rows("paper-asymmetric", None, eng, {}, chunk, ENGINE_AXES["tail"],
                             executor="serial", progress=False)
        go()
        rates = []
        for _ in range(1 if quick or eng in ("pybullet", "opensees") else 3):
            c0 = time.process_time()
            go()
            rates.append(len(chunk) / (time.process_time() - c0))
        out.append(f"| {eng} | {fmt(rates)} | {1 / stats(rates)[0]:.3g} |")
        print(out[-1], flush=True)
    return out + [""]


# --- 2. the full map -----------------------------------------------------------------------------
def _worker(args):
    name, cells = args
    scene = load_scene(name)
    run_pulse_grid(scene, cells[:1])            # compiled code from the cache, outside the timing
    c0 = time.process_time()
    df = run_pulse_grid(scene, cells)
    return time.process_time() - c0, int(df["overturned"].sum()), int((df["status"] != "ok").sum())


def full_map(name, cells, repeat, pool):
    scene = load_scene(name)
    out = {"1 process": ([], []), "2 processes": ([], []), "2 threads (prange)": ([], [])}
    counts = {}
    for _ in range(repeat):
        # 1 process
        w0, c0 = time.perf_counter(), time.process_time()
        df = run_pulse_grid(scene, cells)
        out["1 process"][0].append(time.perf_counter() - w0)
        out["1 process"][1].append(time.process_time() - c0)
        counts["1 process"] = (int(df["overturned"].sum()), int((df["status"] != "ok").sum()))
        # 2 processes: interleaved halves (equal work), workers already started and warm
        halves = [cells[0::2], cells[1::2]]
        w0 = time.perf_counter()
        res = pool.map(_worker, [(name, h) for h in halves])
        out["2 processes"][0].append(time.perf_counter() - w0)
        out["2 processes"][1].append(sum(r[0] for r in res))
        counts["2 processes"] = (sum(r[1] for r in res), sum(r[2] for r in res))
        # 2 threads
        w0, c0 = time.perf_counter(), time.process_time()
        df = run_pulse_grid(scene, cells, parallel=True)
        out["2 threads (prange)"][0].append(time.perf_counter() - w0)
        out["2 threads (prange)"][1].append(time.process_time() - c0)
        counts["2 threads (prange)"] = (int(df["overturned"].sum()),
                                        int((df["status"] != "ok").sum()))
    return out, counts


# --- 3. records ----------------------------------------------------------------------------------
def record_rtf(name, rec, repeat_ref, repeat_fast):
    scene = load_scene(name)
    ref_rtf, fast_rtf, fast_int = [], [], []
    n_imp, peak = {}, {}
    for _ in range(repeat_ref):
        c0 = time.process_time()
        r = simulate(scene, rec, settings=AnalyticSettings(method="DOP853"))
        ref_rtf.append(r.cost.sim_time / (time.process_time() - c0))
        n_imp["reference"] = r.summary.n_impacts
        peak["reference"] = r.summary.max_abs_phi_over_alpha
    for _ in range(repeat_fast):
        c0 = time.process_time()
        r = simulate_compiled(scene, rec)
        fast_rtf.append(r.cost.sim_time / (time.process_time() - c0))
        fast_int.append(r.cost.real_time_factor)
        n_imp["compiled"] = r.summary.n_impacts
        peak["compiled"] = r.summary.max_abs_phi_over_alpha
    return ref_rtf, fast_rtf, fast_int, n_imp, peak, r.cost.sim_time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, one repeat (smoke test)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    quick = args.quick
    lines = ["# Compiled analytic path vs the solve_ivp reference", "",
             "Measured side by side in one run of `benchmarks/compiled_analytic.py`"
             + (" (--quick)" if quick else "") + ". Process CPU time (`time.process_time()`); "
             "median (min-max, n repeats).", ""]

    # compilation / cache load, once
    scene = load_scene("paper-asymmetric")
    t0 = time.perf_counter()
    run_pulse_grid(scene, [("symmetric", 1, 3.0, 3.0)])
    run_pulse_grid(scene, [("symmetric", 1, 3.0, 3.0)], parallel=True)
    simulate_compiled(scene, RickerPulse.dimensionless(3.0, 3.0, scene.structure))
    warm = time.perf_counter() - t0

    lines += ["## Machine", ""] + [f"- {k}: {v}" for k, v in machine().items()] + [
        f"- numba compilation or cache load (first calls, excluded below): {warm:.2f} s wall",
        "- the 2 cores are shared with other sessions: CPU times are the robust figures, wall "
        "times depend on the load", ""]

    # 1. chunk
    n_map = 20 if quick else 100
    cells = full_map_cells(n_map)
    rng = np.random.default_rng(11)
    chunk = [cells[i] for i in rng.choice(len(cells), 40 if quick else 200, replace=False)]
    ref_r, fast_r, drop_r = chunk_rate(scene, chunk, 1 if quick else 3, 1 if quick else 5)
    lines += ["## One map chunk (paper-asymmetric)", "",
              f"{len(chunk)} cells drawn (seed 11) from the {n_map} x {n_map} x 4 grid "
              "(A 0.5..8, W 0.5..10, both shapes and signs), default durations (pulse + 10 s), "
              "1 process.", "",
              "| path | cells per CPU second | ms per cell |", "|:--|--:|--:|",
              f"| reference (`simulate`, minimal history) | {fmt(ref_r)} | "
              f"{1e3 / stats(ref_r)[0]:.3g} |",
              f"| compiled, drop-in (`simulate_compiled`, minimal history) | {fmt(drop_r)} | "
              f"{1e3 / stats(drop_r)[0]:.3g} |",
              f"| compiled, batch (`run_pulse_grid`) | {fmt(fast_r)} | "
              f"{1e3 / stats(fast_r)[0]:.3g} |",
              "", f"Speed-up of the batch path over the reference: "
              f"{stats(fast_r)[0] / stats(ref_r)[0]:.0f} x.", ""]

    # 1b. every engine on one chunk of the report's engine map
    lines += engine_chunk_lines(quick)

    # 2. full map
    ctx = mp.get_context("spawn")
    with ctx.Pool(2) as pool:
        pool.map(_worker, [("paper-asymmetric", cells[:1])] * 2)     # start + warm the workers
        res, counts = full_map("paper-asymmetric", cells, 1 if quick else 3, pool)
    lines += [f"## Full {n_map} x {n_map} x 4 map of paper-asymmetric ({len(cells)} cells), "
              "compiled path", "",
              "CPU = all processes or threads of the run (workers report their own process CPU "
              "time).", "",
              "| run | wall s | CPU s | CPU ms per cell | overturned cells | not ok |",
              "|:--|--:|--:|--:|--:|--:|"]
    for k, (walls, cpus) in res.items():
        lines.append(f"| {k} | {fmt(walls)} | {fmt(cpus)} | "
                     f"{1e3 * stats(cpus)[0] / len(cells):.3g} | {counts[k][0]} | {counts[k][1]} |")
    cpu2 = stats(res["2 processes"][1])[0]
    lines += ["", f"On 2 idle cores the 2-process run would take about CPU / 2 = {cpu2 / 2:.1f} s "
              "of wall time; a wall time far above that means the cores were shared (see the "
              "load average above).", ""]

    # 3. records
    if RECORD.exists():
        from rockbench.scene.records import load_record
        rec = load_record(RECORD)
        lines += ["## El Centro 1940 (IV1940_ElCentro_180), real-time factor", "",
                  "Simulated seconds per CPU second of the whole call (history at 1 ms, full "
                  "columns, events); `integration only` = `Cost.real_time_factor` "
                  "(sim_time / wall_s of the integration).", "",
                  "| scene | sim s | \\|peak difference\\| / alpha | impacts (ref / compiled)* | "
                  "reference | compiled | compiled, integration only | speed-up |",
                  "|:--|--:|--:|--:|--:|--:|--:|--:|"]
        for name in ("paper-asymmetric", "paper-asymmetric-hybrid-eps1"):
            ref_rtf, fast_rtf, fast_int, n_imp, peak, sim = record_rtf(name, rec, 1,
                                                                       1 if quick else 5)
            lines.append(f"| {name} | {sim:.2f} | "
                         f"{abs(peak['reference'] - peak['compiled']):.1e} | "
                         f"{n_imp['reference']} / {n_imp['compiled']} | "
                         f"{fmt(ref_rtf, digits=3)} | {fmt(fast_rtf, digits=3)} | "
                         f"{fmt(fast_int, digits=3)} | "
                         f"{stats(fast_rtf)[0] / stats(ref_rtf)[0]:.0f} x |")
        lines += ["", "The reference is run once per scene (about a minute of CPU each).",
                  "* The impact count of a 40-s record is chaotic: the two paths round "
                  "differently and a 1-ulp change of the record moves it (241 -> 251 on "
                  "paper-asymmetric); it differs between CPUs and BLAS kernels and is never "
                  "compared (docs/reproducibility.md, benchmarks/analytic_divergence.py).", ""]
    else:
        lines += [f"Record {RECORD} not found: records benchmark skipped.", ""]

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "compiled_analytic.md"
    path.write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"\nwritten to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

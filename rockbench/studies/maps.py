"""Overturning maps (the paper's Figs. 4-7) for any backend: grids of Ricker pulses, a resumable
Parquet store.

A map is one row per cell (:data:`MAP_COLUMNS`): the pulse (``pulse`` shape, ``sign``) at
``amplitude`` A = a_g / (g tan alpha) and ``frequency`` W = omega_g / p (alpha and p of the
taller column), each run from rest for the pulse window (6 T_g) plus 10 s; with a vertical
ratio r every pulse also moves the ground vertically, a_v = r u_g'' (in phase). The column
``outside`` marks the cells outside the analytic model (:func:`cell_outside`).

* :func:`map_cells` - the grid (inclusive ranges, ``grid=(nA, nW)``, the pulses selected);
* :func:`run_map` - run every cell with one backend: the analytic model through its compiled
  path (:mod:`rockbench.analytic.compiled`, ``method="compiled"``, the default for maps) or the
  ``solve_ivp`` reference (``method="solve_ivp"``); engines through
  :func:`rockbench.sweep.run_cases`
  (MuJoCo batched in ``mujoco.rollout``), on a local process pool or a Dask cluster. With a
  ``store`` (a Parquet dataset: a folder ``NAME.parquet`` of parts plus ``_inputs.json``) every
  finished chunk is written at once; a rerun skips the stored cells, and a store written for
  other inputs is refused;
The agreement of two maps (cell by cell, Cohen's kappa, the boundary's shift) is
:mod:`rockbench.studies.map_agreement`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from .map_cells import (check_vertical_ratio, cell_outside, mark_outside, mirror_twins,
                        reversed_mirrors, with_mirrored)
from ..errors import ParameterError, RockbenchError
from ..run_length import pulse_run_length
from ..sweep.map_store import (COMPACT_EVERY, MAP_COLUMNS, MAP_KEY, cell_key, compact_map_store,
                              error_rows, input_differences, load_map, map_rows, open_map_store,
                              part_files, read_inputs, simulated_rows, store_error, store_inputs,
                              tidy_map, write_part)
from ..verdict import fall_under_way, finish_fall

__all__ = ["MAP_COLUMNS", "PULSES", "map_cells", "run_map", "load_map", "reuse_map",
           "check_vertical_ratio", "cell_outside", "mark_outside", "map_row"]

#: The pulses of a map: name -> (shape, sign).
PULSES: dict[str, tuple[str, int]] = {"symmetric+": ("symmetric", 1),
                                      "symmetric-": ("symmetric", -1),
                                      "antisymmetric+": ("antisymmetric", 1),
                                      "antisymmetric-": ("antisymmetric", -1)}

def _range(text_or_pair: Any, name: str) -> tuple[float, float]:
    if isinstance(text_or_pair, str):
        parts = text_or_pair.split(":")
        if len(parts) != 2:
            raise ParameterError(name, text_or_pair, "LO:HI (inclusive), e.g. 0.5:8")
        try:
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise ParameterError(name, text_or_pair, "LO:HI with two numbers") from None
    else:
        lo, hi = (float(x) for x in text_or_pair)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise ParameterError(name, text_or_pair, "0 < LO <= HI, both finite")
    return lo, hi


def _grid(text_or_pair: Any) -> tuple[int, int]:
    if isinstance(text_or_pair, str):
        try:
            na, nw = (int(x) for x in text_or_pair.lower().split("x"))
        except ValueError:
            raise ParameterError("grid", text_or_pair, "NAxNW, e.g. 100x100") from None
    else:
        na, nw = (int(x) for x in text_or_pair)
    if not (1 <= na <= 1000 and 1 <= nw <= 1000):
        raise ParameterError("grid", text_or_pair, "NAxNW with 1 <= NA, NW <= 1000")
    return na, nw


def _pulses(pulses: str | Sequence[str]) -> list[str]:
    names = list(PULSES) if pulses in ("all", None) else (
        [p.strip() for p in pulses.split(",")] if isinstance(pulses, str) else list(pulses))
    bad = [p for p in names if p not in PULSES]
    if bad or not names:
        raise ParameterError("pulses", pulses, f"all, or a comma-separated subset of "
                                               f"{', '.join(PULSES)}")
    return names


def map_cells(*, grid: Any = (100, 100), amplitude: Any = (0.5, 8.0),
              frequency: Any = (0.5, 10.0), pulses: str | Sequence[str] = "all"
              ) -> list[tuple[str, int, float, float]]:
    """The cells (shape, sign, A, W) of a map: ``grid`` = (nA, nW) points spread evenly over
    the inclusive ranges ``amplitude`` and ``frequency`` ("LO:HI" or a pair), for each selected
    pulse. ``grid=(8, 8), amplitude="1:8"`` gives A = 1, 2, ..., 8. Both ranges must lie
    within the limits of every run (:data:`rockbench.limits.LIMITS` ``A`` and ``W``)."""
    from ..limits import check_count

    As, Ws = _axes(grid, amplitude, frequency)
    names = _pulses(pulses)
    check_count("map_cells", "grid", len(As) * len(Ws) * len(names), "cells")
    return [(PULSES[p][0], PULSES[p][1], float(A), float(W))
            for p in names for W in Ws for A in As]


def _axes(grid: Any, amplitude: Any, frequency: Any) -> tuple[np.ndarray, np.ndarray]:
    """The A and W values of a map's grid (checked against the limits of every run)."""
    from ..limits import check_in_limit

    na, nw = _grid(grid)
    a0, a1 = _range(amplitude, "amplitude")
    w0, w1 = _range(frequency, "frequency")
    for key, name, lo, hi, n in (("A", "amplitude", a0, a1, na), ("W", "frequency", w0, w1, nw)):
        for v in (lo, hi):  # the limits of `rockbench run`, for every path of a map
            check_in_limit(key, name, v)
        if n > 1 and not lo < hi:
            raise ParameterError(name, amplitude if key == "A" else frequency,
                                 f"LO:HI with LO < HI for a grid of {n} points along {key} "
                                 f"(equal ends would give one cell {n} times)")
    As = np.linspace(a0, a1, na) if na > 1 else np.array([a0])
    Ws = np.linspace(w0, w1, nw) if nw > 1 else np.array([w0])
    return np.round(As, 12), np.round(Ws, 12)


# ------------------------------------------------------------------------------------------
# Running a map
# ------------------------------------------------------------------------------------------
def _load_scene_ref(ref: Any, overrides: dict | None = None):
    """A Scene from what travels to a worker: a built-in name or a path (with ``overrides``),
    or a scene's table (:meth:`Scene.to_dict`, overrides already applied)."""
    from ..scene.scene import Scene, load_scene

    if isinstance(ref, dict):
        return Scene.from_dict(ref, source=f"scene {ref.get('name', '')!r}")
    return load_scene(ref, overrides or None)


def _analytic_rows(scene, cells: Sequence, method: str, tail: float | None,
                   extra: float = 0.0, parallel: bool = False,
                   vertical: float = 0.0) -> pd.DataFrame:
    """Map rows of analytic ``cells`` in their order, each run for its map length
    (:func:`rockbench.run_length.pulse_run_length`) plus ``extra`` seconds (``parallel``: the
    compiled kernel's cells on numba's threads); on the compiled path with the last state of
    each run (``phi_end``, ``intact_end``) after the map's columns.

    With a vertical part (``vertical`` = r > 0: a_v = r u_g'', in phase) the compiled path runs
    each cell as one call of the run kernel on its pulse
    (:func:`~rockbench.analytic.compiled.run_pulse_grid` ``vertical_ratio``: the grid kernel
    builds horizontal pulses only); the reference path runs each as :func:`rockbench.run`."""
    if method == "compiled":
        from ..analytic.compiled import run_pulse_grid
        if tail is None and not extra:
            df = run_pulse_grid(scene, cells, parallel=parallel, vertical_ratio=vertical)
        else:
            byw: dict[float, list] = {}
            for i, c in enumerate(cells):
                byw.setdefault(c[3], []).append(i)
            df = pd.concat([run_pulse_grid(scene, [cells[i] for i in ix],
                                           duration=pulse_run_length(w, scene.p, tail, extra),
                                           parallel=parallel, vertical_ratio=vertical)
                            for w, ix in byw.items()], ignore_index=True)
            order = np.concatenate([np.asarray(ix) for ix in byw.values()])
            df = df.iloc[np.argsort(order, kind="stable")].reset_index(drop=True)  # cells' order
        return df[[*MAP_COLUMNS, "phi_end", "intact_end"]]
    from ..runner import run
    from ..scene.motion import RickerPulse
    rows = []
    for shape, sign, A, W in cells:
        pulse = RickerPulse.dimensionless(A, W, scene.structure, shape, sign,
                                          vertical_ratio=vertical)
        dur = pulse_run_length(W, scene.p, tail, extra)
        rows.append(map_row((shape, sign, A, W),
                            run(scene, pulse, history="minimal", duration=dur)))
    return pd.DataFrame(rows, columns=list(MAP_COLUMNS))


def map_row(cell: tuple, result) -> dict[str, Any]:
    """The map row (:data:`MAP_COLUMNS`) of a cell (shape, sign, A, W) from its run's
    :class:`~rockbench.result.Result`."""
    shape, sign, A, W = cell
    s = result.summary
    return {"amplitude": A, "frequency": W, "pulse": shape, "sign": sign,
            "overturned": s.overturned, "exceeded_critical": s.exceeded_critical,
            "max_abs_phi_over_alpha": s.max_abs_phi_over_alpha, "n_impacts": s.n_impacts,
            "fractured": s.fractured, "status": s.status, "cpu_s": result.cost.cpu_s}


def _analytic_chunk(args: tuple) -> pd.DataFrame:
    """One chunk of analytic cells (in a worker): compiled path or the solve_ivp reference,
    a fall under way finished (:func:`_analytic_cells`)."""
    scene_ref, overrides, cells, method, tail, vertical = args
    return _analytic_cells(_load_scene_ref(scene_ref, overrides), cells, method, tail,
                           vertical=vertical)


def _analytic_cells(scene, cells: Sequence, method: str, tail: float | None,
                    parallel: bool = False, vertical: float = 0.0) -> pd.DataFrame:
    """The rows of analytic ``cells``, each fall under way at the end of its run finished by
    the verdict rule of every backend (:mod:`rockbench.verdict`: a cell that ends past its
    critical angle is run :data:`~rockbench.constants.FALL_EXTENSION` seconds longer, and the
    longer run's row stands if it fell). The ``solve_ivp`` path runs each cell through the
    analytic backend, which finishes its own falls; the compiled path's cells are finished
    here (their cost: both runs)."""
    df = _analytic_rows(scene, cells, method, tail, parallel=parallel, vertical=vertical)
    if method != "compiled":
        return df
    from ..analytic.reference import reference_of

    cols = list(MAP_COLUMNS)
    under = fall_under_way(df["status"].to_numpy(), df["overturned"].to_numpy(dtype=bool),
                           df["phi_end"].to_numpy(dtype=float),
                           df["intact_end"].to_numpy(dtype=bool), reference_of(scene).critical)
    pending = np.flatnonzero(under)
    df = df[cols]
    if not pending.size:
        return df
    short = df.iloc[pending].to_dict("records")
    done, longer = finish_fall(
        short, [True] * len(short),
        lambda ix, extension: _analytic_rows(
            scene, [cells[pending[k]] for k in ix], method, tail, extra=extension,
            parallel=parallel, vertical=vertical)[cols].to_dict("records"),
        fell=lambda row: bool(row["overturned"]))
    rows = df.to_dict("records")
    for k, i in enumerate(pending):
        rows[i] = dict(done[k], cpu_s=float(short[k]["cpu_s"]) + float(longer[k]["cpu_s"]))
    return pd.DataFrame(rows, columns=cols)


#: Cells per part of an analytic map run in this process (its progress and store grain).
LOCAL_CHUNK = 2000


def _check_backend(engine: str) -> None:
    """BackendUnavailable (one line: which backend, why) before any cell runs."""
    from ..engines import get_backend
    from ..errors import BackendUnavailable

    ok, info = get_backend(engine).available()
    if not ok:
        raise BackendUnavailable(f"backend {engine!r} cannot run here: {info}")


def run_map(scene: Any, engine: str = "analytic", *, grid: Any = (100, 100),
            amplitude: Any = (0.5, 8.0), frequency: Any = (0.5, 10.0),
            pulses: str | Sequence[str] = "all", overrides: dict | None = None,
            settings: dict | None = None, method: str | None = None,
            store: str | os.PathLike | None = None, workers: int | None = None,
            scheduler: str | None = None, progress: bool = True,
            chunk: int | None = None, tail: float | None = None,
            keyed_by_code: bool = True, adaptive: bool = False,
            vertical: float = 0.0) -> pd.DataFrame:
    """Run an overturning map of ``scene`` (a built-in name, a .toml path or a
    :class:`~rockbench.Scene`, with scene ``overrides``) with backend ``engine`` (and its
    ``settings`` overrides) and return it (:data:`MAP_COLUMNS`, sorted by pulse, sign,
    frequency, amplitude).

    ``method`` (analytic only): "compiled" (default when numba imports) or "solve_ivp".
    ``store``: a Parquet dataset folder (created; resumed when it exists for the same inputs;
    refused for other inputs, or while another process writes it). Every finished chunk of
    analytic cells (``chunk`` cells, at most 200) and every finished engine cell (MuJoCo: each
    batch of 16) is on disk before the next result is taken. ``workers``: local processes
    (default and maximum: the cores); ``scheduler``: the address of a running Dask scheduler
    (``tcp://host:port``). ``progress``: a tqdm bar with cells done, rate, time left and how
    many were reused. ``tail``: free rocking after the pulse window [s] (default None: 10 s,
    the package default); shorter tails are for quick looks and tests.
    ``keyed_by_code``: False keys the store by its inputs and the engine version only (not by
    rockbench's code), for measured maps kept across code changes that are checked with
    :func:`reuse_map` before they are reused.
    ``adaptive``: simulate only where the verdict can change
    (:func:`rockbench.sweep.adaptive.adaptive_map`) and infer the
    other cells; the map (and the store) then has a column ``inferred``.
    ``vertical``: r in [0, 3] (limit ``vertical_ratio``, as ``rockbench run --vertical``):
    every cell's pulse has the vertical part a_v = r u_g'' (the same wavelet, in phase;
    :class:`~rockbench.scene.motion.RickerPulse` ``vertical_ratio``), for every backend; the
    analytic model's compiled path then calls its run kernel once per cell (the grid kernel
    builds horizontal pulses only; ``docs/maps.md`` gives the cost), in the worker pool when
    there is more than one worker. r is part of the store's inputs.
    The map has a column ``outside`` (not stored: it follows from the cell): the cell's motion
    is outside the analytic model by the one rule (:func:`cell_outside`).
    ``attrs``: ``reused`` (cells taken from the store), ``cells_run`` (simulated now),
    ``vertical_ratio``, ``outside`` (cells outside the model) and, adaptive, ``inferred``.
    """
    from ..runner import resolve_engines
    from ..scene.scene import Scene, apply_overrides
    from ..sweep.executors import check_options
    from ..sweep.store import need_pyarrow, writer_lock

    if isinstance(scene, Scene):
        sc = (Scene.from_dict(apply_overrides(scene.to_dict(), overrides), source=scene.name)
              if overrides else scene)
        scene_ref: Any = sc.to_dict()
        ref_name = sc.name
        overrides = None
    else:
        sc = _load_scene_ref(scene, overrides)
        scene_ref = str(scene)
        ref_name = str(scene)
    (engine,) = resolve_engines([engine], name="engine")
    settings = dict(settings or {})
    if engine == "analytic":
        method = method or _default_method()
        if method not in ("compiled", "solve_ivp"):
            raise ParameterError("method", method, "'compiled' or 'solve_ivp'")
        if method == "compiled" and settings:
            raise ParameterError("settings", settings, "none with method='compiled'")
    elif method is not None:
        raise ParameterError("method", method, "given only for the analytic backend")
    if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, int)
                              or chunk < 1):
        raise ParameterError("chunk", chunk, "an integer >= 1 or None")
    vertical = check_vertical_ratio(vertical)
    executor = "dask" if scheduler else "process"
    check_options(executor, workers, scheduler)
    _check_backend(engine)
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    path = Path(store) if store is not None else None
    common = (executor, workers, scheduler, progress, chunk, tail, vertical)

    def go(stored: tuple[Path, pd.DataFrame] | None) -> pd.DataFrame:
        if not adaptive:
            df = _run_cells(sc, scene_ref, ref_name, engine, settings, method, overrides,
                            cells, stored, *common)
        else:
            from ..sweep.adaptive import adaptive_map
            from ..sweep.executors import kept_pools

            with kept_pools():            # the rounds share one pool of workers
                df = adaptive_map(sc, lambda cs, st: _run_cells(
                    sc, scene_ref, ref_name, engine, settings, method, overrides, cs, st,
                    *common), _axes(grid, amplitude, frequency),
                    [PULSES[p] for p in _pulses(pulses)], stored)
        return mark_outside(df, sc, vertical)

    if path is None:
        return go(None)
    need_pyarrow()
    if path.exists() and not path.is_dir():
        raise ParameterError("store", str(path), "a map store folder (NAME.parquet), not a file")
    created = not path.exists()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise store_error(path, e, "create") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise RockbenchError(f"cannot write the map store {path}: the folder is not writable; "
                             f"give a --store in a folder you can write")
    try:
        with writer_lock(path, "map store"):
            inputs = store_inputs(sc, ref_name, engine, settings, method or "", tail,
                                  keyed_by_code, vertical_ratio=vertical)
            done = open_map_store(path, inputs)
            return go((path, done))
    except BaseException:
        if created and not part_files(path):  # nothing computed: leave no empty store behind
            import shutil
            shutil.rmtree(path, ignore_errors=True)
        raise


def _run_cells(sc, scene_ref: Any, ref_name: str, engine: str, settings: dict,
               method: str | None, overrides: dict | None, cells: list,
               stored: tuple[Path, pd.DataFrame] | None, executor: str,
               workers: int | None, scheduler: str | None, progress: bool,
               chunk: int | None, tail: float | None, vertical: float = 0.0) -> pd.DataFrame:
    """Run the cells not yet in the store (``stored`` = (folder, its rows), or None), writing
    each finished result to it at once; return the map of ``cells``."""
    from ..sweep.executors import cpu_count, execute, local_workers

    path, done = stored if stored is not None else (None, pd.DataFrame(
        columns=list(MAP_COLUMNS)))
    done = simulated_rows(done)
    have = {cell_key(p, s, a, w) for p, s, a, w in zip(done["pulse"], done["sign"],
                                                         done["amplitude"], done["frequency"])}
    todo = [c for c in cells if cell_key(*c) not in have] if have else list(cells)
    reused = len(cells) - len(todo)
    twins: dict[str, tuple] = {}
    if engine == "analytic" and reversed_mirrors(sc, vertical):
        todo, twins = mirror_twins(todo)
    frames = [done]
    written = [len(part_files(path)) if path is not None else 0]

    def on_result(_key: str, df: pd.DataFrame) -> None:
        if twins and len(df):
            df = with_mirrored(df, twins)
        frames.append(df)
        if path is not None and len(df):
            write_part(path, tidy_map(df))
            written[0] += 1
            if written[0] > COMPACT_EVERY:
                compact_map_store(path)
                written[0] = 1

    if path is not None and written[0] > 1:
        compact_map_store(path)                    # duplicates a killed compaction may have left
    compiled_here = engine == "analytic" and method == "compiled" and executor != "dask"
    threads = local_workers(workers) if compiled_here and executor == "process" else 1
    if compiled_here and todo and not (vertical and threads > 1):
        # the compiled kernel in this process, its cells on numba's threads (one per core):
        # no worker process to start, import and feed, parts of many cells (a vertical map's
        # cells are run one by one: on one core here, on more in the worker pool below)
        from ..progress import bar as progress_bar

        scene = _load_scene_ref(scene_ref, overrides)
        size = chunk or max(LOCAL_CHUNK, math.ceil(len(todo) / 20))
        bar = progress_bar(len(todo), f"map {sc.name} analytic ({reused} reused)", "cell",
                           show=progress)
        try:
            for i in range(0, len(todo), size):
                part = todo[i:i + size]
                on_result("", _analytic_cells(scene, part, method, tail, parallel=threads > 1,
                                              vertical=vertical))
                bar.update(len(part))
        finally:
            bar.close()
    elif engine == "analytic":
        n_workers = (threads if compiled_here and executor == "process"   # warned once
                     else local_workers(workers) if executor == "process"
                     else workers or cpu_count())
        size = chunk or (max(1, min(200, math.ceil(len(todo) / (4 * n_workers)))))
        items = [(f"chunk-{i}", (scene_ref, overrides or {}, todo[i:i + size], method, tail,
                                 vertical))
                 for i in range(0, len(todo), size)]
        execute(_analytic_chunk, items, on_result=on_result,
                crashed=lambda item, why: error_rows(item[2], why),
                label=lambda item: f"{len(item[2])} cells",
                executor=executor,
                workers=n_workers if executor == "process" else workers,
                dask_address=scheduler, progress=progress and bool(items),
                desc=f"map {sc.name} analytic ({reused} reused)", unit="chunk")
    elif todo:
        _engine_rows(scene_ref, overrides, engine, settings, todo, tail,
                     on_rows=lambda rows: on_result("", rows), executor=executor,
                     workers=workers, dask_address=scheduler, progress=progress,
                     vertical=vertical)
    if path is not None and written[0] > 1:
        compact_map_store(path)
    out = pd.concat([f for f in frames if len(f)], ignore_index=True) if any(
        len(f) for f in frames) else pd.DataFrame(columns=list(MAP_COLUMNS))
    out = tidy_map(out).drop_duplicates(list(MAP_KEY), keep="last")
    out = out[list(MAP_COLUMNS)]
    out = out[_rows_of(out, cells)].sort_values(["pulse", "sign", "frequency", "amplitude"],
                                ascending=[True, False, True, True]).reset_index(drop=True)
    out.attrs.update(scene=sc.name, engine=engine, method=method or "", reused=reused,
                     cells_run=len(todo), vertical_ratio=vertical)
    return out


def _rows_of(df: pd.DataFrame, cells: Sequence) -> np.ndarray:
    """Which rows of the map ``df`` are among ``cells`` (shape, sign, A, W), by the map's key
    (:func:`rockbench.sweep.map_store.cell_key`: A and W to 9 decimals), in one vectorized
    membership test."""
    if not len(df):
        return np.zeros(0, dtype=bool)
    c = list(zip(*cells)) if len(cells) else [[], [], [], []]
    want = pd.MultiIndex.from_arrays([
        pd.Index(c[0], dtype=object), np.asarray(c[1], dtype=np.int64),
        np.round(np.asarray(c[2], dtype=float), 9), np.round(np.asarray(c[3], dtype=float), 9)])
    have = pd.MultiIndex.from_arrays([
        pd.Index(df["pulse"].astype(str).to_numpy(dtype=object), dtype=object),
        df["sign"].to_numpy().astype(np.int64),
        np.round(df["amplitude"].to_numpy(dtype=float), 9),
        np.round(df["frequency"].to_numpy(dtype=float), 9)])
    return np.asarray(have.isin(want), dtype=bool)


def _engine_rows(scene_ref: Any, overrides: dict | None, engine: str, settings: dict,
                 cells: Sequence, tail: float | None, on_rows=None, vertical: float = 0.0,
                 **execution) -> pd.DataFrame:
    """Map rows of engine ``cells`` (shape, sign, A, W), run through
    :func:`rockbench.sweep.run_cases` (MuJoCo batched) with ``execution`` options;
    ``on_rows(frame)`` is called with the map rows of each finished executor item (a cell, or
    a MuJoCo batch) as it finishes. ``vertical`` > 0: each pulse's vertical ratio (the case's
    motion carries it; without one the cases are those of a horizontal map, key for key)."""
    from ..sweep import run_cases

    sc = _load_scene_ref(scene_ref, overrides)
    extra = {"vertical_ratio": float(vertical)} if vertical else {}
    cases = [{"scene": scene_ref, "overrides": overrides or {}, "engine": engine,
              "settings": settings, "duration": pulse_run_length(W, sc.p, tail),
              "motion": {"kind": "ricker", "shape": sh, "sign": sg, "A": A, "W": W, **extra}}
             for sh, sg, A, W in cells]
    rows = run_cases(cases, on_rows=(None if on_rows is None else
                                     (lambda rs: on_rows(map_rows(rs)))), keep="summary",
                     **execution)
    return map_rows(rows.to_dict("records"))


# ------------------------------------------------------------------------------------------
# Reusing a measured map: verified by re-running sample cells
# ------------------------------------------------------------------------------------------
#: Relative tolerance on max |phi| / alpha when a stored cell is re-run (the engines are
#: deterministic: the same wheel on the same kind of CPU reproduces a run bit for bit).
VERIFY_RTOL = 1e-6


def _check_cells(df: pd.DataFrame, n: int) -> pd.DataFrame:
    """Up to ``n`` stored cells to re-run: short runs (the highest frequencies), one per pulse
    and sign, alternately a survivor that rocked (the median rocking amplitude of the
    survivors) and an overturning cell far from the boundary (the largest A). Only simulated
    cells: an adaptive map's inferred cells (column ``inferred``) have no run to repeat."""
    if "inferred" in df.columns:
        df = df[~df["inferred"].fillna(False).astype(bool)]
    top = df[df["frequency"] >= df["frequency"].quantile(0.66)]
    picks = []
    for i, ((_p, _s), g) in enumerate(top.groupby(["pulse", "sign"], sort=True)):
        g = g[g["status"] == "ok"]
        ot = g[g["overturned"].astype(bool)]
        sv = g[~g["overturned"].astype(bool) & (g["max_abs_phi_over_alpha"] > 0.05)]
        if i % 2 == 0 and len(sv):
            sv = sv.sort_values("max_abs_phi_over_alpha")
            picks.append(sv.iloc[len(sv) // 2])
        elif len(ot):
            picks.append(ot.sort_values(["amplitude", "frequency"]).iloc[-1])
        elif len(g):
            picks.append(g.iloc[len(g) // 2])
        if len(picks) >= n:
            break
    return pd.DataFrame(picks).reset_index(drop=True)


class MapReuse(str):
    """Why a measured map is (not) reused, in words, with its ``kind``: "absent", "unreadable",
    "stale" (written for other inputs: measure it again from scratch), "partial" (some cells
    missing: a run resumes it), "unverified" (a cell re-run now disagrees) or "reused"."""

    kind: str

    def __new__(cls, text: str, kind: str) -> MapReuse:
        obj = super().__new__(cls, text)
        obj.kind = kind
        return obj


def reuse_map(store: str | os.PathLike, scene: str, engine: str, *, grid: Any,
              amplitude: Any, frequency: Any, pulses: str | Sequence[str] = "all",
              tail: float | None = None, check: int = 4,
              rtol: float = VERIFY_RTOL, workers: int | None = 1
              ) -> tuple[pd.DataFrame | None, MapReuse]:
    """A measured map (a store written with ``keyed_by_code=False``) if it can be trusted on
    this code and machine: written for the same scene, engine version, default settings and
    run length, complete for the grid, and reproduced at ``check`` cells re-run now (verdicts,
    status and impacts equal, max |phi| / alpha within ``rtol``). Returns (map, how it was
    verified) or (None, why it is not reused). ``workers``: processes that re-run the cells
    (1: in this process)."""
    path = Path(store)
    meta = path / "_inputs.json"
    if not meta.is_file():
        return None, MapReuse(f"no measured map at {path}", "absent")
    from ..scene.scene import load_scene

    sc = load_scene(scene)
    want = store_inputs(sc, str(scene), engine, {}, "", tail, keyed_by_code=False)
    old = read_inputs(path)
    if isinstance(old, str):
        return None, MapReuse(f"the measured map {path.name} has an unreadable {meta.name} "
                              f"({old})", "unreadable")
    diff = input_differences(old, want)
    if diff:
        return None, MapReuse(f"the measured map {path.name} was written for other inputs "
                              f"({', '.join(diff)} differ)", "stale")
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    df = load_map(path)
    keys = {(p, int(s), round(float(a), 9), round(float(w), 9))
            for p, s, a, w in zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])}
    missing = [c for c in cells if (c[0], c[1], round(c[2], 9), round(c[3], 9)) not in keys]
    if missing:
        return None, MapReuse(f"the measured map {path.name} lacks {len(missing)} of "
                              f"{len(cells)} cells", "partial")
    df = tidy_map(df)
    keep = {(c[0], c[1], round(c[2], 9), round(c[3], 9)) for c in cells}
    df = df[[(p, int(s), round(a, 9), round(w, 9)) in keep for p, s, a, w in
             zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])]]
    df = df.sort_values(["pulse", "sign", "frequency", "amplitude"],
                        ascending=[True, False, True, True]).reset_index(drop=True)
    picks = _check_cells(df, check)
    now = tidy_map(_engine_rows(str(scene), None, engine, {}, [
        (r.pulse, int(r.sign), float(r.amplitude), float(r.frequency))
        for r in picks.itertuples()], tail, progress=False,
        **(dict(executor="serial") if workers == 1 else dict(workers=workers))))
    m = picks.merge(now, on=list(MAP_KEY), suffixes=("", "_now"))
    worst = 0.0
    for r in m.itertuples():
        cell = (f"{r.pulse} {'+' if r.sign > 0 else '-'} A={r.amplitude:.4g} "
                f"W={r.frequency:.4g}")
        for c in ("status", "overturned", "exceeded_critical", "fractured", "n_impacts"):
            if getattr(r, c) != getattr(r, c + "_now"):
                return None, MapReuse(f"the measured map {path.name} does not reproduce: at "
                                      f"{cell} {c} was {getattr(r, c)}, is "
                                      f"{getattr(r, c + '_now')} now", "unverified")
        a, b = r.max_abs_phi_over_alpha, r.max_abs_phi_over_alpha_now
        d = abs(a - b) / max(abs(a), 1e-12)
        worst = max(worst, d)
        if not d <= rtol:
            return None, MapReuse(f"the measured map {path.name} does not reproduce: at {cell} "
                                  f"max |phi|/alpha was {a:.9g}, is {b:.9g} now", "unverified")
    df = mark_outside(df, sc)
    df.attrs.update(scene=sc.name, engine=engine, method="", reused=len(df))
    return df, MapReuse(f"measured earlier ({len(df)} cells, {want['engine_version']}), "
                        f"reproduced now at {len(m)} re-run cells (largest relative difference "
                        f"in max |phi|/alpha {worst:.1e})", "reused")


def _default_method() -> str:
    try:
        from ..analytic import compiled  # noqa: F401
        compiled._require_numba()
    except Exception:
        return "solve_ivp"
    return "compiled"

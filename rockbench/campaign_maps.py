"""The overturning-map part of the default campaign (paper Figs. 4-7, issue 11).

* Analytic maps at the paper's resolution (:data:`ANALYTIC_GRID`) for the paper's frames,
  through the compiled analytic path;
* every engine at 12 x 12 x 4 (:data:`MEASURED_GRID`) on a free-standing and a fracturing
  hybrid frame, each overlaid on the analytic map of the same cells and run length, with the
  fraction of agreeing cells, Cohen's kappa, the shift of the minimum-overturning boundary
  along A per frequency, and the cells near the analytic boundary (within
  :data:`rockbench.maps.NEAR_BOUNDARY_MARGIN` in A, where a verdict says little) counted apart.

The engine maps take about 40 minutes on 2 cores, four times the report's budget: ``full=True``
(``rockbench report --full``) measures them into a folder kept with the report
(``reports/engine-maps``), and the default report reuses each one only after
:func:`rockbench.maps.reuse_map` has re-run sample cells on the current code and found them
reproduced; otherwise it computes the fast engines on a coarser grid (:data:`ENGINE_GRIDS`) and
says why. Every map is kept in a resumable store.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any, Sequence

import pandas as pd

from .maps import (NEAR_BOUNDARY_MARGIN, describe_shift, map_agreement, mark_near_boundary,
                   reuse_map, run_map)

__all__ = ["ANALYTIC_SCENES", "ANALYTIC_GRID", "ENGINE_SCENES", "ENGINE_GRIDS", "run_maps"]

#: Scenes of the analytic maps and their grid (the paper's resolution).
ANALYTIC_SCENES = ("paper-symmetric", "paper-asymmetric", "paper-asymmetric-hybrid",
                   "paper-asymmetric-hybrid-eps2", "paper-asymmetric-hybrid-eps1")
ANALYTIC_GRID = dict(grid=(100, 100), amplitude="0.5:8", frequency="0.5:10", pulses="all")
#: Scenes of the engine maps (a free-standing and a fracturing hybrid frame).
ENGINE_SCENES = ("paper-asymmetric", "paper-asymmetric-hybrid-eps1")
#: Engine-map cells: A from 1 (below it the frame never uplifts), W from 1, and 3 s of free
#: rocking after the pulse window (the analytic overlay uses the same cells and length).
ENGINE_AXES = dict(amplitude="1:8", frequency="1:10", pulses="all", tail=3.0)
#: Grid of the measured engine maps (every engine, both scenes): run by ``full=True``
#: (``rockbench report --full``) into ``measured`` (``reports/engine-maps``, kept in the
#: repository), and reused by the default report when :func:`rockbench.maps.reuse_map`
#: reproduces sample cells of each on the current code.
MEASURED_GRID = (12, 12)
#: Grid per (engine speed class, scene) computed by the default report when no verified
#: measured map exists (``make report`` stays within its 10-minute budget on 2 cores).
ENGINE_GRIDS = {"fast": {"paper-asymmetric": (6, 6)}, "slow": {}}
#: Engines fast enough for the larger default grids (real-time factor >= 20 through rockbench).
FAST_ENGINES = ("pymunk", "mujoco")


def _engine_map(sc: str, eng: str, store: Path, measured: Path | None, *, full: bool,
                quick: bool, run: dict) -> tuple[pd.DataFrame | None, tuple[int, int], str]:
    """One engine's map of ``sc``: (map or None, grid, where it comes from)."""
    if quick:
        g = (4, 4)
        return (run_map(sc, eng, store=store / f"{sc}_{eng}_4x4.parquet",
                        **dict(ENGINE_AXES, grid=g), **run), g, "computed now")
    cells = dict(ENGINE_AXES, grid=MEASURED_GRID)
    why = "no measured map"
    if measured is not None:
        path = measured / f"{sc}_{eng}_{MEASURED_GRID[0]}x{MEASURED_GRID[1]}.parquet"
        df, why = reuse_map(path, sc, eng, **cells)
        if df is not None:
            return df, MEASURED_GRID, why
        if full:
            if path.exists() and "lacks" not in why:      # stale: measure again
                shutil.rmtree(path)
            df = run_map(sc, eng, store=path, keyed_by_code=False, **cells, **run)
            return df, MEASURED_GRID, f"measured now ({why})"
    cls = "fast" if eng in FAST_ENGINES else "slow"
    g = ENGINE_GRIDS[cls].get(sc)
    if g is None:
        return None, (0, 0), why
    return (run_map(sc, eng, store=store / f"{sc}_{eng}_{g[0]}x{g[1]}.parquet",
                    **dict(ENGINE_AXES, grid=g), **run), g, f"computed now ({why})")


def run_maps(engines: Sequence[str], store: Path, *, full: bool = False, quick: bool = False,
             measured: Path | None = None, progress: bool = True, workers: int | None = None,
             scheduler: str | None = None) -> dict[str, Any]:
    """Run the map part; return {"analytic": {scene: frame}, "engine": {(scene, engine):
    frame}, "overlay_ref": {(scene, grid): frame}, "agreement": frame, "words": [str],
    "provenance": [str]}. ``measured``: the folder of the measured engine maps
    (:data:`MEASURED_GRID`), reused when verified, (re)measured with ``full``."""
    run = dict(progress=progress, workers=workers, scheduler=scheduler)
    out: dict[str, Any] = {"analytic": {}, "engine": {}, "overlay_ref": {}, "words": [],
                           "provenance": []}
    scenes = ANALYTIC_SCENES[1:2] if quick else ANALYTIC_SCENES
    grid = dict(ANALYTIC_GRID, grid=(12, 12)) if quick else ANALYTIC_GRID
    for sc in scenes:
        out["analytic"][sc] = run_map(sc, "analytic", store=store / f"{sc}_analytic.parquet",
                                      **grid, **run)
    rows = []
    for sc in (ENGINE_SCENES[:1] if quick else ENGINE_SCENES):
        for eng in engines:
            if eng == "analytic":
                continue
            df, g, source = _engine_map(sc, eng, store, measured, full=full, quick=quick,
                                        run=run)
            out["provenance"].append(f"{eng} on {sc}: " + (
                f"{g[0]}x{g[1]}x4 cells, {source}" if df is not None else
                f"no map ({source}; `rockbench report --full` measures it)"))
            if df is None:
                continue
            cells = dict(ENGINE_AXES, grid=g)
            key = (sc, g)
            if key not in out["overlay_ref"]:
                out["overlay_ref"][key] = mark_near_boundary(run_map(
                    sc, "analytic", store=store / f"{sc}_analytic_{g[0]}x{g[1]}.parquet",
                    **cells, **run), sc, tail=ENGINE_AXES["tail"])
            ref = out["overlay_ref"][key]
            out["engine"][(sc, eng)] = df
            ag = map_agreement(ref, df)
            shift = ag["shift"]["shift"].dropna()
            words = describe_shift(ag["shift"], eng)
            rows.append({"scene": sc, "backend": eng, "grid": f"{g[0]}x{g[1]}x4",
                         "cells": ag["n"], "agree_fraction": ag["fraction"],
                         "kappa": ag["kappa"],
                         "engine_overturns_analytic_survives": ag["b_overturns_a_survives"],
                         "analytic_overturns_engine_survives": ag["a_overturns_b_survives"],
                         "boundary_shift_mean": float(shift.mean()) if len(shift) else None,
                         "boundary_shift_max_abs": float(shift.abs().max()) if len(shift)
                         else None,
                         "not_ok": int((df["status"] != "ok").sum()),
                         "near_boundary": ag["near_boundary"],
                         "disagree_near_boundary": ag["disagree_near_boundary"],
                         "disagree_away": ag["disagree_away"], "in_words": words})
            out["words"].append(f"{eng} on {sc} ({g[0]}x{g[1]}x4 cells): "
                                f"{100 * ag['fraction']:.1f} % of the verdicts agree with the "
                                f"analytic map (Cohen's kappa {ag['kappa']:.3f}); "
                                f"{ag['near_boundary']} cells lie within "
                                f"{100 * NEAR_BOUNDARY_MARGIN:g} % in A of the analytic boundary "
                                f"(near the boundary), {ag['disagree_near_boundary']} differing "
                                f"verdicts there and {ag['disagree_away']} away from it; "
                                f"{words}.")
    out["agreement"] = pd.DataFrame(rows)
    return out

"""The overturning-map part of the default campaign (paper Figs. 4-7; ``docs/maps.md``).

* Analytic maps at the paper's resolution (the plan's ``analytic_grid``) for the paper's
  frames, through the compiled analytic path;
* every engine at the plan's ``measured_grid`` or ``full_grid`` on a free-standing and a fracturing
  hybrid frame, each overlaid on the analytic map of the same cells and run length, with the
  fraction of agreeing cells, Cohen's kappa, the shift of the minimum-overturning boundary
  along A per frequency, and the cells near the analytic boundary (within
  :data:`rockbench.studies.maps.NEAR_BOUNDARY_MARGIN` in A, where a verdict says little) counted apart.

The engine maps take about 40 minutes on 2 cores, four times the report's budget: ``full=True``
(``rockbench report --full``) measures them into a folder kept with the report
(``reports/engine-maps``), and the default report reuses each one only after
:func:`rockbench.studies.maps.reuse_map` has re-run sample cells on the current code and found them
reproduced; otherwise it computes the fast engines on a coarser grid (the plan's
``fast_grids``) and says why. Every map is kept in a resumable store.
"""

from __future__ import annotations

import functools
import shutil
from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

from ..studies.map_agreement import (describe_shift, map_agreement,
                                     mark_near_boundary)
from ..report.words import agreement_words
from ..studies.maps import reuse_map, run_map
from ..sweep.map_store import map_store_path

__all__ = ["engine_axes", "run_maps", "is_fast"]

def _paper_maps() -> dict[str, Any]:
    """The paper plan's maps (``scenarios/paper-plan.toml``, ``[campaign.maps]``); another
    plan brings its own."""
    from .plan import campaign_plan

    return campaign_plan()["maps"]


def engine_axes(maps: dict[str, Any] | None = None) -> dict[str, Any]:
    """The engine maps' cells of a plan's ``maps`` (default the paper's): A and W ranges, the
    four pulses, the free-rocking tail [s] after the pulse window (the analytic overlay uses
    the same cells and length)."""
    m = _paper_maps() if maps is None else maps
    return dict(amplitude=m["engine_amplitude"], frequency=m["engine_frequency"],
                pulses="all", tail=m["engine_tail"])


def is_fast(engine: str) -> bool:
    """The engine is fast enough for the larger default grids: its backend's ``fast``
    capability (real-time factor >= 20 through rockbench, ``rockbench.engines.base``)."""
    from ..engines import get_backend
    from ..errors import BackendUnavailable

    try:
        return bool(get_backend(engine).fast)
    except BackendUnavailable:
        return False


def scene_label(ref: Any) -> str:
    """A scene's label in file names and on the page: a built-in name as it is, a TOML path by
    the scene's own ``name`` (its file's stem when the file gives none), a Scene by its name."""
    if isinstance(ref, (str, Path)) and (str(ref).endswith(".toml") or "/" in str(ref)):
        return _file_label(str(ref))
    return str(getattr(ref, "name", ref))


@functools.lru_cache(maxsize=256)
def _file_label(path: str) -> str:
    import tomllib

    try:
        name = tomllib.loads(Path(path).read_text(encoding="utf-8")).get("name")
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        name = None                # the scene loader says what is wrong with the file
    return str(name) if isinstance(name, str) and name.strip() else Path(path).stem


def _axes(maps: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(analytic grid, engine axes) of a plan's maps part."""
    return (dict(grid=tuple(maps["analytic_grid"]), amplitude=maps["analytic_amplitude"],
                 frequency=maps["analytic_frequency"], pulses="all"),
            engine_axes(maps))


def _engine_map(sc: Any, eng: str, store: Path, measured: Path | None, *, full: bool,
                quick: bool, run: dict, maps: Mapping[str, Any], vertical: float = 0.0
                ) -> tuple[pd.DataFrame | None, tuple[int, int], str]:
    """One engine's map of ``sc``: (map or None, grid, where it comes from). With a vertical
    part (``vertical`` r > 0) no measured map applies (they are horizontal): the fast
    engines' maps are computed now."""
    axes = dict(_axes(maps)[1], vertical=vertical)
    lab = scene_label(sc)
    if quick:           # a first look decides on its evidence; maps are for the full report
        return None, (0, 0), "--quick draws the analytic map only"
    why = "no measured map"
    if vertical:
        why = "the measured maps are of horizontal pulses"
    elif measured is not None:
        # the finest verified map first: the paper's resolution (measured adaptively by
        # --full), then the plan's measured grid
        fg, mg = tuple(maps.get("full_grid", maps["measured_grid"])), tuple(maps["measured_grid"])
        whys = []
        for g in dict.fromkeys((fg, mg)):
            path = map_store_path(measured, lab, eng, f"{g[0]}x{g[1]}")
            horizontal = {k: v for k, v in axes.items() if k != "vertical"}
            df, w = reuse_map(path, sc, eng, **horizontal, grid=g, workers=run.get("workers"))
            if df is not None and not (full and g != fg):   # --full wants the finest
                return df, g, w
            whys.append(w)
        why = whys[-1] if len(whys) == 1 else f"{whys[0]}; {whys[1]}"
        if full:
            path = map_store_path(measured, lab, eng, f"{fg[0]}x{fg[1]}")
            if path.exists() and getattr(whys[0], "kind", "") != "partial":  # not resumable
                shutil.rmtree(path)
            df = run_map(sc, eng, store=path, keyed_by_code=False, adaptive=fg != mg,
                         **dict(axes, grid=fg), **run)
            return df, fg, f"measured now ({whys[0]})"
    g = maps["fast_grids"].get(lab) if is_fast(eng) else None
    if g is None:
        return None, (0, 0), why
    g = tuple(g)
    return (run_map(sc, eng, store=map_store_path(store, lab, eng, f"{g[0]}x{g[1]}"),
                    **dict(axes, grid=g), **run), g, f"computed now ({why})")


def run_maps(engines: Sequence[str], store: Path, *, full: bool = False, quick: bool = False,
             measured: Path | None = None, progress: bool = True, workers: int | None = None,
             scheduler: str | None = None, maps: Mapping[str, Any] | None = None,
             vertical: float = 0.0) -> dict[str, Any]:
    """Run the map part; return {"analytic": {scene: frame}, "engine": {(scene, engine):
    frame}, "overlay_ref": {(scene, grid): frame}, "agreement": frame, "words": [str],
    "provenance": [str]}. ``measured``: the folder of the measured engine maps (the plan's
    ``measured_grid``), reused when verified, (re)measured with ``full``. ``maps``: the plan's
    maps part (default: the paper plan's, ``scenarios/paper-plan.toml``); scenes are keyed by
    their label (:func:`scene_label`). ``vertical``: r, every pulse's vertical part
    a_v = r u_g'' (in phase; :func:`rockbench.studies.maps.run_map`)."""
    maps = dict(_paper_maps() if maps is None else maps)
    grid_a, axes = _axes(maps)
    grid_a, axes = dict(grid_a, vertical=vertical), dict(axes, vertical=vertical)
    run = dict(progress=progress, workers=workers, scheduler=scheduler)
    out: dict[str, Any] = {"analytic": {}, "engine": {}, "overlay_ref": {}, "words": [],
                           "provenance": []}
    scenes = list(maps["analytic_scenes"])
    eng_scenes = list(maps["engine_scenes"])
    if quick:
        scenes = [s for s in scenes if s in eng_scenes[:1]] or scenes[:1]
        grid_a = dict(grid_a, grid=(12, 12))
    for sc in scenes:
        lab = scene_label(sc)
        out["analytic"][lab] = run_map(sc, "analytic", store=map_store_path(store, lab, "analytic"),
                                       **grid_a, **run)
    rows = []
    for sc in (eng_scenes[:1] if quick else eng_scenes):
        lab = scene_label(sc)
        for eng in engines:
            if eng == "analytic":
                continue
            df, g, source = _engine_map(sc, eng, store, measured, full=full, quick=quick,
                                        run=run, maps=maps, vertical=vertical)
            out["provenance"].append(f"{eng} on {lab}: " + (
                f"{g[0]}x{g[1]}x4 cells, {source}" if df is not None else
                f"no map ({source}; `rockbench report"
                + ("` maps the fast engines" if quick else " --full` measures it") + ")"))
            if df is None:
                continue
            cells = dict(axes, grid=g)
            key = (lab, g)
            if key not in out["overlay_ref"]:
                out["overlay_ref"][key] = mark_near_boundary(run_map(
                    sc, "analytic", store=map_store_path(store, lab, "analytic", f"{g[0]}x{g[1]}"),
                    **cells, **run), sc, tail=axes["tail"], vertical=vertical,
                    parallel=run.get("workers") != 1)
            ref = out["overlay_ref"][key]
            out["engine"][(lab, eng)] = df
            ag = map_agreement(ref, df)
            shift = ag["shift"]["shift"].dropna()
            words = describe_shift(ag["shift"], eng)
            rows.append({"scene": lab, "backend": eng, "grid": f"{g[0]}x{g[1]}x4",
                         "cells": ag["n"], "differ": ag["differ"],
                         "agree_fraction": ag["fraction"], "kappa": ag["kappa"],
                         "engine_overturns_analytic_survives": ag["b_overturns_a_survives"],
                         "analytic_overturns_engine_survives": ag["a_overturns_b_survives"],
                         "boundary_shift_mean": float(shift.mean()) if len(shift) else None,
                         "boundary_shift_max_abs": float(shift.abs().max()) if len(shift)
                         else None,
                         "not_ok": ag["not_ok_first"] + ag["not_ok_second"],
                         "near_boundary": ag["near_boundary"],
                         "disagree_near_boundary": ag["disagree_near_boundary"],
                         "disagree_away": ag["disagree_away"], "in_words": words})
            out["words"].append(agreement_words(rows[-1], engine=eng, scene=lab)
                                + f"; {words}.")
    from ..report.tables import CAMPAIGN_COLUMNS

    out["agreement"] = pd.DataFrame(rows, columns=list(CAMPAIGN_COLUMNS["map_agreement.csv"]))
    return out

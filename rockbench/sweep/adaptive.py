"""Adaptive overturning maps (``docs/maps.md``): simulate where the verdict can
change, infer the rest. Used by :func:`rockbench.studies.maps.run_map` (``adaptive=True``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .map_store import (MAP_COLUMNS, MAP_KEY, cell_key, compact_map_store, simulated_rows,
                        tidy_map, write_part)

__all__ = ["COARSE_STRIDE", "COARSE_STRIDE_FINE", "FINE_GRID", "NEAR_CRITICAL", "adaptive_map",
           "coarse_stride"]

#: Adaptive maps: the coarse pass simulates every COARSE_STRIDE-th point along A and W (and
#: the last); a block of cells between simulated corners is halved until its corners agree.
COARSE_STRIDE = 4
#: ... and every COARSE_STRIDE_FINE-th on a grid of at least FINE_GRID points along both axes
#: (the paper's 100 x 100): measured on the analytic maps of the paper's five frames at
#: 100 x 100 x 4 (docs/maps.md), without the mode rule below it simulated 4-12 % of the cells
#: instead of 9-16 % and reproduced 99.88-100 % of the full grid's verdicts (99.94-100 % with
#: stride 4); with it 4-15 % and 99.93-100 %.
COARSE_STRIDE_FINE = 8
FINE_GRID = 96


def coarse_stride(na: int, nw: int) -> int:
    """The coarse pass's stride on a grid of ``na`` x ``nw`` points (:data:`COARSE_STRIDE`, or
    :data:`COARSE_STRIDE_FINE` when both are at least :data:`FINE_GRID`)."""
    return COARSE_STRIDE_FINE if min(na, nw) >= FINE_GRID else COARSE_STRIDE


#: Adaptive maps: a surviving corner whose max |phi| reaches this fraction of the critical
#: angle makes its block "near" (refined), so that survival close to overturning is looked at.
#: (On a grid of at least FINE_GRID points a side, whose coarse blocks are 8 cells wide, a
#: block whose corners all overturn is also refined when they overturn in both modes, with
#: and without an impact: the islands of survival inside the overturning region lie between.
#: Below, the blocks of 4 cells miss no more than 0-2 cells without it, and it would take the
#: 24 x 24 maps of the paper's frames from 31 % of the cells simulated to 39 %.)
NEAR_CRITICAL = 0.7


def adaptive_map(sc, compute, axes: tuple[np.ndarray, np.ndarray],
                 pulses: list[tuple[str, int]],
                 stored: tuple[Path, pd.DataFrame] | None) -> pd.DataFrame:
    """An adaptive map: simulate the corners of the coarse blocks (every
    :func:`coarse_stride`-th A and W, and the last), then, level by level, halve every block
    whose corners do not all give one verdict with status ok, where a surviving corner
    rocked beyond :data:`NEAR_CRITICAL` of the critical angle, or (on a grid of at least
    :data:`FINE_GRID` a side) whose corners all overturn but some after an impact and some
    without one (the two overturning modes, between which islands of survival lie: Zhang &
    Makris 2001), until blocks are one cell wide;
    the cells of a block whose corners agree take their verdict (``inferred`` True, peak and
    impacts unknown). ``compute(cells, stored)`` simulates cells (reusing stored ones) and
    returns their rows; ``pulses`` are (shape, sign) pairs, ``axes`` the grid's A and W
    values, ``stored`` (store folder, its rows) or None. Measured on the analytic maps of the
    paper's frames: at 24 x 24 x 4 it simulates 16-31 % of the cells and reproduces
    99.91-100 % of the full grid's verdicts; at 100 x 100 x 4 (stride 8, mode rule) 4-15 %
    and 99.93-100 % (``docs/maps.md``)."""
    from ..runner import info

    As, Ws = axes
    na, nw = len(As), len(Ws)
    consts = info(sc)
    # the smallest critical angle of any direction and device state [alpha] (a frame with
    # intact tendons has none until they fracture)
    crits = [abs(float(v)) for k, v in consts.items() if k.startswith("phi_cr_")
             and v is not None and math.isfinite(float(v))]
    crit = min(crits) / consts["alpha"] if crits else math.inf
    path = stored[0] if stored is not None else None
    known: dict[tuple, Any] = {}                 # (pulse, sign, i, j) -> row (namedtuple)
    frames: list[pd.DataFrame] = []
    reused = run = 0

    def simulate(need: list[tuple[str, int, int, int]]) -> None:
        nonlocal reused, run
        need = [k for k in dict.fromkeys(need) if k not in known]
        if not need:
            return
        cells = [(p, s, float(As[i]), float(Ws[j])) for p, s, i, j in need]
        st = None if path is None else (path, pd.concat(
            [stored[1]] + frames, ignore_index=True) if frames else stored[1])
        df = compute(cells, st)
        reused += int(df.attrs.get("reused", 0))
        run += int(df.attrs.get("cells_run", 0))
        frames.append(df)
        by = {cell_key(r.pulse, r.sign, r.amplitude, r.frequency): r for r in df.itertuples()}
        for k, c in zip(need, cells):
            known[k] = by[cell_key(*c)]

    by_mode = False
    if na < 2 or nw < 2:
        simulate([(p, s, i, j) for p, s in pulses for i in range(na)
                  for j in range(nw)])
        blocks: list[tuple] = []
    else:
        stride = coarse_stride(na, nw)
        by_mode = stride == COARSE_STRIDE_FINE        # see :data:`NEAR_CRITICAL`
        ia = sorted(set(range(0, na, stride)) | {na - 1})
        iw = sorted(set(range(0, nw, stride)) | {nw - 1})
        blocks = [(p, s, a0, a1, w0, w1) for p, s in pulses
                  for a0, a1 in zip(ia, ia[1:]) for w0, w1 in zip(iw, iw[1:])]
    verdict: dict[tuple, bool] = {}
    while blocks:
        simulate([(p, s, a, w) for p, s, a0, a1, w0, w1 in blocks
                  for a in (a0, a1) for w in (w0, w1)])
        finer = []
        for p, s, a0, a1, w0, w1 in blocks:
            cs = [known[(p, s, a, w)] for a in (a0, a1) for w in (w0, w1)]
            ok = all(c.status == "ok" for c in cs)
            over = {bool(c.overturned) for c in cs if ok}
            near = any(not bool(c.overturned) and c.max_abs_phi_over_alpha >= NEAR_CRITICAL
                       * crit for c in cs if ok)
            # overturning after an impact and without one: an island of survival lies between
            modes = ({_impacted(c) for c in cs} if by_mode and ok and over == {True}
                     else set())
            if ok and len(over) == 1 and not near and len(modes) <= 1:
                v = over.pop()
                for a in range(a0, a1 + 1):
                    for w in range(w0, w1 + 1):
                        verdict.setdefault((p, s, a, w), v)
                continue
            am = [a0, (a0 + a1) // 2, a1] if a1 - a0 > 1 else [a0, a1]
            wm = [w0, (w0 + w1) // 2, w1] if w1 - w0 > 1 else [w0, w1]
            if len(am) == 2 and len(wm) == 2:
                continue                          # one cell wide: every cell is simulated
            finer += [(p, s, x0, x1, y0, y1) for x0, x1 in zip(am, am[1:])
                      for y0, y1 in zip(wm, wm[1:])]
        blocks = finer
    # a cell the store holds simulated (e.g. by a full run) is taken as it is, not inferred
    old = simulated_rows(stored[1]) if stored is not None else pd.DataFrame()
    if len(old):
        index = {(p, s, round(float(As[a]), 9), round(float(Ws[w]), 9)): (p, s, a, w)
                 for p, s in pulses
                 for a in range(na) for w in range(nw)}
        have = {cell_key(r.pulse, r.sign, r.amplitude, r.frequency) for r in
                old.itertuples()}
        take = [index[k] for k in have if k in index and index[k] in verdict
                and index[k] not in known]
        if take:
            frames.append(tidy_map(old[[cell_key(r.pulse, r.sign, r.amplitude, r.frequency)
                                     in {(p, s, round(float(As[a]), 9),
                                          round(float(Ws[w]), 9)) for p, s, a, w in take}
                                     for r in old.itertuples()]]))
            reused += len(take)
            known.update({k: None for k in take})
    sim = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(
        columns=list(MAP_COLUMNS))
    sim = tidy_map(sim).drop_duplicates(list(MAP_KEY), keep="last")[list(MAP_COLUMNS)]
    sim = sim.assign(inferred=False)
    guessed = [{"amplitude": float(As[a]), "frequency": float(Ws[w]), "pulse": p, "sign": s,
                "overturned": v, "exceeded_critical": True if v else None,
                "max_abs_phi_over_alpha": math.nan, "n_impacts": None, "fractured": None,
                "status": "ok", "cpu_s": 0.0, "inferred": True}
               for (p, s, a, w), v in verdict.items() if (p, s, a, w) not in known]
    out = sim
    if guessed:
        inf = tidy_map(pd.DataFrame(guessed))
        if path is not None:
            # the store already holding every one of these verdicts (a rerun) is left as it is
            had = _stored_inferred(stored[1]) if stored is not None else {}
            if any(had.get(cell_key(g["pulse"], g["sign"], g["amplitude"], g["frequency"]))
                   is not g["overturned"] for g in guessed):
                write_part(path, inf)
                compact_map_store(path)
        out = pd.concat([sim, inf], ignore_index=True)
    out = out.sort_values(["pulse", "sign", "frequency", "amplitude"],
                          ascending=[True, False, True, True]).reset_index(drop=True)
    out.attrs.update(scene=sc.name, engine=frames[0].attrs.get("engine", "") if frames else "",
                     method=frames[0].attrs.get("method", "") if frames else "",
                     reused=reused, cells_run=run, inferred=len(guessed))
    return out


def _stored_inferred(df: pd.DataFrame) -> dict[tuple, bool]:
    """The inferred cells of a store's rows: cell key -> verdict."""
    if not len(df) or "inferred" not in df.columns:
        return {}
    inf = df[df["inferred"].astype("boolean").fillna(False).astype(bool)]
    return {cell_key(p, s, a, w): bool(o) for p, s, a, w, o in
            zip(inf["pulse"], inf["sign"], inf["amplitude"], inf["frequency"],
                inf["overturned"])}


def _impacted(c) -> bool:
    """Whether a map row's run had an impact (None or NaN: unknown, taken as none)."""
    n = c.n_impacts
    try:
        return n is not None and float(n) > 0
    except (TypeError, ValueError):
        return False

"""The agreement of two overturning maps (:mod:`rockbench.studies.maps`), cell by cell: the
fraction of equal verdicts and Cohen's kappa on the cells both ran ok, what was left out (cells
held by one map only, cells not ok), the minimum-overturning boundary of each and its shift
along A per frequency, and the cells near the reference's boundary (within
:data:`NEAR_BOUNDARY_MARGIN` in A), where a verdict says little about an engine.

A = a_g / (g tan alpha), W = omega_g / p, alpha and p of the taller column.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from ..errors import ParameterError, RockbenchError
from ..sweep.map_store import MAP_KEY, cell_key
from .maps import _analytic_cells, _default_method, _load_scene_ref

__all__ = ["boundary", "mark_near_boundary", "NEAR_BOUNDARY_MARGIN", "map_agreement",
           "describe_shift"]


def boundary(df: pd.DataFrame) -> pd.DataFrame:
    """The minimum-overturning boundary of a map: for each (pulse, sign, frequency), the
    smallest amplitude A that overturns (NaN if none does)."""
    ok = df[df["status"] == "ok"]
    keys = ["pulse", "sign", "frequency"]
    if not len(ok):
        return pd.DataFrame(columns=keys + ["a_min"])
    ok = ok.assign(sign=ok["sign"].astype(int), frequency=ok["frequency"].astype(float),
                   a_ot=ok["amplitude"].astype(float).where(ok["overturned"].astype(bool)))
    out = ok.groupby(keys, sort=True)["a_ot"].min().rename("a_min").reset_index()
    return out[keys + ["a_min"]]


#: Relative margin in A within which a cell is "near the boundary": the engines' own
#: boundary is blurred and not monotone within about 2 % of the reference's (measured:
#: MuJoCo overturns at A = 14.90 and survives at A = 15.00, W = 6), so a verdict
#: there says little about an engine.
NEAR_BOUNDARY_MARGIN = 0.02


def mark_near_boundary(ref: pd.DataFrame, scene: Any, *, margin: float = NEAR_BOUNDARY_MARGIN,
                       tail: float | None = None, overrides: dict | None = None,
                       method: str | None = None, vertical: float = 0.0,
                       parallel: bool = False) -> pd.DataFrame:
    """``ref`` (an analytic map of ``scene``) with a column ``near_boundary``: True where the
    reference verdict changes within ``margin`` (relative) of the cell's A, i.e. where the
    analytic model run at A (1 - margin) or A (1 + margin), same pulse and W, gives the other
    verdict than at A (cells not ok: False). ``tail`` and ``vertical`` (the pulses' vertical
    ratio) as the map's; ``parallel``: the compiled path's cells on numba's threads."""
    from ..errors import check_positive

    if not 0 < check_positive("margin", margin) < 1:
        raise ParameterError("margin", margin, "in (0, 1)")
    out = ref.copy()
    out["near_boundary"] = False
    ok = out[out["status"] == "ok"]
    if not len(ok):
        return out
    from ..scene.scene import Scene

    sc = scene if isinstance(scene, Scene) else _load_scene_ref(str(scene), overrides)
    method = method or _default_method()
    base = [(r.pulse, int(r.sign), float(r.amplitude), float(r.frequency))
            for r in ok.itertuples()]
    verdicts = []
    for f in (1.0 - margin, 1.0 + margin):
        cells = [(p, s, a * f, w) for p, s, a, w in base]
        df = _analytic_cells(sc, cells, method, tail, vertical=float(vertical),
                             parallel=parallel and method == "compiled")
        verdicts.append(df["overturned"].astype(bool).to_numpy())
    here = ok["overturned"].astype(bool).to_numpy()
    near = (verdicts[0] != here) | (verdicts[1] != here)
    out.loc[ok.index, "near_boundary"] = near
    out["near_boundary"] = out["near_boundary"].astype(bool)
    return out


def map_agreement(a: pd.DataFrame, b: pd.DataFrame) -> dict[str, Any]:
    """Agreement of map ``b`` with map ``a`` (normally the analytic one) on the cells both ran
    with status ok: ``n`` cells, ``fraction`` of equal verdicts, Cohen's ``kappa`` (agreement
    beyond chance; 1 perfect, 0 chance; NaN if both maps are uniform), ``b_overturns_a_survives``
    and ``a_overturns_b_survives`` counts, and ``shift``: a frame per (pulse, sign, frequency)
    of the boundary A_min of each *on those common cells* and ``shift`` = A_min(b) - A_min(a)
    [-] (negative: b overturns at smaller pulses, earlier).

    When ``a`` has a ``near_boundary`` column (:func:`mark_near_boundary`): ``near_boundary``
    (cells within the margin of the reference boundary), ``disagree_near_boundary`` and
    ``disagree_away`` (differing verdicts near and away from it). ``cells``: the common ok
    cells (key, both verdicts, ``agree``, ``near_boundary``).

    What is left out is counted, never hidden: ``cells_first``, ``cells_second`` (each map's
    cells), ``common`` (cells both hold), ``not_ok_first``, ``not_ok_second`` (common cells not
    ok in that map: left out of ``n``), ``differ`` (of the ``n`` compared, the verdicts that
    differ).

    RockbenchError when the maps have no cell in common (nothing to compare); ``n`` = 0 when
    they share cells but none ran ok in both (``fraction`` and ``kappa`` then NaN)."""
    key = list(MAP_KEY)
    ka = [cell_key(*k) for k in zip(a["pulse"], a["sign"], a["amplitude"], a["frequency"])]
    kb = [cell_key(*k) for k in zip(b["pulse"], b["sign"], b["amplitude"], b["frequency"])]
    a = a.assign(_k=ka)
    b = b.assign(_k=kb)
    m = a.merge(b.drop(columns=key + [c for c in ("near_boundary",) if c in b.columns]),
                on="_k", suffixes=("_a", "_b"))
    if not len(m):
        raise RockbenchError(
            f"the two maps have no cell in common (first: {len(a)} cells, A "
            f"{_span(a['amplitude'])}, W {_span(a['frequency'])}; second: {len(b)} cells, A "
            f"{_span(b['amplitude'])}, W {_span(b['frequency'])}): compare maps run on the "
            f"same grid (--grid, --amplitude, --frequency, --pulses)")
    n_common = len(m)
    not_ok_a = int((m["status_a"] != "ok").sum())
    not_ok_b = int((m["status_b"] != "ok").sum())
    m = m[(m["status_a"] == "ok") & (m["status_b"] == "ok")].reset_index(drop=True)
    va = m["overturned_a"].astype(bool).to_numpy()
    vb = m["overturned_b"].astype(bool).to_numpy()
    n = len(m)
    agree = float((va == vb).mean()) if n else math.nan
    kappa = math.nan
    if n:
        pa, pb = va.mean(), vb.mean()
        pe = pa * pb + (1 - pa) * (1 - pb)
        kappa = (agree - pe) / (1 - pe) if pe < 1 else math.nan
    common_a = m[key + ["overturned_a", "status_a"]].rename(
        columns={"overturned_a": "overturned", "status_a": "status"})
    common_b = m[key + ["overturned_b", "status_b"]].rename(
        columns={"overturned_b": "overturned", "status_b": "status"})
    ba = boundary(common_a).merge(boundary(common_b), on=["pulse", "sign", "frequency"],
                                  suffixes=("_a", "_b"))
    ba["shift"] = ba["a_min_b"] - ba["a_min_a"]
    has_near = "near_boundary" in m.columns
    near = (m["near_boundary"].fillna(False).astype(bool).to_numpy() if has_near
            else np.zeros(n, dtype=bool))
    cells = m[key].assign(overturned_a=va, overturned_b=vb, agree=va == vb, near_boundary=near)
    out = {"n": n, "fraction": agree, "kappa": float(kappa), "differ": int((va != vb).sum()),
           "cells_first": len(a), "cells_second": len(b), "common": n_common,
           "not_ok_first": not_ok_a, "not_ok_second": not_ok_b,
           "b_overturns_a_survives": int((vb & ~va).sum()),
           "a_overturns_b_survives": int((va & ~vb).sum()), "shift": ba, "cells": cells}
    if has_near:
        out.update(near_boundary=int(near.sum()),
                   disagree_near_boundary=int(((va != vb) & near).sum()),
                   disagree_away=int(((va != vb) & ~near).sum()))
    return out


def _span(x: pd.Series) -> str:
    return f"{float(x.min()):.4g}-{float(x.max()):.4g}" if len(x) else "none"


def describe_shift(shift: pd.DataFrame, name: str = "the engine") -> str:
    """Where a boundary sits against the reference, in words, per pulse (and one-sided)."""
    parts = []
    for (p, s), g in shift.groupby(["pulse", "sign"], sort=True):
        bits, tag = [], f"{p} {'+' if s > 0 else '-'}"
        for col, other, what in (("a_min_b", "a_min_a", "overturns where the reference "
                                  "survives every A"), ("a_min_a", "a_min_b", "survives every "
                                                        "A where the reference overturns")):
            one = g[g[col].notna() & g[other].isna()]
            if len(one):
                bits.append(f"{name} {what}, at W = " + ", ".join(
                    f"{w:.3g} ({'reference ' * (col == 'a_min_a')}from A = {a:.3g})"
                    for w, a in zip(one["frequency"], one[col])))
        g = g.dropna(subset=["shift"])
        early, late = g[g["shift"] < 0], g[g["shift"] > 0]
        if not len(early) and not len(late):
            if len(g) or bits:
                parts.append(f"{tag}: " + ("; ".join(bits) + "; elsewhere the same boundary"
                                           if bits else "same boundary at every frequency"))
            continue
        shifts = []
        if len(early):
            shifts.append(f"earlier (at smaller A, by up to {-early['shift'].min():.3g}) at "
                          "W = " + ", ".join(f"{w:.3g}" for w in early["frequency"]))
        if len(late):
            shifts.append(f"later (by up to {late['shift'].max():.3g}) at W = "
                          + ", ".join(f"{w:.3g}" for w in late["frequency"]))
        parts.append(f"{tag}: {name} overturns " + "; ".join(shifts + bits))
    return "; ".join(parts) if parts else "no overturning boundary in both maps"

"""Sentences rendered from table rows, one function per kind of row, so that a sentence says
exactly what its row holds and nothing the row does not: a changed row changes the sentence.

* :func:`agreement_words` - a map's agreement with the analytic one (a ``map_agreement.csv``
  row): the cells compared, how many differ (never rounded up to all), Cohen's kappa, the cells
  left out (not ok, or held by one map only), near the boundary and away from it.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

__all__ = ["agreement_words", "share"]


def _num(v: Any) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return math.nan
    return x


def share(part: int, whole: int) -> str:
    """``part`` of ``whole`` as a percentage that is never rounded to 100 % (or 0 %) while one
    differs: two decimals, more where they would hide it."""
    if whole <= 0:
        return "n/a"
    f = 100.0 * part / whole
    for digits in (2, 3, 4, 5, 6):
        text = f"{f:.{digits}f}"
        if (part == whole) == (float(text) == 100.0) and (part == 0) == (float(text) == 0.0):
            return f"{text} %"
    return f"{f:.6f} %"


def agreement_words(row: Mapping[str, Any], *, engine: str | None = None,
                    scene: str | None = None, against: str = "the analytic map") -> str:
    """A map agreement in words, from a row with ``cells`` (compared: ok in both maps),
    ``differ`` (of those, different verdicts), ``kappa``; optionally ``not_ok`` (cells not ok,
    left out), ``only_first`` / ``only_second`` (cells held by one map only, left out),
    ``near_boundary``, ``disagree_near_boundary``, ``disagree_away``, ``grid``. ``against``:
    the map compared with, in words."""
    n = int(_num(row.get("cells")) if math.isfinite(_num(row.get("cells"))) else 0)
    differ = row.get("differ")
    if differ is None or not math.isfinite(_num(differ)):
        frac = _num(row.get("agree_fraction"))
        differ = int(round(n * (1.0 - frac))) if math.isfinite(frac) else 0
    differ = int(_num(differ))
    kappa = _num(row.get("kappa"))
    who = " ".join(x for x in (engine, f"on {scene}" if scene else None,
                               f"({row['grid']} cells)" if row.get("grid") else None) if x)
    text = (f"{who + ': ' if who else ''}{differ} of {n} cells differ from {against} "
            f"({share(n - differ, n)} agree), Cohen's kappa "
            + (f"{kappa:.3f}" if math.isfinite(kappa) else
               "undefined (every cell has one verdict in both maps)"))
    near, dn, da = (row.get(k) for k in ("near_boundary", "disagree_near_boundary",
                                         "disagree_away"))
    if near is not None and math.isfinite(_num(near)):
        text += (f"; {int(_num(dn))} of the differing cells lie within the boundary's margin "
                 f"({int(_num(near))} cells there), {int(_num(da))} away from it")
    left = []
    bad = _num(row.get("not_ok"))
    if math.isfinite(bad) and bad > 0:
        left.append(f"{int(bad)} runs not ok, left out")
    o1, o2 = _num(row.get("only_first")), _num(row.get("only_second"))
    if (math.isfinite(o1) and o1 > 0) or (math.isfinite(o2) and o2 > 0):
        left.append(f"compared on the cells both maps hold ({int(o1 or 0)} only in the "
                    f"first, {int(o2 or 0)} only in the second, left out)")
    return text + ("; " + "; ".join(left) if left else "")

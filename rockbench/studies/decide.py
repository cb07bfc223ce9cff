"""The rules of a decision, pure: when a setting of an engine is accepted for a tolerance, and
when two costs are a tie. Numbers in, verdicts out, so that the rules are tested on controlled
curves.

* :func:`convergence` - on one error curve (worst error against the precision knob), the
  largest step within the tolerance whose next finer step is within it too (the error falls,
  or the two agree within :data:`CONVERGED_FRACTION` of the tolerance); a lucky step is not
  accepted; an error that grows at a finer step is "erratic";
The search that applies them is :mod:`rockbench.studies.search`.
"""

from __future__ import annotations

import math
from typing import Any, Sequence


from ..errors import ParameterError
from ..result import as_float

__all__ = ["TIE", "CONVERGED_FRACTION", "ERRATIC_FACTOR", "ERRATIC_FLOOR", "convergence"]

#: Engines whose cost is within this factor of the cheapest are a tie (CPU time of one setting
#: moved by up to 40 % between sweeps 35 minutes apart on the shared machine:
#: docs/choosing.md).
TIE = 1.25
#: Convergence: two successive steps agreeing within this fraction of the tolerance are
#: converged, whatever the direction of the change; an error that grows by more than
#: ERRATIC_FACTOR at a finer step (and exceeds ERRATIC_FLOOR x the tolerance) is erratic.
CONVERGED_FRACTION = 0.25
ERRATIC_FACTOR = 1.5
ERRATIC_FLOOR = 0.5


def convergence(errors: Sequence[tuple[float, float]], tolerance: float) -> dict[str, Any]:
    """The convergence rule on one error curve.

    ``errors``: (step, worst error [-]) pairs (any order; sorted here from the largest step
    down). Returns ``{"index": i or None, "step": the accepted step or None, "status",
    "erratic": bool, "curve": str, "note": str}``: the accepted step is the largest one within
    ``tolerance`` whose next finer step is also within it and either no larger (the error falls
    as the step falls) or within :data:`CONVERGED_FRACTION` x tolerance of it (converged).
    status: "converged", "unconfirmed" (within the tolerance only at the finest step run: a
    finer one is needed), "lucky steps only" (within it only at steps whose finer neighbour is
    not) or "cannot reach". ``erratic``: the error grows by more than :data:`ERRATIC_FACTOR` at
    a finer step and above :data:`ERRATIC_FLOOR` x tolerance somewhere on the curve."""
    pts = sorted(((float(s), float(e)) for s, e in errors), key=lambda p: -p[0])
    curve = ", ".join(f"{_pct(e)} at {s:g}" for s, e in pts)
    erratic = any(e2 > ERRATIC_FACTOR * e1 and e2 > ERRATIC_FLOOR * tolerance
                  for (_, e1), (_, e2) in zip(pts, pts[1:]) if math.isfinite(e1))
    out = {"index": None, "step": None, "status": "cannot reach", "erratic": erratic,
           "curve": curve, "note": ""}
    lucky = []
    for i, (s, e) in enumerate(pts):
        if not e <= tolerance:
            continue
        if i + 1 == len(pts):
            out["status"] = "unconfirmed"
            out["note"] = f"within the tolerance at {s:g}, the finest step run: no finer " \
                          "step confirms it"
            break
        e2 = pts[i + 1][1]
        if e2 <= tolerance and (e2 <= e or abs(e2 - e) <= CONVERGED_FRACTION * tolerance):
            out.update(index=i, step=s, status="converged",
                       note=f"next finer step {pts[i + 1][0]:g}: {_pct(e2)}")
            break
        lucky.append(s)
    if out["status"] != "converged" and lucky:
        out["note"] = (out["note"] + "; " if out["note"] else "") + \
            "lucky step(s) not accepted: " + ", ".join(f"{s:g}" for s in lucky)
        if out["status"] == "cannot reach":
            out["status"] = "lucky steps only"
    if erratic:
        out["note"] = (out["note"] + "; " if out["note"] else "") + \
            f"erratic error against the step ({curve})"
    return out


def _pct(e: float) -> str:
    e = as_float(e)
    return "not run" if math.isnan(e) else "inf" if not math.isfinite(e) else f"{100 * e:.3g} %"


def _fmt_err(e: float) -> str:
    return "inf (a run not ok or a wrong verdict)" if not math.isfinite(e) else f"{100 * e:.3g} %"


def _check_tolerance(tolerance: Any) -> float:
    try:
        t = float(tolerance)
    except (TypeError, ValueError):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02"
                             ) from None
    if not (0.0 < t < 1.0):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02")
    return t

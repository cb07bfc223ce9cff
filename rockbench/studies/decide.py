"""The rules of a decision, pure: which setting of an engine meets a tolerance, and which
engine to use. Tables in, rankings out, so that the rules are tested on controlled tables and
every caller (``rockbench advise``, the report) decides the same way.

* :func:`convergence` - on one error curve (worst error against the precision knob), the
  largest step within the tolerance whose next finer step is within it too (the error falls,
  or the two agree within :data:`CONVERGED_FRACTION` of the tolerance); a lucky step is not
  accepted; an error that grows at a finer step is "erratic";
* :func:`held_out_stats` - how a setting did on the held-out part of the evidence;
* :func:`decide` - the ranking of engines for one tolerance from a tradeoff table.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..result import as_float

__all__ = ["TIE", "CONVERGED_FRACTION", "ERRATIC_FACTOR", "ERRATIC_FLOOR", "convergence",
           "held_out_stats", "decide"]

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


def held_out_stats(runs: pd.DataFrame, tolerance: float) -> dict[str, Any]:
    """On the held-out runs of one setting (rows of :data:`rockbench.studies.tradeoff.RUN_COLUMNS`):
    ``n`` (runs counted: not a NaN error), ``n_all`` (all), ``beyond`` (fraction > tolerance),
    ``beyond2`` (count > 2 x tolerance), ``wrong_verdicts`` (away from the boundary, or not ok),
    ``near_disagree`` (near the boundary: reported, not counted), ``outside_band`` (records)."""
    h = runs[runs["part"] == "held-out"] if "part" in runs else runs.iloc[0:0]
    e = h["error"].to_numpy(dtype=float)
    counted = e[~np.isnan(e)]
    va = h["verdict_agrees"].astype(object).where(h["verdict_agrees"].notna(), True)
    near = h["near_boundary"].fillna(False).astype(bool)
    return {"n": int(counted.size), "n_all": int(len(h)),
            "beyond": float(np.mean(counted > tolerance)) if counted.size else math.nan,
            "beyond2": int(np.sum(counted > 2 * tolerance)),
            "wrong_verdicts": int(np.sum(np.isinf(counted))),
            "near_disagree": int((near & ~va.astype(bool)).sum()),
            "outside_band": int((h["kind"].eq("record") & h["in_band"].eq(False)).sum())
            if "in_band" in h else 0}


def _pct(e: float) -> str:
    e = as_float(e)
    return "not run" if math.isnan(e) else "inf" if not math.isfinite(e) else f"{100 * e:.3g} %"


def _fmt_err(e: float) -> str:
    return "inf (a run not ok or a wrong verdict)" if not math.isfinite(e) else f"{100 * e:.3g} %"


def _variant(label: str, knob: str = "dt") -> str:
    """The setting label without its precision knob (the contact variant): "" for defaults."""
    return ",".join(p for p in str(label).split(",") if not p.startswith(f"{knob}="))


def decide(table: pd.DataFrame, tolerance: float, *, engines: Sequence[str] | None = None,
           unavailable: dict[str, str] | None = None, knobs: dict[str, str] | None = None,
           absent: Mapping[str, tuple[str, str]] | None = None) -> list[dict[str, Any]]:
    """The ranking of :class:`Advice` from a tradeoff table (:data:`rockbench.studies.tradeoff.
    TABLE_COLUMNS`: at least engine, setting, dt, worst_error [, worst_error_choice,
    worst_error_heldout], cpu_per_sim_s, real_time_factor).

    Per engine and contact variant (the setting label without the knob): the error curve on
    the choice part (``worst_error_choice``, else ``worst_error``) goes through
    :func:`convergence`; the accepted setting meets the tolerance when its held-out worst error
    (``worst_error_heldout``; a table without it: the choice error) is within it. Per engine
    the cheapest variant that meets it (ties of cost: the larger step) is kept; an engine without
    one gets its most informative failure: "fails held-out" (accepted, refused by the held-out
    part), "unconfirmed", "lucky steps only" or "cannot reach". ``engines``: the engines
    considered (default: those in the table); ``unavailable``: engine -> why it could not run;
    ``absent``: engine -> (state, detail) of registered engines that did not run (their rows
    come last, with that state as the status); ``knobs``: engine -> the name of its precision
    knob (default dt)."""
    tolerance = _check_tolerance(tolerance)
    gone: dict[str, tuple[str, str]] = {n: ("unavailable", why)
                                        for n, why in (unavailable or {}).items()}
    gone.update(absent or {})
    unavailable = {n: why for n, (_, why) in gone.items()}
    knobs = dict(knobs or {})
    names = list(dict.fromkeys(list(engines) if engines is not None else list(table["engine"])))
    for n in unavailable:
        if n not in names:
            names.append(n)
    ce = "worst_error_choice" if "worst_error_choice" in table else "worst_error"
    meets, others, missing = [], [], []
    order = {"fails held-out": 0, "unconfirmed": 1, "lucky steps only": 2, "cannot reach": 3}
    for n in names:
        g = table[table["engine"] == n]
        if n in unavailable or g.empty:
            missing.append({"engine": n, "meets": False,
                            "status": gone.get(n, ("unavailable", ""))[0],
                            "setting": None, "dt": None, "worst_error": None,
                            "worst_error_choice": None, "worst_error_heldout": None,
                            "cpu_per_sim_s": None, "real_time_factor": None,
                            "reason": unavailable.get(n, "not measured"), "erratic": False,
                            "convergence": ""})
            continue
        knob = knobs.get(n, "dt")
        kcol = knob if knob in g else "dt"
        best_meet, best_other = None, None
        for var, gv in g.groupby(g["setting"].map(lambda s: _variant(s, knob)), sort=False):
            gv = gv.sort_values(kcol, ascending=False)
            errs = [(float(r[kcol]), as_float(r[ce])) for _, r in gv.iterrows()]
            errs = [(s, e if not math.isnan(e) else math.inf) for s, e in errs]
            conv = convergence(errs, tolerance)
            base = {"engine": n, "variant": var, "erratic": conv["erratic"],
                    "convergence": conv["note"], "curve": conv["curve"]}
            if conv["index"] is not None:
                r = gv.iloc[conv["index"]]
                held = as_float(r.get("worst_error_heldout", math.nan)) \
                    if "worst_error_heldout" in gv else as_float(r[ce])
                row = {**base, **_row(r, ce), "worst_error_heldout": held}
                if math.isnan(held):
                    row.update(meets=False, status="unconfirmed",
                               reason="accepted on the choice part; the held-out part was "
                                      "not run")
                elif held <= tolerance:
                    row.update(meets=True, status="meets", reason="")
                else:
                    row.update(meets=False, status="fails held-out",
                               reason=f"chosen {r['setting']} (choice worst "
                                      f"{_fmt_err(row['worst_error_choice'])}) but held-out "
                                      f"worst {_fmt_err(held)} > tolerance "
                                      f"{100 * tolerance:g} %")
            else:
                fin = gv.assign(_e=[e for _, e in errs]).sort_values(["_e", "cpu_per_sim_s"])
                r = fin.iloc[0]
                row = {**base, **_row(r, ce),
                       "worst_error_heldout": as_float(r.get("worst_error_heldout", math.nan)),
                       "meets": False, "status": conv["status"]}
                tried = ", ".join(str(s) for s in gv["setting"])
                row["reason"] = (f"{conv['status']}: best choice error "
                                 f"{_fmt_err(row['worst_error_choice'])} at {r['setting']}, "
                                 f"tolerance {100 * tolerance:g} % (tried: {tried})"
                                 + (f"; {conv['note']}" if conv["note"] else ""))
            if row["meets"]:
                if best_meet is None or (row["cpu_per_sim_s"], -row["dt"]) < (
                        best_meet["cpu_per_sim_s"], -best_meet["dt"]):
                    best_meet = row
            elif best_other is None or (order.get(row["status"], 9),
                                        row["worst_error_choice"]) < (
                    order.get(best_other["status"], 9), best_other["worst_error_choice"]):
                best_other = row
        if best_meet is not None:
            meets.append(best_meet)
        else:
            others.append(best_other)
    meets.sort(key=lambda r: (r["cpu_per_sim_s"], -r["dt"]))
    for r in meets:   # CPU time moves by a few percent between measurements: call it a tie
        r["tie_with_cheapest"] = r["cpu_per_sim_s"] <= TIE * meets[0]["cpu_per_sim_s"]
    others.sort(key=lambda r: (order.get(r["status"], 9), r["worst_error_choice"],
                               r["cpu_per_sim_s"]))
    return meets + others + missing


def _row(r: pd.Series, ce: str) -> dict[str, Any]:
    return {"setting": str(r["setting"]), "dt": float(r["dt"]),
            "worst_error": as_float(r.get("worst_error", r[ce])),
            "worst_error_choice": as_float(r[ce]),
            "cpu_per_sim_s": as_float(r["cpu_per_sim_s"]),
            "real_time_factor": as_float(r["real_time_factor"]),
            "build_cpu_s": as_float(r.get("build_cpu_s", math.nan)),
            "warmup_cpu_s": as_float(r.get("warmup_cpu_s", math.nan)),
            "near_disagree": int(as_float(r.get("near_disagree", 0)) or 0)}


def _check_tolerance(tolerance: Any) -> float:
    try:
        t = float(tolerance)
    except (TypeError, ValueError):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02"
                             ) from None
    if not (0.0 < t < 1.0):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02")
    return t

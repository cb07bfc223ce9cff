"""The outcomes of the decision's search (:mod:`rockbench.studies.search`): an engine's fate at a
tolerance when it does not meet it, the table of outcomes ranked per tolerance (the cheapest
confirmed first; among those as cheap within the machine's noise, :data:`rockbench.studies.
decide.TIE`, the most accurate), and what to run next where nothing meets a tolerance."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from ..fates import ORDER
from .decide import TIE, convergence

__all__ = ["finer", "fate", "outcome_rows", "tie_order", "next_step", "worst_both"]


def finer(knob: str, value: float) -> float | None:
    """The next value past the end of a ladder (a finest value within the tolerance is
    confirmed by one finer): half the time step, a tenth of an accuracy."""
    v = value / 2 if knob == "dt" else value / 10
    return v if v >= 1e-6 or knob != "dt" else None


def fate(n, knob, t, rungs, failed, held_err, dearer) -> dict[str, Any]:
    """The fate of an engine that does not meet ``t``, with the closest it came."""
    if not rungs:
        return {"status": "dearer" if dearer else "not reached", "setting": None,
                "value": math.nan, "worst_error_choice": math.nan,
                "worst_error_heldout": math.nan, "cpu_per_sim_s": math.nan,
                "reason": dearer or "not run", "erratic": False}
    pts = [(r.value, r.choice_error) for r in rungs]
    conv = convergence(pts, t)
    fin = [r for r in rungs if math.isfinite(r.choice_error)]
    closest = min(fin, key=lambda r: r.choice_error) if fin else rungs[-1]
    base = {"setting": closest.setting, "value": closest.value,
            "worst_error_choice": closest.choice_error,
            "worst_error_heldout": closest.held_error, "cpu_per_sim_s": closest.cost,
            "erratic": conv["erratic"]}
    curve = ", ".join(f"{100 * r.choice_error:.3g} % at {knob}={r.value:g}"
                      if math.isfinite(r.choice_error) else f"not ok at {knob}={r.value:g}"
                      for r in rungs)
    if failed[t]:
        v = failed[t][-1]                 # the finest setting that converged and failed
        e = held_err[v][0]
        r = next(r for r in rungs if r.value == v)
        return {**base, "status": "fails held-out", "setting": r.setting, "value": v,
                "worst_error_choice": r.choice_error, "cpu_per_sim_s": r.cost,
                "worst_error_heldout": e,
                "reason": f"converged at {knob}={v:g} but {100 * e:.3g} % held out > "
                          f"{100 * t:g} %" + (f"; {dearer}" if dearer else "")
                          + f" (choice: {curve})"}
    if dearer:
        return {**base, "status": "dearer", "reason": f"{dearer} (choice: {curve})"}
    if not fin:
        return {**base, "status": "diverged", "reason": f"no setting ran ok ({curve})"}
    if any(r.choice_error <= t for r in fin):
        return {**base, "status": "not converged",
                "reason": f"{conv['status']}: {conv['note'] or curve}"}
    return {**base, "status": "not reached", "reason": f"choice: {curve}"}


def outcome_rows(tols, names, states, outcome) -> pd.DataFrame:
    rows = []
    order = {f: k for k, f in enumerate(ORDER)}
    for t in tols:
        group = []
        for n in names:
            o = dict(outcome.get((t, n), {"status": "not reached", "reason": "not run"}))
            group.append({"tolerance": t, "engine": n, **o})
        for r in states:
            if r["state"] != "ran":
                group.append({"tolerance": t, "engine": r["name"], "status": r["state"],
                              "reason": r["detail"]})
        meets = tie_order(sorted([g for g in group if g["status"] == "meets"],
                                  key=lambda g: (g["cpu_per_sim_s"], -g.get("value", 0))))
        rest = sorted([g for g in group if g["status"] != "meets"],
                      key=lambda g: (order.get(g["status"], 9),
                                     g.get("worst_error_choice", math.inf)
                                     if g.get("worst_error_choice") == g.get(
                                         "worst_error_choice") else math.inf))
        for k, g in enumerate(meets + rest, 1):
            g["rank"] = k
            g["recommended"] = k == 1 and g["status"] == "meets"
            g["tie_with_cheapest"] = bool(g["status"] == "meets" and meets and g[
                "cpu_per_sim_s"] <= TIE * min(m["cpu_per_sim_s"] for m in meets))
            rows.append(g)
    cols = ["tolerance", "rank", "engine", "status", "recommended", "setting", "value",
            "worst_error_choice", "worst_error_heldout", "cpu_per_sim_s", "erratic",
            "tie_with_cheapest", "reason"]
    df = pd.DataFrame(rows)
    for c in cols:
        if c not in df:
            df[c] = math.nan
    return df[cols]


def worst_both(g: dict[str, Any]) -> float:
    """The worst of an outcome's choice and held-out errors (NaN parts ignored)."""
    e = [float(g.get(k, math.nan)) for k in ("worst_error_choice", "worst_error_heldout")]
    e = [x for x in e if math.isfinite(x)]
    return max(e) if e else math.inf


def tie_order(meets: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Outcomes that meet a tolerance, cheapest first, except that those as cheap as the
    cheapest within the machine's noise (:data:`TIE`) come first most accurate first (their
    worst error, choice or held out): the recommendation among a tie does not flip with the
    load of the machine, and it is the more accurate of equals."""
    if not meets:
        return meets
    floor = meets[0]["cpu_per_sim_s"]
    tie = [g for g in meets if g["cpu_per_sim_s"] <= TIE * floor]
    rest = [g for g in meets if g["cpu_per_sim_s"] > TIE * floor]
    return sorted(tie, key=lambda g: (worst_both(g), g["cpu_per_sim_s"])) + rest


def next_step(t, rows, knobs, scene_arg: str, sim_total: float, size: str,
               vertical: float = 0.0, overhead: float = 1.0,
               finest: dict[str, tuple[float, float]] | None = None
               ) -> dict[str, Any] | None:
    """When nothing meets ``t``: what to run next - the setting one finer than the finest
    each engine ran (``finest``: engine -> (value, CPU s per simulated s); else the value of
    its outcome row), of the engine whose next step is the cheapest among those that came
    within ``t`` on the choice part (else of the one that came closest) - and an estimate of
    what running it (choice and held-out) costs [CPU s]: that rung's cost scaled by the step
    ratio, times the search's measured overhead around its runs (builds, warm-ups, pools)."""
    g = rows[np.isclose(rows["tolerance"].astype(float), t)]
    if (g["status"] == "meets").any():
        return None
    cand = g[g["status"].isin(["fails held-out", "not converged", "not reached", "dearer",
                               "budget ended"])]
    cand = cand[np.isfinite(cand["worst_error_choice"].astype(float))]
    steps = []
    for _, r in cand.iterrows():
        knob = knobs.get(r["engine"], "dt")
        last, cost = (finest or {}).get(r["engine"],
                                        (float(r["value"]), float(r["cpu_per_sim_s"])))
        v = finer(knob, last)
        if v is None:
            continue
        per = cost * ((last / v) if knob == "dt" else 1.0)
        steps.append((float(r["worst_error_choice"]) > t,
                      per if math.isfinite(per) else math.inf,
                      float(r["worst_error_choice"]), r["engine"], knob, v, per))
    if not steps:
        return None
    if any(not s[0] for s in steps):       # some came within t: the cheapest next step
        _, _, _, eng, knob, v, per = min(s for s in steps if not s[0])
    else:                                  # none did: the closest one's
        _, _, _, eng, knob, v, per = min(steps, key=lambda s: s[2])
    cmd = (f"rockbench advise {scene_arg} --tolerance {t:g} --engine {eng} "
           f"--setting {eng}.{knob}={v:g}"
           + ("" if size == "default" else f" --{size}" if size != "quick" else " --quick")
           + (f" --vertical {vertical:g}" if vertical else ""))
    return {"engine": eng, "setting": f"{knob}={v:g}", "knob": knob, "value": v,
            "cpu_s": per * sim_total * overhead if math.isfinite(per) else math.nan,
            "command": cmd}

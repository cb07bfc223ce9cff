"""The first screen of the campaign page: the decision. One sentence per tolerance (the engine
and setting to use, at what cost, with what error on the cases the choice never saw), one row
per engine (its cheapest setting within each tolerance, steady cost, worst errors, map agreement,
eta error, where it breaks), and the work-precision plot. Reads tables only; everything it says
is a number from them.

Inputs are the campaign's tables (``docs/report.md``): ``advice`` (advice.csv: tolerance,
engine, status, setting, worst_error, cpu_per_sim_s [, held_out_worst_error]), ``agreement``
(map_agreement.csv), ``eta_summary`` (eta_summary.csv), ``breaks``
(stress_breaking_points.csv) and ``tradeoff`` (tradeoff.csv, for the plot).
"""

from __future__ import annotations

import math
from html import escape
from typing import Any, Mapping, Sequence

import pandas as pd

from ..result import as_float

__all__ = ["decision_sentences", "decision_table", "decision_html", "evidence_note", "pct"]

#: Advice statuses of a setting within the tolerance on the chosen cases that is not
#: recommended, and why (rockbench.studies.advise.decide).
_ALMOST = {"unconfirmed": "unconfirmed: no finer step was run, or the finer one misses the "
                          "tolerance (docs/choosing.md, convergence)",
           "fails held-out": "it fails on the held-out cases",
           "lucky steps only": "only at isolated steps: its error is erratic against dt"}

#: Columns that may hold the error on held-out cases, in order of preference.
_HELD_OUT = ("held_out_worst_error", "heldout_worst_error", "confirm_worst_error")


def pct(x: Any, digits: int = 2) -> str:
    """A fraction as a percentage ("1.68 %"); "n/a" when missing."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return "n/a"
    if not math.isfinite(v):
        return "n/a" if math.isnan(v) else "∞"
    return f"{100.0 * v:.{digits}f} %"


def _held_out(row: Mapping[str, Any]) -> float:
    for c in _HELD_OUT:
        if c in row and not pd.isna(row[c]):
            return as_float(row[c])
    return math.nan


def _meets(g: pd.DataFrame) -> pd.DataFrame:
    return g[g["status"].astype(str) == "meets"]


def decision_sentences(advice: pd.DataFrame, scene: str) -> list[str]:
    """One sentence per tolerance: what to use on ``scene``, its cost and errors; or that no
    engine reaches it and which comes closest."""
    out: list[str] = []
    if advice is None or not len(advice):
        return ["No engine besides the analytic reference ran: there is nothing to choose."]
    for tol, g in advice.groupby("tolerance", sort=False):
        g = g.sort_values("rank") if "rank" in g else g
        meets = _meets(g)
        if len(meets):
            b = meets.iloc[0]
            ho = _held_out(b)
            conf = (f", {pct(ho)} on held-out cases" if math.isfinite(ho) else "")
            text = (f"For {pct(tol, 1 if tol < 0.01 else 0)} on {scene}: use {b['engine']} at "
                    f"{b['setting']} ({as_float(b['cpu_per_sim_s']):.3g} CPU s per simulated s; "
                    f"worst error {pct(b['worst_error'])} on the chosen cases{conf})")
            if len(meets) > 1:
                n = meets.iloc[1]
                text += (f"; next cheapest: {n['engine']} at {n['setting']} "
                         f"({as_float(n['cpu_per_sim_s']):.3g} CPU s/s)")
            out.append(text + ".")
        else:
            t = pct(tol, 1 if tol < 0.01 else 0)
            best = g.assign(_e=g["worst_error"].astype(float)).sort_values("_e")
            best = best[best["_e"].notna() & (best["_e"] < math.inf)]
            near = best[best["status"].astype(str).isin(_ALMOST)] if len(best) else best
            if len(near):
                b = near.iloc[0]
                ho = _held_out(b)
                out.append(f"For {t} on {scene}: no setting is confirmed. {b['engine']} at "
                           f"{b['setting']} has a worst error of {pct(b['worst_error'])} on the "
                           "chosen cases" + (f" and {pct(ho)} held out" if math.isfinite(ho)
                                             else "")
                           + f", but {_ALMOST[str(b['status'])]}.")
            elif len(best):
                b = best.iloc[0]
                out.append(f"For {t} on {scene}: no engine "
                           f"reaches it at the settings tried; closest: {b['engine']} "
                           f"({pct(b['worst_error'])} at {b['setting']}).")
            else:
                out.append(f"For {pct(tol, 1 if tol < 0.01 else 0)} on {scene}: no engine "
                           "reaches it at the settings tried.")
    return out


def _where_it_breaks(breaks: pd.DataFrame | None, engine: str) -> str:
    if breaks is None or not len(breaks) or "engine" not in breaks:
        return ""
    b = breaks[breaks["engine"] == engine]
    if not len(b):
        return "nowhere tried"
    parts = []
    for _, r in b.iterrows():
        v = r.get("value")
        try:
            v = f"{float(v):g}"
        except (TypeError, ValueError):
            v = str(v)
        parts.append(f"{r.get('axis')} {v} ({r.get('class')})")
    return "; ".join(parts)


def decision_table(advice: pd.DataFrame, *, agreement: pd.DataFrame | None = None,
                   eta_summary: pd.DataFrame | None = None,
                   breaks: pd.DataFrame | None = None,
                   scene: str | None = None) -> pd.DataFrame:
    """One row per engine: for each tolerance its cheapest setting meeting it (or "not
    reached") with the steady cost [CPU s per simulated s] and worst errors [%], then map
    agreement [%] and Cohen's kappa on ``scene``'s map, the worst free-rocking eta error [%],
    and where it first breaks (stability sweep). Values are display strings."""
    if advice is None or not len(advice):
        return pd.DataFrame()
    engines = list(dict.fromkeys(advice["engine"]))
    rows = []
    for e in engines:
        row: dict[str, Any] = {"engine": e}
        for tol, g in advice[advice["engine"] == e].groupby("tolerance", sort=False):
            t = pct(tol, 1 if tol < 0.01 else 0)
            m = _meets(g)
            if len(m):
                r = m.iloc[0]
                ho = _held_out(r)
                row[f"within {t}"] = (f"{r['setting']}: {as_float(r['cpu_per_sim_s']):.3g} CPU s/s, "
                                      f"worst {pct(r['worst_error'])}"
                                      + (f", held-out {pct(ho)}" if math.isfinite(ho) else ""))
            else:
                r = g.iloc[0]
                err = as_float(r.get("worst_error"))
                st = str(r.get("status", ""))
                word = st if st in _ALMOST else "not reached"
                row[f"within {t}"] = (word + (f" (best {pct(err)} at {r['setting']})"
                                              if math.isfinite(err) and st in _ALMOST else
                                              f" (best {pct(err)})" if math.isfinite(err)
                                              else ""))
        if agreement is not None and len(agreement):
            a = agreement[agreement["backend"] == e]
            if scene is not None and "scene" in a and (a["scene"] == scene).any():
                a = a[a["scene"] == scene]
            if len(a):
                row["map agreement"] = (f"{pct(a['agree_fraction'].astype(float).min(), 1)}, "
                                        f"kappa {a['kappa'].astype(float).min():.3f}")
            else:
                row["map agreement"] = "no map (report --full measures it)"
        if eta_summary is not None and len(eta_summary):
            s = eta_summary[(eta_summary["backend"] == e)]["rel_error"].astype(float).abs()
            if len(s.dropna()):
                row["free-rocking eta error (worst, every scene)"] = pct(s.max())
        w = _where_it_breaks(breaks, e)
        if w:
            row["breaks first at"] = w
        rows.append(row)
    return pd.DataFrame(rows)


def evidence_note(tradeoff: pd.DataFrame | None, *, size: str = "quick") -> str:
    """What the decision rests on: how many cases were chosen on and held out (columns
    n_choice, n_heldout of the work-precision table) of which ``size`` of evidence ("quick",
    "default", "full"), and what a larger set is."""
    if tradeoff is None or not len(tradeoff) or "n_choice" not in tradeoff:
        return ""
    nc, nh = int(tradeoff["n_choice"].max()), int(tradeoff["n_heldout"].max())
    more = {"quick": " `rockbench advise SCENE` chooses on the default evidence and `--full` "
                     "on the full one: a setting confirmed here can still fail there (a "
                     "small-uplift record is the usual culprit, docs/choosing.md).",
            "default": " `rockbench advise SCENE --full` chooses on the full evidence and "
                       "adds a search of the contact settings (docs/choosing.md)."
            }.get(size, "")
    return (f"Evidence: the {size} set of the scene's own cases, {nc} to choose on and {nh} "
            f"held out to confirm (free rocking, pulses near and away from the boundary, "
            f"records).{more}")


def decision_html(advice: pd.DataFrame, *, scene: str, structure: str = "",
                  agreement: pd.DataFrame | None = None,
                  eta_summary: pd.DataFrame | None = None, breaks: pd.DataFrame | None = None,
                  work_precision_html: str = "", notes: Sequence[str] = (),
                  structures: pd.DataFrame | None = None) -> str:
    """The decision section: sentences, the per-engine table, the work-precision figure;
    ``notes``: lines under the table (e.g. :func:`evidence_note`); ``structures``: the fields
    of the scenes the report is about (``rockbench.campaign.plan.structure_table``), shown
    collapsed under the "About" line."""
    lead = decision_sentences(advice, scene)
    parts = ['<div id="decision">']
    if structure:
        parts.append(f'<p class="lead">About: {escape(structure)}</p>')
    if structures is not None and len(structures):
        from .html import html_table

        parts.append("<details><summary>The structures, field by field (SI units; "
                     "docs/scenes.md)</summary>" + html_table(
                         structures, list(structures.columns), graded=False, scroll=True)
                     + "</details>")
    parts.append("<ul>" + "".join(f"<li>{escape(s)}</li>" for s in lead) + "</ul>")
    tab = decision_table(advice, agreement=agreement, eta_summary=eta_summary, breaks=breaks,
                         scene=scene)
    if len(tab):
        head = "".join(f"<th class=\"txt\">{escape(c)}</th>" for c in tab.columns)
        body = "".join("<tr>" + "".join(
            f"<td class=\"txt\">{escape('' if pd.isna(v) else str(v))}</td>" for v in r)
            + "</tr>" for r in tab.itertuples(index=False))
        parts.append(f'<table id="decision-table"><thead><tr>{head}</tr></thead>'
                     f"<tbody>{body}</tbody></table>")
        parts.append("<p><small>Cost: process CPU seconds per simulated second, steady state "
                     "(docs/choosing.md); errors: worst relative error against the analytic "
                     "model; map agreement: share of equal overturning verdicts and Cohen's "
                     "kappa; breaks: first value along each stability axis where the engine is "
                     "off by more than 5 %, diverges or is invalid.</small></p>")
    for n in notes:
        parts.append(f"<p>{escape(n)}</p>")
    parts.append(work_precision_html)
    parts.append("</div>")
    return "\n".join(parts)

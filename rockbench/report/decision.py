"""The first screen of the campaign page: the decision. One sentence per tolerance (the engine
and setting to use, at what cost, with what error on the cases the choice never saw; or why no
engine is confirmed, and what to run next), one row per engine (its fate at each tolerance in
the words of :data:`rockbench.fates.FATES`, its map agreement, eta error, where it breaks), and
the work-precision plot. Reads tables only; every sentence is rendered from them, so a sentence
cannot say what its table does not.

Inputs are the campaign's tables (``docs/report.md``): ``advice`` (advice.csv: tolerance, rank,
engine, status, recommended, setting, worst_error_choice, worst_error_heldout, cpu_per_sim_s,
reason), ``agreement`` (map_agreement.csv), ``eta_summary`` (eta_summary.csv), ``breaks``
(stress_breaking_points.csv), ``tradeoff`` (tradeoff.csv, for the plot), and the search's
``next_steps`` (tolerance -> what to run next) and ``coverage`` (the held-out part's cases).
"""

from __future__ import annotations

import math
from html import escape
from typing import Any, Mapping, Sequence

import pandas as pd

from ..fates import ABSENT, ALMOST, CONFIRMED, FATES
from ..result import as_float

__all__ = ["decision_sentences", "decision_table", "decision_html", "evidence_note", "pct",
           "tol_text", "model_sentence"]


def pct(x: Any, digits: int = 2) -> str:
    """A fraction as a percentage ("1.68 %"); "n/a" when missing."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return "n/a"
    if not math.isfinite(v):
        return "n/a" if math.isnan(v) else "∞"
    return f"{100.0 * v:.{digits}f} %"


def tol_text(tol: Any) -> str:
    """A tolerance as the page writes it: "2 %", "0.5 %"."""
    return f"{100 * float(tol):g} %"


def _cost(x: Any) -> str:
    v = as_float(x)
    return f"{v:.3g} CPU s per simulated s" if math.isfinite(v) else "cost not measured"


def _by_tolerance(advice: pd.DataFrame):
    for tol, g in advice.groupby("tolerance", sort=False):
        yield float(tol), (g.sort_values("rank") if "rank" in g else g)


def model_sentence(model: Mapping[str, Any], advice: pd.DataFrame | None) -> str:
    """The analytic model's place in the decision: inside its validity (``model["holds"]``,
    e.g. "PGA <= mu g = 1 g, no sliding onset, contact kept") it is the reference and costs
    ``model["cpu_per_sim_s"]`` [CPU s per simulated s], compared with the cheapest confirmed
    engine setting of the advice; outside it only the engines answer."""
    cost = as_float(model.get("cpu_per_sim_s"))
    text = (f"Inside the analytic model's validity ({model['holds']}) the analytic model is the "
            f"exact reference at {_cost(cost)}")
    if advice is not None and len(advice) and math.isfinite(cost) and cost > 0:
        ok = advice[advice["status"].astype(str) == CONFIRMED]
        c = pd.to_numeric(ok["cpu_per_sim_s"], errors="coerce").dropna()
        if len(c):
            r = float(c.min()) / cost
            text += f" (the cheapest confirmed engine setting costs {r:.3g} times as much)"
    return text + ("; outside it (a base or beam that slides, a structure that leaves the "
                   "ground) only the engines answer, and no engine is checked against it there.")


def decision_sentences(advice: pd.DataFrame, scene: str, *,
                       next_steps: Mapping[float, Mapping[str, Any] | None] | None = None,
                       model: Mapping[str, Any] | None = None) -> list[str]:
    """One sentence per tolerance, rendered from the advice table: what to use on ``scene``,
    its cost and errors; or, when none meets it, which engine reaches it without being
    confirmed and why; "no engine reaches" only when none does; and what to run next
    (``next_steps``). With ``model`` (:func:`model_sentence`), the analytic model's place
    first."""
    out: list[str] = [model_sentence(model, advice)] if model else []
    if advice is None or not len(advice):
        return out + ["No engine besides the analytic reference ran: there is nothing to "
                      "choose."]
    for tol, g in _by_tolerance(advice):
        t = tol_text(tol)
        st = g["status"].astype(str)
        meets = g[st == CONFIRMED]
        if len(meets):
            b = meets.iloc[0]
            text = (f"Within {t} on {scene}: use {b['engine']} at {b['setting']} "
                    f"({_cost(b['cpu_per_sim_s'])}; worst error {pct(b['worst_error_choice'])} "
                    f"on the cases it was chosen on, {pct(b['worst_error_heldout'])} on the "
                    f"held-out ones)")
            ties = meets.iloc[1:]
            ties = ties[ties["tie_with_cheapest"].fillna(False).astype(bool)] \
                if "tie_with_cheapest" in ties else ties.iloc[0:0]
            if len(ties):
                text += ("; as cheap within the machine's noise: " + ", ".join(
                    f"{r['engine']} at {r['setting']}" for _, r in ties.iterrows()))
            out.append(text + ".")
            continue
        err = pd.to_numeric(g["worst_error_choice"], errors="coerce")
        almost = g[st.isin(ALMOST) | ((st == "budget ended") & (err <= tol))]
        if len(almost):
            parts = []
            for _, r in almost.iterrows():
                if r["status"] == "fails held-out":
                    parts.append(f"{r['engine']} reaches it at {r['setting']} on the chosen "
                                 f"cases ({pct(r['worst_error_choice'])}) but misses it on "
                                 f"the held-out ones ({pct(r['worst_error_heldout'])})")
                elif r["status"] == "budget ended":
                    parts.append(f"{r['engine']} reaches it ({pct(r['worst_error_choice'])} "
                                 f"at {r['setting']}) but the search's CPU budget ended before "
                                 "a finer setting could confirm it")
                else:
                    parts.append(f"{r['engine']} reaches it ({pct(r['worst_error_choice'])} "
                                 f"at {r['setting']}) but is not confirmed: "
                                 f"{FATES['not converged']}")
            text = f"Within {t} on {scene}: no engine is confirmed. " + "; ".join(parts)
        else:
            ran = g[~st.isin(ABSENT)]
            fin = ran[pd.to_numeric(ran["worst_error_choice"], errors="coerce").notna()]
            fin = fin.assign(_e=fin["worst_error_choice"].astype(float)).sort_values("_e")
            fin = fin[fin["_e"] < math.inf]
            text = f"Within {t} on {scene}: no engine reaches it at the settings tried"
            if len(fin):
                b = fin.iloc[0]
                text += f"; closest: {b['engine']} ({pct(b['_e'])} at {b['setting']})"
        nxt = (next_steps or {}).get(tol)
        if nxt:
            text += (f". To try next: {nxt['engine']} at {nxt['setting']}, about "
                     f"{as_float(nxt['cpu_s']):.0f} CPU s")
        out.append(text + ".")
    return out


def _short_reason(reason: Any, limit: int = 48) -> str:
    """The first clause of a reason, at most ``limit`` characters."""
    text = str(reason or "").split(";")[0].strip()
    return text if len(text) <= limit else text[:limit - 1].rstrip() + "…"


def _where_it_breaks(breaks: pd.DataFrame | None, engine: str, *, first_only: bool = False
                     ) -> str:
    """The first value along each stability axis where ``engine`` is not within 5 %, with
    its unit and the real reason (short): "alpha = 0.6 rad: diverged (mechanical energy
    grew ...)"."""
    if breaks is None or not len(breaks) or "engine" not in breaks:
        return ""
    b = breaks[breaks["engine"] == engine]
    if not len(b):
        return "holds at every point tried"
    parts = []
    for _, r in b.iterrows():
        v = r.get("value")
        try:
            v = f"{float(v):g}"
        except (TypeError, ValueError):
            v = str(v)
        name = str(r.get("axis"))
        unit = str(r.get("unit") or "") if pd.notna(r.get("unit")) else ""
        unit = "" if unit in ("-", "") else (" " + unit)
        parts.append(f"{name} = {v}{unit}: {r.get('class')} "
                     f"({_short_reason(r.get('reason'), 30 if first_only else 48)})")
    if first_only and len(parts) > 1:
        return f"{parts[0]} (+{len(parts) - 1} more axes)"
    return "; ".join(parts)


def _cell(r: Mapping[str, Any]) -> str:
    """One engine's fate at one tolerance, short: a page cell."""
    st = str(r["status"])
    if st == CONFIRMED:
        return (f"{r['setting']} · {as_float(r['cpu_per_sim_s']):.2g} CPU s/s · "
                f"{pct(r['worst_error_choice'])} / {pct(r['worst_error_heldout'])}")
    if st in ABSENT:
        return st
    err = as_float(r.get("worst_error_choice"))
    where = f" at {r['setting']}" if isinstance(r.get("setting"), str) else ""
    return st + (f" ({pct(err)}{where})" if math.isfinite(err) else "")


def decision_table(advice: pd.DataFrame, *, agreement: pd.DataFrame | None = None,
                   eta_summary: pd.DataFrame | None = None,
                   breaks: pd.DataFrame | None = None,
                   scene: str | None = None,
                   model: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """One row per engine: its fate at each tolerance (a confirmed setting with its steady
    cost [CPU s per simulated s] and worst errors chosen / held out [%], or the fate's word
    with its closest error), then map agreement on ``scene``'s map (the cells that differ, the
    share, Cohen's kappa), the worst free-rocking eta error [%], and where it first breaks.
    With ``model`` (``cpu_per_sim_s``, ``holds``, ``breaks``), a first row for the analytic
    model: the reference inside its validity, at its cost, and where that validity ends.
    Values are display strings."""
    if advice is None or not len(advice):
        return pd.DataFrame()
    # the engines in the order of the loosest tolerance's ranking (the first column)
    engines = list(dict.fromkeys(advice.sort_values(["tolerance", "rank"],
                                                    ascending=[False, True])["engine"]))
    rows = []
    for e in engines:
        row: dict[str, Any] = {"engine": e}
        for tol, g in _by_tolerance(advice[advice["engine"] == e]):
            row[f"within {tol_text(tol)}"] = _cell(g.iloc[0])
        if agreement is not None and len(agreement):
            a = agreement[agreement["backend"] == e]
            if scene is not None and "scene" in a and (a["scene"] == scene).any():
                a = a[a["scene"] == scene]
            if len(a):
                w = a.iloc[a["agree_fraction"].astype(float).argmin()]
                n, frac = int(as_float(w.get("cells", math.nan)) or 0), as_float(
                    w["agree_fraction"])
                d = as_float(w.get("differ", math.nan))
                differ = int(d) if math.isfinite(d) else (int(round(n * (1 - frac))) if n
                                                          else None)
                row["map agreement"] = (f"{differ} of {n} differ" if differ is not None
                                        else pct(frac, 1)) + f", kappa {as_float(w['kappa']):.3f}"
            else:
                row["map agreement"] = "no map (the maps section says why)"
        if eta_summary is not None and len(eta_summary):
            s = eta_summary[(eta_summary["backend"] == e)]["rel_error"].astype(float).abs()
            if len(s.dropna()):
                row["free-rocking eta error (worst)"] = pct(s.max())
        w = _where_it_breaks(breaks, e, first_only=True)
        if w:
            row["breaks first at"] = w
        rows.append(row)
    if model:
        cost = as_float(model.get("cpu_per_sim_s"))
        first = {"engine": "analytic model"}
        for tol, _ in _by_tolerance(advice):
            first[f"within {tol_text(tol)}"] = (f"exact · {cost:.2g} CPU s/s · inside its "
                                                "validity" if math.isfinite(cost) else
                                                "exact · inside its validity")
        if model.get("breaks"):
            first["breaks first at"] = str(model["breaks"])
        for col in ("map agreement", "free-rocking eta error (worst)"):
            if any(col in r for r in rows):
                first[col] = "the reference"
        rows.insert(0, first)
    return pd.DataFrame(rows)


def evidence_note(tradeoff: pd.DataFrame | None, *, size: str = "quick",
                  coverage: Mapping[str, Any] | None = None, cpu_s: float | None = None) -> str:
    """What the decision rests on: how many cases were chosen on and held out (columns
    n_choice, n_heldout of the work-precision table) of which ``size`` of evidence ("quick",
    "default", "full"); the held-out part's ``coverage`` (counted cases, overturning ones,
    records, near the boundary; a thin part said so); what the search spent (``cpu_s``)."""
    if tradeoff is None or not len(tradeoff) or "n_choice" not in tradeoff:
        return ""
    nc, nh = int(tradeoff["n_choice"].max()), int(tradeoff["n_heldout"].max())
    text = (f"Evidence: the {size} set of the scene's own cases, {nc} to choose on and {nh} "
            f"held out to confirm (free rocking, pulses near and away from the boundary, "
            f"records)")
    if coverage:
        nrec = int(coverage["records"])
        text += (f"; held out: {coverage['counted']} counted ({coverage['overturning']} "
                 f"overturning, {nrec} record{'' if nrec == 1 else 's'}), "
                 f"{coverage['near_boundary']} near the boundary (reported, not counted)")
        if coverage.get("thin"):
            text += f". Note: {coverage['thin']}"
    if cpu_s is not None and math.isfinite(cpu_s):
        text += (f". The search spent {cpu_s:.0f} CPU s" if cpu_s > 0.5 else
                 ". The search's runs were reused from the store (their cost: advice.csv)")
    more = {"quick": " `rockbench advise SCENE` decides on the default evidence and `--full` "
                     "on the full one (with a search of the contact settings).",
            "default": " `rockbench advise SCENE --full` decides on the full evidence and "
                       "adds a search of the contact settings."}.get(size, "")
    return text + "." + more


def _row_cells(values: list[Any], columns: list[str]) -> str:
    """A decision row's cells; equal neighbouring cells of the tolerance columns are one cell
    spanning them (an engine whose setting holds at several tolerances says it once)."""
    out, i = [], 0
    while i < len(values):
        v = "" if pd.isna(values[i]) else str(values[i])
        n = 1
        if columns[i].startswith("within "):
            while (i + n < len(values) and columns[i + n].startswith("within ")
                   and ("" if pd.isna(values[i + n]) else str(values[i + n])) == v):
                n += 1
        span = f' colspan="{n}"' if n > 1 else ""
        out.append(f'<td class="txt"{span}>{escape(v)}</td>')
        i += n
    return "".join(out)


def decision_html(advice: pd.DataFrame, *, scene: str, structure: str = "",
                  agreement: pd.DataFrame | None = None,
                  eta_summary: pd.DataFrame | None = None, breaks: pd.DataFrame | None = None,
                  work_precision_html: str = "", notes: Sequence[str] = (),
                  structures: pd.DataFrame | None = None,
                  next_steps: Mapping[float, Any] | None = None,
                  model: Mapping[str, Any] | None = None) -> str:
    """The decision section: sentences, the per-engine table, the work-precision figure;
    ``notes``: lines under the table (e.g. :func:`evidence_note`); ``structures``: the fields
    of the scenes the report is about (``rockbench.campaign.plan.structure_table``), shown
    collapsed under the "About" line; ``model``: the analytic model's row and sentence
    (:func:`model_sentence`)."""
    lead = decision_sentences(advice, scene, next_steps=next_steps, model=model)
    parts = ['<div id="decision">']
    # every engine's row first (the first screen of a small laptop holds it), then the
    # sentences, then what the cells mean
    tab = decision_table(advice, agreement=agreement, eta_summary=eta_summary, breaks=breaks,
                         scene=scene, model=model)
    if len(tab):
        head = "".join(f"<th class=\"txt\">{escape(c)}</th>" for c in tab.columns)
        body = "".join("<tr>" + _row_cells(list(r), list(tab.columns)) + "</tr>"
                       for r in tab.itertuples(index=False))
        parts.append(f'<table id="decision-table"><caption>Each engine on {escape(scene)}: '
                     "the setting to use within each tolerance, its cost in CPU s per "
                     "simulated s, and its worst error on the chosen / the held-out cases"
                     f"</caption><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
    parts.append('<ul class="lead">' + "".join(f"<li>{escape(s)}</li>" for s in lead)
                 + "</ul>")
    if len(tab):
        fates = "; ".join(f"<b>{escape(k)}</b>: {escape(v)}" for k, v in FATES.items())
        parts.append("<details><summary>What a cell says</summary><p><small>A cell: the "
                     "setting, its cost in process CPU seconds per simulated second (steady "
                     "state) and its worst relative error against the analytic model on the "
                     "chosen / the held-out cases; otherwise the engine's fate "
                     f"({fates}) with its closest error. Map agreement: the cells whose "
                     "overturning verdict differs from the analytic map's, of those compared, "
                     "and Cohen's kappa. Breaks first at: the first value along a stability "
                     "axis, with its unit, where the engine is not within 5 % (the class and "
                     "the reason measured; every axis in the section Choosing a modelling "
                     "approach, docs/choosing.md).</small></p></details>")
    if structure:
        parts.append(f'<p>About: {escape(structure)}</p>')
    if structures is not None and len(structures):
        from .html import html_table

        parts.append("<details><summary>The structures, field by field (SI units; "
                     "docs/scenes.md)</summary>" + html_table(
                         structures, list(structures.columns), graded=False)
                     + "</details>")
    for n in notes:
        parts.append(f"<p>{escape(n)}</p>")
    parts.append(work_precision_html)
    parts.append("</div>")
    return "\n".join(parts)

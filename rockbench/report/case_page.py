"""The report of one comparison: :func:`write_case_report` turns a
:class:`rockbench.comparison.Comparison` into a self-contained ``index.html`` (summary table
coloured by agreement, conclusion, rotation histories, eta per impact, settings and versions)
plus the tables as CSV; :func:`case_conclusion` writes the findings in words from the metrics
table alone. Built from the blocks of :mod:`rockbench.report.html`; reads the Comparison only
(its Results, tables and the scene's constants), never runs a backend. What the page shows:
``docs/report.md``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ..comparison import DERIVED_COLUMNS, ETA_COLUMNS, METRIC_COLUMNS, with_derived
from ..result import motion_label
from ..run_length import describe
from . import figures as F
from .html import (_dl, conclusion_html, figure_html, fmt, grade_legend, html_metric_table,
                   html_table, render_page, versions_html)

__all__ = ["SUMMARY_COLUMNS", "case_conclusion", "write_case_report"]

#: The columns of the coloured summary table of a case (all columns are in metrics.csv).
SUMMARY_COLUMNS: list[str] = [
    "backend", "status", "max_abs_phi_over_alpha", "peak_rel_error", "nrmse",
    "max_abs_error_over_alpha", "t_uplift_error", "t_first_impact_error", "n_impacts",
    "n_impacts_ref", "eta_ccw_mean", "eta_ccw_ref", "eta_cw_mean", "eta_cw_ref",
    "eta_mean_rel_error", "eta_max_rel_error", "overturned", "overturned_ref", "verdict_agrees",
    "energy_gained_at_impact", "max_penetration", "max_sliding", "contact_opened", "cpu_s",
    "cpu_per_sim_s", "steps"]


def _engine_versions(table: pd.DataFrame) -> dict[str, str]:
    """Backend -> engine version that ran (or why it could not), from a metrics table."""
    out = {}
    for r in table.itertuples(index=False):
        if r.status == "unavailable":
            out[r.backend] = f"unavailable: {r.reason}"
        else:
            out[r.backend] = r.engine_version
    return out


# ------------------------------------------------------------------------------------------
def _pct(x: float) -> str:
    """A signed percentage with 2 decimals, "n/a" when missing."""
    return "n/a" if x is None or pd.isna(x) else f"{100.0 * x:+.2f} %"


def case_conclusion(table: pd.DataFrame) -> list[str]:
    """Plain-language findings computed from a case's metrics table (columns of
    METRIC_COLUMNS): which engine is closest to the analytic model and by how much, which is
    fastest, and where they disagree (verdicts, energy gain, diverged or missing runs, contact
    penetration and sliding beyond the "fair" thresholds).

    Numbers are written as: nrmse and real-time factors with 3 significant digits (``.3g``),
    relative errors in percent with 2 decimals and a sign, eta with 4 decimals.
    """
    t = with_derived(table)
    ref = t[t["backend"] == "analytic"]
    eng = t[t["backend"] != "analytic"]
    status = eng["status"].astype(str)
    ok = eng[status == "ok"]
    lines: list[str] = []
    if len(eng) == 0:
        lines.append("Only the analytic reference ran: there is no engine to compare.")
    elif len(ok) == 0:
        lines.append("No engine finished a clean run: nothing to compare with the analytic "
                     "model.")
    else:
        ranked = ok.assign(_k=ok["nrmse"].astype(float).fillna(np.inf)).sort_values("_k")
        b = ranked.iloc[0]
        lines.append(
            f"Closest to the analytic model: {b['backend']}, with nrmse {b['nrmse']:.3g} "
            f"(RMS of (phi - phi_ref) / alpha) and a peak rotation error of "
            f"{_pct(b['peak_rel_error'])}"
            + (" (the analytic model does not uplift: no peak to compare)."
               if pd.isna(b["peak_rel_error"]) else "."))
        for _, r in ranked.iloc[1:].iterrows():
            ratio = r["nrmse"] / b["nrmse"] if b["nrmse"] > 0 else math.inf
            lines.append(f"{r['backend']}: nrmse {r['nrmse']:.3g} ({ratio:.3g} times that of "
                         f"{b['backend']}), peak rotation error {_pct(r['peak_rel_error'])}.")
    costs = [f"{r['backend']} {r['cpu_per_sim_s']:.3g}" for _, r in pd.concat([ok, ref]).iterrows()
             if r.get("status") == "ok" and pd.notna(r.get("cpu_per_sim_s"))]
    if costs:
        # one run on a shared machine ranks nothing: the advice measures cost with repeats
        lines.append("CPU s per simulated s of this one run: " + ", ".join(costs)
                     + " (one run ranks no engine: rockbench advise measures cost with repeats).")
    for _, r in ok.iterrows():
        parts = []
        for tag, word in (("ccw", "counterclockwise"), ("cw", "clockwise")):
            m, e = r[f"eta_{tag}_mean"], r[f"eta_{tag}_ref"]
            if pd.notna(m) and pd.notna(e) and e:
                parts.append(f"{m:.4f} {word} against {e:.4f} ({_pct(m / e - 1.0)})")
        if parts:
            lines.append(f"Effective eta of {r['backend']}: " + "; ".join(parts) + ".")
    problems = []
    ref_ot = bool(ref.iloc[0]["overturned"]) if len(ref) and pd.notna(
        ref.iloc[0]["overturned"]) else None
    for _, r in ok.iterrows():
        if pd.notna(r["verdict_agrees"]) and not bool(r["verdict_agrees"]):
            what = "overturns" if bool(r["overturned"]) else "survives"
            other = "survives" if what == "overturns" else "overturns"
            problems.append(f"{r['backend']} {what} where the analytic model {other}.")
        if pd.notna(r.get("energy_gained_at_impact")) and bool(r["energy_gained_at_impact"]):
            problems.append(f"{r['backend']} gained energy at an impact (largest |eta / eta_ref "
                            f"- 1| = {_pct(r['eta_max_rel_error'])}).")
        if F.grade("max_penetration", r["max_penetration"]) == "poor":
            problems.append(f"{r['backend']} penetrated the contacts by up to "
                            f"{1e3 * r['max_penetration']:.3g} mm.")
        if F.grade("max_sliding", r["max_sliding"]) == "poor":
            problems.append(f"{r['backend']} slid by up to {1e3 * r['max_sliding']:.3g} mm at "
                            f"a contact the analytic model keeps fixed.")
        if pd.notna(r.get("contact_opened")) and bool(r["contact_opened"]):
            problems.append(f"{r['backend']} opened a contact the analytic model keeps closed.")
    for _, r in eng[~status.isin(["ok", "unavailable"])].iterrows():
        problems.append(f"{r['backend']} did not finish cleanly ({r['status']}): "
                        f"{r['reason'] or 'no reason given'}.")
    for _, r in eng[status == "unavailable"].iterrows():
        problems.append(f"{r['backend']} is not installed here ({r['reason']}).")
    if len(ok) and ref_ot is not None and ok["verdict_agrees"].fillna(True).astype(bool).all():
        lines.append("Every engine that ran agrees with the analytic verdict: the structure "
                     + ("overturns." if ref_ot else "does not overturn."))
    lines.extend(problems)
    return lines


# ------------------------------------------------------------------------------------------
def write_case_report(comparison, out_dir, *, histories: bool = True,
                      title: str | None = None) -> Path:
    """Write the report of one comparison into ``out_dir`` (created) and return the path of
    ``out_dir/index.html``.

    Files: ``index.html`` (self-contained: summary table coloured by agreement, conclusion,
    rotation histories, eta per impact, settings and versions), ``metrics.csv`` (the
    comparison table, columns :data:`rockbench.comparison.METRIC_COLUMNS`), ``eta.csv``
    (:data:`rockbench.comparison.ETA_COLUMNS`), ``history.csv`` when ``histories`` (backend, t [s],
    phi [rad], phidot [rad/s], ground_acc [m/s^2], mode), and the figures as PNG in
    ``out_dir/figures/``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figdir = out / "figures"
    scene = comparison.scene
    alpha = float(scene.alpha)
    table = comparison.table
    eta = comparison.eta
    table.to_csv(out / "metrics.csv", index=False)
    eta.to_csv(out / "eta.csv", index=False)
    if histories and hasattr(comparison, "histories"):
        comparison.histories().to_csv(out / "history.csv", index=False)
    motion = dict(comparison.motion or {"kind": "none"})
    mlabel = motion_label(motion, long=True)
    if motion.get("kind", "none") == "none":
        mlabel += f" from phi0 = {fmt(comparison.phi0)} rad"
    title = title or f"rockbench: {scene.name} under {mlabel}"
    units = {**METRIC_COLUMNS, **DERIVED_COLUMNS}

    lines = case_conclusion(table)
    shown = with_derived(table)
    summary = (grade_legend()
               + html_metric_table(shown, SUMMARY_COLUMNS, units=units, table_id="summary")
               + "<p>Every column (with its unit and definition) is in "
                 '<a href="metrics.csv">metrics.csv</a>; hover a header for its definition.</p>')
    fig_h = F.plot_histories(comparison.results, alpha=alpha, title=f"{scene.name}: {mlabel}")
    hist = figure_html(
        fig_h, f"Rotation of the left (taller) column phi / alpha [-] against time t [s], every "
        f"backend (analytic reference bold black; impacts marked), with the ground acceleration "
        f"[m/s^2] above and the difference from the reference (phi - phi_ref) / alpha [-] "
        f"below. alpha = {alpha:.4f} rad.", name="histories", png_dir=figdir)
    eta_fig = figure_html(
        F.plot_eta(eta, title=f"{scene.name}: effective eta per impact"),
        "Coefficient of restitution eta [-] of every impact, per rocking direction after the "
        "impact: engines' effective eta (measured from their motion) against the analytic eta "
        "(dashed); right: mean +- standard deviation per backend.", name="eta", png_dir=figdir)
    eta_tab = (html_table(eta, list(ETA_COLUMNS), units=ETA_COLUMNS, graded=False, scroll=True)
               if len(eta) else "<p>No impacts.</p>")
    eta_html = eta_fig + "<details><summary>eta per impact (table)</summary>" + eta_tab + \
        "</details>"

    consts = dict(getattr(comparison, "constants", None) or {})
    run_items = [("scene", scene.name), ("description", getattr(scene, "description", "")),
                 ("ground motion", mlabel), ("motion parameters", motion),
                 ("phi0 [rad]", comparison.phi0),
                 ("duration [s]", getattr(comparison, "duration", None)
                  or f"default ({describe()})")]
    set_items = [(f"settings {k}", v) for k, v in (getattr(comparison, "settings", None) or {
        k: r.settings for k, r in comparison.results.items()}).items()]
    settings_html = ("<h3>Run</h3>" + _dl(run_items) + "<h3>Analytic constants</h3>"
                     + _dl((k, v) for k, v in consts.items())
                     + "<p>Angles in rad, p in rad/s, masses in kg, lengths in m.</p>"
                     + "<h3>Backend settings</h3>" + _dl(set_items)
                     + "<h3>Versions</h3>" + versions_html(_engine_versions(table)))
    files = ['<a href="metrics.csv">metrics.csv</a>', '<a href="eta.csv">eta.csv</a>']
    if (out / "history.csv").exists():
        files.append('<a href="history.csv">history.csv</a>')
    sections = [
        ("conclusion-section", "Conclusion", conclusion_html(lines)),
        ("summary-section", "Summary against the analytic model", summary),
        ("histories-section", "Rotation histories", hist),
        ("eta-section", "Coefficient of restitution", eta_html),
        ("settings-section", "Settings and versions", settings_html),
        ("files-section", "Tables", "<p>" + ", ".join(files) + "</p>"),
    ]
    page = render_page(title, sections, subtitle="How far does each engine stand from the "
                       "analytic rocking model, and at what cost?")
    path = out / "index.html"
    path.write_text(page, encoding="utf-8")
    return path

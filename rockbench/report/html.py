"""The self-contained HTML page of a report, and the report of one comparison case.

:func:`write_case_report` turns a :class:`rockbench.compare.Comparison` into ``index.html``
(figures embedded as base64 PNG, CSS inlined: the page needs no network) plus the tables as CSV.
The building blocks (:func:`render_page`, :func:`html_table`, :func:`figure_html`,
:func:`versions`, :func:`case_conclusion`) are shared with the campaign page
(:mod:`rockbench.report.campaign`). The page template and style sheet are package data
(``page.html``, ``style.css``) filled with :class:`string.Template`; no template engine is
needed. What the page shows and how to read it: ``docs/report.md``.
"""

from __future__ import annotations

import datetime as _dt
import math
import platform
import string
import sys
from collections.abc import Iterable, Mapping, Sequence
from html import escape
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from . import figures as F

__all__ = [
    "DERIVED_COLUMNS",
    "SUMMARY_COLUMNS",
    "case_conclusion",
    "figure_html",
    "fmt",
    "html_table",
    "render_page",
    "versions",
    "versions_html",
    "with_derived",
    "write_case_report",
]

#: Columns computed from a metrics table for display and grading (not in METRIC_COLUMNS).
DERIVED_COLUMNS: dict[str, str] = {
    "eta_mean_rel_error": "-, max over the two directions of |eta_mean / eta_ref - 1| "
                          "(mean effective eta against the analytic eta)",
}

#: The columns of the coloured summary table of a case (all columns are in metrics.csv).
SUMMARY_COLUMNS: list[str] = [
    "backend", "status", "max_abs_phi_over_alpha", "peak_rel_error", "nrmse",
    "max_abs_error_over_alpha", "t_uplift_error", "t_first_impact_error", "n_impacts",
    "n_impacts_ref", "eta_ccw_mean", "eta_ccw_ref", "eta_cw_mean", "eta_cw_ref",
    "eta_mean_rel_error", "eta_max_rel_error", "overturned", "overturned_ref", "verdict_agrees",
    "energy_gained_at_impact", "max_penetration", "max_sliding", "contact_opened", "wall_s",
    "steps", "real_time_factor"]

_TEXT_COLUMNS = {"backend", "status", "reason", "engine_version", "scene", "shape", "frame",
                 "record", "case", "engine", "motion"}


def fmt(value: Any) -> str:
    """A table cell: 4 significant digits, yes/no for booleans, empty for missing values."""
    try:
        if value is pd.NA or value is pd.NaT:
            return ""
    except TypeError:  # pragma: no cover
        pass
    return F._fmt(value)


def with_derived(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` (columns of METRIC_COLUMNS) with :data:`DERIVED_COLUMNS` added."""
    t = table.copy()
    if {"eta_ccw_mean", "eta_ccw_ref", "eta_cw_mean", "eta_cw_ref"} <= set(t.columns):
        a = (t["eta_ccw_mean"].astype(float) / t["eta_ccw_ref"].astype(float) - 1.0).abs()
        b = (t["eta_cw_mean"].astype(float) / t["eta_cw_ref"].astype(float) - 1.0).abs()
        t["eta_mean_rel_error"] = pd.concat([a, b], axis=1).max(axis=1, skipna=True)
    return t


# ------------------------------------------------------------------------------------------
# Page building blocks
# ------------------------------------------------------------------------------------------
def _resource(name: str) -> str:
    return resources.files("rockbench.report").joinpath(name).read_text(encoding="utf-8")


def render_page(title: str, sections: Sequence[tuple[str, str, str]], *,
                subtitle: str = "") -> str:
    """The whole page: ``sections`` are (anchor id, heading, inner HTML) in order."""
    from .. import __version__

    body = "\n".join(f'<section id="{escape(sid)}">\n<h2>{escape(head)}</h2>\n{inner}\n'
                     f"</section>" for sid, head, inner in sections)
    nav = " ".join(f'<a href="#{escape(sid)}">{escape(head)}</a>' for sid, head, _ in sections)
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return string.Template(_resource("page.html")).substitute(
        title=escape(title), subtitle=escape(subtitle), css=_resource("style.css"), nav=nav,
        body=body, version=escape(__version__), generated=now)


def _unit(units: Mapping[str, str] | None, col: str) -> tuple[str, str]:
    if not units or col not in units:
        return "", ""
    text = units[col]
    unit = text.split(",", 1)[0].strip()
    return unit, text


def html_table(df: pd.DataFrame, columns: Sequence[str] | None = None, *,
               units: Mapping[str, str] | None = None, graded: bool = True,
               grade_as: Mapping[str, str] | None = None, table_id: str | None = None,
               scroll: bool = False) -> str:
    """An HTML table of ``df``; each header shows the column's unit (from ``units``: column ->
    "unit, definition", the definition as a tooltip); with ``graded`` each cell of a graded
    metric gets the class good / fair / poor (:func:`rockbench.report.figures.grade`).
    ``grade_as`` maps a displayed column to the metric whose thresholds grade it."""
    cols = [c for c in (columns if columns is not None else df.columns) if c in df.columns]
    grade_as = dict(grade_as or {})
    head = []
    for c in cols:
        unit, text = _unit(units, c)
        cls = ' class="txt"' if c in _TEXT_COLUMNS else ""
        tip = f' title="{escape(text)}"' if text else ""
        label = escape(c) + (f"<br><small>[{escape(unit)}]</small>" if unit else "")
        head.append(f"<th{cls}{tip}>{label}</th>")
    rows = []
    for rec in df[cols].itertuples(index=False):
        cells = []
        for c, v in zip(cols, rec):
            classes = []
            if c in _TEXT_COLUMNS:
                classes.append("txt")
            if graded:
                g = F.grade(grade_as.get(c, c), None if _missing(v) else v)
                if g != "na":
                    classes.append(g)
            cls = f' class="{" ".join(classes)}"' if classes else ""
            cells.append(f"<td{cls}>{escape(fmt(v))}</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    tid = f' id="{escape(table_id)}"' if table_id else ""
    html = (f"<table{tid}>\n<thead><tr>{''.join(head)}</tr></thead>\n<tbody>\n"
            + "\n".join(rows) + "\n</tbody>\n</table>")
    return f'<div class="scroll">{html}</div>' if scroll else html


def _missing(v: Any) -> bool:
    if v is None:
        return True
    try:
        return bool(pd.isna(v))
    except (TypeError, ValueError):
        return False


def grade_legend() -> str:
    """One line explaining the cell colours, with the thresholds."""
    parts = []
    for m, (good, fair) in F.THRESHOLDS.items():
        parts.append(f"{escape(m)}: good &le; {good:g}, fair &le; {fair:g}")
    return ('<p class="legend"><span class="good">good</span><span class="fair">fair</span>'
            '<span class="poor">poor</span> Thresholds on |value| (units as in the table: '
            + "; ".join(parts) + "); verdict_agrees: no is poor; energy_gained_at_impact and "
            "contact_opened: yes is fair; a status other than ok is poor. See docs/report.md."
            "</p>")


def figure_html(fig, caption: str, *, name: str | None = None,
                png_dir: str | Path | None = None, dpi: int = 100) -> str:
    """A ``<figure>`` with the figure embedded as a base64 PNG ``data:`` URI; when ``png_dir``
    and ``name`` are given the PNG is also written to ``png_dir/name.png``. The figure is
    closed (its memory released) afterwards."""
    import base64

    png = F.png_bytes(fig, dpi=dpi)
    fig.clear()
    if png_dir is not None and name:
        d = Path(png_dir)
        d.mkdir(parents=True, exist_ok=True)
        (d / f"{name}.png").write_bytes(png)
    uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
    fid = f' id="fig-{escape(name)}"' if name else ""
    return (f'<figure{fid}><img src="{uri}" alt="{escape(caption)}">'
            f"<figcaption>{escape(caption)}</figcaption></figure>")


def versions() -> dict[str, Any]:
    """Versions of rockbench, Python, the platform, the scientific stack and every registered
    engine (available or the reason it is not)."""
    import matplotlib
    import scipy

    from .. import __version__, engine_info

    out: dict[str, Any] = {
        "rockbench": __version__,
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or "",
        "cpu_count": _cpu_count(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "pandas": pd.__version__,
        "matplotlib": matplotlib.__version__,
    }
    for row in engine_info():
        out[f"engine {row['name']}"] = (row.get("version") if row["available"]
                                        else f"unavailable: {row.get('reason', '')}")
    return out


def _cpu_count() -> int:
    import os

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _dl(items: Iterable[tuple[str, Any]]) -> str:
    return ('<dl class="settings">' + "".join(
        f"<dt>{escape(str(k))}</dt><dd>{escape(_plain(v))}</dd>" for k, v in items) + "</dl>")


def _plain(v: Any) -> str:
    if isinstance(v, float):
        return fmt(v)
    if isinstance(v, Mapping):
        return ", ".join(f"{k}={_plain(x)}" for k, x in v.items())
    if isinstance(v, (list, tuple)):
        return ", ".join(_plain(x) for x in v)
    return "" if v is None else str(v)


def versions_html() -> str:
    """The versions as a definition list."""
    return _dl(versions().items())


# ------------------------------------------------------------------------------------------
# Conclusion of one case
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
    if len(ok):
        f = ok.loc[ok["real_time_factor"].astype(float).idxmax()]
        sent = (f"Fastest engine: {f['backend']} at a real-time factor of "
                f"{f['real_time_factor']:.3g} (simulated s per wall s of stepping, "
                f"{f['wall_s']:.3g} s)")
        if len(ref) and ref.iloc[0]["status"] == "ok":
            sent += f"; the analytic reference ran at {ref.iloc[0]['real_time_factor']:.3g}"
        lines.append(sent + ".")
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


def conclusion_html(lines: Sequence[str]) -> str:
    return '<div id="conclusion"><ul>' + "".join(f"<li>{escape(s)}</li>" for s in lines) \
        + "</ul></div>"


# ------------------------------------------------------------------------------------------
# The report of one comparison
# ------------------------------------------------------------------------------------------
def _motion_label(motion: Mapping[str, Any]) -> str:
    kind = motion.get("kind", "none")
    if kind == "ricker":
        return (f"{motion.get('shape')} Ricker pulse, sign {int(motion.get('sign', 1)):+d}, "
                f"A = {fmt(motion.get('A'))}, W = {fmt(motion.get('W'))} "
                f"(a_g = {fmt(motion.get('amplitude_m_s2'))} m/s^2, "
                f"T_g = {fmt(motion.get('period_s'))} s)")
    if kind == "none":
        return "free rocking"
    name = motion.get("name") or motion.get("path") or kind
    return f"{kind} {name}"


def write_case_report(comparison, out_dir, *, histories: bool = True,
                      title: str | None = None) -> Path:
    """Write the report of one comparison into ``out_dir`` (created) and return the path of
    ``out_dir/index.html``.

    Files: ``index.html`` (self-contained: summary table coloured by agreement, conclusion,
    rotation histories, eta per impact, settings and versions), ``metrics.csv`` (the
    comparison table, columns :data:`rockbench.compare.METRIC_COLUMNS`), ``eta.csv``
    (:data:`rockbench.compare.ETA_COLUMNS`), ``history.csv`` when ``histories`` (backend, t [s],
    phi [rad], phidot [rad/s], ground_acc [m/s^2], mode), and the figures as PNG in
    ``out_dir/figures/``.
    """
    from ..compare import ETA_COLUMNS, METRIC_COLUMNS

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
    mlabel = _motion_label(motion)
    if motion.get("kind", "none") == "none":
        mlabel += f" from phi0 = {fmt(comparison.phi0)} rad"
    title = title or f"rockbench: {scene.name} under {mlabel}"
    units = {**METRIC_COLUMNS, **DERIVED_COLUMNS}

    lines = case_conclusion(table)
    shown = with_derived(table)
    summary = (grade_legend()
               + html_table(shown, SUMMARY_COLUMNS, units=units, table_id="summary",
                            scroll=True)
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

    consts = {}
    try:
        from .. import info
        consts = info(scene)
    except Exception as e:  # pragma: no cover - info should not fail on a valid scene
        consts = {"error": str(e)}
    run_items = [("scene", scene.name), ("description", getattr(scene, "description", "")),
                 ("ground motion", mlabel), ("motion parameters", motion),
                 ("phi0 [rad]", comparison.phi0),
                 ("duration [s]", getattr(comparison, "duration", None) or "default (motion "
                  "length + 10 s, or 10 s of free rocking)")]
    set_items = [(f"settings {k}", v) for k, v in (getattr(comparison, "settings", None) or {
        k: r.settings for k, r in comparison.results.items()}).items()]
    settings_html = ("<h3>Run</h3>" + _dl(run_items) + "<h3>Analytic constants</h3>"
                     + _dl((k, v) for k, v in consts.items())
                     + "<p>Angles in rad, p in rad/s, masses in kg, lengths in m.</p>"
                     + "<h3>Backend settings</h3>" + _dl(set_items)
                     + "<h3>Versions</h3>" + versions_html())
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

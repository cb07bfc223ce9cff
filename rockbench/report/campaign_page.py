"""The campaign page: its sections, assembled from the campaign's tables, conclusion and
comparison payloads (``docs/report.md``, "The campaign page"). Reads tables and payloads only;
the campaign passes the plan, labels, versions and fingerprint it needs."""

from __future__ import annotations

from collections.abc import Mapping
from html import escape

import pandas as pd

from ..comparison import DERIVED_COLUMNS, METRIC_COLUMNS
from ..run_length import describe
from . import figures as F
from . import html as H
from .tables import CAMPAIGN_COLUMNS

#: The columns of record_peaks.csv the page shows (the file has them all).
RECORD_SHOWN = ("record", "frame", "polarity", "backend", "status", "max_abs_phi_over_alpha",
                "band_low", "band_high", "within_band", "overturned", "verdict_agrees")

__all__ = ["page_sections", "runtime_html", "render", "fracture_html", "band_summary_html",
           "SECTION_ORDER", "ordered"]

#: The page's sections, in the order a reader asks: the decision, the findings, the evidence
#: per question, the choice's details, maps and fragility, then settings, tables and run time.
SECTION_ORDER = ("decision-section", "conclusion-section", "summary-section",
                 "histories-section", "cases-section", "fracture-section", "eta-section",
                 "records-section", "choice-section", "maps-section", "validity-section",
                 "fragility-section", "settings-section", "files-section", "runtime-section")


def ordered(sections: Mapping[str, tuple[str, str]]) -> list[tuple[str, str, str]]:
    """(id, title, html) of ``sections`` (id -> (title, html)) in :data:`SECTION_ORDER`; an
    id outside it is an error (a new section gets its place there)."""
    unknown = [k for k in sections if k not in SECTION_ORDER]
    if unknown:
        raise ValueError(f"sections without a place in SECTION_ORDER: {unknown}")
    return [(k, *sections[k]) for k in SECTION_ORDER if k in sections]


def render(sections, *, quick: bool, with_records: bool, about: str | None = None) -> str:
    """The whole page (title, subtitle, sections). ``about``: the structures of a user's
    campaign (None: the paper's frames)."""
    what = (f"Your structures ({about})" if about else
            "The paper's rocking frames, free-standing and hybrid,")
    return H.render_page("rockbench: physics engines against the analytic rocking model",
                         sections, subtitle=what + " under Ricker pulses"
                         + (" and records" if with_records else "")
                         + ": how far each engine stands from the analytic model, and at what "
                         "cost." + (" (quick campaign)" if quick else ""))


def runtime_html(timings: Mapping[str, tuple[float, float]], total: tuple[float, float],
                 workers: int) -> str:
    """The Run time section: per part of the campaign and in total, wall-clock seconds and
    CPU seconds (this process and its workers), and the workers."""
    rows = "".join(f"<tr><td>{escape(k)}</td><td>{w:.1f}</td><td>{c:.1f}</td></tr>"
                   for k, (w, c) in timings.items())
    rows += f"<tr><th>total</th><th>{total[0]:.1f}</th><th>{total[1]:.1f}</th></tr>"
    return ("<table><thead><tr><th>part</th><th>wall [s]</th><th>CPU [s]</th></tr></thead>"
            f"<tbody>{rows}</tbody></table><p>Wall-clock and CPU seconds (user + system, this "
            f"process and its {workers} worker(s)) of each part of this run; cases reused from "
            "the store cost nothing here.</p>")


def band_summary_html(records, what: str = "record peaks") -> str:
    """Per engine: how many of its peaks (``what``) lie within the analytic model's
    sensitivity band, and how far the others are (columns within_band, band_distance of
    record_peaks.csv or metrics.csv)."""
    if not len(records) or "within_band" not in records:
        return ""
    items = []
    eng = records[(records["backend"] != "analytic") & (records["status"] == "ok")]
    for name, g in eng.groupby("backend", sort=False):
        w = g["within_band"].dropna()
        if not len(w):
            continue
        inside = int(w.astype(bool).sum())
        out = g.loc[w.index[~w.astype(bool).to_numpy()], "band_distance"].abs()
        far = f"; outside by at most {out.max():.3g} alpha" if len(out) else ""
        items.append(f"<li><b>{escape(str(name))}</b>: {inside} of {len(w)} {what} "
                     f"within the model's own sensitivity{far}.</li>")
    return (f"<p>Each engine's {what} against the analytic model's sensitivity band:</p>"
            "<ul>" + "".join(items) + "</ul>") if items else ""


def fracture_html(frac, units) -> str:
    """The Fracture section: per engine, whether it fractures when the analytic model does and
    when, then the cases' table (rows of ``metrics`` with part "fracture")."""
    cols = ["case", "backend", "status", "fractured", "fractured_ref", "fracture_agrees",
            "t_fracture_error", "overturned", "overturned_ref", "verdict_agrees",
            "t_overturn_error", "max_abs_phi_over_alpha", "peak_rel_error", "max_sliding"]
    items = []
    eng = frac[frac["backend"] != "analytic"]
    for name, g in eng.groupby("backend", sort=False):
        ok = g[g["status"] == "ok"]
        agree = int(ok["fracture_agrees"].fillna(False).astype(bool).sum())
        terr = ok["t_fracture_error"].to_numpy(dtype=float)
        terr = terr[terr == terr]
        when = (f"; fracture time off by at most {1e3 * abs(terr).max():.3g} ms"
                if terr.size else "")
        bad = len(g) - len(ok)
        reasons = "; ".join(g.loc[g["status"] != "ok", "reason"].astype(str))
        items.append(f"<li><b>{escape(name)}</b>: fractures when the analytic model does in "
                     f"{agree} of {len(ok)} cases that ran{when}"
                     + (f" ({bad} not ok: {escape(reasons)})" if bad else "") + ".</li>")
    intro = ("<p>Hybrid frames under pulses where the analytic model fractures the tendons "
             "(the plan's <code>fracture_cases</code>, docs/plans.md): does each engine "
             "fracture when the analytic model does, and when?</p>")
    return (intro + "<ul>" + "".join(items) + "</ul>"
            + H.html_table(frac, cols, units=units, table_id="fracture", scroll=True))


def _file_label(ref) -> str:
    """A scene's label on the page when the plan's ``labels`` do not give its name: a built-in
    name, or a scene file's stem."""
    text = str(ref)
    return text.replace("\\", "/").rsplit("/", 1)[-1].removesuffix(".toml")


def _details(summary: str, inner: str, *, open_: bool = False) -> str:
    """Long evidence, collapsed under a one-line summary."""
    return (f'<details class="evidence"{" open" if open_ else ""}><summary>{H.escape(summary)}'
            f"</summary>{inner}</details>")


def engines_state_html(states) -> str:
    """Every registered engine with its state in this run (ran / not installed / left out)
    and the detail (version; or why and the remedy; or the option), as a table."""
    rows = pd.DataFrame([{"engine": r["name"], "state": r["state"], "detail": r["detail"]}
                         for r in states])
    if not len(rows):
        return ""
    return H.html_table(rows, ["engine", "state", "detail"])


def page_sections(t, lines, figdir, *, engine_versions, files) -> dict[str, tuple[str, str]]:
    """The sections (id -> (title, html)) of the campaign page that a campaign's tables ``t``
    make (:class:`rockbench.campaign.run.CampaignTables`, read by attribute: ``plan``,
    ``names``, ``states``, ``payloads`` (each with a ``label``), ``metrics``, ``eta_summary``,
    ``engines``, ``records``, ``notes``, ``quick``, ``records_dir``, ``store_dir``,
    ``fingerprint``); figures are written under ``figdir``. The campaign adds its other parts'
    sections and :func:`ordered` puts them in place. ``lines``: the findings in words;
    ``engine_versions``: backend name -> version (or why it is unavailable); ``files``: the
    CSV files written."""
    plan, names, payloads = t.plan, t.names, t.payloads
    metrics, eta_summary, engines_tab = t.metrics, t.eta_summary, t.engines
    records, notes = t.records, t.notes
    quick, records_dir, store_dir = t.quick, t.records_dir, t.store_dir
    fingerprint, engine_states = t.fingerprint, t.states
    units = {**METRIC_COLUMNS, **DERIVED_COLUMNS}
    names_of = plan.get("labels") or {}         # scene reference -> the scene's own name

    def _label(ref) -> str:
        return names_of.get(ref) or _file_label(ref)

    for tab in CAMPAIGN_COLUMNS.values():
        for k, v in tab.items():
            units.setdefault(k, v)
    sections: dict[str, tuple[str, str]] = {}

    # findings (the decision above them is assembled by the campaign: report/decision.py)
    conc = _details(f"All findings, in words ({len(lines)})", H.conclusion_html(lines),
                    open_=False)
    if notes:
        conc += "<h3>Notes</h3><ul>" + "".join(f"<li>{H.escape(n)}</li>" for n in notes) + \
            "</ul>"
    sections["conclusion-section"] = ("Findings", conc)

    # engine summary
    eng_cols = list(CAMPAIGN_COLUMNS["engines.csv"])
    grade_as = {"nrmse_median": "nrmse", "nrmse_max": "nrmse",
                "peak_rel_error_median": "peak_rel_error", "peak_rel_error_max": "peak_rel_error",
                "eta_mean_rel_error": "eta_mean_rel_error"}
    summ = H.grade_legend() + H.html_table(engines_tab, eng_cols, units=units, grade_as=grade_as,
                                           table_id="engines", scroll=True)
    sections["summary-section"] = ("Summary per engine", summ)

    # histories: the decision's structure open (its histories are the evidence a reader
    # checks first), every other structure's collapsed
    hist, decisive = [], _label(plan.get("choice_scene", plan["scenes"][0]))
    pulses = [p for p in payloads if p["job"]["kind"] == "pulse"]
    for scene in plan["scenes"]:
        ps = [p for p in pulses if p["job"]["scene"] == scene]
        if not ps:
            continue
        scene = _label(scene)
        panels = [(p["label"].replace(scene + " ", ""),
                   {k: F.as_trace(v) for k, v in p["traces"].items()}) for p in ps]
        bands = [(p["band"]["low"], p["band"]["high"]) if p.get("band") else None
                 for p in ps]
        fig = F.plot_history_grid(panels, alpha=ps[0]["alpha"], ncols=min(4, len(panels)),
                                  title=f"{scene}: rotation histories under Ricker pulses",
                                  bands=bands)
        html = H.figure_html(
            fig, f"{scene}: phi / alpha [-] against t [s] for every pulse case (analytic "
                 f"reference bold black; impacts marked), alpha = {ps[0]['alpha']:.4f} rad. "
                 f"Panel titles: pulse shape and sign, A = a_g / (g tan alpha), W = omega_g / p. "
                 f"Grey: +-[low, high] of the analytic model's sensitivity band of the peak "
                 f"(docs/records.md).",
            name=f"histories_{scene}", png_dir=figdir)
        hist.append(html if scene == decisive else
                    _details(f"{scene}: rotation histories ({len(ps)} pulse cases)", html))
    sections["histories-section"] = ("Rotation histories", "\n".join(hist) if hist
                                     else "<p>No pulse case finished.</p>")

    # pulse table
    shown = H.with_derived(metrics) if len(metrics) else metrics
    cols = ["case", "backend", "status", "max_abs_phi_over_alpha", "peak_rel_error", "nrmse",
            "n_impacts", "n_impacts_ref", "eta_mean_rel_error", "verdict_agrees",
            "energy_gained_at_impact", "max_sliding", "cpu_per_sim_s"]
    if "within_band" in shown:
        cols[4:4] = ["band_low", "band_high", "within_band"]
    pulse_rows = shown[shown["part"] == "pulse"] if len(shown) else shown
    tab = H.html_table(pulse_rows, cols, units=units, table_id="cases", scroll=True)
    sections["cases-section"] = ("Every pulse case",
                     band_summary_html(pulse_rows, "pulse-case peaks")
                     + _details(f"The table of every pulse case ({len(pulse_rows)} runs)",
                                H.grade_legend() + tab)
                     + '<p>All columns: <a href="metrics.csv">metrics.csv</a>.</p>')

    # fracture cases
    frac = shown[shown["part"] == "fracture"] if len(shown) else shown
    if len(frac):
        sections["fracture-section"] = ("Fracture", fracture_html(frac, units))

    # eta
    etah = []
    if len(eta_summary):
        etah.append(H.figure_html(
            F.plot_eta_summary(eta_summary, title="Free rocking: effective eta against the "
                                                  "analytic eta"),
            f"Free rocking from phi0 = {plan['free_phi0']:g} alpha for "
            f"{plan['free_duration']:g} s: each engine's mean effective coefficient of "
            f"restitution relative to the analytic eta, 100 (eta_mean / eta_ref - 1) [%], "
            f"error bars one standard deviation over the impacts, per rocking direction after "
            f"the impact. Free-standing frames: the engines measure eta from the energy of "
            f"successive rocking peaks. Hybrid frames: from the angular velocities fitted just "
            f"before and after each impact (docs/metrics.md), which the tendon and damper "
            f"forces bend, so part of a hybrid frame's deviation may be the measurement's.",
            name="eta_free_rocking", png_dir=figdir))
        etah.append(H.html_table(eta_summary, list(CAMPAIGN_COLUMNS["eta_summary.csv"]),
                                 units=units, grade_as={"rel_error": "eta_mean_rel_error"},
                                 scroll=True))
    first = next((p for p in payloads if p["job"]["kind"] == "free"), None)
    if first is not None and len(first["eta"]):
        etah.append(H.figure_html(
            F.plot_eta(first["eta"], title=f"{first['job']['scene']}, free rocking: eta per "
                                           f"impact"),
            "eta [-] of every impact of one free-rocking run (engines: measured from their "
            "motion; analytic dashed), per direction; right: mean +- standard deviation.",
            name="eta_per_impact", png_dir=figdir))
    sections["eta-section"] = ("Coefficient of restitution", "\n".join(etah) or
                     "<p>No free-rocking run finished.</p>")

    # records
    if len(records):
        sections["records-section"] = ("Records (paper Fig. 9)", H.figure_html(
            F.plot_record_peaks(records, title="Peak rotation per record"),
            "Peak rotation max |phi| / alpha [-] of the free-standing and the hybrid "
            "(eps_f = 1 %) asymmetric frame under each record, as recorded (filled) and "
            "reversed (open); triangles at the top: overturned. Grey: the analytic model's "
            "own sensitivity band (eta x (1 +- 0.5 %, 1 %), pivots +- 1 mm, record x (1 +- "
            "1 %), half-sample resampling; docs/records.md).", name="record_peaks",
            png_dir=figdir) + band_summary_html(records) + "<details><summary>record runs (table)</summary>" + H.html_table(
                records, [c for c in RECORD_SHOWN if c in records], units=units,
                scroll=True) + "</details>")

    # settings
    items = [("engines", ", ".join(names)),
             ("engines that did not run", "; ".join(
                 f"{r['name']} ({r['state']})" for r in engine_states
                 if r["state"] != "ran" and r["name"] not in names) or "none"),
             ("scenes", ", ".join(map(str, plan["scenes"]))),
             ("pulse (A, W) points", ", ".join(f"({a:g}, {w:g})"
                                               for a, w in plan["pulse_points"])),
             ("pulse shapes", ", ".join(f"{s} {g:+d}" for s, g in plan["pulse_shapes"])),
             ("pulse run length", describe("pulse", plan["pulse_tail"])),
             ("free rocking", f"phi0 = {plan['free_phi0']:g} alpha, "
                              f"{plan['free_duration']:g} s"),
             ("vertical ground motion", (
                 f"a_v = {plan['vertical']:g} x the horizontal acceleration, in phase, in every "
                 "pulse and record (a record's own vertical channel where it has one); the "
                 "stability sweep is horizontal" if plan.get("vertical")
                 else "none (horizontal only)")),
             ("records folder", str(records_dir) if records_dir else "none"),
             ("quick", str(bool(quick))), ("store", str(store_dir)),
             ("code fingerprint", fingerprint)]
    default_settings = {}
    for p in payloads:
        for k, v in p.get("settings", {}).items():
            default_settings.setdefault(k, v)
    sett = (H._dl(items) + "<h3>Backend settings (defaults: every comparison; the decision "
            "tries its own)</h3>" + H._dl((f"settings {k}", v) for k, v in default_settings.items())
            + "<h3>Engines</h3>" + engines_state_html(engine_states)
            + "<h3>Versions</h3>" + H.versions_html(engine_versions))
    sections["settings-section"] = ("Settings and versions", sett)
    links = ", ".join(f'<a href="{f}">{f}</a>' for f in files)
    sections["files-section"] = ("Tables", f"<p>{links}. Columns and units: "
                     f"docs/report.md.</p>")
    return sections

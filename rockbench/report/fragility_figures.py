"""Figures and the page block of the fragility section (``docs/fragility.md``).

Inputs are plain data: the runs frame and the analysis dict of :mod:`rockbench.studies.fragility`
(``runs``: backend, record, polarity, scale, im, peak = max |phi| / alpha [-], overturned,
status; ``analysis``: per backend median [IM unit], dispersion [-], intervals, bands, tests).
Probabilities are drawn as percentages. Figures are at most 11.6 in wide (shown at 100 % in a
1400 px window at 100 dpi) with text of at least 9 pt (12.5 px).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from . import figures as F

__all__ = ["plot_fragility", "plot_fig9", "plot_peak_stripes", "fragility_table",
           "measures_table", "fragility_html"]

_WIDTH = 11.6      # in: the page's content width (1160 px) at 100 dpi
_FONT = 10         # pt


def _curve(x, median, dispersion):
    from scipy.stats import norm

    if not (median is not None and dispersion is not None and math.isfinite(median)
            and math.isfinite(dispersion)):
        return np.full(np.shape(x), math.nan)
    return norm.cdf(np.log(np.asarray(x, float) / median) / dispersion)


def _empirical(runs: pd.DataFrame, backend: str) -> tuple[np.ndarray, np.ndarray]:
    """Median intensity and overturning fraction of each scale step of ``backend``."""
    g = runs[(runs["backend"] == backend) & (runs["status"] == "ok")]
    if not len(g):
        return np.array([]), np.array([])
    s = g.groupby("scale").agg(im=("im", "median"), p=("overturned", "mean"))
    return s["im"].to_numpy(float), s["p"].to_numpy(float)


def plot_fragility(analysis: Mapping[str, Any], runs: pd.DataFrame, *,
                   title: str | None = None) -> Figure:
    """One panel per engine: the fragility curve P(overturn | IM) [%] of the engine (its colour)
    over the analytic model's (black; on its whole ladder when ``analysis`` has
    ``reference_full``), each with its bootstrap band (shaded) and the measured overturning
    fraction of each scale step (markers: open circles analytic, squares the engine)."""
    ref = analysis["reference"]
    name, unit = analysis["intensity"]["name"], analysis["intensity"]["unit"]
    grid = np.asarray(analysis["grid"], float)
    backs = dict(analysis["backends"])
    full = analysis.get("reference_full")   # the analytic model on its whole ladder
    if full is not None:
        backs[ref] = full
        grid = np.geomspace(min(grid.min(), min(full["grid"])),
                            max(grid.max(), max(full["grid"])), 80)
    engines = [b for b in F._order(list(backs)) if b != ref] or [ref]
    ncol = min(3, len(engines))
    nrow = math.ceil(len(engines) / ncol)
    fig = Figure(figsize=(_WIDTH, 3.3 * nrow + 0.5), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False, sharey=True)).ravel()
    for ax in axes[len(engines):]:
        ax.set_visible(False)
    for ax, eng in zip(axes, engines):
        for b, colour, marker in ((ref, "black", "o"), (eng, F.engine_color(eng), "s")):
            if b not in backs or (b == ref and eng == ref and marker == "s"):
                continue
            v = backs[b]
            band = v.get("band") or {}
            if band.get("low") is not None:
                bx = np.asarray(v.get("grid", analysis["grid"]), float)
                ax.fill_between(bx, 100 * np.asarray(band["low"], float),
                                100 * np.asarray(band["high"], float), color=colour,
                                alpha=0.15, lw=0)
            ax.plot(grid, 100 * _curve(grid, v["median"], v["dispersion"]), color=colour,
                    lw=2.0 if b == ref else 1.6, label=f"{b}: median "
                    f"{v['median']:.3g} {unit}, beta {v['dispersion']:.2f}"
                    if math.isfinite(v["median"]) else f"{b}: {v['note']}")
            x, p = _empirical(runs, b)
            ax.plot(x, 100 * p, marker, color=colour, ms=5, mfc="none" if b == ref else colour,
                    ls="none")
        v = backs.get(eng, {})
        if "p_value" in v and v.get("p_value") is not None and math.isfinite(v["p_value"]):
            ax.set_title(f"{eng}: smallest KS p = {v['p_value']:.2g}", fontsize=_FONT)
        else:
            ax.set_title(eng, fontsize=_FONT)
        ax.set_xlabel(f"{name} [{unit}]", fontsize=_FONT)
        ax.set_ylim(-3, 103)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=_FONT - 1)
    for ax in axes[::ncol]:
        ax.set_ylabel("P(overturn) [%]", fontsize=_FONT)
    F.legend_below(fig, fontsize=_FONT - 1, max_cols=2)     # never over the curves
    if title:
        fig.suptitle(title, fontsize=_FONT + 1)
    return fig


def plot_fig9(frames: Mapping[str, pd.DataFrame], *, scale: float = 1.0,
              scales: Mapping[str, float] | None = None, title: str | None = None) -> Figure:
    """The paper's Fig. 9 from fragility runs: the peak rotation max |phi| / alpha [-] per record
    and direction at one ``scale`` (per frame: ``scales[label]`` when given; the nearest step,
    in ratio, that every backend ran, on the records every backend ran), one panel per
    frame (``frames``: label -> runs), every backend beside the analytic model
    (:func:`rockbench.report.figures.plot_record_peaks`)."""
    parts = []
    for label, runs in frames.items():
        target = (scales or {}).get(label, scale)
        if not len(runs):
            continue
        # the steps every backend ran (the engines may run a part of the ladder)
        per = [set(np.round(g["scale"], 9)) for _, g in runs.groupby("backend")]
        steps = np.array(sorted(set.intersection(*per) or set(np.round(runs["scale"], 9))))
        s = steps[np.argmin(np.abs(np.log(steps / target)))]
        g = runs[np.isclose(runs["scale"], s)]
        g = g[g["record"].isin(set.intersection(*[set(x["record"]) for _, x in
                                                 g.groupby("backend")]))]
        parts.append(pd.DataFrame({
            "record": g["record"], "frame": f"{label} (scale {s:.3g})",
            "polarity": g["polarity"].astype(int), "backend": g["backend"],
            "max_abs_phi_over_alpha": g["peak"].astype(float),
            "overturned": g["overturned"].astype(bool), "status": g["status"]}))
    df = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(
        columns=["record", "frame", "polarity", "backend", "max_abs_phi_over_alpha",
                 "overturned", "status"])
    return F.plot_record_peaks(df, title=title)


def plot_peak_stripes(runs: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Peak rotations at each scale step: the survivors' max |phi| / alpha [-] of every backend
    side by side (dots, one per run), with the overturned percentage above each group."""
    backs = F._order(list(dict.fromkeys(runs["backend"])))
    steps = np.unique(runs["scale"].to_numpy(float))
    fig = Figure(figsize=(_WIDTH, 3.8), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / max(len(backs), 1)
    ok = runs[runs["status"] == "ok"]
    top = 0.0
    for j, b in enumerate(backs):
        for i, s in enumerate(steps):
            g = ok[(ok["backend"] == b) & np.isclose(ok["scale"], s)]
            sv = g.loc[~g["overturned"].astype(bool), "peak"].to_numpy(float)
            x = i - 0.4 + width * (j + 0.5)
            jitter = np.linspace(-0.3, 0.3, sv.size) * width if sv.size > 1 else np.zeros(sv.size)
            ax.plot(x + jitter, sv, ".", color=F.engine_color(b), ms=4,
                    label=b if i == 0 else None)
            top = max(top, float(sv.max()) if sv.size else 0.0)
            if len(g):
                ax.annotate(f"{100 * g['overturned'].astype(bool).mean():.0f} %", (x, 0.98),
                            xycoords=("data", "axes fraction"), ha="center", va="top",
                            fontsize=_FONT - 1, rotation=90, color=F.engine_color(b))
    ax.set_xticks(range(len(steps)), [f"{s:.3g}" for s in steps], fontsize=_FONT - 1)
    ax.set_xlabel("scale factor of the records [-]", fontsize=_FONT)
    ax.set_ylabel("max |phi| / alpha of survivors [-]", fontsize=_FONT)
    ax.tick_params(labelsize=_FONT - 1)
    ax.set_ylim(0, max(top * 1.45, 0.1))
    ax.grid(alpha=0.3, axis="y")
    F.legend_below(fig, fontsize=_FONT - 1)
    if title:
        ax.set_title(title + " (at the top: % of the runs overturned)", fontsize=_FONT + 1)
    return fig


def fragility_table(analysis: Mapping[str, Any]) -> pd.DataFrame:
    """One row per backend: median and record-to-record dispersion with their 95 % intervals,
    the numerical dispersion beta_num and beta_total = sqrt(beta_RR^2 + beta_num^2), runs,
    overturned, and (engines) the smallest KS p-value, its statistic, the median difference
    with its interval, and the verdict."""
    unit = analysis["intensity"]["unit"]
    rows = []
    for b, v in analysis["backends"].items():
        lo, hi = v.get("median_ci", [math.nan] * 2)
        dlo, dhi = v.get("median_difference_ci", [math.nan] * 2)
        rows.append({"backend": b, f"median [{unit}]": v["median"],
                     "median 95 % interval": f"{lo:.3g} to {hi:.3g}",
                     "dispersion beta_RR [-]": v["dispersion"],
                     "dispersion 95 % interval": "{:.3g} to {:.3g}".format(
                         *v.get("dispersion_ci", [math.nan] * 2)),
                     "beta_num [-]": v.get("dispersion_numerical", math.nan),
                     "beta_total [-]": v.get("dispersion_total", math.nan),
                     "runs": v["runs"], "overturned": v["overturned"],
                     "not ok": v["not_ok"], "KS statistic [-]": v.get("statistic", math.nan),
                     "smallest p": v.get("p_value", math.nan),
                     f"median difference [{unit}]": v.get("median_difference", math.nan),
                     "difference 95 % interval": (f"{dlo:.3g} to {dhi:.3g}"
                                                  if "median_difference_ci" in v else ""),
                     "verdict": v.get("verdict", "reference")})
    return pd.DataFrame(rows)


def measures_table(analysis: Mapping[str, Any]) -> pd.DataFrame:
    """One row per backend (the analytic model on its whole ladder, ``measures_full``, last),
    one column per intensity measure: its dispersion beta_RR [-] with its rank (1: the most
    efficient) and the share [%] of resampled ensembles of records in which its family is the
    most efficient (the medians are in the exports' ``measures.csv``). Empty without the
    table."""
    m = analysis.get("measures")
    if not m:
        return pd.DataFrame()
    cols = list(m["backends"].items())
    full = (analysis.get("measures_full") or {}).get("backends", {})
    ref = analysis.get("reference", m.get("reference", "analytic"))
    if ref in full:
        cols.append((f"{ref} (whole ladder)", full[ref]))
    rows = []
    for b, v in cols:
        row: dict[str, Any] = {"backend": b}
        for k, d in m["measures"].items():
            f = v["fits"][k]
            share = (v.get("p_best") or {}).get(f.get("family", k))
            cell = (f"{f['dispersion']:.3f} ({f['rank']})" if f["rank"] is not None
                    else "no fit")
            if share is not None:
                cell += f", {100.0 * share:.0f} %"
            row[d["name"]] = cell
        rows.append(row)
    return pd.DataFrame(rows)


def _numerical_sentence(analysis: Mapping[str, Any]) -> str:
    """How beta_num was measured, per engine, in words with units."""
    num = analysis.get("numerical") or {}
    bits = []
    for e, v in num.items():
        if "cases" in v:
            bits.append(f"{e} at {v['setting']}: {v['cases']} pulses, worst |peak error| "
                        f"{100 * v['worst']:.2g} %, beta_num {v['beta']:.2g}")
        else:
            bits.append(f"{e}: beta_num {v['beta']:.2g} (given)")
    if not bits:
        return ("beta_num: not measured (NaN); beta_total is then NaN for the engines.")
    return ("beta_num is each engine's own error on this frame at the setting these runs use: "
            "the RMS of ln(1 + e) over its relative peak errors e against the analytic model "
            "on the frame's surviving Ricker pulses of the work-precision evidence (away from "
            "the overturning boundary); beta_total = sqrt(beta_RR^2 + beta_num^2). "
            + "; ".join(bits) + ".")


def fragility_html(section: Mapping[str, Any], figdir=None) -> str:
    """The page block of the fragility section (``section``: what
    :func:`rockbench.studies.fragility.fragility_section` returns)."""
    from . import html as H

    if section.get("error"):
        return f"<p>The fragility runs failed: {H.fmt(section['error'])}</p>"
    parts = [f"<p>{section['what']}</p>"]
    if section.get("provenance"):
        parts.append("<p>The slower engines (no compiled stepping loop: their runs are measured "
                     "by <code>rockbench report --full</code> into the report's "
                     "<code>fragility-engines</code> folder, docs/fragility.md):</p><ul>"
                     + "".join(f"<li>{H.fmt(t)}</li>" for t in section["provenance"])
                     + "</ul>")
    for i, frame in enumerate(section["frames"]):
        a, runs, label = frame["analysis"], frame["runs"], frame["label"]
        im = a["intensity"]
        verdicts = [v["verdict"] for v in a["backends"].values() if "verdict" in v]
        parts.append(f"<h3>{label}</h3>")
        if verdicts:
            parts.append("<ul>" + "".join(f"<li>{H.fmt(t)}</li>" for t in verdicts) + "</ul>")
        parts.append(H.figure_html(
            plot_fragility(a, runs, title=f"{label}: fragility against {im['name']}"),
            f"Overturning probability against {im['name']} [{im['unit']}] "
            f"({im['definition']}), lognormal maximum-likelihood fit per backend, with the "
            f"{100 * a['level']:.0f} % bootstrap band over {a['n_boot']} resamples of the records "
            f"(shaded); markers: measured fraction overturned at each scale step.",
            name=f"fragility_{i}", png_dir=figdir))
        parts.append(H.figure_html(
            plot_peak_stripes(runs, title=f"{label}: peak rotations"),
            "Peak rotation max |phi| / alpha [-] of every surviving run at each scale step, "
            "each backend; the percentage overturned above each group. The Kolmogorov-Smirnov "
            "test compares these distributions (overturned runs ranked above every survivor).",
            name=f"fragility_peaks_{i}", png_dir=figdir))
        parts.append(H.html_table(fragility_table(a), graded=False, scroll=True))
        if (a.get("vertical") or {}).get("text"):
            parts.append(f"<p>{H.fmt(a['vertical']['text'])}</p>")
        if (a.get("validity") or {}).get("text"):
            parts.append(f"<p>{H.fmt(a['validity']['text'])}</p>")
        parts.append(f"<p>{H.fmt(_numerical_sentence(a))}</p>")
        mt = measures_table(a)
        if len(mt):
            st = a.get("structure") or {}
            parts.append(
                "<p>Efficiency of the intensity measures (the dispersion beta_RR of the fit "
                "against each; the smaller, the less record-to-record spread is left), on the "
                "runs the engines and the analytic model both made"
                + (f"; Sa at T_p = 2 pi / p = {st['sa_period']:.3g} s" if st else "")
                + ". Each cell: beta_RR [-], its rank (1: the most efficient), and the "
                  "share [%] of resampled ensembles of records in which it is the most "
                  "efficient (the medians: measures.csv of the exports). A dimensionless "
                  "measure has its dimensional one's dispersion for one frame (they rank "
                  "together).</p>")
            parts.append(H.html_table(mt, graded=False, scroll=True))
            sent = [v["sentence"] for v in a["measures"]["backends"].values() if "sentence" in v]
            if sent:
                parts.append("<ul>" + "".join(f"<li>{H.fmt(t)}</li>" for t in sent) + "</ul>")
    exports = section.get("exports") or {}
    if exports:
        parts.append("<p>The fitted curves for risk tools (docs/fragility-export.md): "
                     + ", ".join(H.fmt(str(p)) for p in exports.values())
                     + " (OpenQuake NRML .xml, pelicun .csv; measures.csv: the "
                       "intensity-measure table).</p>")
    if section.get("export_error"):
        parts.append(f"<p>The curves could not be written: {H.fmt(section['export_error'])}</p>")
    if section.get("fig9"):
        parts.append(H.figure_html(
            plot_fig9({f["label"]: f["runs"] for f in section["frames"]},
                      scales={f["label"]: f["fig9_scale"] for f in section["frames"]
                              if "fig9_scale" in f},
                      title="Peak rotation per record and direction (paper Fig. 9)"),
            "The paper's Fig. 9 over this ensemble: max |phi| / alpha [-] per record, as "
            "recorded (filled) and reversed (open), every backend beside the analytic model; "
            "overturned runs are drawn at the top.", name="fragility_fig9", png_dir=figdir))
    return "\n".join(parts)

"""Figures of the work-precision sweep and of the stability maps (matplotlib, off-screen).

Like :mod:`rockbench.report.figures`, every function returns a :class:`matplotlib.figure.Figure`
built without pyplot, from plain tables only:

* :func:`plot_work_precision` - the table of :func:`rockbench.studies.tradeoff.tradeoff`
  (:data:`rockbench.studies.tradeoff.TABLE_COLUMNS`): error against cost, log-log, one curve per engine
  through its time steps, the median cost of the repeats with its min-max spread as horizontal
  bars, the Pareto front (no other point both cheaper and more accurate) marked, in the style of
  the SciML benchmarks' work-precision diagrams;
* :func:`plot_stability_map` - the table of :func:`rockbench.studies.robustness.stress`
  (:data:`rockbench.studies.robustness.STRESS_COLUMNS`): per backend, each axis value coloured by its class
  (within 1 %, within 5 %, off, diverged / invalid, outside the analytic model's validity).

Units: cost in process CPU seconds per simulated second [s/s]; errors relative [-].
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from . import figures as F
from .figures import engine_color

__all__ = ["pareto_front", "plot_work_precision", "plot_stability_map", "CLASS_COLORS"]

#: Colour of every stress class (rockbench.studies.tradeoff.VERDICTS).
CLASS_COLORS = {"within 1%": "#2e7d32", "within 5%": "#9ccc65", "off": "#ef6c00",
                "diverged": "#c62828", "invalid": "#6a1b9a", "outside model": "#9e9e9e"}

_ERROR_LABELS = {
    "worst_error": "worst validation error [-]\n(|peak error| of pulses and records, "
                   "free-rocking eta)",
    "peak_error_worst": "worst |peak error| over the surviving pulses [-]",
    "peak_error_median": "median |peak error| over the surviving pulses [-]",
    "nrmse_worst": "worst nrmse [-]",
    "nrmse_median": "median nrmse [-]",
    "eta_error_worst": "worst free-rocking eta error [-]",
    "self_peak_error_worst": "self-consistency: worst |peak(dt) / peak(dt/4) - 1| [-]",
    "self_nrmse_worst": "self-consistency: worst nrmse against dt/4 [-]",
}


def pareto_front(table: pd.DataFrame, error: str = "worst_error",
                 cost: str = "cpu_per_sim_s") -> pd.Index:
    """Index of the rows no other row dominates (cheaper or as cheap, and more accurate or as
    accurate, one of them strictly), among rows with a finite cost and error."""
    t = table[np.isfinite(table[cost].astype(float)) & np.isfinite(table[error].astype(float))]
    keep = []
    c = t[cost].to_numpy(float)
    e = np.abs(t[error].to_numpy(float))
    for i, idx in enumerate(t.index):
        dominated = np.any((c <= c[i]) & (e <= e[i]) & ((c < c[i]) | (e < e[i])))
        if not dominated:
            keep.append(idx)
    return pd.Index(keep)


def plot_work_precision(table: pd.DataFrame, *, errors: Sequence[str] = ("worst_error",
                                                                         "self_peak_error_worst"),
                        cost: str = "cpu_per_sim_s", tolerance: float | None = None,
                        title: str | None = None) -> Figure:
    """Work-precision diagram: one panel per column of ``errors`` (y, log), cost (x, log:
    ``cpu_per_sim_s``, process CPU s per simulated s, median of the repeats; horizontal bars:
    ``cpu_per_sim_s_min`` .. ``_max``), one curve per engine through its settings (labelled with
    dt), the Pareto front of the panel as a grey step line with ringed points. Settings whose
    error is infinite (a run not ok or a wrong overturning verdict) are drawn as crosses on the
    top edge. ``tolerance`` [-] draws a horizontal line (an advice's tolerance)."""
    def has_data(col: str) -> bool:
        v = np.abs(table[col].astype(float).to_numpy())
        return bool(np.any(np.isfinite(v) & (v > 0)))

    errors = [e for e in errors if e in table.columns and has_data(e)] or ["worst_error"]
    fig = Figure(figsize=(6.0 * len(errors) + 0.6, 4.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, max(1, len(errors)), squeeze=False)).ravel()
    for ax, err in zip(axes, errors):
        t = table.copy()
        y_all = np.abs(t[err].astype(float).to_numpy())
        finite = y_all[np.isfinite(y_all) & (y_all > 0)]
        top = float(finite.max()) * 3 if finite.size else 1.0
        bottom = float(finite.min()) / 3 if finite.size else 1e-4
        key = "curve" if "curve" in t.columns else "engine"     # an engine may have two
        for name in dict.fromkeys(t[key]):
            s = t[t[key] == name].sort_values("knob_value" if "knob_value" in t.columns
                                              else "dt", ascending=False)
            x = s[cost].astype(float).to_numpy()
            y = np.abs(s[err].astype(float).to_numpy())
            col = engine_color(str(s["engine"].iloc[0]))
            ok = np.isfinite(x) & np.isfinite(y) & (y > 0)
            ax.plot(x[ok], y[ok], marker="o", color=col, label=name, lw=1.5,
                    ls="-" if name == s["engine"].iloc[0] else "--")
            if {f"{cost}_min", f"{cost}_max"} <= set(s.columns):
                lo = s[f"{cost}_min"].astype(float).to_numpy()
                hi = s[f"{cost}_max"].astype(float).to_numpy()
                ax.errorbar(x[ok], y[ok], xerr=[x[ok] - lo[ok], hi[ok] - x[ok]], fmt="none",
                            ecolor=col, elinewidth=1, capsize=2)
            bad = np.isfinite(x) & np.isinf(y)
            if bad.any():
                ax.plot(x[bad], np.full(bad.sum(), top), "x", color=col, ms=8)
            knob = s["knob_value"] if "knob_value" in s.columns else s["dt"]
            for xi, yi, dt in zip(x[ok], y[ok], knob.to_numpy()[ok]):
                ax.annotate(f"{float(dt):g}", (xi, yi), fontsize=7, color=col,
                            textcoords="offset points", xytext=(4, 3))
        front = t.loc[pareto_front(t, err, cost)].sort_values(cost)
        if len(front):
            fx = front[cost].astype(float).to_numpy()
            fy = np.abs(front[err].astype(float).to_numpy())
            ax.step(fx, fy, where="post", color="0.4", lw=1, ls="--", zorder=0,
                    label="Pareto front")
            ax.plot(fx, fy, "o", mfc="none", mec="k", ms=11, mew=1.2, zorder=3)
        if tolerance is not None:
            ax.axhline(tolerance, color="#c62828", lw=0.8, ls=":",
                       label=f"tolerance {tolerance:g}")
        if finite.size:
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_ylim(bottom, top * 1.5)
            ax.margins(x=0.12)        # room for the rightmost point's label
        # short, and clear of the lowest y tick label even when no x tick is labelled (a
        # sweep within one decade): the details are in the caption
        ax.set_xlabel("cost: CPU s per simulated s [s/s] (median; bars min-max; left = "
                      "cheaper)\nlabels: dt [s], or the engine's own knob", labelpad=10)
        ax.set_ylabel(_ERROR_LABELS.get(err, err) + "\n(down = more accurate)")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    F.legend_below(fig)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_stability_map(stress: pd.DataFrame, engine: str, *, title: str | None = None,
                       base: str | None = None, labels: Mapping[str, str] | None = None,
                       base_values: Mapping[str, float] | None = None) -> Figure:
    """Stability map of one backend: one row per stress axis, its values on a log or linear
    x axis (log when they span more than a factor of 20 and are positive), each point coloured
    by its class (``class`` column: :data:`CLASS_COLORS`). ``stress`` columns: engine, axis,
    value, class (:data:`rockbench.studies.robustness.STRESS_COLUMNS`). ``base``: the name of
    the scene the axes start from (in the title); ``labels``: axis -> its label with unit
    (``rockbench.studies.robustness.axis_label``); ``base_values``: axis -> the base scene's
    value, drawn as a dashed line where it lies in the axis's range."""
    s = stress[stress["engine"] == engine]
    axes_names = list(dict.fromkeys(s["axis"]))
    n = max(1, len(axes_names))
    fig = Figure(figsize=(7.5, 0.9 * n + 1.4), layout="constrained")
    axs = np.atleast_1d(fig.subplots(n, 1, squeeze=False)).ravel()
    for ax, name in zip(axs, axes_names):
        g = s[s["axis"] == name]
        x = g["value"].astype(float).to_numpy()
        pos = x[x > 0]
        if pos.size and pos.size == x.size and pos.max() / pos.min() > 20:
            ax.set_xscale("log")
        for cls, col in CLASS_COLORS.items():
            m = (g["class"] == cls).to_numpy()
            if m.any():
                ax.scatter(x[m], np.zeros(m.sum()), s=70, color=col, edgecolor="k", lw=0.4,
                           label=cls, zorder=3)
        b = (base_values or {}).get(name)
        if b is not None and np.isfinite(b) and (b > 0 or ax.get_xscale() != "log"):
            ax.axvline(b, color="0.35", ls="--", lw=0.8, zorder=2,
                       label="base scene's value")
        ax.set_yticks([])
        ax.set_ylabel((labels or {}).get(name, name), rotation=0, ha="right", va="center",
                      fontsize=8)
        ax.grid(True, axis="x", which="both", lw=0.3, alpha=0.5)
        ax.tick_params(axis="x", labelsize=7)
    handles = [h for ax in axs for h in ax.get_legend_handles_labels()[0]]
    labels = [lab for ax in axs for lab in ax.get_legend_handles_labels()[1]]
    uniq = dict(zip(labels, handles))
    if uniq:
        fig.legend(list(uniq.values()), list(uniq.keys()), loc="outside lower center",
                   ncol=min(6, len(uniq)), fontsize=8)
    fig.suptitle(title or f"{engine}: stability map (one axis at a time from "
                 f"{base or 'the base scene'})", fontsize=10)
    return fig

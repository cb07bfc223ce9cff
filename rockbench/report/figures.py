"""Figures of the reports (matplotlib, rendered off-screen; never shown).

Every function builds and returns a :class:`matplotlib.figure.Figure` without pyplot, so no
window, no global state and no GUI backend is involved; :func:`png_bytes` and :func:`data_uri`
render one to PNG (the HTML pages embed them as ``data:`` URIs, so a page needs no network).

Inputs are plain tables (pandas frames whose columns are those of
:data:`rockbench.comparison.METRIC_COLUMNS` / :data:`~rockbench.comparison.ETA_COLUMNS`, or the
campaign's tables documented in ``docs/report.md``) and :class:`rockbench.result.Result` objects
(or light "traces", see :func:`as_trace`). Units: time in s, rotations as phi / alpha [-] with
alpha the slenderness of the taller column [rad], eta [-], real-time factor [-] (simulated s per
wall s), A = a_g / (g tan alpha) [-], W = omega_g / p [-].

Agreement colours (:func:`grade`, from ``rockbench.comparison.TOLERANCES["grades"]``) are shared
with the HTML tables; the thresholds are stated in ``docs/report.md``.
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .legibility import wrap_at
from matplotlib.lines import Line2D

from ..comparison import TOLERANCES

__all__ = [
    "GRADE_COLORS",
    "Trace",
    "as_trace",
    "data_uri",
    "engine_color",
    "grade",
    "plot_eta",
    "plot_eta_summary",
    "plot_histories",
    "plot_history_grid",
    "plot_record_peaks",
    "legend_below",
    "plot_summary_table",
    "png_bytes",
]

# ------------------------------------------------------------------------------------------
# Agreement grades
# ------------------------------------------------------------------------------------------
#: metric -> (good limit, fair limit) on the metric's absolute value: the one tolerance table's
#: "grades" entry (its comment says how they were chosen).
_GRADES: dict[str, tuple[float, float]] = TOLERANCES["grades"]

#: Boolean metrics: value -> grade.
_BOOL_GRADES: dict[str, dict[bool, str]] = {
    "verdict_agrees": {True: "good", False: "poor"},
    "energy_gained_at_impact": {False: "good", True: "fair"},
    "contact_opened": {False: "good", True: "fair"},
}

#: Grade -> colour (the HTML uses the same hues as CSS classes).
GRADE_COLORS: dict[str, str] = {"good": "#c8e6c9", "fair": "#ffe0b2", "poor": "#ffcdd2",
                                 "na": "#ffffff"}


def grade(metric: str, value: Any) -> str:
    """Agreement grade of one metric value: "good", "fair", "poor", or "na" (metric not graded,
    value missing). A ``status`` other than "ok" is "poor"."""
    if metric == "status":
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "na"
        return "good" if value == "ok" else ("na" if value == "unavailable" else "poor")
    if metric in _BOOL_GRADES:
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return "na"
        return _BOOL_GRADES[metric].get(bool(value), "na")
    if metric not in _GRADES:
        return "na"
    try:
        x = abs(float(value))
    except (TypeError, ValueError):
        return "na"
    if math.isnan(x):
        return "na"
    good, fair = _GRADES[metric]
    return "good" if x <= good else ("fair" if x <= fair else "poor")


# ------------------------------------------------------------------------------------------
# Engine colours
# ------------------------------------------------------------------------------------------
#: Colours of the backends in registry order (the analytic reference is black); a name the
#: registry does not know gets one of the last colours by its letters.
_PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
            "#17becf", "#bcbd22", "#7f7f7f"]


def _registered() -> list[str]:
    from ..registry import REGISTRY

    return list(REGISTRY)


def engine_color(name: str) -> str:
    """A fixed colour per backend (analytic black, then the registry's order), so every
    figure uses the same one."""
    reg = _registered()
    if name == reg[0]:
        return "#000000"
    if name in reg:
        return _PALETTE[(reg.index(name) - 1) % len(_PALETTE)]
    return _PALETTE[-1 - sum(map(ord, name)) % 3]


def _order(names) -> list[str]:
    """Backends with the analytic reference first, then in registry order, then the rest."""
    names = list(dict.fromkeys(names))
    reg = _registered()
    return [n for n in reg if n in names] + sorted(n for n in names if n not in reg)


# ------------------------------------------------------------------------------------------
# Traces
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Trace:
    """What a history figure needs of one run: times t [s], phi [rad], the ground acceleration
    [m/s^2] (may be empty), the impact times [s] and the run's status."""

    t: np.ndarray
    phi: np.ndarray
    ground_acc: np.ndarray
    impacts: np.ndarray
    status: str = "ok"

    @staticmethod
    def from_result(result: Any, max_points: int | None = None) -> Trace:
        h = result.history
        t = h["t"].to_numpy(float)
        phi = h["phi"].to_numpy(float)
        acc = h["ground_acc"].to_numpy(float) if "ground_acc" in h else np.empty(0)
        ev = result.events
        imp = ev.loc[ev["kind"] == "impact", "t"].to_numpy(float) if len(ev) else np.empty(0)
        tr = Trace(t, phi, acc, imp, getattr(result.summary, "status", "ok"))
        return tr.thinned(max_points) if max_points else tr

    def thinned(self, max_points: int) -> Trace:
        """Every k-th sample so that at most ``max_points`` remain (the last sample kept)."""
        n = len(self.t)
        if n <= max_points:
            return self
        k = int(math.ceil(n / max_points))
        idx = np.r_[np.arange(0, n, k), n - 1] if (n - 1) % k else np.arange(0, n, k)
        acc = self.ground_acc[idx] if len(self.ground_acc) == n else self.ground_acc
        return Trace(self.t[idx], self.phi[idx], acc, self.impacts, self.status)

    def to_dict(self) -> dict[str, Any]:
        return {"t": self.t, "phi": self.phi, "ground_acc": self.ground_acc,
                "impacts": self.impacts, "status": self.status}


def as_trace(obj: Any) -> Trace:
    """A :class:`Trace` from a Result, a Trace, or a mapping with keys t, phi (and optionally
    ground_acc, impacts, status)."""
    if isinstance(obj, Trace):
        return obj
    if hasattr(obj, "history") and hasattr(obj, "events"):
        return Trace.from_result(obj)
    if isinstance(obj, Mapping):
        return Trace(np.asarray(obj["t"], float), np.asarray(obj["phi"], float),
                     np.asarray(obj.get("ground_acc", np.empty(0)), float),
                     np.asarray(obj.get("impacts", np.empty(0)), float),
                     str(obj.get("status", "ok")))
    raise TypeError(f"cannot make a history trace from {type(obj).__name__}")


# ------------------------------------------------------------------------------------------
# Legends: below the panels, never over the data
# ------------------------------------------------------------------------------------------
def legend_below(fig: Figure, *, extra: Sequence[tuple[Any, str]] = (), fontsize: float = 8,
                 max_cols: int = 5) -> None:
    """One legend for the whole figure, below its panels (``fig`` must use the constrained
    layout, which makes room for it): the unique labelled artists of every axes, then
    ``extra`` (handle, label) pairs; every axes-level legend is removed. Never over the data,
    never wider than the figure (at most ``max_cols`` columns)."""
    seen: dict[str, Any] = {}
    for ax in fig.axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab and not lab.startswith("_"):
                seen.setdefault(lab, h)
        if ax.get_legend() is not None:
            ax.get_legend().remove()
    for h, lab in extra:
        seen.setdefault(lab, h)
    if not seen:
        return
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()
    width = fig.get_figwidth() * fig.dpi
    for ncol in range(min(len(seen), max_cols), 0, -1):   # as many columns as fit
        leg = fig.legend(list(seen.values()), list(seen), loc="outside lower center",
                         ncol=ncol, fontsize=fontsize, frameon=False)
        if ncol == 1 or leg.get_window_extent(renderer).width <= 0.98 * width:
            return
        leg.remove()


# ------------------------------------------------------------------------------------------
# Rotation histories
# ------------------------------------------------------------------------------------------
_IMPACTS = (Line2D([], [], color="0.3", marker="|", linestyle="none", markersize=9),
            "impacts (analytic |, engines x)")


def _plot_traces(ax, traces: Mapping[str, Trace], alpha: float, *, legend: bool = True):
    for name in _order(traces):
        tr = traces[name]
        ref = name == "analytic"
        label = name if tr.status == "ok" else f"{name} ({tr.status})"
        ax.plot(tr.t, tr.phi / alpha, color=engine_color(name), lw=2.2 if ref else 1.1,
                zorder=3 if ref else 2, label=label, alpha=1.0 if ref else 0.85)
        if len(tr.impacts):
            ys = np.interp(tr.impacts, tr.t, tr.phi / alpha) if len(tr.t) else tr.impacts * 0
            ax.plot(tr.impacts, ys, linestyle="none", marker="|" if ref else "x",
                    markersize=9 if ref else 5, color=engine_color(name), zorder=4)
    ax.axhline(0.0, color="0.6", lw=0.6, zorder=1)
    ax.set_ylabel("phi / alpha [-]")
    ax.grid(True, lw=0.3, alpha=0.5)
    if legend:
        legend_below(ax.figure, extra=[_IMPACTS])


def plot_histories(runs: Mapping[str, Any], *, alpha: float, title: str | None = None,
                   detail: bool = True) -> Figure:
    """Rotation histories phi / alpha against t [s], one line per backend (the analytic
    reference bold, black), impacts marked.

    With ``detail`` the figure has three panels: the ground acceleration [m/s^2], phi / alpha,
    and the difference (phi - phi_ref) / alpha on the reference's time grid.
    ``runs`` maps a backend name to a Result, Trace or mapping (:func:`as_trace`); ``alpha``
    [rad] is the slenderness of the taller column.
    """
    _check_alpha(alpha)
    traces = {k: as_trace(v) for k, v in runs.items()}
    if not detail:
        fig = Figure(figsize=(8, 3.4), layout="constrained")
        ax = fig.subplots()
        _plot_traces(ax, traces, alpha)
        ax.set_xlabel("t [s]")
        if title:
            ax.set_title(title, fontsize=10)
        return fig
    fig = Figure(figsize=(8.5, 7.0), layout="constrained")
    ax0, ax1, ax2 = fig.subplots(3, 1, sharex=True, height_ratios=[1, 2.6, 1.4])
    acc = next((tr for tr in traces.values() if len(tr.ground_acc) == len(tr.t)), None)
    if acc is not None and len(acc.t):
        ax0.plot(acc.t, acc.ground_acc, color="0.3", lw=1.0)
    ax0.set_ylabel("ground acc.\n[m/s^2]")
    ax0.grid(True, lw=0.3, alpha=0.5)
    _plot_traces(ax1, traces, alpha)
    ref = traces.get("analytic")
    if ref is not None and len(ref.t) > 1:
        for name in _order(traces):
            if name == "analytic":
                continue
            tr = traces[name]
            if len(tr.t) < 2:
                continue
            t_end = min(ref.t[-1], tr.t[-1])
            m = ref.t <= t_end
            err = (np.interp(ref.t[m], tr.t, tr.phi) - ref.phi[m]) / alpha
            ax2.plot(ref.t[m], err, color=engine_color(name), lw=1.0, label=name)
    ax2.axhline(0.0, color="0.6", lw=0.6)
    ax2.set_ylabel("(phi - phi_ref)\n/ alpha [-]")
    ax2.set_xlabel("t [s]")
    ax2.grid(True, lw=0.3, alpha=0.5)
    legend_below(fig, extra=[_IMPACTS])
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_history_grid(panels: Sequence[tuple[str, Mapping[str, Any]]], *, alpha: float,
                      ncols: int = 2, title: str | None = None,
                      bands: Sequence[tuple[float, float] | None] | None = None) -> Figure:
    """Several compact rotation-history panels (phi / alpha [-] against t [s]), one per
    ``(panel title, runs)`` pair, all backends overlaid in each (analytic bold); ``bands``: per
    panel None or (low, high), the analytic sensitivity band of max|phi| / alpha, shaded."""
    _check_alpha(alpha)
    if not panels:
        raise ValueError("plot_history_grid needs at least one panel")
    ncols = max(1, min(ncols, len(panels)))
    nrows = int(math.ceil(len(panels) / ncols))
    fig = Figure(figsize=(5.2 * ncols, 2.9 * nrows + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    for k, (ptitle, runs) in enumerate(panels):
        traces = {n: as_trace(v) for n, v in runs.items()}
        _plot_traces(axes[k], traces, alpha, legend=False)
        b = bands[k] if bands is not None and k < len(bands) else None
        for sgn in ((1.0, -1.0) if b is not None and all(map(math.isfinite, b)) else ()):
            axes[k].axhspan(sgn * b[0], sgn * b[1], color="0.5", alpha=0.25, lw=0, zorder=0)
        axes[k].set_title(ptitle, fontsize=9)
        axes[k].set_xlabel("t [s]")
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    legend_below(fig, extra=[_IMPACTS])
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def _check_alpha(alpha: float) -> None:
    if not (isinstance(alpha, (int, float, np.floating)) and math.isfinite(alpha) and alpha > 0):
        from ..errors import ParameterError
        raise ParameterError("alpha", alpha, "a finite angle > 0 rad")


# ------------------------------------------------------------------------------------------
# eta
# ------------------------------------------------------------------------------------------
_DIR_LABEL = {1: "counterclockwise (+1)", -1: "clockwise (-1)"}


def plot_eta(eta: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Coefficient of restitution per impact: each engine's effective eta against the analytic
    eta of the impact's direction (dashed), for each rocking direction; right panels: mean and
    standard deviation per backend.

    ``eta`` has the columns of :data:`rockbench.comparison.ETA_COLUMNS` (backend, impact, t,
    direction, eta, eta_ref, rel_error).
    """
    fig = Figure(figsize=(9.5, 6.0), layout="constrained")
    axes = fig.subplots(2, 2, width_ratios=[2.4, 1], squeeze=False)
    data = eta.dropna(subset=["eta"]) if len(eta) else eta
    for row, d in enumerate((1, -1)):
        ax, axm = axes[row]
        sub = data[data["direction"] == d] if len(data) else data
        backends = _order(sub["backend"]) if len(sub) else []
        ref_vals = sub["eta_ref"].dropna() if len(sub) else pd.Series(dtype=float)
        ref = float(ref_vals.iloc[0]) if len(ref_vals) else math.nan
        for name in backends:
            s = sub[sub["backend"] == name]
            ax.plot(s["impact"], s["eta"], linestyle="-" if name == "analytic" else "none",
                    marker="o" if name == "analytic" else "x", color=engine_color(name),
                    lw=0.8, markersize=4, label=name)
        if math.isfinite(ref):
            ax.axhline(ref, color="k", ls="--", lw=1.2, label=f"analytic eta = {ref:.4f}")
        ax.set_xlabel("impact number [-]")
        ax.set_ylabel("eta [-]")
        ax.set_title(f"impacts after which it rocks {_DIR_LABEL[d]}", fontsize=9)
        ax.grid(True, lw=0.3, alpha=0.5)
        if not backends and not math.isfinite(ref):
            ax.text(0.5, 0.5, "no impacts", transform=ax.transAxes, ha="center")
        for k, name in enumerate(backends):
            vals = sub.loc[sub["backend"] == name, "eta"].to_numpy(float)
            if not len(vals):
                continue
            axm.errorbar([k], [vals.mean()], yerr=[vals.std()], fmt="o", capsize=4,
                         color=engine_color(name))
        if math.isfinite(ref):
            axm.axhline(ref, color="k", ls="--", lw=1.2)
        axm.set_xticks(range(len(backends)), backends, rotation=90, fontsize=8)
        axm.set_ylabel("eta mean +- std [-]")
        axm.set_xlabel("backend")
        axm.set_xlim(-0.6, max(len(backends), 1) - 0.4)
        axm.grid(True, lw=0.3, alpha=0.5)
    legend_below(fig)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_eta_summary(summary: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Effective eta relative to the analytic eta, per scene, backend and direction:
    100 (mean / eta_ref - 1) [%] with the standard deviation as error bar.

    ``summary`` columns: scene, backend, direction (+1/-1), eta_ref [-], eta_mean [-],
    eta_std [-], n_impacts [-] (one row per scene x backend x direction; the analytic rows
    are at 0 by construction and may be omitted).
    """
    fig = Figure(figsize=(9.5, 5.6), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    scenes = list(dict.fromkeys(summary["scene"])) if len(summary) else []
    engines = [b for b in _order(summary["backend"]) if b != "analytic"] if len(summary) else []
    width = 0.8 / max(len(engines), 1)
    for ax, d in zip(axes, (1, -1)):
        for j, name in enumerate(engines):
            s = summary[(summary["backend"] == name) & (summary["direction"] == d)]
            xs, ys, es = [], [], []
            for i, sc in enumerate(scenes):
                r = s[s["scene"] == sc]
                if not len(r) or not np.isfinite(r["eta_mean"].iloc[0]):
                    continue
                ref = float(r["eta_ref"].iloc[0])
                xs.append(i - 0.4 + width * (j + 0.5))
                ys.append(100.0 * (float(r["eta_mean"].iloc[0]) / ref - 1.0))
                es.append(100.0 * float(r["eta_std"].iloc[0]) / ref)
            ax.errorbar(xs, ys, yerr=es, fmt="o", capsize=3, color=engine_color(name),
                        label=name)
        good, fair = _GRADES["eta_mean_rel_error"]
        ax.axhspan(-100 * good, 100 * good, color=GRADE_COLORS["good"], zorder=0)
        ax.axhline(0.0, color="k", lw=1.0)
        ax.set_ylabel("eta / eta_analytic - 1 [%]")
        ax.set_title(f"impacts after which it rocks {_DIR_LABEL[d]} "
                     f"(green band: +-{100 * good:g} %)", fontsize=9)
        ax.grid(True, lw=0.3, alpha=0.5)
    legend_below(fig)
    axes[-1].set_xticks(range(len(scenes)), [wrap_at(str(x), "-", 12) for x in scenes], fontsize=8)
    axes[-1].set_xlabel("scene (free rocking)")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


# ------------------------------------------------------------------------------------------
# Summary table
# ------------------------------------------------------------------------------------------
def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        x = float(value)
        if math.isnan(x):
            return ""
        if x == 0.0:
            return "0"
        if abs(x) >= 1e4 or abs(x) < 1e-3:
            return f"{x:.3g}"
        return f"{x:.4g}"
    return str(value)


def plot_summary_table(table: pd.DataFrame, columns: Sequence[str] | None = None, *,
                       grade_as: Mapping[str, str] | None = None,
                       title: str | None = None) -> Figure:
    """The summary table as a figure, cells coloured by agreement (:func:`grade`; ``grade_as``
    maps a column to the metric whose thresholds grade it, e.g. nrmse_median -> nrmse).

    ``columns`` defaults to the graded columns present in ``table`` (plus backend and status).
    """
    if columns is None:
        columns = [c for c in ("backend", "status", "peak_rel_error", "nrmse",
                               "eta_mean_rel_error", "eta_max_rel_error", "verdict_agrees",
                               "max_penetration", "max_sliding", "real_time_factor")
                   if c in table.columns]
    columns = [c for c in columns if c in table.columns]
    grade_as = dict(grade_as or {})
    recs = list(table[list(columns)].itertuples(index=False))
    cells = [[_fmt(v) for v in row] for row in recs]
    colours = [[GRADE_COLORS[grade(grade_as.get(c, c), v)] for c, v in zip(columns, row)]
               for row in recs]
    units = 3.0 + 1.4 * len(cells)          # header: 3 text lines; a row: 1.4
    fig = Figure(figsize=(max(6.0, 0.95 * len(columns)), 0.2 * units + (0.9 if title else 0.4)),
                 layout="constrained")
    ax = fig.subplots()
    ax.axis("off")
    if cells:
        tb = ax.table(cellText=cells, cellColours=colours,
                      colLabels=[wrap_at(c, "_", 11) for c in columns], bbox=[0, 0, 1, 1],
                      cellLoc="center")
        tb.auto_set_font_size(False)
        tb.set_fontsize(8)
        for (r, _c), cell in tb.get_celld().items():
            cell.set_height((3.0 if r == 0 else 1.4) / units)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


# ------------------------------------------------------------------------------------------
# Peak rotation per record (the paper's Fig. 9)
# ------------------------------------------------------------------------------------------
def plot_record_peaks(df: pd.DataFrame, *, title: str | None = None) -> Figure:
    """Peak rotation max |phi| / alpha [-] per ground-motion record, as in the paper's Fig. 9:
    one panel per frame (e.g. free-standing, hybrid), both polarities of each record (filled
    markers: record as given, +1; open: reversed, -1), one colour per backend (analytic
    black, larger). Overturned runs are drawn at the top of the panel as triangles.

    ``df`` columns: record, frame, polarity (+1/-1), backend, max_abs_phi_over_alpha [-],
    overturned (bool), status; with band_low and band_high (the analytic model's sensitivity
    band, ``rockbench.studies.sensitivity``), each record's band is shaded grey behind its markers
    (darker: as recorded, lighter: reversed).
    """
    frames = list(dict.fromkeys(df["frame"])) if len(df) else ["-"]
    records = list(dict.fromkeys(df["record"])) if len(df) else []
    backends = _order(df["backend"]) if len(df) else []
    fig = Figure(figsize=(max(8.0, 0.45 * len(records) + 2.5), 3.4 * len(frames) + 0.6),
                 layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(frames), 1, sharex=True, squeeze=False)).ravel()
    width = 0.8 / max(len(backends), 1)
    for ax, frame in zip(axes, frames):
        s = df[df["frame"] == frame] if len(df) else df
        ok = s[s["status"].fillna("ok").eq("ok")] if len(s) else s
        finite = ok.loc[~ok["overturned"].astype(bool), "max_abs_phi_over_alpha"] \
            if len(ok) else pd.Series(dtype=float)
        top = float(finite.max()) * 1.25 if len(finite) and np.isfinite(finite.max()) else 1.0
        top = max(top, 1.1)
        shade = s.dropna(subset=["band_low", "band_high"]) if "band_low" in s else s.iloc[:0]
        for _, b in shade.drop_duplicates(["record", "polarity"]).iterrows():  # the band
            x0 = records.index(b["record"]) - 0.4
            ax.fill_between([x0, x0 + 0.8], min(b["band_low"], top), min(b["band_high"], top),
                            color="0.55", lw=0, alpha=0.22 if b["polarity"] == 1 else 0.12)
        for j, name in enumerate(backends):
            for pol, filled in ((1, True), (-1, False)):
                r = ok[(ok["backend"] == name) & (ok["polarity"] == pol)]
                xs = np.array([records.index(x) for x in r["record"]], float)
                xs += -0.4 + width * (j + 0.5)
                ot = r["overturned"].astype(bool).to_numpy()
                y = r["max_abs_phi_over_alpha"].to_numpy(float)
                color = engine_color(name)
                size = 40 if name == "analytic" else 22
                kw = dict(color=color) if filled else dict(facecolors="none", edgecolors=color)
                ax.scatter(xs[~ot], y[~ot], marker="o", s=size, **kw)
                if ot.any():
                    ax.scatter(xs[ot], np.full(ot.sum(), top * 0.97), marker="^", s=size + 10,
                               **kw)
        ax.axhline(top * 0.93, color="#c62828", lw=0.6, ls=":")
        ax.text(0.005, top * 0.95, "overturned", color="#c62828", fontsize=7,
                transform=ax.get_yaxis_transform(), va="bottom")
        ax.set_ylim(0.0, top)
        ax.set_ylabel("max |phi| / alpha [-]")
        ax.set_title(str(frame), fontsize=9)
        ax.grid(True, axis="y", lw=0.3, alpha=0.5)
    handles = [Line2D([], [], marker="o", linestyle="none", color=engine_color(b), label=b)
               for b in backends]
    handles += [Line2D([], [], marker="o", linestyle="none", color="0.3", label="polarity +1"),
                Line2D([], [], marker="o", linestyle="none", markerfacecolor="none",
                       color="0.3", label="polarity -1 (reversed)"),
                Line2D([], [], marker="^", linestyle="none", color="0.3", label="overturned")]
    fig.legend(handles=handles, fontsize=7, loc="outside lower center",
               ncol=min(len(handles), 5), frameon=False)
    axes[-1].set_xticks(range(len(records)), records, rotation=60, fontsize=7, ha="right")
    axes[-1].set_xlabel("ground-motion record")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


# ------------------------------------------------------------------------------------------
# Rendering
# ------------------------------------------------------------------------------------------
def png_bytes(fig: Figure, dpi: int = 100) -> bytes:
    """The figure as PNG bytes (Agg, off-screen)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def data_uri(fig: Figure, dpi: int = 100) -> str:
    """The figure as a ``data:image/png;base64,...`` URI (for a self-contained page)."""
    return "data:image/png;base64," + base64.b64encode(png_bytes(fig, dpi)).decode("ascii")

"""Figures of overturning maps (paper Figs. 4-7): the four pulse panels of one map, and an
engine's verdicts overlaid on the analytic map of the same cells. Reads map frames only
(columns of :data:`rockbench.studies.maps.MAP_COLUMNS`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

__all__ = ["plot_map_panels", "plot_map_overlay", "PANELS"]

#: The paper's four panels: (shape, sign, title).
PANELS = (("symmetric", 1, "symmetric pulse, +"), ("symmetric", -1, "symmetric pulse, -"),
          ("antisymmetric", 1, "antisymmetric pulse, +"),
          ("antisymmetric", -1, "antisymmetric pulse, -"))

_CMAP = ListedColormap(["#e8f1fa", "#c0392b"])
#: Above this many cells per panel an overlay draws the engine's boundary as a line instead of
#: a marker per cell (at 100 x 100 the markers fill the panel and hide the analytic map).
DENSE_CELLS = 900


def _pivot(df: pd.DataFrame, shape: str, sign: int, value: str = "overturned"):
    g = df[(df["pulse"] == shape) & (df["sign"] == sign)]
    if not len(g):
        return None
    v = g[value].astype(float).where(g["status"] == "ok")
    t = pd.DataFrame({"A": g["amplitude"].astype(float), "W": g["frequency"].astype(float),
                      "v": v.to_numpy()}).pivot(index="A", columns="W", values="v")
    return t.sort_index().sort_index(axis=1)


def _edges(x: np.ndarray) -> np.ndarray:
    if len(x) == 1:
        return np.array([x[0] - 0.5, x[0] + 0.5])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate(([x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]))


def plot_map_panels(df: pd.DataFrame, *, title: str) -> Figure:
    """The four panels of one map: overturning region (red) and, where the structure
    survives, max |phi| / alpha (blue shades, colour bar), on W = omega_g / p (x) and
    A = a_g / (g tan alpha) (y). Cells an adaptive map inferred instead of simulating
    (``inferred`` column) carry a verdict but no max |phi|: they are grey (survives) or red,
    never white, which would read as a structure at rest."""
    fig = Figure(figsize=(11, 8.5))
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    mesh = None
    inferred = "inferred" in df and bool(df["inferred"].fillna(False).astype(bool).any())
    for ax, (shape, sign, label) in zip(axes.ravel(), PANELS):
        ot = _pivot(df, shape, sign)
        ax.set_title(label, fontsize=10)
        if ot is None:
            ax.text(0.5, 0.5, "not run", transform=ax.transAxes, ha="center")
            continue
        pk = _pivot(df, shape, sign, "max_abs_phi_over_alpha")
        W, A = ot.columns.to_numpy(float), ot.index.to_numpy(float)
        surv = np.where(ot.to_numpy() == 0, np.clip(pk.to_numpy(), 0, 1), np.nan)
        mesh = ax.pcolormesh(_edges(W), _edges(A), surv, cmap="Blues", vmin=0, vmax=1.2,
                             shading="flat")
        if inferred:
            guess = _pivot(df, shape, sign, "inferred").to_numpy().astype(float)
            grey = np.where((ot.to_numpy() == 0) & (guess == 1) & np.isnan(pk.to_numpy()),
                            1.0, np.nan)
            ax.pcolormesh(_edges(W), _edges(A), grey, cmap=ListedColormap(["#d5d8dc"]),
                          shading="flat")
        over = np.where(ot.to_numpy() == 1, 1.0, np.nan)
        ax.pcolormesh(_edges(W), _edges(A), over, cmap=ListedColormap(["#c0392b"]),
                      shading="flat")
        ex, ey = _edges(W), _edges(A)      # one value on an axis: its cell's own width
        ax.set_xlim(*((W.min(), W.max()) if len(W) > 1 else (ex[0], ex[-1])))
        ax.set_ylim(*((A.min(), A.max()) if len(A) > 1 else (ey[0], ey[-1])))
    for ax in axes[1]:
        ax.set_xlabel("W = omega_g / p [-]")
    for ax in axes[:, 0]:
        ax.set_ylabel("A = a_g / (g tan alpha) [-]")
    fig.suptitle(title + "\nred: overturns; blue: max |phi| / alpha of a surviving "
                 "structure" + ("; grey: survives, inferred by the adaptive map, not simulated"
                                if inferred else ""), fontsize=11)
    fig.tight_layout()
    if mesh is not None:
        fig.colorbar(mesh, ax=list(axes.ravel()), shrink=0.6, pad=0.02,
                     label="max |phi| / alpha of a surviving structure [-] (above 1 drawn as 1)")
    return fig


def plot_map_overlay(ref: pd.DataFrame, eng: pd.DataFrame, *, name: str, title: str) -> Figure:
    """An engine's verdicts (markers: filled square overturns, open circle survives; above
    :data:`DENSE_CELLS` cells per panel its overturning boundary as a line instead; black
    ring: differs from the analytic verdict, grey x: run not ok) on the analytic map of the
    same cells (background: red overturns, light blue survives)."""
    fig = Figure(figsize=(11, 8.5))
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    for ax, (shape, sign, label) in zip(axes.ravel(), PANELS):
        ax.set_title(label, fontsize=10)
        r = _pivot(ref, shape, sign)
        if r is not None:
            W, A = r.columns.to_numpy(float), r.index.to_numpy(float)
            ax.pcolormesh(_edges(W), _edges(A), r.to_numpy(), cmap=_CMAP, vmin=0, vmax=1,
                          shading="flat", alpha=0.55)
        g = eng[(eng["pulse"] == shape) & (eng["sign"] == sign)]
        if not len(g):
            continue
        m = g.merge(ref[["pulse", "sign", "amplitude", "frequency", "overturned"]],
                    on=["pulse", "sign", "amplitude", "frequency"], how="left",
                    suffixes=("", "_ref"))
        ok = m["status"] == "ok"
        ot = m["overturned"].fillna(False).astype(bool) & ok
        sv = ~m["overturned"].fillna(True).astype(bool) & ok
        if len(m) <= DENSE_CELLS:
            ax.scatter(m.loc[ot, "frequency"], m.loc[ot, "amplitude"], marker="s", s=28,
                       color="#7b241c", label=f"{name}: overturns")
            ax.scatter(m.loc[sv, "frequency"], m.loc[sv, "amplitude"], marker="o", s=28,
                       facecolors="none", edgecolors="#1f4e79", label=f"{name}: survives")
        else:          # a dense map: the engine's boundary as a line, not a marker per cell
            e = _pivot(eng, shape, sign)
            if e is not None and e.shape[0] > 1 and e.shape[1] > 1:
                ax.contour(e.columns.to_numpy(float), e.index.to_numpy(float),
                           e.to_numpy(float), levels=[0.5], colors="#1f4e79",
                           linewidths=1.4)
                ax.plot([], [], color="#1f4e79", linewidth=1.4,
                        label=f"{name}: its overturning boundary")
        dis = ok & (m["overturned"].astype("boolean") != m["overturned_ref"].astype("boolean"))
        dis = dis.fillna(False).astype(bool)
        ax.scatter(m.loc[dis, "frequency"], m.loc[dis, "amplitude"], marker="o", s=140,
                   facecolors="none", edgecolors="black", linewidths=1.5,
                   label="differs from analytic")
        ax.scatter(m.loc[~ok, "frequency"], m.loc[~ok, "amplitude"], marker="x", s=40,
                   color="grey", label="not ok")
    for ax in axes[1]:
        ax.set_xlabel("W = omega_g / p [-]")
    for ax in axes[:, 0]:
        ax.set_ylabel("A = a_g / (g tan alpha) [-]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=9, frameon=False)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig

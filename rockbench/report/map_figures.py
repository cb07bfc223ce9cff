"""Figures of overturning maps (paper Figs. 4-7): the four pulse panels of one map, and an
engine's verdicts overlaid on the analytic map of the same cells. Reads map frames only
(columns of :data:`rockbench.studies.maps.MAP_COLUMNS`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

__all__ = ["plot_map_panels", "plot_map_overlay", "plot_map_grid", "plot_overlay_grid", "PANELS"]

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


def _draw_analytic(ax, df: pd.DataFrame, shape: str, sign: int, inferred: bool):
    """One panel of a map: red where it overturns, blue shades of max |phi| / alpha where it
    survives, grey where an adaptive map inferred a survivor; returns the mesh (or None)."""
    ot = _pivot(df, shape, sign)
    if ot is None:
        ax.text(0.5, 0.5, "not run", transform=ax.transAxes, ha="center")
        return None
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
    return mesh


def _hatch_outside(ax, df: pd.DataFrame, shape: str, sign: int) -> bool:
    """Hatch the rows of A whose cells lie outside the analytic model (column ``outside``: it
    depends on the pulse, sign and A only); whether any was hatched."""
    if "outside" not in df:
        return False
    g = df[(df["pulse"] == shape) & (df["sign"] == sign)]
    rows = g.groupby("amplitude")["outside"].any().sort_index()
    if not rows.any():
        return False
    A = rows.index.to_numpy(float)
    e = _edges(A)
    for i in np.flatnonzero(rows.to_numpy()):
        ax.axhspan(e[i], e[i + 1], facecolor="none", edgecolor="#444444", hatch="//",
                   linewidth=0.0)
    return True


def _is_inferred(df: pd.DataFrame) -> bool:
    return "inferred" in df and bool(df["inferred"].fillna(False).astype(bool).any())


def plot_map_panels(df: pd.DataFrame, *, title: str) -> Figure:
    """The four panels of one map: overturning region (red) and, where the structure
    survives, max |phi| / alpha (blue shades, colour bar), on W = omega_g / p (x) and
    A = a_g / (g tan alpha) (y). Cells an adaptive map inferred instead of simulating
    (``inferred`` column) carry a verdict but no max |phi|: they are grey (survives) or red,
    never white, which would read as a structure at rest. Cells outside the analytic model
    (``outside`` column: the base slides or the ground lifts the structure off) are hatched."""
    fig = Figure(figsize=(11, 8.5))
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    mesh = None
    inferred = _is_inferred(df)
    hatched = False
    for ax, (shape, sign, label) in zip(axes.ravel(), PANELS):
        ax.set_title(label, fontsize=10)
        mesh = _draw_analytic(ax, df, shape, sign, inferred) or mesh
        hatched = _hatch_outside(ax, df, shape, sign) or hatched
    for ax in axes[1]:
        ax.set_xlabel("W = omega_g / p [-]")
    for ax in axes[:, 0]:
        ax.set_ylabel("A = a_g / (g tan alpha) [-]")
    fig.suptitle(title + "\nred: overturns; blue: max |phi| / alpha of a surviving "
                 "structure" + ("; grey: survives, inferred by the adaptive map, not simulated"
                                if inferred else "")
                 + ("\nhatched: outside the analytic model (its base slides or the ground lifts "
                    "it off)" if hatched else ""), fontsize=11)
    fig.tight_layout()
    if mesh is not None:
        fig.colorbar(mesh, ax=list(axes.ravel()), shrink=0.6, pad=0.02,
                     label="max |phi| / alpha of a surviving structure [-] (above 1 drawn as 1)")
    return fig


#: Short row labels of the small multiples (the four pulses).
_ROW = {("symmetric", 1): "symmetric +", ("symmetric", -1): "symmetric -",
        ("antisymmetric", 1): "antisym. +", ("antisymmetric", -1): "antisym. -"}


def _grid(ncols: int, title: str):
    """A small-multiples figure: four pulse rows, ``ncols`` columns of about 2.6 in, shared
    axes, at most as wide as the page (11.6 in at 100 dpi) and about 9 in tall."""
    width = min(11.6, 1.4 + 2.6 * max(ncols, 1))
    panel = (width - 1.4) / max(ncols, 1)
    row = min(0.75 * panel, 1.9)
    fig = Figure(figsize=(width, 4 * row + 1.9), layout="constrained")
    axes = fig.subplots(4, ncols, sharex=True, sharey=True, squeeze=False)
    fig.suptitle(title, fontsize=11)
    for i, (shape, sign, _) in enumerate(PANELS):
        axes[i, 0].set_ylabel(f"{_ROW[(shape, sign)]}\nA [-]")
    for ax in axes[-1]:
        ax.set_xlabel("W [-]")
    return fig, axes


def plot_map_grid(maps: "dict[str, pd.DataFrame]", *, title: str) -> Figure:
    """Small multiples of several analytic maps: one column per map (its label on top), one
    row per pulse, on W = omega_g / p (x) and A = a_g / (g tan alpha) (y); red overturns,
    blue shades max |phi| / alpha of a survivor (one colour bar), grey an inferred
    survivor."""
    from .legibility import wrap_at

    names = list(maps)
    fig, axes = _grid(len(names), title)
    mesh = None
    for j, name in enumerate(names):
        df = maps[name]
        axes[0, j].set_title(wrap_at(name, "-", 16), fontsize=10)
        for i, (shape, sign, _) in enumerate(PANELS):
            mesh = _draw_analytic(axes[i, j], df, shape, sign, _is_inferred(df)) or mesh
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, orientation="horizontal", shrink=0.5, aspect=40,
                     label="max |phi| / alpha of a surviving structure [-] (red: overturns)")
    return fig


def _draw_overlay(ax, ref: pd.DataFrame | None, eng: pd.DataFrame, shape: str, sign: int,
                  name: str, *, dense: int | None = None) -> None:
    """One panel of an engine on the analytic map of the same cells (see
    :func:`plot_map_overlay`)."""
    r = _pivot(ref, shape, sign) if ref is not None else None
    if r is not None:
        W, A = r.columns.to_numpy(float), r.index.to_numpy(float)
        ax.pcolormesh(_edges(W), _edges(A), r.to_numpy(), cmap=_CMAP, vmin=0, vmax=1,
                      shading="flat", alpha=0.55)
    g = eng[(eng["pulse"] == shape) & (eng["sign"] == sign)]
    if not len(g):
        return
    m = g.merge(ref[["pulse", "sign", "amplitude", "frequency", "overturned"]],
                on=["pulse", "sign", "amplitude", "frequency"], how="left",
                suffixes=("", "_ref"))
    ok = m["status"] == "ok"
    ot = m["overturned"].fillna(False).astype(bool) & ok
    sv = ~m["overturned"].fillna(True).astype(bool) & ok
    if len(m) <= (DENSE_CELLS if dense is None else dense):
        size = 28 if dense is None else 10
        ax.scatter(m.loc[ot, "frequency"], m.loc[ot, "amplitude"], marker="s", s=size,
                   color="#7b241c", label=f"{name}: overturns")
        ax.scatter(m.loc[sv, "frequency"], m.loc[sv, "amplitude"], marker="o", s=size,
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
    ax.scatter(m.loc[dis, "frequency"], m.loc[dis, "amplitude"], marker="o",
               s=140 if dense is None else 50, facecolors="none", edgecolors="black",
               linewidths=1.5, label="differs from analytic")
    ax.scatter(m.loc[~ok, "frequency"], m.loc[~ok, "amplitude"], marker="x",
               s=40 if dense is None else 16, color="grey", label="not ok")


def plot_map_overlay(ref: pd.DataFrame, eng: pd.DataFrame, *, name: str, title: str) -> Figure:
    """An engine's verdicts (markers: filled square overturns, open circle survives; above
    :data:`DENSE_CELLS` cells per panel its overturning boundary as a line instead; black
    ring: differs from the analytic verdict, grey x: run not ok) on the analytic map of the
    same cells (background: red overturns, light blue survives)."""
    fig = Figure(figsize=(11, 8.5))
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    for ax, (shape, sign, label) in zip(axes.ravel(), PANELS):
        ax.set_title(label, fontsize=10)
        _draw_overlay(ax, ref, eng, shape, sign, name)
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


def plot_overlay_grid(pairs: "dict[str, tuple[pd.DataFrame, pd.DataFrame]]", *,
                      title: str) -> Figure:
    """Small multiples of several engines on one structure: one column per engine (name ->
    (analytic map of its cells, its map)), one row per pulse. Background: the analytic
    verdict (red overturns, light blue survives); markers: the engine's verdicts (its
    boundary as a line on a dense grid); black ring: a cell where it differs; grey x: not ok.
    The legend sits below the panels, never over the data."""
    from .legibility import wrap_at

    names = list(pairs)
    fig, axes = _grid(len(names), title)
    for j, name in enumerate(names):
        ref, eng = pairs[name]
        axes[0, j].set_title(wrap_at(name, "-", 16), fontsize=10)
        for i, (shape, sign, _) in enumerate(PANELS):
            _draw_overlay(axes[i, j], ref, eng, shape, sign, "engine", dense=400)
    seen: dict[str, object] = {}
    for ax in axes.ravel():
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    if seen:
        fig.legend(list(seen.values()), list(seen), loc="outside lower center",
                   ncol=min(len(seen), 5), fontsize=9, frameon=False)
    return fig

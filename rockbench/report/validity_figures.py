"""The validity map in a report: its figure (:func:`plot_validity_map`), its sentences
(:func:`validity_sentences`, computed from the frame) and its page block
(:func:`validity_html`). Reads validity-map frames only (columns of
:data:`rockbench.studies.validity_map.VALIDITY_COLUMNS`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

__all__ = ["plot_validity_map", "validity_sentences", "validity_html", "REGION_COLORS",
           "REGION_LABELS"]

#: The regions in legend order, with their colours (categorical, distinguishable in grey).
REGION_COLORS: dict[str, str] = {"model": "#4c9be8", "agree": "#9bd08a",
                                 "disagree": "#f0a04b", "diverged": "#7f7f7f"}

#: What each region means, as the legend says it.
REGION_LABELS: dict[str, str] = {
    "model": "analytic model holds",
    "agree": "outside the model, engines agree",
    "disagree": "outside the model, engines disagree",
    "diverged": "outside the model, an engine diverged or failed"}


def _edges(x: np.ndarray) -> np.ndarray:
    if len(x) == 1:
        return np.array([x[0] - 0.5, x[0] + 0.5])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate(([x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]))


def plot_validity_map(frame: pd.DataFrame, *, title: str | None = None,
                      a_mu: float | None = None) -> Figure:
    """The regions of a validity map over (W, A): one colour per region
    (:data:`REGION_COLORS`), the legend below the panel; with ``a_mu`` [-] (A at which the
    PGA reaches mu g, mu / tan alpha, for a pulse whose peak is a_g) a dashed line there, the
    a-priori limit without rocking."""
    from .figures import legend_below

    codes = {r: i for i, r in enumerate(REGION_COLORS)}
    t = pd.DataFrame({"A": frame["A"].astype(float), "W": frame["W"].astype(float),
                      "c": frame["region"].map(codes).astype(float)})
    t = t.pivot_table(index="A", columns="W", values="c", aggfunc="first")
    t = t.sort_index().sort_index(axis=1)
    A, W = t.index.to_numpy(float), t.columns.to_numpy(float)
    fig = Figure(figsize=(6.4, 5.4), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(_edges(W), _edges(A), t.to_numpy(), shading="flat", vmin=-0.5,
                  vmax=len(codes) - 0.5, cmap=ListedColormap(list(REGION_COLORS.values())),
                  edgecolors="white", linewidth=0.5)
    ax.set_xlabel("W = ω_g / p [-]")
    ax.set_ylabel("A = a_g / (g tan α) [-]")
    if title:
        ax.set_title(title)
    if a_mu is not None and A.min() <= a_mu <= A.max():
        ax.axhline(a_mu, color="black", linestyle="--", linewidth=1.2,
                   label="PGA = mu g (structure at rest)")
    present = set(frame["region"])
    legend_below(fig, extra=[(Patch(color=REGION_COLORS[r]), REGION_LABELS[r])
                             for r in REGION_COLORS if r in present], max_cols=2)
    return fig


def validity_sentences(frame: pd.DataFrame, *, friction: float, tolerance: float,
                       engines: Sequence[str], friction_given: bool = True,
                       left_out: Sequence[str] = ()) -> list[str]:
    """Two or three sentences counting the cells of each region of ``frame`` with the scene's
    friction ``friction`` [-] (``friction_given``: the scene's own; else the engines' common
    default), the agreement ``tolerance`` [-], the ``engines`` run outside the model and
    those ``left_out`` of it."""
    n = len(frame)
    c = frame["region"].value_counts()
    k = {r: int(c.get(r, 0)) for r in REGION_COLORS}
    whose = (f"the scene's friction mu = {friction:.3g}" if friction_given else
             f"mu = {friction:.3g}, the validity rule's default, given to every engine for "
             "this map (the scene gives none)")
    out = [f"In {k['model']} of {n} cells the analytic model holds with {whose}: no contact needs more friction than it has and the ground never "
           f"falls faster than gravity."]
    outside = n - k["model"]
    if outside:
        who = ", ".join(engines) if engines else "no engine (none is installed)"
        one = " (one engine: it agrees with itself)" if len(engines) == 1 else ""
        out.append(f"In the other {outside} cells the structure slides or leaves the ground, and "
                   f"{who} ran{one}: they agree (the same verdict, and where the structure "
                   f"survives, its peak rotation and sliding within {100 * tolerance:.0f} %) "
                   f"in {k['agree']}, disagree in "
                   f"{k['disagree']}, and at least one diverged or failed in {k['diverged']}.")
        ag = frame[frame["region"] == "agree"]
        if len(ag) and len(engines) > 1:
            best = ag["cheapest"].value_counts()
            out.append("Where they agree, the cheapest in CPU time is "
                       + ", ".join(f"{e} in {int(m)} cells" for e, m in best.items()) + ".")
        if left_out:
            out.append(f"Not run outside the model here: {', '.join(left_out)} (the slower "
                       "engines; `rockbench report --full` runs every engine).")
    else:
        out.append("No cell of this grid is outside the model: the analytic model is the "
                   "reference everywhere on it, and no engine had to run.")
    return out


def validity_html(section: Mapping[str, Any], figdir: Any = None) -> str:
    """The page block of the section "Where the analytic model holds" (``section``: ``frame``,
    ``scene``, ``friction``, ``tolerance``, ``engines``, ``shape``, ``sign``, ``tail`` [s], or
    ``error``)."""
    from . import html as H

    if section.get("error"):
        return f"<p>The validity map failed: {H.fmt(section['error'])}</p>"
    df = section["frame"]
    words = validity_sentences(df, friction=section["friction"],
                               tolerance=section["tolerance"], engines=section["engines"],
                               friction_given=section.get("friction_given", True),
                               left_out=section.get("left_out", ()))
    sign = "+" if section.get("sign", 1) > 0 else "-"
    caption = (f"{section['scene']}: where the analytic model holds under {section['shape']} "
               f"Ricker pulses ({sign}), {df['A'].nunique()} x {df['W'].nunique()} cells, "
               f"A in [{df['A'].min():g}, {df['A'].max():g}], W in [{df['W'].min():g}, "
               f"{df['W'].max():g}], with mu = {section['friction']:.3g}. Outside the model the "
               f"engines run at their default settings; they agree when they give the same "
               f"verdict and their peak |phi| and sliding spread by at most "
               f"{100 * section['tolerance']:.0f} % of the median (docs/maps.md).")
    parts = ["<ul>" + "".join(f"<li>{H.fmt(s)}</li>" for s in words) + "</ul>",
             H.figure_html(plot_validity_map(df, title=f"{section['scene']}: validity map",
                                             a_mu=section.get("a_mu")),
                           caption, name="validity_map", png_dir=figdir)]
    return "\n".join(parts)

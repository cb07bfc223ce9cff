"""The overturning-map section of the campaign page (paper Figs. 4-7): analytic maps at the
paper's resolution, every engine overlaid on the analytic map of the same cells, and the
agreement table (fraction, Cohen's kappa, boundary shift)."""

from __future__ import annotations

from typing import Any, Mapping

from . import html as H
from .tables import CAMPAIGN_COLUMNS
from .map_figures import plot_map_grid, plot_overlay_grid

__all__ = ["maps_html"]

#: The columns of ``map_agreement.csv`` the page shows (every one is in the file,
#: :data:`rockbench.report.tables.CAMPAIGN_COLUMNS`); the words say the rest.
SHOWN = ("scene", "backend", "grid", "cells", "differ", "agree_fraction", "kappa", "not_ok",
         "disagree_near_boundary", "disagree_away", "boundary_shift_mean")


def maps_html(maps: Mapping[str, Any], figdir, *, analytic_grid: str, axes: str,
              paper: bool = True) -> str:
    """HTML of the map section from :func:`rockbench.campaign.maps.run_maps`'s output;
    ``paper``: the paper's plan (its maps are the paper's Figs. 4-7; a user's are not)."""
    parts = []
    if maps["analytic"]:
        names = list(maps["analytic"])
        parts.append(H.figure_html(
            plot_map_grid(maps["analytic"], title="Analytic overturning maps"),
            f"The analytic model (compiled path), {analytic_grid}, one column per structure ("
            + ", ".join(names) + "), one row per pulse"
            + (" (the paper's Figs. 4-7)" if paper else "") +
            ": red overturns, blue shades are max |phi| / alpha of a surviving structure; "
            "W = omega_g / p [-], A = a_g / (g tan alpha) [-].",
            name="maps_analytic", png_dir=figdir))
    ag = maps.get("agreement")
    if ag is not None and len(ag):
        parts.append("<h3>Every engine against the analytic map</h3><ul>"
                     + "".join(f"<li>{H.escape(w)}</li>" for w in maps["words"]) + "</ul>")
        by_scene: dict[str, dict[str, tuple]] = {}
        for (scene, eng), df in maps["engine"].items():
            g = next(k for k in maps["overlay_ref"] if k[0] == scene and
                     f"{k[1][0]}x{k[1][1]}x4" == ag[(ag.scene == scene) &
                                                     (ag.backend == eng)]["grid"].iloc[0])
            by_scene.setdefault(scene, {})[eng] = (maps["overlay_ref"][g], df)
        for scene, pairs in by_scene.items():
            parts.append(H.figure_html(
                plot_overlay_grid(pairs, title=f"{scene}: each engine on the analytic map"),
                f"{scene}: each engine's verdicts (markers, or its boundary as a line on a "
                f"dense grid) on the analytic map of the same cells (background: red "
                f"overturns), {axes}; a black ring marks a cell where the engine differs, a "
                "grey x a run that did not finish ok.",
                name=f"maps_{scene}_engines", png_dir=figdir))
        cols = CAMPAIGN_COLUMNS["map_agreement.csv"]
        parts.append(H.html_table(ag, [c for c in SHOWN if c in ag], units=cols, graded=False))
        if maps.get("provenance"):
            parts.append(_details_list(
                "Where each engine map comes from", "The plan's measured grid is measured by "
                "<code>rockbench report --full</code> and reused only when sample cells re-run "
                "now reproduce them:", maps["provenance"]))
    return "\n".join(parts) or "<p>No map.</p>"


def _details_list(summary: str, lead: str, items) -> str:
    return (f"<details><summary>{H.escape(summary)}</summary><p>{lead}</p><ul>"
            + "".join(f"<li>{H.escape(w)}</li>" for w in items) + "</ul></details>")

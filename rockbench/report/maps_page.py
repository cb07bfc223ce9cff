"""The overturning-map section of the campaign page (paper Figs. 4-7): analytic maps at the
paper's resolution, every engine overlaid on the analytic map of the same cells, and the
agreement table (fraction, Cohen's kappa, boundary shift)."""

from __future__ import annotations

from typing import Any, Mapping

from . import html as H
from .map_figures import plot_map_overlay, plot_map_panels

__all__ = ["AGREEMENT_COLUMNS", "maps_html"]

#: Columns of ``map_agreement.csv``.
AGREEMENT_COLUMNS: dict[str, str] = {
    "scene": "-", "backend": "-", "grid": "-, A points x W points x 4 pulses",
    "cells": "-, cells both maps ran with status ok",
    "agree_fraction": "-, cells whose overturning verdict equals the analytic one",
    "kappa": "-, Cohen's kappa of the verdicts (1: perfect, 0: chance)",
    "engine_overturns_analytic_survives": "-, cells",
    "analytic_overturns_engine_survives": "-, cells",
    "boundary_shift_mean": "-, mean over pulses and frequencies of A_min(engine) - "
                           "A_min(analytic) (negative: the engine overturns earlier)",
    "boundary_shift_max_abs": "-, largest |A_min(engine) - A_min(analytic)|",
    "not_ok": "-, engine cells that did not finish ok",
    "near_boundary": "-, cells within 2 % in A of the analytic boundary (near the boundary)",
    "disagree_near_boundary": "-, differing verdicts near the boundary",
    "disagree_away": "-, differing verdicts away from the boundary",
    "in_words": "-, where the engine's boundary sits relative to the analytic one",
}


def maps_html(maps: Mapping[str, Any], figdir, *, analytic_grid: str, axes: str,
              paper: bool = True) -> str:
    """HTML of the map section from :func:`rockbench.campaign.maps.run_maps`'s output;
    ``paper``: the paper's plan (its maps are the paper's Figs. 4-7; a user's are not)."""
    parts = []
    for scene, df in maps["analytic"].items():
        parts.append(H.figure_html(
            plot_map_panels(df, title=f"{scene}: analytic overturning map"),
            f"{scene}, analytic model (compiled path), {analytic_grid}: the four panels "
            + ("of the paper's Figs. 4-7 " if paper else "") +
            "(symmetric and antisymmetric pulses, both signs) on "
            "W = omega_g / p [-] and A = a_g / (g tan alpha) [-].",
            name=f"map_{scene}_analytic", png_dir=figdir))
    ag = maps.get("agreement")
    if ag is not None and len(ag):
        parts.append("<h3>Every engine against the analytic map</h3><ul>"
                     + "".join(f"<li>{H.escape(w)}</li>" for w in maps["words"]) + "</ul>")
        if maps.get("provenance"):
            parts.append("<p>Where each engine map comes from (the plan's measured grid is "
                         "measured by <code>rockbench report --full</code> and reused only when "
                         "sample cells re-run now reproduce them):</p><ul>"
                         + "".join(f"<li>{H.escape(w)}</li>" for w in maps["provenance"])
                         + "</ul>")
        parts.append(H.html_table(ag, list(AGREEMENT_COLUMNS), units=AGREEMENT_COLUMNS,
                                  graded=False, scroll=True))
        for (scene, eng), df in maps["engine"].items():
            g = next(k for k in maps["overlay_ref"] if k[0] == scene and
                     f"{k[1][0]}x{k[1][1]}x4" == ag[(ag.scene == scene) &
                                                     (ag.backend == eng)]["grid"].iloc[0])
            parts.append(H.figure_html(
                plot_map_overlay(maps["overlay_ref"][g], df, name=eng,
                                 title=f"{scene}: {eng} on the analytic map"),
                f"{scene}: {eng}'s verdicts (markers) on the analytic map of the same cells "
                f"(background), {axes}; a black ring marks a cell where {eng} differs.",
                name=f"map_{scene}_{eng}", png_dir=figdir))
    return "\n".join(parts) or "<p>No map.</p>"

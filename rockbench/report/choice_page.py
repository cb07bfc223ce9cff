"""The "choosing a modelling approach" section of the campaign page: the recommendation, the
work-precision plot and table it rests on, and each engine's stability map."""

from __future__ import annotations

from typing import Any, Mapping

from . import html as H
from .tradeoff_figures import plot_stability_map, plot_work_precision

__all__ = ["choice_html"]


def choice_html(choice: Mapping[str, Any], figdir) -> str:
    parts = []
    if choice.get("words"):
        parts.append("<ul>" + "".join(f"<li>{H.escape(w)}</li>" for w in choice["words"])
                     + "</ul>")
    tab = choice.get("tradeoff")
    if tab is not None and len(tab):
        parts.append(H.figure_html(
            plot_work_precision(tab),
            "Work-precision on paper-asymmetric (the validation set: free rocking from two "
            "amplitudes in both directions, pulses that the frame survives, near and far "
            "from the boundary, and pulses that overturn it): worst error against the analytic "
            "model [-] against the cost in process CPU seconds per simulated second [-], one "
            "curve per engine over its time steps, Pareto front marked. The full sweeps: "
            "docs/choosing.md (self-consistency at dt / 4, more time steps, repeats).",
            name="work_precision", png_dir=figdir))
        adv = choice["advice"]
        if len(adv):
            parts.append("<h3>The cheapest setting of each engine within 2 % and 0.2 %</h3>"
                         + H.html_table(adv, list(adv.columns), graded=False, scroll=True))
    st = choice.get("stress")
    br = choice.get("breaks")
    if br is not None and len(br):
        parts.append("<h3>Where each engine breaks first</h3><p>Per engine and axis, going away "
                     "from the paper's frame on either side, the first value at which the run "
                     "is off (beyond 5 % of the analytic model, or flagged), diverged or "
                     "invalid; points where the analytic model itself stops applying are "
                     "skipped (stress_breaking_points.csv; every point: stress.csv).</p>"
                     + H.html_table(br, list(br.columns), graded=False, scroll=True))
    if st is not None and len(st):
        for eng in [e for e in dict.fromkeys(st["engine"])]:
            parts.append(H.figure_html(
                plot_stability_map(st, eng), f"{eng}: where it stays within 1 % and 5 % of "
                "the analytic model, where it breaks, and where the analytic model itself stops "
                "applying, one axis at a time from the paper's frame (rockbench stress, "
                + ("full form" if choice.get("stress_full") else "fast form; the full form: "
                   "rockbench report --full or rockbench stress --full") + ").",
                name=f"stability_{eng}", png_dir=figdir))
    return "\n".join(parts) or "<p>No engine besides the analytic reference.</p>"

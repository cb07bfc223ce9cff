"""The "choosing a modelling approach" section of the campaign page: the recommendation, the
work-precision plot and table it rests on, and each engine's stability map."""

from __future__ import annotations

from typing import Any, Mapping

import pandas as pd

from . import html as H
from .decision import pct
from .tradeoff_figures import plot_stability_map, plot_work_precision

__all__ = ["choice_html", "work_precision_html", "advice_display"]

#: advice.csv columns that are fractions, shown as percentages.
_FRACTIONS = ("tolerance", "worst_error_choice", "worst_error_heldout")


def advice_display(adv: pd.DataFrame) -> pd.DataFrame:
    """The advice table as a reader wants it: fractions as percentages, and no setting on a row
    whose engine cannot reach the tolerance (the setting there is only its best try, which the
    ``reason`` names)."""
    out = adv.copy()
    for c in _FRACTIONS:
        if c in out:
            out[c] = [pct(v) for v in out[c]]
    if "status" in out and "setting" in out:
        out["setting"] = out["setting"].where(out["status"].astype(str) != "not installed", "")
    out = out.drop(columns=[c for c in ("dt", "rank") if c in out and "setting" in out])
    names = {c: f"{c.replace('_', ' ')} [%]" for c in _FRACTIONS if c in out}
    names.update({"cpu_per_sim_s": "CPU s per simulated s", "real_time_factor":
                  "real-time factor [-]"})
    return out.rename(columns=names)


def work_precision_html(choice: Mapping[str, Any], figdir, *, scene: str) -> str:
    """The work-precision figure of the choice, or nothing."""
    tab = choice.get("tradeoff")
    if tab is None or not len(tab):
        return ""
    return H.figure_html(
        plot_work_precision(tab),
        f"Work-precision on {scene}: worst error against the analytic model [-] over the cost "
        "[CPU s per simulated s], one curve per engine and setting, Pareto front marked.",
        name="work_precision", png_dir=figdir)


def choice_html(choice: Mapping[str, Any], figdir, *, with_work_precision: bool = True) -> str:
    parts = []
    if choice.get("words"):
        parts.append("<ul>" + "".join(f"<li>{H.escape(w)}</li>" for w in choice["words"])
                     + "</ul>")
    tab = choice.get("tradeoff")
    if tab is not None and len(tab) and with_work_precision:
        parts.append(H.figure_html(
            plot_work_precision(tab),
            f"Work-precision on {choice.get('scene', 'the scene')} (the "
            f"{choice.get('evidence', 'quick')} evidence of rockbench advise: free "
            "rocking from small and large angles, pulse cells across the A-W plane away from "
            "and near the overturning boundary, scaled records; both parts, choice and "
            "held-out): worst error against the analytic model [-] against the steady-state "
            "cost in process CPU seconds per simulated second [-] (model build and warm-up "
            "apart), one curve per engine over its time steps, Pareto front marked. The "
            "advice below is chosen on the choice part and confirmed on the held-out part "
            "(docs/choosing.md).",
            name="work_precision", png_dir=figdir))
    adv = choice.get("advice")
    if adv is not None and len(adv):
        shown = advice_display(adv)
        parts.append("<details><summary>The advice table (advice.csv): each engine's fate and "
                     "cheapest setting within each tolerance, with the reason</summary>"
                     + H.html_table(shown, list(shown.columns), graded=False) + "</details>")
    st = choice.get("stress")
    br = choice.get("breaks")
    base = choice.get("stress_base") or "the base scene"
    if br is not None and len(br):
        parts.append("<h3>Where each engine breaks first</h3><p>Per engine and axis, going away "
                     f"from {H.escape(base)} on either side, the first value at which the run "
                     "is off (beyond 5 % of the analytic model, or flagged), diverged or "
                     "invalid; points where the analytic model itself stops applying are "
                     "skipped (stress_breaking_points.csv; every point: stress.csv).</p>"
                     + H.html_table(br, list(br.columns), graded=False, scroll=True))
    skipped = choice.get("stress_skipped") or {}
    if skipped:
        parts.append(f"<p>Not run: points whose structure the model refuses (they say nothing "
                     f"about an engine) from {H.escape(base)}: "
                     + "; ".join(f"{H.escape(k)} ({H.escape(v)})" for k, v in skipped.items())
                     + ".</p>")
    if st is not None and len(st):
        for eng in [e for e in dict.fromkeys(st["engine"])]:
            parts.append(H.figure_html(
                plot_stability_map(st, eng, base=base, labels=choice.get("stress_labels"),
                                   base_values=choice.get("stress_base_values")),
                f"{eng}: where it stays within 1 % and 5 % of "
                "the analytic model, where it breaks, and where the analytic model itself stops "
                f"applying, one axis at a time from {base} (dashed: its own value; rockbench "
                "stress, "
                + ("full form" if choice.get("stress_full") else "fast form; the full form: "
                   "rockbench report --full or rockbench stress --full") + ").",
                name=f"stability_{eng}", png_dir=figdir))
    return "\n".join(parts) or "<p>No engine besides the analytic reference.</p>"

"""The "choosing a modelling approach" part of the default campaign (issues 13, 24):
work-precision of every engine on the paper's asymmetric frame (the quick evidence of
:func:`rockbench.studies.validation.validation_set` - a subset of the default one, split into a choice
and a held-out part - at three time steps; ``full=True``: the default evidence; steady-state
process CPU time), the advice it supports at 2 % and 0.2 % (chosen on the choice part,
confirmed on the held-out part, :func:`rockbench.studies.advise.decide`), and the stability sweep (the
fast form of ``rockbench stress``; ``full=True`` runs its full form).

Self-consistency (each setting against the same engine at dt / 4) is left to ``rockbench
tradeoff`` (``docs/choosing.md``). Results are kept in the campaign's store.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

__all__ = ["run_choice", "recommendation"]


def run_choice(engines: Sequence[str], store: Path, *, quick: bool = False,
               full: bool = False, workers: int | None = None,
               progress: bool = False, scene: Any = None, dts: Sequence[float] | None = None,
               stress_scene: Any = None, stress_hybrid: Any = None,
               evidence: str = "quick",
               absent: Sequence[Mapping[str, str]] = ()) -> dict[str, Any]:
    """{"tradeoff": table, "advice": frame, "stress": table or None, "breaks": the first
    breaking point of each engine along each axis (:func:`rockbench.studies.robustness.breaking_points`)
    or None, "words": [str]}: the
    stability sweep runs in its fast form (``full``: the full form; ``quick``: none).
    ``evidence``: the validation set the advice is chosen and confirmed on (a plan's
    ``choice_evidence``); ``full`` takes the next larger one, ``quick`` the quick one.
    ``absent``: the registered engines that did not run (:func:`rockbench.engines.
    engine_states` rows: name, state, detail), listed in the advice with their state."""
    from ..studies.advise import advice_for_report
    from ..scene.scene import load_scene
    from ..studies.robustness import AXES, axis_label, base_values, breaking_points, stress
    from ..studies.tradeoff import tradeoff

    names = [e for e in engines if e != "analytic"]
    if not names:
        return {"tradeoff": pd.DataFrame(), "advice": pd.DataFrame(), "stress": None,
                "breaks": None, "words": []}
    from ..studies.validation import validation_set

    from .plan import campaign_plan

    paper = campaign_plan()                   # the paper's plan when the caller gives none
    scene = paper["choice_scene"] if scene is None else scene
    dts = tuple(paper["choice_dts"] if dts is None else dts)
    dts = dts[:2] if quick else dts
    size = ("quick" if quick else
            {"quick": "default", "default": "full", "full": "full"}[evidence] if full
            else evidence)
    cases = validation_set(load_scene(scene), size=size)
    t = tradeoff(scene, names, dts=dts, repeat=1, cases=cases,
                 self_consistency="none", workers=workers, store=store / "tradeoff",
                 progress=progress)
    gone = {r["name"]: (r["state"], r["detail"]) for r in absent}
    gone.update({n: ("not installed", why) for n, why in t.unavailable.items()})
    advice = advice_for_report(t.table, absent=gone)
    sw = None if quick else stress(names, full=full, workers=workers, progress=progress,
                                   scene=stress_scene, hybrid=stress_hybrid)
    st = None if sw is None else sw.table
    label = getattr(load_scene(scene), "name", str(scene))
    # the stability sweep's base, by its own name (the paper's frame when the plan names none)
    stress_base = load_scene(stress_scene if stress_scene is not None else "paper-asymmetric")
    return {"tradeoff": t.table, "advice": advice, "stress": st, "stress_full": full,
            "evidence": size,
            "breaks": breaking_points(st, stress_scene) if st is not None else None,
            "words": recommendation(advice, label), "scene": label,
            "stress_base": stress_base.name,
            "stress_labels": {a: axis_label(a) for a in [*AXES, "paper", "base"]},
            "stress_base_values": base_values(stress_scene),
            "stress_skipped": {} if sw is None else sw.skipped}


def recommendation(advice: pd.DataFrame, scene: str = "the structure") -> list[str]:
    """The report's headline: per tolerance, the recommended engine and setting (rank 1 when
    it meets the tolerance), then the others in order, and those that cannot reach it."""
    lines = []
    if not len(advice):
        return lines
    for tol, g in advice.groupby("tolerance", sort=False):
        g = g.sort_values("rank")
        meets = g[g["status"] == "meets"]
        pct = f"{100 * tol:g} %"
        if len(meets):
            b = meets.iloc[0]
            ho = b.get("held_out_worst_error", float("nan"))
            ho_text = (f", {100 * ho:.2f} % on the held-out cases" if ho == ho else "")
            text = (f"Within {pct} of the analytic model on {scene} (worst error over "
                    f"the choice part of the evidence, confirmed on its held-out part): use "
                    f"{b['engine']} with {b['setting']} "
                    f"(worst error {100 * b['worst_error']:.2f} %{ho_text}, "
                    f"{b['cpu_per_sim_s']:.3g} CPU s per simulated s, real-time factor "
                    f"{b['real_time_factor']:.3g})")
            from ..studies.advise import TIE

            tied = [r for _, r in meets.iloc[1:].iterrows()
                    if r["cpu_per_sim_s"] <= TIE * b["cpu_per_sim_s"]]
            if tied:
                safest = min([b] + tied, key=lambda r: r["worst_error"])
                text += (f". A tie on cost with {', '.join(r['engine'] for r in tied)} (within "
                         f"{100 * (TIE - 1):.0f} %, which CPU time moves between measurements "
                         f"on a shared machine): of these, {safest['engine']} "
                         f"({safest['setting']}) has the largest margin, worst error "
                         f"{100 * safest['worst_error']:.2f} %")
            if len(meets) > 1:
                text += "; in order of cost: " + ", ".join(
                    f"{r['engine']} ({r['setting']}, {100 * r['worst_error']:.2f} %, "
                    f"{r['cpu_per_sim_s']:.3g} CPU s/s)" for _, r in meets.iloc[1:].iterrows())
            lines.append(text + ".")
        else:
            lines.append(f"No engine reaches {pct} on {scene} at the time steps tried.")
        miss = g[g["status"] != "meets"]
        if len(miss):
            lines.append(f"Not within {pct}: " + "; ".join(
                f"{r['engine']} ({r['reason']})" for _, r in miss.iterrows()) + ".")
    return lines

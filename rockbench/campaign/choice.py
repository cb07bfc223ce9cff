"""The "choosing a modelling approach" part of a campaign: the decision on the plan's choice
scene - the one search of ``rockbench advise`` (:func:`rockbench.studies.search.search`: the
same scene and evidence give the same answer) over the ladder of tolerances
(:data:`rockbench.studies.search.TOLERANCE_LADDER`), on the plan's evidence - and the stability
sweep (the fast form of ``rockbench stress``; ``full=True`` runs its full form, ``quick`` none).
Results are kept in the campaign's store; a rerun resumes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import pandas as pd

__all__ = ["run_choice"]


def run_choice(engines: Sequence[str], store: Path, *, quick: bool = False,
               full: bool = False, workers: int | None = None,
               progress: bool = False, scene: Any = None,
               stress_scene: Any = None, stress_hybrid: Any = None,
               evidence: str = "quick", vertical: float = 0.0) -> dict[str, Any]:
    """{"decision": the search's Decision (or None with no engine), "tradeoff": its evidence
    table, "advice": its advice table (:func:`rockbench.studies.advise.advice_table`),
    "evidence": the size, "scene": the scene's name, "stress": table or None, "breaks": the
    first breaking point of each engine along each axis or None, the stability sweep's
    labels}. ``evidence``: the plan's ``choice_evidence`` (``full`` takes the next larger one,
    ``quick`` the quick one); ``engines``: the engines that run (the others are listed by the
    search with their state); ``vertical``: r, the evidence's vertical motion (a_v = r x
    horizontal; the stability sweep stays horizontal: its axes are the structure's and the
    engines')."""
    from ..scene.scene import load_scene
    from ..studies.advise import advice_table
    from ..studies.robustness import AXES, axis_label, base_values, breaking_points, stress
    from ..studies.search import TOLERANCE_LADDER, search
    from .plan import campaign_plan

    names = [e for e in engines if e != "analytic"]
    scene = campaign_plan()["choice_scene"] if scene is None else scene
    size = ("quick" if quick else
            {"quick": "default", "default": "full", "full": "full"}[evidence] if full
            else evidence)
    label = load_scene(scene).name
    decision = None
    if names:
        decision = search(scene, TOLERANCE_LADDER, names, size=size,
                          store=Path(store) / "search", workers=workers, progress=progress,
                          vertical=vertical)
    sw = None if quick or not names else stress(names, full=full, workers=workers,
                                                progress=progress, scene=stress_scene,
                                                hybrid=stress_hybrid)
    st = None if sw is None else sw.table
    # the stability sweep's base, by its own name (the paper's frame when the plan names none)
    stress_base = load_scene(stress_scene if stress_scene is not None else "paper-asymmetric")
    return {"decision": decision,
            "tradeoff": decision.evidence if decision is not None else pd.DataFrame(),
            "advice": advice_table(decision) if decision is not None else pd.DataFrame(),
            "stress": st, "stress_full": full, "evidence": size,
            "breaks": breaking_points(st, stress_scene) if st is not None else None,
            "scene": label, "stress_base": stress_base.name,
            "stress_labels": {a: axis_label(a) for a in [*AXES, "paper", "base"]},
            "stress_base_values": base_values(stress_scene),
            "stress_skipped": {} if sw is None else sw.skipped}

"""A campaign's page: the sections its tables make (:func:`rockbench.report.campaign_page.
page_sections`), the decision first (:mod:`rockbench.report.decision`), the maps, the choice,
fragility and the run time, written as one self-contained ``index.html``. Reads the
:class:`~rockbench.campaign.run.CampaignTables` only: nothing here runs a simulation."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pandas as pd

from ..report import campaign_page as P
from ..report.conclusions import campaign_conclusion
from ..run_length import describe
from ..sweep.executors import cpu_count

__all__ = ["write_page", "model_row"]


def _engine_versions() -> dict[str, str]:
    """Backend name -> engine version, or why it is unavailable (the page's versions)."""
    from ..engines import engine_info

    return {r["name"]: (r.get("version") if r["available"]
                        else f"unavailable: {r.get('reason', '')}") for r in engine_info()}


def _all_frames(scenes) -> bool:
    """Whether every scene is a frame (the findings then say "frames", else "structures")."""
    from ..scene import load_scene

    return all(hasattr(load_scene(s).structure, "column_height_left") for s in scenes)


def _hybrid(scenes, labels: dict[str, str]) -> dict[str, bool]:
    """Scene name -> whether it has devices (tendons, dampers)."""
    from ..scene import load_scene

    out = {}
    for s in scenes:
        try:
            out[s] = out[labels.get(s, s)] = load_scene(s).devices is not None
        except Exception:  # noqa: BLE001 - not loadable here: judged by its name
            pass
    return out


def _model_cost(t: Any) -> float | None:
    """The analytic model's cost [CPU s per simulated s]: the median over the comparisons'
    cases of its compiled path's run (``model_cpu_per_sim_s`` of each payload, measured beside
    the engines: the cheapest way to run the model); None when none was measured."""
    import math
    import statistics

    costs = [float(c) for p in (t.payloads or [])
             if (c := p.get("model_cpu_per_sim_s")) is not None and math.isfinite(float(c))]
    return float(statistics.median(costs)) if costs else None


def model_row(t: Any, scene_word: str) -> dict[str, Any] | None:
    """The analytic model's row of the decision for the decision's scene (``scene_word``, a
    label of ``t.labels`` or a scene of the plan): its cost (:func:`_model_cost`) and where it
    holds and ends by the one validity rule (:mod:`rockbench.validity`); None without a
    measured cost."""
    from ..constants import G
    from ..scene import load_scene
    from ..validity import friction_of, pga_limit

    cost = _model_cost(t)
    if cost is None:
        return None
    scenes = list(t.plan["scenes"])
    pick = next((s for s in scenes if t.labels.get(s, s) == scene_word or s == scene_word),
                scenes[0] if scenes else None)
    if pick is None:
        return None
    scene = load_scene(pick)
    mu, lim = friction_of(scene), pga_limit(scene) / G
    given = ("the scene's friction" if scene.friction is not None
             else "the validity rule's default, which every engine's own friction reaches: "
                  "the scene gives none")
    return {"cpu_per_sim_s": cost,
            "holds": f"PGA <= mu g = {lim:.3g} g with mu = {mu:g} ({given}), no sliding "
                     "onset along the run, contact kept",
            "breaks": f"PGA > {lim:.3g} g: the base slides (outside the model)"}


def _write_runtime(timings: dict[str, tuple[float, float]], path: Path) -> None:
    """``runtime.csv``: wall and CPU seconds of each part of the run (columns in
    :data:`rockbench.report.tables.CAMPAIGN_COLUMNS`)."""
    from ..machine import cpu_name

    pd.DataFrame([{"part": k, "wall_s": round(w, 2), "cpu_s": round(c, 2),
                   "workers": cpu_count(), "processor": cpu_name()}
                  for k, (w, c) in timings.items()]).to_csv(path, index=False)


def _render_apart(jobs: dict[str, tuple[Any, tuple, dict]]):
    """Start rendering ``jobs`` (key -> (function, args, kwargs), each returning a page
    block's HTML) in one spawned process, unless the machine has a single core; return a
    function that waits for them and gives key -> HTML. The child's CPU is counted with this
    process's once it has ended (:func:`rockbench.machine.tree_cpu_s`)."""
    if cpu_count() < 2 or not jobs:
        return lambda: {k: f(*a, **kw) for k, (f, a, kw) in jobs.items()}
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ex = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
    futures = {k: ex.submit(f, *a, **kw) for k, (f, a, kw) in jobs.items()}

    def wait() -> dict[str, str]:
        try:
            return {k: fu.result() for k, fu in futures.items()}
        finally:
            ex.shutdown(wait=True, cancel_futures=True)
    return wait


def write_page(t: Any, out: Path) -> Path:
    """Write ``out/index.html`` (and its figures under ``out/figures``) from a campaign's
    tables ``t``; return the page's path."""
    from ..report.choice_page import choice_html, work_precision_html
    from ..report.decision import decision_html, decision_sentences, evidence_note
    from ..report.maps_page import maps_html
    from ..machine import tree_cpu_s
    from .plan import structure_table

    w0, c0 = time.perf_counter(), tree_cpu_s()
    plan, choice, maps = t.plan, t.choice, t.maps
    decision = choice.get("decision")
    scene_word = choice.get("scene", "the structure")
    mp = plan["maps"]
    g = (12, 12) if t.quick else mp["analytic_grid"]           # what run_maps ran
    # the maps', validity and fragility figures render in a process of their own while this
    # one renders the others (figures are the page's cost; each block reads its own tables)
    apart = {"maps-section": ("Overturning maps" + (" (paper Figs. 4-7)" if t.paper else ""),
                              maps_html, (maps, out / "figures"), dict(
        analytic_grid=f"{g[0]} x {g[1]} cells per panel, A in {mp['analytic_amplitude']}, "
                      f"W in {mp['analytic_frequency']}, {describe('pulse')}",
        axes=f"A in {mp['engine_amplitude']}, W in {mp['engine_frequency']}, "
             f"{describe('pulse', mp['engine_tail'])}", paper=t.paper))}
    if t.validity:
        from ..report.validity_figures import validity_html
        apart["validity-section"] = ("Where the analytic model holds", validity_html,
                                     (t.validity, out / "figures"), {})
    if t.fragility:
        from ..report.fragility_figures import fragility_html
        apart["fragility-section"] = ("Fragility over records" + (" (paper Fig. 9)"
                                                                  if t.paper else ""),
                                      fragility_html, (t.fragility, out / "figures"), {})
    pending = _render_apart({k: v[1:] for k, v in apart.items()})
    lines = campaign_conclusion(t.engines, t.metrics, t.eta_summary, t.records,
                                hybrid=_hybrid(plan["scenes"], t.labels),
                                noun="frames" if _all_frames(plan["scenes"]) else "structures")
    # the decision first (measured, CPU time), then the maps' agreement, then the evidence
    model = model_row(t, scene_word)
    words = decision_sentences(choice["advice"], scene_word,
                               next_steps=decision.next_steps if decision else None, model=model)
    lines = words + maps["words"] + lines
    sections = P.page_sections(t, lines, out / "figures", engine_versions=_engine_versions(),
                               files=list(t.files()))
    sections["choice-section"] = ("Choosing a modelling approach",
                                  choice_html(choice, out / "figures", with_work_precision=False))
    sections["decision-section"] = ("Which engine and settings", decision_html(
        choice["advice"], scene=scene_word, structure=plan.get("description", ""),
        structures=None if t.paper else structure_table(plan["scenes"]),
        agreement=maps["agreement"], eta_summary=t.eta_summary, breaks=choice.get("breaks"),
        next_steps=decision.next_steps if decision else None, model=model,
        notes=[n for n in [evidence_note(choice.get("tradeoff"),
                                         size=choice.get("evidence", "quick"),
                                         coverage=decision.coverage if decision else None,
                                         cpu_s=decision.cpu_s if decision else None)] if n],
        work_precision_html=work_precision_html(choice, out / "figures", scene=scene_word)))
    for key, html in pending().items():
        sections[key] = (apart[key][0], html)
    timings = dict(t.timings, report=(time.perf_counter() - w0, tree_cpu_s() - c0))
    total = (time.perf_counter() - t.t_start, tree_cpu_s() - t.cpu_start)
    sections["runtime-section"] = ("Run time", P.runtime_html(timings, total, cpu_count()))
    _write_runtime(dict(timings, total=total), out / "runtime.csv")
    path = out / "index.html"
    path.write_text(P.render(P.ordered(sections), quick=t.quick,
                             with_records=bool(len(t.records)),
                             about=None if t.paper else plan.get("description", "")),
                    encoding="utf-8")
    return path

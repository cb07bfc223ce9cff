"""``rockbench advise``: which engine, which setting, for one or several tolerances, at what
cost - chosen on one part of the scene's evidence and confirmed on another.

:func:`advise` is :func:`rockbench.studies.search.search` (the one search the report uses too:
the same scene and evidence give the same answer) seen from a command: :class:`Advice` is its
answer in words (:meth:`Advice.text`) and as JSON (:meth:`Advice.to_json`). The evidence, the
rule (converge on the choice part, confirm on the held-out part, a held-out failure sends the
engine to its next finer setting), the order (cheapest engines first, none going finer once it
is dearer than a confirmed answer), the budget and the vocabulary of the fates
(:data:`rockbench.fates.FATES`) are the search's.

**Cost** is steady-state process CPU seconds per simulated second (the model build of every
run and each process's one-off warm-up measured apart, never ranked):
:mod:`rockbench.studies.tradeoff`. Engines within :data:`rockbench.studies.decide.TIE` of the
cheapest are a tie. Runs are kept in the one store (``store``): a rerun resumes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import pandas as pd

from ..errors import ParameterError
from ..result import as_float
from .decide import TIE, _pct

__all__ = ["Advice", "advise", "precision_knob", "setting_args",
           "advice_table"]

_EVIDENCE = ["engine", "setting", "dt", "worst_error_choice", "worst_error_heldout",
             "worst_error", "verdict", "peak_error_worst", "eta_error_worst", "nrmse_worst",
             "near_disagree", "outside_band", "n_ok", "n_cases", "n_choice", "n_heldout",
             "cpu_per_sim_s", "real_time_factor", "build_cpu_s", "warmup_cpu_s"]


def precision_knob(engine: str) -> tuple[str, tuple[float, ...]]:
    """(name, values from coarse to fine) of ``engine``'s precision knob: the first of its
    work-precision curves (its backend's ``precision_sweeps``) that sweeps its own knob with
    its own values (e.g. an error-controlled integrator's accuracy), else
    ``("dt", DT_LADDER)`` (:data:`rockbench.constants.DT_LADDER`)."""
    from .tradeoff_tables import DT_LADDER, precision_sweeps

    for knob, values, fixed in precision_sweeps(engine):
        if knob != "dt" and values and not fixed:
            return str(knob), tuple(float(v) for v in values)
    return "dt", tuple(DT_LADDER)


def setting_args(engine: str, settings: dict[str, Any]) -> list[str]:
    """The ``--setting`` values (``ENGINE.KEY=VALUE``, the CLI's one grammar) of a settings
    mapping: ``rockbench run --engine E --setting A --setting B ...``."""
    return [f"{engine}.{k}={v}" for k, v in settings.items()]


def _settings_of(engine: str, label: str) -> dict[str, Any]:
    """The mapping ``rb.run(**settings)`` takes for a setting label (output_dt raised to dt
    where dt exceeds the default output interval)."""
    from ..engines.setting_text import parse_overrides
    from .tradeoff import Setting, _run_overrides

    over = parse_overrides(str(label), option="setting").for_engine(engine)
    return _run_overrides(Setting(engine, tuple(sorted(over.items()))))


def _clean(row: dict[str, Any]) -> dict[str, Any]:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in row.items()}


@dataclass
class Advice:
    """The answer of :func:`advise`: the search's :class:`~rockbench.studies.search.Decision`
    (``decision``) read at each of its tolerances. ``recommended(tol)``: the cheapest engine
    and setting that meets ``tol`` with ``settings`` (what ``rb.run(**settings)`` takes).
    JSON: :meth:`to_json`; words: :meth:`text`."""

    decision: Any

    @property
    def scene(self) -> str:
        return self.decision.scene

    @property
    def size(self) -> str:
        return self.decision.size

    @property
    def tolerances(self) -> tuple[float, ...]:
        return self.decision.tolerances

    def ranking(self, tolerance: float | None = None) -> list[dict[str, Any]]:
        """Every engine's row at ``tolerance`` (default the tightest), recommended first, with
        its run settings."""
        tol = self.tolerances[-1] if tolerance is None else tolerance
        rows = []
        for _, r in self.decision.at(tol).iterrows():
            d = r.to_dict()
            d["settings"] = (_settings_of(d["engine"], d["setting"])
                             if d["status"] == "meets" and isinstance(d.get("setting"), str)
                             else None)
            rows.append(d)
        return rows

    def recommended(self, tolerance: float | None = None) -> dict[str, Any] | None:
        r = self.ranking(tolerance)
        return r[0] if r and r[0]["recommended"] else None

    def to_json(self) -> dict[str, Any]:
        from ..fates import FATES
        from ..result import jsonable

        d = self.decision
        ev = d.evidence[[c for c in _EVIDENCE if c in d.evidence.columns]] if len(
            d.evidence) else pd.DataFrame()
        answers = []
        for t in self.tolerances:
            rec = self.recommended(t)
            answers.append({
                "tolerance": t,
                "recommended": None if rec is None else _clean(rec),
                "setting_args": None if rec is None else setting_args(rec["engine"],
                                                                      rec["settings"]),
                "next_step": d.next_steps.get(t),
                "ranking": [_clean(r) for r in self.ranking(t)]})
        return jsonable({
            "scene": d.scene, "size": d.size, "tolerances": list(self.tolerances),
            "vertical_ratio": d.vertical,
            "answers": answers, "fates": FATES, "coverage": d.coverage,
            "engines": d.engines, "search_cpu_s": d.cpu_s, "runs_cpu_s": d.runs_cpu_s,
            "stopped": d.stopped,
            "error_definition": "worst over a part of the evidence of each case's measure: "
                                "|peak error| (a surviving pulse away from the boundary), eta "
                                "error (free rocking without devices), the RMS history error "
                                "over the initial amplitude (free rocking with devices), the "
                                "relative distance of a record's peak to the analytic "
                                "sensitivity band (0 inside); inf if a run is not ok or its "
                                "overturning verdict is wrong away from the boundary; cases "
                                "near the boundary (within 2 % in A, or whose verdict flips "
                                "within their band): reported, not counted",
            "cost_definition": "steady-state process CPU s per simulated s over the setting's "
                               "runs (the model build per run and the warm-up per process "
                               "measured apart)",
            "evidence": [_clean(r) for r in ev.to_dict("records")],
            "contact": [_clean(r) for r in d.contact.to_dict("records")] if len(d.contact)
            else [],
            "cases": [c.to_dict() for c in d.cases], "machine": d.machine})

    def text(self) -> str:
        """The answer in words: per tolerance the recommendation (or what to run next), then
        every engine's line; the evidence's coverage; what the search spent."""
        d = self.decision
        n_c = sum(1 for c in d.cases if c.part == "choice")
        lines = [f"Scene {d.scene}: {d.size} evidence, chosen on {n_c} cases, confirmed on "
                 f"{len(d.cases) - n_c} held-out cases ({d.coverage['counted']} counted: "
                 f"{d.coverage['overturning']} overturning, {d.coverage['records']} records; "
                 f"{d.coverage['near_boundary']} near the boundary, not counted)"
                 + (f"; every pulse and record with a vertical part a_v = {d.vertical:g} x "
                    "the horizontal (in phase)" if d.vertical else "") + "."]
        if d.coverage["thin"]:
            lines.append(f"  Note: {d.coverage['thin']}.")
        for t in self.tolerances:
            lines.append(f"Within {100 * t:g} %:")
            rec = self.recommended(t)
            if rec:
                args = " ".join(f"--setting {a}" for a in setting_args(rec["engine"],
                                                                       rec["settings"]))
                lines.append(f"  use {rec['engine']} {args}: worst error "
                             f"{_pct(rec['worst_error_choice'])} chosen, "
                             f"{_pct(rec['worst_error_heldout'])} held out; "
                             f"{rec['cpu_per_sim_s']:.3g} CPU s per simulated s")
                ties = [r["engine"] for r in self.ranking(t)[1:] if r.get("tie_with_cheapest")]
                if ties:
                    lines.append(f"  (within {100 * (TIE - 1):.0f} % of its cost, a tie on "
                                 f"this machine: {', '.join(ties)})")
            else:
                nxt = d.next_steps.get(t)
                lines.append("  no engine meets it"
                             + (f"; to try next: {nxt['engine']} at {nxt['setting']}, about "
                                f"{nxt['cpu_s']:.0f} CPU s ({nxt['command']})" if nxt else ""))
            for i, r in enumerate(self.ranking(t), 1):
                head = f"  {i}. {r['engine']}: {r['status']}"
                if isinstance(r.get("setting"), str):
                    head += (f" at {r['setting']} (chosen {_pct(r['worst_error_choice'])}, "
                             f"held out {_pct(r['worst_error_heldout'])}, "
                             f"{as_float(r['cpu_per_sim_s']):.3g} CPU s/s)")
                if r["status"] != "meets" and r.get("reason"):
                    head += f": {r['reason']}"
                lines.append(head)
        lines.append(f"The search spent {d.cpu_s:.0f} CPU s"
                     + (f" and stopped early: {d.stopped}" if d.stopped else "") + ".")
        return "\n".join(lines)


def advise(scene, tolerance: float | Sequence[float] | None = None,
           engines: Sequence[str] | None = None, store=None, *,
           dts: Iterable[float] | None = None, quick: bool = False, full: bool = False,
           contact: bool | None = None, seed: int | None = None, vertical: float = 0.0,
           budget_cpu_s: float | None | str = "auto", executor: str = "process",
           workers: int | None = None, progress: bool = False) -> Advice:
    """The cheapest confirmed engine and setting within ``tolerance`` (one, several, or the
    ladder :data:`rockbench.studies.search.TOLERANCE_LADDER` when None) on ``scene``.

    ``quick``: the quick evidence; ``full``: the full evidence and the contact search
    (``contact`` defaults to ``full``); ``store``: a folder, runs reused (resumable);
    ``budget_cpu_s``: the search's CPU budget ("auto": per evidence size); ``vertical``: r,
    the evidence's vertical motion (a_v = r x horizontal, in phase); the rest as
    :func:`rockbench.studies.search.search`.
    """
    from .search import TOLERANCE_LADDER, search

    if quick and full:
        raise ParameterError("quick", quick, "not together with full")
    size = "quick" if quick else "full" if full else "default"
    tols = (TOLERANCE_LADDER if tolerance is None else [tolerance]
            if isinstance(tolerance, (int, float)) else list(tolerance))
    d = search(scene, tols, engines, size=size, store=store, budget_cpu_s=budget_cpu_s,
               dts=dts, contact=full if contact is None else bool(contact), seed=seed,
               vertical=vertical,
               executor=executor, workers=workers, progress=progress)
    return Advice(d)


def advice_table(decision) -> pd.DataFrame:
    """The report's ``advice.csv``: one row per (tolerance, engine) of a decision, columns
    tolerance [-], rank, engine, status (:data:`rockbench.fates.FATES`), recommended,
    setting, worst_error_choice, worst_error_heldout [-], cpu_per_sim_s [CPU s per simulated
    s], real_time_factor [-], erratic, tie_with_cheapest, reason."""
    o = decision.outcomes.copy()
    c = o["cpu_per_sim_s"].astype(float)
    o["real_time_factor"] = [1.0 / v if v > 0 and math.isfinite(v) else math.nan for v in c]
    cols = ["tolerance", "rank", "engine", "status", "recommended", "setting",
            "worst_error_choice", "worst_error_heldout", "cpu_per_sim_s", "real_time_factor",
            "erratic", "tie_with_cheapest", "reason"]
    return o[cols]

"""``rockbench advise``: which engine, which setting, for a tolerance, at what cost - chosen on
one part of the scene's evidence and confirmed on another.

:func:`advise` answers from measurements on the user's scene (a built-in name, a scene file or a
:class:`~rockbench.scene.scene.Scene`). The evidence (:func:`rockbench.studies.validation.validation_set`:
free rocking from small and large angles, pulse cells over the scene's whole A-W plane, near and
away from its overturning boundary, scaled records) is split, deterministically, into a
**choice** part and a **held-out** part. For every engine:

1. **choose**: the engine's precision knob (the time step ``dt``, or what its backend class
   declares as its first ``precision_sweeps`` curve) is run from the coarsest
   value down on the choice part; the worst validation error of each
   (:func:`rockbench.studies.tradeoff.case_error`) is recorded;
2. **converge** (:func:`convergence`): a value is accepted only when the next finer one also
   meets the tolerance and the error falls as the step falls (or the two agree with each
   other within a quarter of the tolerance: converged); a lucky step - within the tolerance
   with a finer step outside it - is not. An error curve that rises at a finer step is named
   "erratic" in the answer;
3. **confirm**: the accepted setting runs on the held-out part; the recommendation stands
   only if the held-out worst error is within the tolerance (status "meets"); otherwise the
   engine is listed as "fails held-out" with both figures.

With ``contact=True`` (``--full``), the contact parameters that decide the impact (each engine's
:data:`CONTACT_VARIANTS`) are measured first, one at a time from the defaults, on the
free-rocking impacts and the smallest-uplift record of the choice part; the variants that lower
that error, alone and combined, get their own ladder, and the cheapest setting that meets the
tolerance wins whatever its contact parameters.

**Cost** is steady-state process CPU seconds per simulated second (the model build of every
run and each process's one-off warm-up measured apart and shown beside it, never ranked):
:mod:`rockbench.studies.tradeoff`. Engines are ranked by it; those within :data:`TIE` of the cheapest
are a tie. :func:`decide` is the pure part (a tradeoff table and a tolerance in, the ranking
out), so the rule is tested on controlled tables and the report turns any tradeoff table into
advice (:func:`advice_for_report`). Runs are reused through the one store (``store``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..result import as_float
from .decide import (TIE, _check_tolerance, _pct, convergence, decide,  # noqa: F401
                     held_out_stats)

__all__ = ["ADVISE_DTS", "QUICK_DTS", "CONTACT_VARIANTS", "Advice", "advise", "decide",
           "convergence", "held_out_stats", "advice_for_report", "precision_knob",
           "setting_args"]

#: Time steps [s] tried, largest first.
ADVISE_DTS: tuple[float, ...] = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)
#: Time steps [s] tried with ``quick`` (the same ladder: a quick answer obeys the same rule).
QUICK_DTS: tuple[float, ...] = ADVISE_DTS
#: The contact parameters searched with ``contact=True`` (one override set each, from the
#: engine's defaults), per engine: those that decide the impact's eta and small uplifts. Each
#: is a field of the engine's Settings (validated there).
CONTACT_VARIANTS: dict[str, list[dict[str, Any]]] = {
    "mujoco": [{"contact_dampratio": 1.0}, {"contact_dampratio": 4.0},
               {"impedance": 0.95}, {"impedance": 0.999}, {"impratio": 1.0},
               {"impratio": 10.0}, {"noslip_iterations": 10}],
    "pybullet": [{"contact_erp": 0.2}, {"contact_erp": 0.02}, {"solver_iterations": 150},
                 {"contact_breaking_threshold": 1e-4}, {"split_impulse": False},
                 {"split_impulse": True}, {"contact_slop": 1e-4}, {"restitution": 0.1}],
    "pymunk": [{"iterations": 60}, {"iterations": 100}, {"collision_slop": 1e-4},
               {"collision_slop": 1e-3}, {"collision_bias": 0.9 ** 300}],
    "opensees": [{"toe_stiffness": 1e11}, {"toe_stiffness": 1e12}, {"integrator": "hht",
                                                                     "hht_alpha": 0.9},
                 {"damping": "stiffness"}],
}

_EVIDENCE = ["engine", "setting", "dt", "worst_error_choice", "worst_error_heldout",
             "worst_error", "verdict", "peak_error_worst", "eta_error_worst", "nrmse_worst",
             "near_disagree", "outside_band", "n_ok", "n_cases", "n_choice", "n_heldout",
             "cpu_per_sim_s", "cpu_per_sim_s_min", "cpu_per_sim_s_max", "real_time_factor",
             "build_cpu_s", "warmup_cpu_s"]


def precision_knob(engine: str) -> tuple[str, tuple[float, ...]]:
    """(name, values from coarse to fine) of ``engine``'s precision knob: the first of its
    work-precision curves (:func:`rockbench.studies.tradeoff.precision_sweeps`, the backend class's
    ``precision_sweeps``) that sweeps its own knob with its own values (e.g. an
    error-controlled integrator's accuracy), else ``("dt", ADVISE_DTS)``."""
    from .tradeoff import precision_sweeps

    for knob, values, fixed in precision_sweeps(engine):
        if knob != "dt" and values and not fixed:
            return str(knob), tuple(float(v) for v in values)
    return "dt", tuple(ADVISE_DTS)


# =========================================================================================
# The answer
# =========================================================================================
@dataclass
class Advice:
    """The answer of :func:`advise` (JSON: :meth:`to_json`).

    scene, tolerance [-] (relative: 0.02 = 2 %);
    ranking : one dict per engine considered: those that meet the tolerance first (cheapest
        first), then the others (fails held-out, unconfirmed, lucky steps only, cannot reach),
        then the unavailable: ``engine``, ``meets``, ``status``, ``setting`` (label),
        ``settings`` (the mapping ``rockbench run --setting`` and ``rb.run(**settings)`` take),
        ``dt`` [s], ``worst_error_choice`` / ``worst_error_heldout`` [-], ``held_out`` (the
        held-out statistics of :func:`held_out_stats`), ``cpu_per_sim_s`` [s/s, steady state],
        ``build_cpu_s`` / ``warmup_cpu_s`` [s, one-off], ``real_time_factor`` [-], ``erratic``,
        ``convergence`` (words), ``reason``, ``tie_with_cheapest``;
    considered : every engine name considered, in the order given;
    evidence : the tradeoff rows behind the answer (every setting run);
    contact : the contact parameters measured (``contact=True``): one row per engine and
        variant with its error on the impact probes and the change against the defaults;
    size : "quick", "default" or "full"; cases : the evidence (with its part);
    machine : where the cost was measured.
    """

    scene: str
    tolerance: float
    ranking: list[dict[str, Any]]
    considered: list[str]
    evidence: pd.DataFrame
    size: str = "default"
    cases: list[dict[str, Any]] = field(default_factory=list)
    machine: dict[str, Any] = field(default_factory=dict)
    contact: pd.DataFrame = field(default_factory=pd.DataFrame)

    @property
    def quick(self) -> bool:
        return self.size == "quick"

    @property
    def recommended(self) -> dict[str, Any] | None:
        """The cheapest engine and setting within the tolerance on both parts (None if none)."""
        return self.ranking[0] if self.ranking and self.ranking[0]["meets"] else None

    def to_json(self) -> dict[str, Any]:
        from ..result import jsonable

        ev = self.evidence[[c for c in _EVIDENCE if c in self.evidence.columns]]

        def clean(rows):
            return [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                     for k, v in r.items()} for r in rows]

        rec = self.recommended
        return jsonable({
            "scene": self.scene, "tolerance": self.tolerance, "size": self.size,
            "quick": self.quick,
            "recommended": None if rec is None else clean([rec])[0],
            "settings": None if rec is None else rec["settings"],
            "setting_args": None if rec is None else setting_args(rec["engine"],
                                                                  rec["settings"]),
            "ranking": clean(self.ranking), "considered": self.considered,
            "error_definition": "worst over a part of the evidence of |peak error| (surviving "
                                "pulses away from the boundary), the relative distance of a "
                                "record's peak to the analytic sensitivity band (0 inside) and "
                                "eta error (free rocking); inf if a run is not ok or its "
                                "overturning verdict is wrong away from the boundary; "
                                "near-boundary cells: verdicts reported, not counted",
            "cost_definition": "steady-state process CPU s per simulated s, median of repeats "
                               "(the model build per run and the warm-up per process "
                               "measured apart: build_cpu_s, warmup_cpu_s)",
            "evidence": clean(ev.to_dict("records")),
            "contact": clean(self.contact.to_dict("records")) if len(self.contact) else [],
            "cases": self.cases, "machine": self.machine})

    def text(self) -> str:
        """A short human answer: the recommendation, then every engine's line."""
        n_c = sum(1 for c in self.cases if c.get("part") == "choice")
        n_h = len(self.cases) - n_c
        lines = [f"Scene {self.scene}, tolerance {100 * self.tolerance:g} % ({self.size} "
                 f"evidence: chosen on {n_c} cases, confirmed on {n_h} held-out cases):"]
        rec = self.recommended
        if rec:
            lines.append(f"  use {rec['engine']} with {_settings_text(rec['engine'], rec['settings'])}: "
                         f"worst error {_pct(rec['worst_error_choice'])} chosen, "
                         f"{_pct(rec['worst_error_heldout'])} held-out; "
                         f"{rec['cpu_per_sim_s']:.3g} CPU s per simulated s (steady state, "
                         f"real-time factor {rec['real_time_factor']:.3g})")
            ties = [r["engine"] for r in self.ranking[1:] if r.get("tie_with_cheapest")]
            if ties:
                lines.append(f"  (as cheap within {100 * (TIE - 1):.0f} %, a tie on this "
                             f"machine: {', '.join(ties)})")
        else:
            lines.append("  no engine meets this tolerance on both parts of the evidence")
        if self.quick:
            lines.append("  quick evidence: trust it as far as its held-out figure; "
                         "the default or --full evidence is larger")
        for i, r in enumerate(self.ranking, 1):
            if r["status"] == "unavailable":
                lines.append(f"  {i}. {r['engine']}: unavailable: {r['reason']}")
                continue
            head = (f"  {i}. {r['engine']}: {r['status']}: {r['setting']}, chosen "
                    f"{_pct(r['worst_error_choice'])}, held-out "
                    f"{_pct(r.get('worst_error_heldout', math.nan))}")
            if r["status"] == "meets":
                head += (f", {r['cpu_per_sim_s']:.3g} CPU s/s (+ build "
                         f"{as_float(r.get('build_cpu_s')):.2g} s per run, warm-up "
                         f"{as_float(r.get('warmup_cpu_s')):.2g} s once)")
            else:
                head += f": {r['reason']}"
            lines.append(head)
            extra = []
            if r.get("erratic"):
                extra.append("ERRATIC error against the step: " + r.get("curve", ""))
            elif r.get("convergence") and r["status"] == "meets":
                extra.append("converged: " + r["convergence"])
            ho = r.get("held_out") or {}
            if ho.get("n"):
                skip = ho.get("n_all", ho["n"]) - ho["n"]
                of = (f"{ho['n']} counted cases (of {ho['n_all']}; {skip} not counted: near "
                      f"the boundary or not measured)" if skip > 0 else f"{ho['n']} cases")
                extra.append(f"held-out: {100 * ho['beyond']:.0f} % of {of} beyond "
                             f"the tolerance, {ho['beyond2']} beyond twice it, "
                             f"{ho['wrong_verdicts']} wrong verdicts or failed runs away from "
                             f"the boundary, {ho['outside_band']} records outside the band")
            nd = r.get("near_disagree") or 0
            if nd:
                extra.append(f"{nd} near-boundary cell(s) with the other verdict (not counted)")
            if r.get("variant"):
                extra.append(f"contact settings: {r['variant']}")
            lines += [f"       {e}" for e in extra]
        if len(self.contact):
            lines.append("  contact settings measured (impact probes: free-rocking eta and the "
                         "smallest-uplift record, choice part):")
            for _, c in self.contact.iterrows():
                ch = as_float(c.get("change"))
                lines.append(f"    {c['engine']} {c['variant'] or 'defaults'}: probe error "
                             f"{_pct(c['probe_error'])} (eta {_pct(c['eta_error'])}, record "
                             f"{_pct(c['record_error'])})"
                             + (f", {ch:.3g} x the defaults'" if math.isfinite(ch) else ""))
        return "\n".join(lines)


def setting_args(engine: str, settings: dict[str, Any]) -> list[str]:
    """The ``--setting`` values (``ENGINE.KEY=VALUE``, the CLI's one grammar) of a settings
    mapping: ``rockbench run --engine E --setting A --setting B ...``."""
    return [f"{engine}.{k}={v}" for k, v in settings.items()]


def _settings_text(engine: str, settings: dict[str, Any]) -> str:
    return " ".join(f"--setting {a}" for a in setting_args(engine, settings))


# =========================================================================================
# Running it
# =========================================================================================
def _settings_of(engine: str, label: str, knob: str) -> dict[str, Any]:
    """The mapping ``rb.run(**settings)`` takes for a setting label (output_dt raised to dt
    where dt exceeds the default output interval)."""
    from .tradeoff import Setting, _parse_value, _run_overrides

    over = {}
    for part in str(label).split(","):
        k, v = part.split("=", 1)
        over[k] = _parse_value(v)
    s = Setting(engine, tuple(sorted(over.items())))
    out = _run_overrides(s)
    order = [knob] + sorted(k for k in out if k != knob)
    return {k: out[k] for k in order if k in out}


def _probe_error(runs: pd.DataFrame, probes: set[str]) -> tuple[float, float, float]:
    r = runs[runs["case"].isin(probes)]
    eta = r.loc[r["kind"] == "free", "error"].to_numpy(dtype=float)
    rec = r.loc[r["kind"] != "free", "error"].to_numpy(dtype=float)
    e1 = float(np.nanmax(eta)) if eta.size else math.nan
    e2 = float(np.nanmax(rec)) if rec.size else math.nan
    return max(e1, e2), e1, e2


def advise(scene, tolerance: float, engines: Sequence[str] | None = None, store=None, *,
           dts: Iterable[float] | None = None, quick: bool = False, full: bool = False,
           contact: bool | None = None, repeat: int | None = None, seed: int | None = None,
           executor: str = "process", workers: int | None = None,
           progress: bool = False) -> Advice:
    """The cheapest setting of every engine within ``tolerance`` on ``scene``, chosen on the
    choice part of its evidence and confirmed on the held-out part (module docstring).

    Parameters
    ----------
    scene : Scene, built-in name or path to a scene file (:func:`rockbench.load_scene`).
    tolerance : relative bound on the worst validation error (0.02 = 2 %).
    engines : backend names (default: every registered engine but the analytic model; those
        that cannot run here are listed as unavailable).
    store : directory of the store to reuse and fill (None: nothing kept).
    dts : the ladder of time steps [s] (default: :data:`ADVISE_DTS`, or the engine's own
        ``precision_sweeps``).
    quick : the quick evidence (a subset of the default; one repeat);
    full : the full evidence and the contact-parameter search.
    contact : search the contact parameters (default: ``full``).
    repeat : runs of each case for the cost (default 3; quick: 1).
    seed : the split's seed (default :data:`rockbench.studies.validation.SEED`).
    """
    from ..engines import REGISTRY, get_backend
    from ..runner import REFERENCE, resolve_engines
    from ..scene.scene import load_scene
    from .tradeoff import machine_info, summarize, tradeoff, validation_set
    from .validation import SEED

    tolerance = _check_tolerance(tolerance)
    if quick and full:
        raise ParameterError("quick", quick, "not together with full")
    size = "quick" if quick else "full" if full else "default"
    contact = full if contact is None else bool(contact)
    scene = load_scene(scene)          # a name, a file or a Scene: the one resolver
    names = ([n for n in REGISTRY if n != REFERENCE] if engines is None
             else [n for n in resolve_engines(engines) if n != REFERENCE])
    if not names:
        raise ParameterError("engines", engines, "at least one engine besides the analytic model")
    repeat = (1 if quick else 3) if repeat is None else repeat
    vset = validation_set(scene, size=size, seed=SEED if seed is None else seed)
    choice = [c for c in vset if c.part == "choice"]
    held = [c for c in vset if c.part == "held-out"]
    free = sorted([c for c in choice if c.kind == "free"], key=lambda c: -abs(c.phi0))
    recs = sorted([c for c in choice if c.kind == "record"],
                  key=lambda c: abs(dict(c.motion)["scale"]))
    probes = free[:2] + recs[:1]
    unavailable: dict[str, str] = {}
    knobs: dict[str, str] = {}
    run_frames: list[pd.DataFrame] = []
    contact_rows: list[dict[str, Any]] = []
    kw = dict(repeat=repeat, self_consistency="none", executor=executor, workers=workers,
              store=store, progress=progress)

    def measure(eng: str, over: dict[str, Any], cases) -> pd.DataFrame:
        return tradeoff(scene, [eng], exact=[over], cases=cases, **kw).runs

    for n in names:
        try:
            ok, why = get_backend(n).available()
        except Exception as e:  # BackendUnavailable: the module does not import
            ok, why = False, str(e)
        if not ok:
            unavailable[n] = why
            continue
        knob, ladder = precision_knob(n)
        knobs[n] = knob
        if dts is not None and knob == "dt":
            ladder = tuple(sorted({float(d) for d in dts}, reverse=True))
        variants: list[dict[str, Any]] = [{}]
        if contact and n in CONTACT_VARIANTS and probes:
            default_val = getattr(get_backend(n).Settings(), knob, ladder[len(ladder) // 2])
            base = measure(n, {knob: default_val}, probes)
            b_err, b_eta, b_rec = _probe_error(base, {c.name for c in probes})
            contact_rows.append({"engine": n, "variant": "", knob: default_val,
                                 "probe_error": b_err, "eta_error": b_eta,
                                 "record_error": b_rec, "change": 1.0})
            helpful = []
            for v in CONTACT_VARIANTS[n]:
                try:
                    get_backend(n).Settings(**{knob: default_val, **v})
                except Exception as e:   # a variant this version's Settings refuses
                    contact_rows.append({"engine": n, "variant": str(v), knob: default_val,
                                         "probe_error": math.nan, "eta_error": math.nan,
                                         "record_error": math.nan, "change": math.nan,
                                         "reason": str(e)})
                    continue
                r = measure(n, {knob: default_val, **v}, probes)
                e, e1, e2 = _probe_error(r, {c.name for c in probes})
                lab = ",".join(f"{k}={v[k]}" for k in sorted(v))
                contact_rows.append({"engine": n, "variant": lab, knob: default_val,
                                     "probe_error": e, "eta_error": e1, "record_error": e2,
                                     "change": e / b_err if 0 < b_err < math.inf
                                     and math.isfinite(e) else math.nan})
                if e < 0.9 * b_err:
                    helpful.append((e, v))
            helpful.sort(key=lambda x: x[0])
            if helpful:
                variants.append(dict(helpful[0][1]))
                combo: dict[str, Any] = {}
                for _, v in helpful:
                    if not set(v) & set(combo):
                        combo.update(v)
                if len(combo) > len(helpful[0][1]):
                    try:
                        get_backend(n).Settings(**{knob: default_val, **combo})
                        variants.append(combo)
                    except Exception:
                        pass
        for v in variants:
            frames = []
            errs: list[tuple[float, float]] = []
            accepted = None
            steps = list(ladder)
            i = 0
            while i < len(steps):
                d = steps[i]
                r = measure(n, {knob: d, **v}, choice)
                frames.append(r)
                tab = summarize(r)
                errs.append((d, float(tab["worst_error_choice"].iloc[0])))
                conv = convergence(errs, tolerance)
                if conv["index"] is not None:
                    accepted = conv["step"]
                    break
                if i == len(steps) - 1 and errs[-1][1] <= tolerance and d / 2 >= 1e-6 \
                        and knob == "dt":
                    steps.append(d / 2)       # confirm the finest step with a finer one
                i += 1
            if accepted is not None:
                frames.append(measure(n, {knob: accepted, **v}, held))
            run_frames += frames
    runs = pd.concat(run_frames, ignore_index=True) if run_frames else pd.DataFrame()
    evidence = summarize(runs) if len(runs) else pd.DataFrame(columns=_EVIDENCE)
    ranking = decide(evidence, tolerance, engines=names, unavailable=unavailable, knobs=knobs)
    for r in ranking:
        if r.get("setting") and r["status"] != "unavailable":
            r["settings"] = _settings_of(r["engine"], r["setting"], knobs.get(r["engine"], "dt"))
            sel = runs[(runs["engine"] == r["engine"]) & (runs["setting"] == r["setting"])]
            r["held_out"] = held_out_stats(sel, tolerance)
        else:
            r["settings"], r["held_out"] = None, {}
    return Advice(scene=scene.name, tolerance=tolerance, ranking=ranking, considered=names,
                  evidence=evidence, size=size, cases=[c.to_dict() for c in vset],
                  machine=machine_info(), contact=pd.DataFrame(contact_rows))


def advice_for_report(table: pd.DataFrame, tolerances: Sequence[float] = (0.02, 0.002), *,
                      absent: Mapping[str, tuple[str, str]] | None = None) -> pd.DataFrame:
    """For the report: one row per (tolerance, engine) of :func:`decide` on a tradeoff table
    (columns tolerance [-], rank, engine, status, setting, dt [s], worst_error [-] (on the
    choice part), held_out_worst_error [-], cpu_per_sim_s [s/s, steady state],
    real_time_factor [-], erratic, reason): the recommendation is rank 1 of each tolerance when
    its status is "meets". ``absent``: engine -> (state, detail) of the registered engines that
    did not run ("not installed", "left out": :data:`rockbench.engines.ENGINE_STATES`), each a
    row with that status and the detail as its reason."""
    rows = []
    for tol in tolerances:
        for i, r in enumerate(decide(table, tol, absent=absent), 1):
            rows.append({"tolerance": float(tol), "rank": i,
                         **{k: r.get(k) for k in ("engine", "status", "setting", "dt")},
                         "worst_error": r.get("worst_error_choice"),
                         "held_out_worst_error": r.get("worst_error_heldout"),
                         **{k: r.get(k) for k in ("cpu_per_sim_s", "real_time_factor",
                                                  "erratic", "reason")}})
    return pd.DataFrame(rows)

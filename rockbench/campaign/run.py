"""The default campaign: what ``rockbench report`` (and ``make report``) runs.

Plan -> sweep -> compare tables -> report. :func:`run_campaign` runs every available backend
against the analytic reference on the paper's frames and writes one self-contained page, the
tables as CSV and the figures as PNG. Its parts (the plan: :func:`campaign_plan`, from
``rockbench/scenarios/paper-plan.toml``; ``docs/report.md`` describes the page and every
table):

1. **Pulse cases** - the plan's scenes under symmetric and antisymmetric Ricker pulses of
   both signs at the plan's (A, W) points: one :func:`rockbench.comparison.compare` per case
   (rotation histories, nrmse, peak error, eta, verdicts, cost).
2. **Free rocking** - every scene released from ``free_phi0`` alpha: the effective eta of each
   engine per rocking direction against the analytic eta.
3. **Fracture cases** - hybrid frames under the pulses of ``fracture_cases`` where the analytic
   model fractures the tendons: whether each engine fractures when the analytic model does,
   and when (``fracture_agrees``, ``t_fracture_error``).
4. **Maps** (:mod:`rockbench.campaign.maps`) - overturning maps, analytic and per engine.
5. **The decision** (:mod:`rockbench.campaign.choice`) - the search of ``rockbench advise``
   over the tolerance ladder and the stability sweep; its work-precision (every engine over
   its time steps on the decision's evidence) is the report's speed against accuracy.
6. **Records** - peak rotation per record and frame, both polarities (the paper's Fig. 9).
7. **Fragility** and **the validity map** (:mod:`rockbench.campaign.fragility`,
   :mod:`rockbench.studies.validity_map`).

The comparisons (parts 1-3) run through the one executor (:mod:`rockbench.sweep.executors`)
and are kept, as small pickles, in the one store (:mod:`rockbench.sweep.store`), under a
fingerprint of the physics code (:func:`code_fingerprint`), beside the sweep cases.
A rerun, e.g. after Ctrl-C, reuses what finished; after a change to a backend, the scene model
or an engine version, everything runs again.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ..report import tables as T
from ..report.tables import CAMPAIGN_COLUMNS
from ..result import motion_label
from ..runner import REFERENCE, resolve_engines
from ..scene.records import bundled_dir, find_records
from ..sweep import store as S
from .plan import campaign_plan
from ..sweep.executors import check_options, execute, run_parts

__all__ = ["CAMPAIGN_COLUMNS", "CampaignTables", "campaign_plan", "code_fingerprint",
           "find_records", "measure_campaign", "run_campaign", "write_tables"]

code_fingerprint = S.code_fingerprint


# ==========================================================================================
# Comparison jobs (histories needed): run through the executor, kept as payloads in the store
# ==========================================================================================
def _job_label(job: Mapping[str, Any]) -> str:
    """``"<scene> symm+ A=3 W=4"``, ``"<scene> free rocking"``, ``"<engine> dt=0.001 s"``."""
    if job["kind"] == "dt":
        return f"{job['engine']} dt={job['dt']:g} s"
    from .maps import scene_label

    return f"{scene_label(job['scene'])} {motion_label(job.get('motion'))}"


#: The form of a comparison payload (:func:`_run_job`): a stored payload of another form was
#: written by code that measured less (it is run again, not read with a field missing).
PAYLOAD_FORMAT = 2


def _run_job(job: dict[str, Any]) -> dict[str, Any]:
    """One comparison job (in a worker): returns a small, picklable payload."""
    from ..comparison import compare
    from ..report.figures import Trace
    from ..scene import load_scene
    from ..scene.motion import motion_from_spec

    scene = load_scene(job["scene"])
    motion = motion_from_spec(job.get("motion"), scene.structure)
    phi0 = float(job.get("phi0_over_alpha", 0.0)) * scene.alpha
    t0 = time.perf_counter()
    c0 = time.process_time()
    c = compare(scene, motion, engines=job["engines"], phi0=phi0, duration=job["duration"])
    traces = {k: Trace.from_result(r, max_points=job.get("max_points", 2500)).to_dict()
              for k, r in c.results.items()}
    band, judged = _pulse_band(scene, motion, job, phi0, c.results)
    return {"job": job, "table": c.table, "eta": c.eta, "traces": traces,
            "band": band, "band_judged": judged, "format": PAYLOAD_FORMAT,
            "model_cpu_per_sim_s": _model_cost(scene, motion, phi0, job["duration"]),
            "alpha": float(scene.alpha), "motion": c.motion, "phi0": phi0,
            "settings": {k: dict(v) for k, v in c.settings.items()},
            "elapsed_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}


def _model_cost(scene, motion, phi0: float, duration: float) -> float:
    """The analytic model's cost on a case [CPU s per simulated s]: one run of its compiled
    path (``method="compiled"``, equal to the reference's solve_ivp path on every
    well-conditioned quantity, docs/reproducibility.md; the kernels' one-off loading apart,
    ``Result.cost.compile_cpu_s``), the cheapest way to run the model; NaN if it fails."""
    from ..runner import run

    try:
        r = run(scene, motion, engine=REFERENCE, duration=duration, phi0=phi0,
                method="compiled")
    except Exception:  # noqa: BLE001 - a cost not measured is NaN, the case stands
        return math.nan
    sim = float(r.cost.sim_time)
    return float(r.cost.cpu_s) / sim if sim > 0 else math.nan


def _pulse_band(scene, motion, job, phi0, results) -> tuple[dict | None, dict]:
    """The analytic model's sensitivity band of a pulse or fracture case
    (:func:`rockbench.studies.sensitivity.band`) as a dict, and each ok backend's (inside, distance
    [alpha]) against it; (None, {}) for free rocking or if the band cannot be computed."""
    if job["kind"] not in ("pulse", "fracture") or motion is None:
        return None, {}
    from ..studies.sensitivity import band

    try:
        b = band(scene, motion, duration=job["duration"], phi0=phi0)
    except Exception:  # noqa: BLE001 - no band is a missing column, not a failed case
        return None, {}
    judged = {}
    for name, r in results.items():
        if r.ok:
            j = b.judge(r)
            judged[name] = (bool(j.inside), float(j.distance))
    return b.to_dict(), judged


def _run_job_safe(job: dict[str, Any]) -> dict[str, Any]:
    """:func:`_run_job`, a failure becoming an error payload (what the executor runs)."""
    try:
        return _run_job(job)
    except Exception as e:  # a failing job is data, not a crash of the campaign
        return {"job": job, "error": f"{type(e).__name__}: {e}"}


def _job_weight(job: Mapping[str, Any]) -> float:
    """Relative cost of a job: the longest run first keeps the pool balanced."""
    w = float(job.get("duration") or 1.0)
    if "hybrid" in job["scene"]:
        w *= 2.5
    return w


def _comparisons(jobs: Sequence[dict[str, Any]], *, cache: Path, desc: str,
                 **run: Any) -> list[dict[str, Any]]:
    """The payloads of ``jobs`` in input order, each with its ``label``: stored ones of this
    :data:`PAYLOAD_FORMAT` loaded, the others run (longest first) and stored as each finishes
    (error payloads are not kept)."""
    out: dict[str, dict[str, Any]] = {}
    todo: dict[str, dict[str, Any]] = {}
    for job in jobs:
        k = S.key(job)
        hit = S.load_payload(cache, k)
        if hit is not None and "error" not in hit and hit.get("format") == PAYLOAD_FORMAT:
            out[k] = hit
        else:
            todo[k] = job

    def on_result(k: str, payload: dict[str, Any]) -> None:
        out[k] = payload
        if "error" not in payload:
            S.write_payload(cache, k, payload)

    items = sorted(todo.items(), key=lambda kj: -_job_weight(kj[1]))
    execute(_run_job_safe, items, on_result=on_result,
            crashed=lambda job, reason: {"job": job, "error": reason}, label=_job_label,
            is_error=lambda p: "error" in p, desc=desc, **run)
    return [dict(out[k], label=_job_label(job)) for job in jobs if (k := S.key(job)) in out]


def _sweep(cases: list[dict[str, Any]], *, store: Path | None, **run: Any) -> pd.DataFrame:
    from ..sweep import run_cases

    if not cases:
        return pd.DataFrame()
    return run_cases(cases, store=store, **run)


# ==========================================================================================
# run_campaign
# ==========================================================================================
def _scene_label(ref: Any) -> str:
    from .maps import scene_label

    return scene_label(ref)


@dataclass
class CampaignTables:
    """What a campaign measured, handed to its page and its files in one object
    (:func:`rockbench.campaign.page.write_page`): the plan, the engines and their states, the
    comparison payloads, every table of ``docs/report.md``, the maps, the decision, fragility,
    the notes and the run's timings."""

    plan: dict[str, Any]
    names: list[str]
    states: list[dict[str, Any]]
    payloads: list[dict[str, Any]]
    metrics: pd.DataFrame
    eta: pd.DataFrame
    eta_summary: pd.DataFrame
    engines: pd.DataFrame
    records: pd.DataFrame
    maps: dict[str, Any]
    choice: dict[str, Any]
    fragility: dict[str, Any]
    validity: dict[str, Any]
    notes: list[str]
    labels: dict[str, str]
    timings: dict[str, tuple[float, float]]
    quick: bool
    records_dir: Any
    store_dir: Path
    fingerprint: str
    paper: bool
    t_start: float = field(default_factory=time.perf_counter)
    cpu_start: float = 0.0

    @property
    def missing(self) -> list[str]:
        """The engines of the selection that are not installed here."""
        return [r["name"] for r in self.states if r["state"] == "not installed"]

    def files(self) -> dict[str, pd.DataFrame]:
        """The CSV tables of the campaign, by file name (``docs/report.md``)."""
        out = {"metrics.csv": self.metrics, "eta.csv": self.eta,
               "eta_summary.csv": self.eta_summary, "engines.csv": self.engines,
               "map_agreement.csv": self.maps["agreement"],
               "tradeoff.csv": self.choice["tradeoff"], "advice.csv": self.choice["advice"]}
        if len(self.records):
            out["record_peaks.csv"] = self.records
        if self.validity.get("frame") is not None:
            out["validity_map.csv"] = self.validity["frame"]
        if self.fragility.get("frames"):
            from .fragility import section_table
            out["fragility.csv"] = section_table(self.fragility)
        if self.choice.get("stress") is not None:
            out["stress.csv"] = self.choice["stress"]
            out["stress_breaking_points.csv"] = self.choice["breaks"]
        return out


def run_campaign(out_dir: str | os.PathLike = "reports", *, engines: Sequence[str] | None = None,
                 records_dir: str | os.PathLike | None = None, quick: bool = False,
                 progress: bool = True, store: str | os.PathLike | None = None,
                 executor: str = "process", dask_address: str | None = None,
                 workers: int | None = None, full: bool = False,
                 scenes: Sequence[Any] | None = None,
                 plan: str | os.PathLike | Mapping[str, Any] | None = None,
                 vertical: float | None = None) -> Path:
    """Run a campaign and write its report; return the path of ``out_dir/index.html``.

    Parameters
    ----------
    out_dir : folder written: ``index.html``, the CSV tables (``docs/report.md``), the figures
        as PNG under ``figures/``.
    engines : backend names (default: every available backend; the analytic reference always
        runs). Every registered engine appears on the page with its state.
    records_dir : a folder of records (``.AT2`` files, or headerless files listed in a
        ``records.csv`` with their dt): the peak rotation per record (paper Fig. 9), with the
        analytic model's sensitivity band of each. Default: the records bundled in the package
        (``rockbench/records``), except with ``quick``.
    quick : the quick form of the plan: a few cases, the quick evidence, an analytic map
        and no engine map, no stability sweep or fragility; it still decides.
    progress : progress bars naming what runs.
    store : folder of the resumable store (default ``out_dir/store``).
    executor : "process" (local process pool, one worker per core), "serial", or "dask"
        (``dask_address``: a running scheduler; none: a local cluster).
    workers : worker processes (default: one per available core).
    full : the long campaign: every engine's map at the plan's full grid, measured into
        ``out_dir/engine-maps`` where it is missing or stale, the next larger evidence and the
        full stability sweep. Everything is kept in the store and reused.
    scenes : the structures to report on (built-in names, TOML paths or Scenes; the first one
        is the structure the decision is about): the campaign's plan is derived from them
        (:func:`rockbench.campaign.plan.plan_for_scenes`). Default: the paper's plan.
    plan : a plan file (``kind = "campaign-plan"``, :func:`rockbench.campaign.plan.load_plan`)
        or a plan mapping; overrides ``scenes``.
    vertical : r in [0, 3]: every pulse and record of the campaign also moves the ground
        vertically, a_v = r x its horizontal acceleration (in phase); overrides the plan's
        ``vertical`` (None: the plan's, 0 by default).
    """
    from .page import write_page

    t = measure_campaign(out_dir, engines=engines, records_dir=records_dir, quick=quick,
                         progress=progress, store=store, executor=executor,
                         dask_address=dask_address, workers=workers, full=full, scenes=scenes,
                         plan=plan, vertical=vertical)
    out = Path(out_dir)
    write_tables(t, out)
    return write_page(t, out)


def write_tables(t: CampaignTables, out: Path) -> list[Path]:
    """Write the campaign's CSV tables into ``out``; an undocumented column with no value
    (left by rows a reused store kept from older code) is not written, so that the files do
    not depend on the store's history."""
    from ..comparison import ETA_COLUMNS, METRIC_COLUMNS
    from ..studies.tradeoff_tables import TABLE_COLUMNS
    from ..studies.validity_map import VALIDITY_COLUMNS

    paths = []
    for name, df in t.files().items():
        doc = CAMPAIGN_COLUMNS.get(name)
        if doc is not None:
            kept = {*doc, *METRIC_COLUMNS, *ETA_COLUMNS, *TABLE_COLUMNS, *VALIDITY_COLUMNS}
            df = df.drop(columns=[c for c in df.columns if c not in kept and df[c].isna().all()])
        df.to_csv(out / name, index=False)
        paths.append(out / name)
    return paths


def measure_campaign(out_dir: str | os.PathLike = "reports", *,
                     engines: Sequence[str] | None = None,
                     records_dir: str | os.PathLike | None = None, quick: bool = False,
                     progress: bool = True, store: str | os.PathLike | None = None,
                     executor: str = "process", dask_address: str | None = None,
                     workers: int | None = None, full: bool = False,
                     scenes: Sequence[Any] | None = None,
                     plan: str | os.PathLike | Mapping[str, Any] | None = None,
                     vertical: float | None = None) -> CampaignTables:
    """Run every part of a campaign (:func:`run_campaign`'s parameters) and return what it
    measured."""
    from ..engines import check_required, engine_states

    t_start = time.perf_counter()
    from ..machine import tree_cpu_s

    cpu_start = tree_cpu_s()
    check_options(executor, workers, dask_address)
    if vertical is not None:
        from ..studies.map_cells import check_vertical_ratio
        vertical = check_vertical_ratio(vertical, "vertical")
    check_required()              # ROCKBENCH_REQUIRE_ENGINES: a missing engine is an error
    # every registered engine has a state, decided once: ran, not installed (why, remedy),
    # left out by --engine; the page, the decision and the command's last lines show it
    states = engine_states(resolve_engines(engines) if engines is not None else None)
    names = [REFERENCE] + [r["name"] for r in states
                           if r["state"] == "ran" and r["name"] != REFERENCE]
    fragility_records = records_dir      # None: the fragility section's own ensemble
    if records_dir is None and not quick:
        records_dir = bundled_dir()       # the public-domain records shipped in the package
    if records_dir is not None:
        find_records(records_dir)          # a bad folder fails now, not after the pulses
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if isinstance(plan, Mapping):
        plan = dict(plan)
    elif plan is not None:
        from .plan import load_plan
        plan = load_plan(plan, quick=quick, folder=out / "scenes")
    elif scenes:
        from .plan import plan_for_scenes
        plan = plan_for_scenes(scenes, quick=quick, folder=out / "scenes")
    else:
        plan = campaign_plan(quick)
    if vertical is not None:
        plan = dict(plan, vertical=vertical)
    paper = (plan["scenes"] == campaign_plan(quick)["scenes"]
             and not plan.get("vertical"))
    store_dir = Path(store) if store is not None else S.default_store(out)
    fingerprint = code_fingerprint()
    cache = S.store_path(store_dir, "comparisons")
    notes: list[str] = []
    sweep_store = S.store_path(store_dir, "cases") if S.have_pyarrow() else None
    if sweep_store is None:
        notes.append("pyarrow is not installed: the sweep cases (records) are not kept "
                     "between runs (pip install 'rockbench[parquet]').")
    run = dict(executor=executor, dask_address=dask_address, progress=progress,
               workers=workers)
    timings: dict[str, tuple[float, float]] = {}

    # the parts are independent of each other: each one runs its cases on its own worker
    # pools. With the local process executor they run in two lanes at once (the second lane
    # in a process of its own), so that one part's last cases, or its work in this process,
    # do not leave a core idle; lanes balanced by the parts' CPU on the paper's plan
    ctx = dict(plan=plan, names=names, store_dir=store_dir, out=out, quick=quick, full=full,
               records_dir=records_dir, fragility_records=fragility_records,
               sweep_store=sweep_store, cache=cache, run=run)
    from .parts import LANES, PARTS

    parts = {name: (fn, (ctx,)) for name, fn in PARTS.items()}
    lanes = LANES if executor == "process" and (workers or 2) > 1 else [list(PARTS)]
    got = run_parts(parts, timings, lanes=lanes)
    timings = {k: timings[k] for k in PARTS}
    payloads = got["comparisons"]
    maps, choice, frag, validity = got["maps"], got["choice"], got["fragility"], got["validity map"]
    records, record_notes = got["records"]
    notes.extend(record_notes)
    for p in payloads:
        if "error" in p:
            notes.append(f"{p['label']} failed: {p['error']}")
    payloads = [p for p in payloads if "error" not in p]

    # tables -----------------------------------------------------------------------------
    metrics = T.metrics_table(payloads)
    eta, eta_summary = T.eta_tables(payloads)
    labels = {r: _scene_label(r) for r in dict.fromkeys(plan["scenes"])}
    for df in (metrics, eta, eta_summary, records):    # a scene by its name, not its file
        if "scene" in df:
            df["scene"] = df["scene"].map(lambda r: labels.get(r, r))
    engines_tab = T.engine_summary(metrics, eta_summary, maps["agreement"])
    return CampaignTables(plan=dict(plan, labels=labels), names=names, states=states,
                          payloads=payloads, metrics=metrics, eta=eta,
                          eta_summary=eta_summary, engines=engines_tab,
                          records=records, maps=maps, choice=choice, fragility=frag,
                          validity=validity, notes=notes, labels=labels, timings=timings,
                          quick=quick,
                          records_dir=records_dir, store_dir=store_dir,
                          fingerprint=fingerprint, paper=paper, t_start=t_start,
                          cpu_start=cpu_start)

"""The parts of a campaign (``rockbench report``): the case-by-case comparisons, the maps,
the decision, the records, fragility and the validity map. Each part is a function of the
campaign's context (a picklable dict made by
:func:`rockbench.campaign.run.measure_campaign`), so that a lane of them can run in a process
of its own (:func:`rockbench.sweep.executors.run_parts`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from ..report import tables as T
from ..runner import REFERENCE
from ..scene.records import find_records
from ..studies.map_cells import reversed_mirrors
from ..sweep import store as S
from ..run_length import pulse_run_length, run_length
from .run import _comparisons, _sweep

__all__ = ["PARTS", "LANES"]


# ==========================================================================================
# The parts of a campaign (each a function of the campaign's context, so that a lane of them
# can run in another process: rockbench.sweep.executors.run_parts)
# ==========================================================================================
def _part_comparisons(c: dict[str, Any]) -> list[dict[str, Any]]:
    """1 + 2: the pulse cases, the fracture cases and free rocking of every scene."""
    plan, names = c["plan"], c["names"]
    vr = _vertical(plan)
    jobs = []
    shapes = {(shape, int(sign)) for shape, sign in plan["pulse_shapes"]}
    for scene in plan["scenes"]:
        mirror = reversed_mirrors(scene, _ratio(plan))
        for (A, W) in plan["pulse_points"]:
            for shape, sign in plan["pulse_shapes"]:
                if mirror and int(sign) == -1 and (shape, 1) in shapes:
                    continue      # the mirror image of the +1 case
                jobs.append({"kind": "pulse", "scene": scene, "engines": names,
                             "motion": {"kind": "ricker", "shape": shape, "sign": int(sign),
                                        "A": float(A), "W": float(W), **vr},
                             "duration": pulse_run_length(W, _p(scene),
                                                          plan["pulse_tail"])})
    for scene, shape, sign, A, W in plan["fracture_cases"]:
        jobs.append({"kind": "fracture", "scene": scene, "engines": names,
                     "motion": {"kind": "ricker", "shape": shape, "sign": int(sign),
                                "A": float(A), "W": float(W), **vr},
                     "duration": pulse_run_length(W, _p(scene), plan["pulse_tail"])})
    for scene in plan["scenes"]:
        jobs.append({"kind": "free", "scene": scene, "engines": names, "motion": None,
                     "phi0_over_alpha": plan["free_phi0"], "duration": plan["free_duration"]})
    return _comparisons(jobs, cache=c["cache"], desc="comparisons", **c["run"])


def _ratio(plan: Any) -> float:
    """The plan's vertical ratio r [-] (``vertical``: a_v = r x the horizontal acceleration,
    in phase; 0 without one)."""
    return float(plan.get("vertical", 0.0) or 0.0)


def _vertical(plan: Any) -> dict[str, float]:
    """The motion-spec entry of the plan's vertical ratio, empty without one."""
    r = _ratio(plan)
    return {"vertical_ratio": r} if r else {}


def _p(scene: Any) -> float:
    """p [rad/s] of a plan's scene (a name, a path or a Scene): a pulse case's run length."""
    from ..scene import load_scene

    return load_scene(scene).p


def _part_maps(c: dict[str, Any]) -> dict[str, Any]:
    """4: overturning maps at the paper's resolution (paper Figs. 4-7)."""
    from .maps import run_maps

    run = c["run"]
    return run_maps(c["names"], S.store_path(c["store_dir"], "maps"), full=c["full"],
                    quick=c["quick"], measured=c["out"] / "engine-maps",
                    progress=run["progress"], workers=run["workers"],
                    scheduler=run["dask_address"] if run["executor"] == "dask" else None,
                    maps=c["plan"]["maps"],
                    vertical=_ratio(c["plan"]))


def _part_choice(c: dict[str, Any]) -> dict[str, Any]:
    """5: choosing a modelling approach (the decision, the stability sweep)."""
    from .choice import run_choice

    plan, run = c["plan"], c["run"]
    return run_choice(c["names"], c["store_dir"], quick=c["quick"], full=c["full"],
                      workers=run["workers"], progress=run["progress"],
                      scene=plan["choice_scene"], stress_scene=plan.get("stress_scene"),
                      stress_hybrid=plan.get("stress_hybrid_scene"),
                      evidence=plan.get("choice_evidence", "quick"),
                      vertical=_ratio(plan))


def _part_records(c: dict[str, Any]) -> tuple[pd.DataFrame, list[str]]:
    """6: records (the peak rotation per record and frame), and the notes of their folder."""
    notes: list[str] = []
    if c["records_dir"] is None:
        return pd.DataFrame(), notes
    return _records(c["records_dir"], c["plan"], c["names"], notes, store=c["sweep_store"],
                    **c["run"]), notes


def _part_fragility(c: dict[str, Any]) -> dict[str, Any]:
    """7: fragility over an ensemble of records (not in the quick campaign)."""
    if c["quick"]:
        return {}
    from .fragility import fragility_section

    run = c["run"]
    return fragility_section(c["plan"]["record_frames"], c["names"],
                             records=c["fragility_records"],
                             size="full" if c["full"] else "default",
                             store=S.store_path(c["store_dir"], "fragility", keyed=False),
                             export_dir=c["out"] / "fragility-export",
                             measured=c["out"] / "fragility-engines", measure=c["full"],
                             executor=run["executor"], workers=run["workers"],
                             scheduler=run["dask_address"], progress=run["progress"],
                             vertical=_ratio(c["plan"]) or None)


def _part_validity(c: dict[str, Any]) -> dict[str, Any]:
    """8: where the analytic model holds (the decision's scene, with its own friction or the
    validity rule's default mu = 1 given to every engine): the fast engines outside the
    model, every engine with ``--full``."""
    return _validity_section(c["plan"].get("validity_map"), c["names"], c["store_dir"],
                             c["run"]["workers"], c["run"]["progress"],
                             _ratio(c["plan"]), every_engine=bool(c.get("full")))


#: The parts of a campaign, in the order of the page's run-time table.
PARTS = {"comparisons": _part_comparisons, "maps": _part_maps, "choice": _part_choice,
         "records": _part_records, "fragility": _part_fragility, "validity map": _part_validity}
#: The two lanes of the local executor (the first in this process), each part's CPU measured
#: on the paper's plan (runtime.csv) so that both lanes end near together.
LANES = [["comparisons", "fragility", "validity map"],
          ["maps", "choice", "records"]]


def _validity_section(spec: Mapping[str, Any] | None, names: Sequence[str], store_dir: Path,
                      workers: int | None, progress: bool,
                      vertical: float = 0.0, every_engine: bool = False) -> dict[str, Any]:
    """The validity map of the plan's ``validity_map`` (``scene``, ``grid`` n, ``tail`` [s];
    None: none) with the plan's vertical ratio, as the page's section wants it
    (:func:`rockbench.report.validity_figures.validity_html`); {} without one. Outside the
    model run the campaign's fast engines (:func:`rockbench.campaign.maps.is_fast`; all of
    them when none is fast), or all of them with ``every_engine``; ``left_out`` names the
    others."""
    if not spec:
        return {}
    from ..scene import load_scene
    from ..studies.validity_map import default_axes, validity_map
    from ..validity import friction_of

    from .maps import is_fast

    scene = load_scene(spec["scene"])
    given = scene.friction is not None      # else validity_map gives the rule's default
    engines = [e for e in names if e != REFERENCE]
    fast = engines if every_engine else [e for e in engines if is_fast(e)] or engines
    left_out, engines = [e for e in engines if e not in fast], fast
    out = {"scene": scene.name, "friction": friction_of(scene), "tolerance": 0.10,
           "friction_given": given, "left_out": left_out,
           "a_mu": friction_of(scene) / math.tan(scene.alpha),
           "engines": engines, "shape": "symmetric", "sign": 1, "tail": spec["tail"],
           "vertical": vertical}
    if not engines:
        return dict(out, error="no engine ran in this campaign")
    A, W = default_axes(scene, int(spec["grid"]))
    try:
        frame = validity_map(scene, A=A, W=W, engines=engines, tolerance=out["tolerance"],
                             tail=spec["tail"], workers=workers, progress=progress,
                             vertical_ratio=vertical,
                             store=store_dir if S.have_pyarrow() else None)
    except Exception as e:  # noqa: BLE001 - the page says it, the rest of the report stands
        return dict(out, error=f"{type(e).__name__}: {e}")
    return dict(out, frame=frame)


def _record_vertical(rec: Mapping[str, Any], plan: Mapping[str, Any]) -> dict[str, Any]:
    """The motion-spec entries of a record's vertical motion: its own vertical channel (a
    records.csv column ``vertical``), else the plan's ratio (a_v = r x the horizontal), else
    none (:func:`rockbench.studies.fragility.vertical_spec`, the one rule)."""
    from ..studies.fragility import vertical_spec

    return vertical_spec(rec, _ratio(plan))


def _record_bands(rows: pd.DataFrame, durations: Mapping[str, float | None],
                  meta: Mapping[str, dict[str, Any]]) -> pd.DataFrame:
    """``rows`` (record peaks) with the analytic model's sensitivity band of each (record,
    scene, polarity) and where each backend's peak stands against it (columns band_*,
    within_band; :mod:`rockbench.studies.sensitivity`). ``durations``: run length [s] per record path
    (None: the default); ``meta``: per path, the dt and units of a headerless record and its
    vertical motion (:func:`_record_vertical`)."""
    from ..scene import load_scene
    from ..scene.motion import motion_from_spec
    from ..studies.sensitivity import band

    out = rows.copy()
    for c in ("band_low", "band_nominal", "band_high", "band_verdict_agreement",
              "band_distance"):
        out[c] = math.nan
    out["within_band"] = pd.array([None] * len(out), dtype="boolean")
    for (path, scene, pol), g in out.groupby(["path", "scene", "polarity"], sort=False):
        sc = load_scene(scene)
        spec = {"kind": "record", "path": path, "scale": float(pol)}
        spec.update(meta.get(path, {}))
        try:
            b = band(sc, motion_from_spec(spec, sc.structure),
                     duration=durations.get(path))
        except Exception:  # noqa: BLE001 - a band that cannot be computed stays NaN
            continue
        out.loc[g.index, ["band_low", "band_nominal", "band_high", "band_verdict_agreement"]] \
            = [b.low, b.nominal, b.high, b.verdict_agreement]
        for i in g.index:
            if str(out.at[i, "status"]) != "ok":
                continue
            j = b.judge(float(out.at[i, "max_abs_phi_over_alpha"]),
                        overturned=bool(out.at[i, "overturned"]))
            out.at[i, "within_band"] = bool(j.inside)
            out.at[i, "band_distance"] = j.distance
    return out


def _records(records_dir, plan: Mapping[str, Any], names: list[str], notes: list[str], *,
             store: Path | None, **run: Any) -> pd.DataFrame:
    """Part 5: every record on every frame of ``plan["record_frames"]``, both polarities, with
    the analytic model's sensitivity band of each."""
    recs, rnotes = find_records(records_dir)
    notes.extend(rnotes)
    if plan["max_records"]:
        recs = recs[: plan["max_records"]]
    frames = plan["record_frames"]
    rec_cases = []
    durations: dict[Any, Any] = {}
    for rec in recs:
        rec_duration = None
        cap = plan.get("record_duration")
        if plan["record_tail"] is not None or cap is not None:
            from ..scene.records import load_record
            r = load_record(rec["path"], dt=rec["dt"], units=rec["units"])
            rec_duration = run_length(r, plan["record_tail"])
            if cap is not None:
                rec_duration = min(rec_duration, float(cap))
        durations[rec["path"]] = rec_duration
        for frame, scene in frames.items():
            for pol in (1.0, -1.0):
                m = {"kind": "record", "path": rec["path"], "scale": pol}
                if rec["dt"] is not None:
                    m.update(dt=rec["dt"], units=rec["units"])
                m.update(_record_vertical(rec, plan))
                for e in names:
                    rec_cases.append({"scene": scene, "engine": e, "motion": m,
                                      "duration": rec_duration})
    records = pd.DataFrame()
    rows = T.sweep_rows(_sweep(rec_cases, store=store, **run))
    if len(rows):
        byscene = {v: k for k, v in frames.items()}
        name_of = {str(r["path"]): r["name"] for r in recs}       # by path, never the stem
        rows["record"] = [name_of.get(str(p), Path(p).stem) for p in rows["path"]]
        rows["frame"] = [byscene.get(s, s) for s in rows["scene"]]
        rows["polarity"] = [int(round(float(v))) for v in rows["polarity"]]
        rows = T.with_verdicts(rows, ("record", "frame", "polarity"))
        meta = {r["path"]: {"dt": r["dt"], "units": r["units"]} for r in recs
                if r["dt"] is not None}
        rows = _record_bands(rows, durations, meta)
        first = ["record", "frame", "scene", "polarity", "backend"]
        records = rows[first + [c for c in rows.columns if c not in first + ["path"]]]
    if not recs:
        notes.append(f"no record files found under {records_dir}")
    return records

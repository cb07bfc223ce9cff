"""Fragility: records judged as earthquake engineers judge them (``docs/fragility.md``).

Every record of an ensemble, as recorded and reversed (both polarities), at a ladder of scale
factors (incremental dynamic analysis), through the analytic model and each engine; then, per
backend, the overturning probability against an intensity measure with a lognormal fragility
fit, and, against the analytic model, a two-sample test of the peak-rotation distributions and
the difference of the fragility medians.

Its parts, one job each: :mod:`rockbench.studies.intensity` (the intensity measures of a
record), :mod:`rockbench.studies.ensembles` (folders, files, bundled ensembles and the synthetic
ensemble resolved to records, identified by path), :mod:`rockbench.studies.fragility_stats`
(the lognormal fit, the bootstrap over records, the two-sample test of peaks, the efficiency of
the intensity measures, the numerical dispersion, the verdicts) and this module (the ladder of
scales, the run lengths, the cases, the engines' measured error, the driver).

One driver: :func:`run_fragility` builds the cases, runs them through the one executor and the
one store (:func:`rockbench.sweep.run_cases`: resumable, in parallel, on Dask with a scheduler
address) and analyses them. The default campaign's part is :mod:`rockbench.campaign.fragility`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError, check_finite
from ..run_length import run_length
from .ensembles import describe_ensemble, record_ims, resolve_records
from .fragility_stats import N_BOOT, analyse, check_bootstrap, numerical_dispersion, stripes
from .intensity import MEASURES, Structure

__all__ = ["RUN_COLUMNS", "RUN_GRID", "parse_scales", "run_lengths", "vertical_spec",
           "fragility_cases", "describe_vertical", "numerical_evidence", "numerical_terms",
           "run_fragility", "Fragility"]

#: Run lengths cut after the strong motion (``tail``) are rounded up to a multiple of this [s],
#: so that the runs of records of about the same length share one length (a batched engine,
#: MuJoCo's rollout, runs cases of one length together).
RUN_GRID = 5.0

#: Columns of the runs frame, with unit and meaning.
RUN_COLUMNS: dict[str, str] = {
    "backend": "-, analytic or an engine",
    "record": "-, record name (file stem)",
    "polarity": "-, +1 as recorded, -1 reversed",
    "scale": "-, scale factor of the ladder (the run's motion: polarity x scale x record)",
    "im": "IM unit, intensity measure of the scaled record (scale x IM of the record)",
    "peak": "-, max |phi| / alpha, alpha of the taller column (overturned: where it stopped)",
    "overturned": "-, the frame overturned",
    "status": "-, ok | diverged | invalid | error",
    "outside": "-, the scaled record's PGA exceeds mu g (with vertical motion: |a_g| > mu "
               "(g + a_v) or g + a_v <= 0 at some time): outside the analytic model (a base at "
               "rest slides, rockbench.validity)",
    "cpu_s": "s, CPU time of the integration or stepping",
}


# =========================================================================================
# The ladder and the cases
# =========================================================================================
def parse_scales(text: Any) -> np.ndarray:
    """The ladder of scale factors: ``"LO:HI:N"`` (N evenly spaced, inclusive; N = 1 gives LO)
    or a sequence of numbers; every factor finite and > 0, at most 200 of them."""
    if isinstance(text, str):
        parts = text.split(":")
        try:
            if len(parts) != 3:
                raise ValueError
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise ParameterError("scales", text, "LO:HI:N, e.g. 0.25:2:8 (N an integer)"
                                 ) from None
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi and 1 <= n <= 200):
            raise ParameterError("scales", text, "LO:HI:N with 0 < LO <= HI and 1 <= N <= 200")
        values = np.linspace(lo, hi, n) if n > 1 else np.array([lo])
    else:
        try:
            values = np.asarray([float(x) for x in text], dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("scales", text, "LO:HI:N or a list of numbers > 0") from None
        if not (1 <= values.size <= 200 and np.all(np.isfinite(values)) and np.all(values > 0)):
            raise ParameterError("scales", text, "1 to 200 finite numbers > 0")
    return np.unique(np.round(values, 12))


def run_lengths(ims: pd.DataFrame, tail: float | None) -> dict[str, float | None]:
    """The run length [s] of each record (``ims``: :func:`record_ims`, by ``path``): None (the
    package default, :func:`rockbench.run_length.run_length` of the record) when ``tail`` is None;
    else the record's end of strong motion t_95 (95 % of int a_g^2 dt) + ``tail`` [s] (>= 0),
    rounded up to a multiple of :data:`RUN_GRID`, and never longer than the default. What is
    left out is the record's weakest 5 % of int a_g^2 dt after t_95 + tail: a frame still
    rocking then is rocking freely under a motion weaker than its strong part."""
    if tail is None:
        return {p: None for p in ims["path"]}
    tail = check_finite("tail", tail)
    if not 0.0 <= tail <= 3600.0:
        raise ParameterError("tail", tail, "in [0, 3600] s (or None: the whole record)")
    out = {}
    for p, t95, d in zip(ims["path"], ims["t95"], ims["duration"]):
        cut = RUN_GRID * math.ceil((float(t95) + tail) / RUN_GRID - 1e-9)
        out[p] = float(cut) if cut < run_length(float(d)) else None
    return out


def vertical_spec(record: Mapping[str, Any], ratio: float = 0.0) -> dict[str, Any]:
    """The vertical part of a record's motion spec (:func:`rockbench.scene.motion.
    motion_from_spec`): its own vertical channel (``record["vertical"]``, a ``records.csv``'s
    column: ``vertical_path``, with ``vertical_dt`` and ``vertical_units`` for a headerless
    file); else, with ``ratio`` r > 0, r times its horizontal channel (``vertical_ratio``);
    else nothing (the spec of a horizontal record, key for key)."""
    if record.get("vertical"):
        out: dict[str, Any] = {"vertical_path": str(record["vertical"])}
        if record.get("vertical_dt") is not None:
            out.update(vertical_dt=float(record["vertical_dt"]),
                       vertical_units=record["vertical_units"])
        return out
    return {"vertical_ratio": float(ratio)} if ratio else {}


def fragility_cases(scene: str, records: Sequence[Mapping[str, Any]], engines: Sequence[str],
                    scales: Sequence[float], *, settings: Mapping[str, Mapping] | None = None,
                    overrides: Mapping[str, Any] | None = None,
                    durations: Mapping[str, float | None] | None = None,
                    vertical: float = 0.0) -> list[dict[str, Any]]:
    """Sweep cases (:mod:`rockbench.sweep.cases`): every engine x record x polarity (+1, -1) x
    scale, each run from rest for ``durations[path]`` [s] (:func:`run_lengths`; missing or None:
    the record + 10 s, the package default). ``settings`` maps a backend to its setting
    overrides; the analytic model runs on its compiled path (``method="compiled"``) unless told
    otherwise. Every run of a record carries its vertical part (:func:`vertical_spec`: its own
    channel, or ``vertical`` r times its horizontal one), scaled and reversed with it."""
    settings = {k: dict(v) for k, v in (settings or {}).items()}
    settings.setdefault("analytic", {}).setdefault("method", "compiled")
    cases = []
    for e in engines:
        for r in records:
            for pol in (1, -1):
                for s in scales:
                    m = {"kind": "record", "path": r["path"], "scale": float(pol * s)}
                    if r.get("dt") is not None:
                        m.update(dt=float(r["dt"]), units=r["units"])
                    m.update(vertical_spec(r, vertical))
                    cases.append({"scene": scene, "overrides": dict(overrides or {}),
                                  "engine": e, "settings": settings.get(e, {}), "motion": m,
                                  "duration": (durations or {}).get(r["path"])})
    return cases


def planned_cases(scene: str, records: Sequence[Mapping[str, Any]], ims: pd.DataFrame,
                  engines: Sequence[str], scales: Sequence[float], *,
                  tail: float | None = None, vertical: float = 0.0,
                  settings: Mapping[str, Mapping] | None = None,
                  overrides: Mapping[str, Any] | None = None) -> list[dict[str, Any]]:
    """The cases :func:`run_fragility` runs for ``engines`` on ``records`` at ``scales``:
    :func:`fragility_cases` with each record's run length from ``tail``
    (:func:`run_lengths` of the records' measures ``ims``, :func:`record_ims`)."""
    return fragility_cases(scene, records, engines, scales, settings=settings,
                           overrides=overrides, durations=run_lengths(ims, tail),
                           vertical=vertical)


# =========================================================================================
# The engines' own error on the scene
# =========================================================================================
def numerical_evidence(scene: Any, engines: Sequence[str], *,
                       settings: Mapping[str, Mapping] | None = None,
                       overrides: Mapping[str, Any] | None = None, size: str = "quick",
                       store: str | os.PathLike | None = None) -> pd.DataFrame:
    """Each engine's measured error on ``scene`` at the setting the fragility runs use
    (``settings[engine]``, default its defaults): the work-precision runs
    (:func:`rockbench.studies.tradeoff.tradeoff`, one repeat, no self-consistency) of the
    surviving Ricker pulses of the scene's evidence (:func:`rockbench.studies.validation.
    validation_set` of ``size``: the cases measured by their peak) away from the overturning
    boundary (a cell near it has an ill-conditioned peak: the evidence does not count it
    either). One row per engine and case (:data:`rockbench.studies.tradeoff.RUN_COLUMNS`: engine,
    setting, case, peak_rel_error, status, ...). ``store``: the tradeoff's store (resumable)."""
    from ..scene.scene import load_scene
    from .tradeoff import tradeoff, validation_set

    sc = load_scene(scene, dict(overrides) if overrides else None)
    cases = [c for c in validation_set(sc, size=size)
             if c.measure == "peak" and not c.near_boundary]
    frames = []
    for e in engines:
        t = tradeoff(sc, [e], exact=[dict((settings or {}).get(e, {}))], repeat=1,
                     self_consistency="none", executor="serial", store=store, cases=cases)
        frames.append(t.runs)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def numerical_terms(evidence: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Per engine of ``evidence`` (:func:`numerical_evidence`): ``beta`` [-]
    (:func:`rockbench.studies.fragility_stats.numerical_dispersion` of its relative peak
    errors: inf when a run was not ok), ``cases`` (how many), ``worst`` (largest |peak error|
    [-]), ``setting`` (its label)."""
    out: dict[str, dict[str, Any]] = {}
    if evidence is None or not len(evidence):
        return out
    for e, g in evidence.groupby("engine", sort=False):
        err = np.where(g["status"] == "ok", g["peak_rel_error"].astype(float), np.inf)
        out[str(e)] = {"beta": numerical_dispersion(err), "cases": int(len(g)),
                       "worst": float(np.max(np.abs(err))) if len(g) else math.nan,
                       "setting": str(g["setting"].iloc[0])}
    return out


def _validity(runs: pd.DataFrame, limit: float, mu: float,
              vertical: bool = False) -> dict[str, Any]:
    """How many runs lie outside the analytic model (PGA above mu g; with vertical motion:
    |a_g| > mu (g + a_v), or g + a_v <= 0, at some time), per backend, with a sentence: such
    runs are physics of another kind (the base slides, the ground throws the structure),
    counted in the fits and tests like the others (leaving them out would cut the ladder
    where the frame overturns)."""
    per = {str(b): {"outside": int(g["outside"].sum()), "runs": int(len(g))}
           for b, g in runs.groupby("backend", sort=False)}
    n_out = sum(v["outside"] for v in per.values())
    why = (f"have a ground motion that asks the base for more than mu (g + a_v) (friction "
           f"mu = {mu:g}) or falls faster than gravity (g + a_v <= 0) at some time, where a "
           "base at rest slides or the structure leaves the ground" if vertical else
           f"have a PGA above mu g = {limit:.3g} m/s^2 (friction mu = {mu:g}), where a base at "
           "rest slides")
    text = "" if n_out == 0 else (
        "Outside the analytic model: " + ", ".join(
            f"{b} {v['outside']} of {v['runs']} runs" for b, v in per.items())
        + f" {why} (rockbench.validity); they are counted in the fits and tests like the "
          "others, and an engine's run that slid beyond its max_sliding is not ok and left out.")
    return {"pga_limit": limit, "friction": mu, "backends": per, "outside": n_out,
            "text": text}


def describe_vertical(records: Sequence[Mapping[str, Any]],
                      ratio: float = 0.0) -> dict[str, Any] | None:
    """Which vertical motion the runs of ``records`` carry (:func:`vertical_spec`), None when
    none does: ``ratio`` r, ``recorded`` (the records with their own channel), ``scaled`` (those
    given r times their horizontal one), ``horizontal`` (the others) and ``text``, one
    sentence for the page and the command's output."""
    recorded = [str(r["name"]) for r in records if r.get("vertical")]
    rest = [str(r["name"]) for r in records if not r.get("vertical")]
    scaled, horizontal = (rest, []) if ratio else ([], rest)
    if not recorded and not scaled:
        return None
    n = len(records)
    parts = []
    if recorded:
        parts.append(f"the recorded vertical channel of {len(recorded)} of {n} records "
                     "(records.csv)" if len(recorded) < n else
                     f"the recorded vertical channel of every record ({n}, records.csv)")
    if scaled:
        parts.append(f"a_v = {ratio:g} u_g'' (in phase, {ratio:g} x the horizontal "
                     f"acceleration) for {'the other ' if recorded else 'every record, '}"
                     f"{len(scaled)}")
    text = ("Vertical ground motion in every run (scaled and reversed with its record): "
            + "; ".join(parts)
            + (f"; the other {len(horizontal)} run horizontal only" if horizontal else "")
            + ". The intensity measures are the horizontal channel's.")
    return {"ratio": float(ratio), "recorded": recorded, "scaled": scaled,
            "horizontal": horizontal, "text": text}


def _outside_with_vertical(runs: pd.DataFrame, records: Sequence[Mapping[str, Any]],
                           scene: Any, ratio: float) -> np.ndarray:
    """The runs frame's ``outside`` by the one rule (:func:`rockbench.validity.motion_validity`)
    on each run's motion with its vertical part: per record and signed scale, once."""
    from ..scene.motion import motion_from_spec
    from ..validity import motion_validity

    by_name = {str(r["name"]): r for r in records}
    motions: dict[str, Any] = {}
    known: dict[tuple[str, float], bool] = {}
    out = np.zeros(len(runs), dtype=bool)
    for i, (name, pol, s) in enumerate(zip(runs["record"], runs["polarity"], runs["scale"])):
        k = (str(name), float(pol) * float(s))
        if k not in known:
            if k[0] not in motions:
                r = by_name[k[0]]
                spec = {"kind": "record", "path": r["path"], **vertical_spec(r, ratio)}
                if r.get("dt") is not None:
                    spec.update(dt=float(r["dt"]), units=r["units"])
                motions[k[0]] = motion_from_spec(spec)
            known[k] = not motion_validity(scene, motions[k[0]], scale=k[1]).inside
        out[i] = known[k]
    return out


@dataclass
class Fragility:
    """What :func:`run_fragility` returns: ``runs`` (:data:`RUN_COLUMNS`), ``analysis``
    (:func:`analyse`), ``stripes`` (:func:`stripes`), ``records`` (record, path, the measures
    of :data:`MEASURES` in their units, duration [s], t95 [s]), the ``scene``, the ``scales``
    and the ``store`` used; ``info``: engines, engine_scales, engine_records, executor,
    ``ensemble`` (:func:`rockbench.studies.ensembles.describe_ensemble`), ``tail`` [s] or None,
    ``structure`` (alpha [rad], p [rad/s], period of Sa [s]), ``numerical`` (per engine:
    :func:`numerical_terms`) and, with vertical motion, ``vertical``
    (:func:`describe_vertical`)."""

    scene: str
    runs: pd.DataFrame
    analysis: dict[str, Any]
    stripes: pd.DataFrame
    records: pd.DataFrame
    scales: list[float]
    store: str | None = None
    info: dict[str, Any] = field(default_factory=dict)


def _runs_frame(rows: pd.DataFrame, ims: pd.DataFrame, measure: str,
                pga_limit: float = math.inf) -> pd.DataFrame:
    """Sweep rows -> the runs frame (:data:`RUN_COLUMNS`); ``pga_limit`` [m/s^2]: the largest
    PGA inside the analytic model (:func:`rockbench.validity.pga_limit`)."""
    pga_of = dict(zip(ims["path"], ims["pga"]))
    im_of = dict(zip(ims["path"], ims[measure]))
    name_of = dict(zip(ims["path"], ims["record"]))
    scale = rows["motion.scale"].astype(float).to_numpy()
    out = pd.DataFrame({
        "backend": rows["engine"].astype(str).to_numpy(),
        "record": [name_of[p] for p in rows["motion.path"]],
        "polarity": np.where(scale > 0, 1, -1),
        "scale": np.round(np.abs(scale), 12),
        "im": np.abs(scale) * np.array([im_of[p] for p in rows["motion.path"]]),
        "peak": rows["max_abs_phi_over_alpha"].astype(float).to_numpy(),
        "overturned": rows["overturned"].fillna(False).astype(bool).to_numpy(),
        "status": rows["status"].astype(str).to_numpy(),
        "outside": np.abs(scale) * np.array([pga_of[p] for p in rows["motion.path"]])
        > pga_limit,
        "cpu_s": rows.get("cpu_s", pd.Series(math.nan, index=rows.index)).astype(float)})
    return out


def run_fragility(scene: str, records: Any, *, engines: Sequence[str] | None = None,
                  scales: Any = "0.25:2:8", measure: str = "pga",
                  engine_scales: Mapping[str, Any] | None = None,
                  engine_records: int | None = None,
                  settings: Mapping[str, Mapping] | None = None,
                  overrides: Mapping[str, Any] | None = None,
                  store: str | os.PathLike | None = None, executor: str | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: bool = True, n_boot: int = N_BOOT, seed: int = 0,
                  keyed_by_code: bool = True, retry_errors: bool = False,
                  tail: float | None = None, numerical: Any = "measure",
                  vertical: float | None = None,
                  numerical_given: Mapping[str, Mapping[str, Any]] | None = None
                  ) -> Fragility:
    """Run and analyse the fragility of ``scene`` (a built-in name or a .toml path) over
    ``records`` (:func:`resolve_records`: folders, files, ``bundled``, ``synthetic``) at the
    ladder ``scales`` (:func:`parse_scales`), both polarities, for the analytic model and
    ``engines`` (default: every available backend), fitted against ``measure`` (a key of
    :data:`MEASURES`) and, for the efficiency table, against every measure.

    ``engine_scales`` / ``engine_records``: a smaller ladder / only the first N records for the
    engines (the analytic model always runs the whole ladder on every record; the tests and
    fits compare the runs both have). ``tail``: None runs each record whole + 10 s; a number
    [s] ends each run ``tail`` s after the record's strong motion (:func:`run_lengths`).
    ``numerical``: "measure" (each engine's error on the scene at its setting,
    :func:`numerical_evidence`, kept in the store), None (not measured: beta_num NaN), or a
    mapping engine -> beta_num [-]; with "measure", ``numerical_given`` (engine ->
    :func:`numerical_terms`' entry, measured before) spares those engines the measurement.
    ``store``: a folder; rows are kept under
    ``store/<code fingerprint>/`` (:func:`rockbench.sweep.store.code_fingerprint`: results of
    other code are never mixed in; ``keyed_by_code=False`` keeps them in ``store`` itself, keyed
    by the case only), the synthetic records under ``store/records`` (else in the temporary
    folder), and a rerun runs only the missing cases (and, with ``retry_errors``, those
    stored with status "error"). ``executor``: "process" (default; ``workers`` processes),
    "serial", or "dask" (implied by ``scheduler``, a running scheduler's address).
    Vertical ground motion: a record a ``records.csv`` lists with a vertical channel (column
    ``vertical``) carries it in every run; ``vertical`` r in [0, 3] (limit ``vertical_ratio``;
    None or 0: none) gives every other record the vertical part a_v = r u_g'' (in phase);
    ``analysis["vertical"]`` (:func:`describe_vertical`) says which, and ``outside`` then
    follows the one rule with the vertical part (:func:`rockbench.validity.motion_validity`).
    Without either the cases are those of a horizontal ensemble, key for key.
    """
    from ..runner import REFERENCE, resolve_engines
    from ..scene.scene import load_scene
    from ..sweep import run_cases
    from ..sweep import store as S

    if measure not in MEASURES:
        raise ParameterError("intensity", measure, f"one of {', '.join(MEASURES)}")
    if not (numerical is None or numerical == "measure" or isinstance(numerical, Mapping)):
        raise ParameterError("numerical", numerical, "'measure', None or engine -> beta_num")
    check_bootstrap(n_boot, seed)                 # every bound before any run
    ratio = 0.0
    if vertical is not None:
        from ..limits import check_in_limit

        if isinstance(vertical, bool):
            raise ParameterError("vertical", vertical, "a number in [0, 3] or None")
        ratio = check_in_limit("vertical_ratio", "vertical", vertical)
    run_lengths(pd.DataFrame({"path": [], "t95": [], "duration": []}), tail)
    ladder = parse_scales(scales)
    names = resolve_engines(engines, name="engine")
    names = [REFERENCE] + [n for n in names if n != REFERENCE]
    from ..validity import friction_of, pga_limit

    sc = load_scene(scene, dict(overrides) if overrides else None)
    structure = Structure.of(sc)
    directory = None
    if store is not None:
        directory = S.store_path(store, "", keyed=keyed_by_code)
    recs = resolve_records(records, cache=Path(store) / "records" if store is not None
                           else None)
    ims = record_ims(recs, structure)
    e_ladder = parse_scales(engine_scales) if engine_scales is not None else ladder
    e_recs = recs[:engine_records] if engine_records else recs
    cases = planned_cases(scene, recs, ims, [REFERENCE], ladder, tail=tail, vertical=ratio,
                          settings=settings, overrides=overrides)
    if len(names) > 1:
        cases += planned_cases(scene, e_recs, ims, names[1:], e_ladder, tail=tail,
                               vertical=ratio, settings=settings, overrides=overrides)
    executor = executor or ("dask" if scheduler else "process")
    rows = run_cases(cases, store=directory, executor=executor, workers=workers,
                     dask_address=scheduler, progress=progress, retry_errors=retry_errors)
    runs = _runs_frame(rows, ims, measure, pga_limit(sc))
    vert = describe_vertical(recs, ratio)
    if vert is not None:          # the one rule with the vertical part, not the PGA alone
        runs["outside"] = _outside_with_vertical(runs, recs, sc, ratio)
    num_info: dict[str, Any] = {}
    if numerical == "measure" and len(names) > 1:
        given = {e: dict(v) for e, v in (numerical_given or {}).items() if e in names[1:]}
        todo = [e for e in names[1:] if e not in given]
        num_info = numerical_terms(numerical_evidence(
            scene, todo, settings=settings, overrides=overrides, store=store)) if todo else {}
        num_info.update(given)
        betas = {e: v["beta"] for e, v in num_info.items()}
    elif numerical == "measure":
        betas = {}
    else:
        betas = {e: float(v) for e, v in (numerical or {}).items()}
        num_info = {e: {"beta": b, "source": "given"} for e, b in betas.items()}
    kw = dict(measure=measure, n_boot=n_boot, seed=seed, record_ims=ims, numerical=betas)
    # the analysis compares the cells both ran: the analytic runs of the engines' cells
    eng = runs["backend"].to_numpy() != REFERENCE
    keys = set(zip(runs["record"][eng], runs["scale"][eng]))
    both = eng | np.array([(r, s) in keys for r, s in zip(runs["record"], runs["scale"])])
    if len(names) == 1 or both.all():
        analysis = analyse(runs, **kw)
    else:
        analysis = analyse(runs[both], **kw)
        # the analytic model on its whole ladder and every record, for its own curve
        full = analyse(runs[~eng], **kw)
        analysis["reference_full"] = dict(full["backends"][REFERENCE], grid=full["grid"])
        if "measures" in full:
            analysis["measures_full"] = full["measures"]
    ens = describe_ensemble(recs)
    analysis["ensemble"] = ens
    analysis["structure"] = {"alpha": structure.alpha, "p": structure.p,
                             "sa_period": structure.period}
    analysis["tail"] = tail
    analysis["numerical"] = num_info
    analysis["validity"] = _validity(runs, pga_limit(sc), friction_of(sc), vert is not None)
    if vert is not None:                # absent without vertical motion (keys unchanged)
        analysis["vertical"] = vert
    return Fragility(scene=str(scene), runs=runs, analysis=analysis, stripes=stripes(runs),
                     records=ims, scales=ladder.tolist(),
                     store=str(directory) if directory is not None else None,
                     info={"engines": names, "engine_scales": e_ladder.tolist(),
                           "engine_records": len(e_recs), "executor": executor,
                           "ensemble": ens, "tail": tail, "structure": analysis["structure"],
                           "numerical": num_info, **({"vertical": vert} if vert else {})})

"""The efficiency of the intensity measures of a fragility study (``docs/fragility.md``): every
backend's runs fitted against every measure of the records (:func:`im_efficiency`), the
measures ranked by their dispersion, how sure that ranking is over resampled ensembles of
records, and whether an engine ranks them as the analytic model does. Pure functions of the runs
frame (:data:`rockbench.studies.fragility.RUN_COLUMNS`) and the records' measures
(:func:`rockbench.studies.ensembles.record_ims`); the fits are
:func:`rockbench.studies.fragility_stats.fit_lognormal`'s.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from .fragility_stats import AT_BOUND, _fit_counts, _fmt, fit_lognormal
from .intensity import BASE_MEASURE, MEASURES

__all__ = ["IM_BOOT", "im_efficiency"]


def _family(measure: str) -> str:
    """The measure a dimensionless measure is a constant multiple of (itself otherwise)."""
    return BASE_MEASURE.get(measure, measure)


def _best_set(dispersions: Mapping[str, float], order: Sequence[str]) -> list[str]:
    """The families of the smallest dispersion (fits at the lower bound tie), in ``order``."""
    d = {f: max(v, AT_BOUND) for f, v in dispersions.items() if math.isfinite(v)}
    if not d:
        return []
    low = min(d.values())
    return [f for f in order if f in d and d[f] == low]


def _im_bootstrap(ok: pd.DataFrame, by_record: pd.DataFrame, families: Sequence[str],
                  backends: Sequence[str], n_boot: int, seed: int) -> dict[str, list[list[str]]]:
    """Per backend, the best set of families (:func:`_best_set`) on each of ``n_boot``
    ensembles of records drawn with replacement (a record keeps all its runs; the same draws
    for every backend, so the comparison is paired)."""
    records = sorted(ok["record"].unique())
    draws = np.random.default_rng(seed).integers(0, len(records), size=(n_boot, len(records)))
    counts: dict[tuple[str, str], tuple[np.ndarray, ...]] = {}
    for b in backends:
        g = ok[ok["backend"] == b]
        r = np.searchsorted(records, g["record"].to_numpy())
        zz = g["overturned"].to_numpy(bool).astype(float)
        for f in families:
            x = g["scale"].to_numpy(float) * by_record.loc[g["record"], f].to_numpy(float)
            xu, j = np.unique(np.round(x, 12), return_inverse=True)
            N, Z = np.zeros((len(records), xu.size)), np.zeros((len(records), xu.size))
            np.add.at(N, (r, j), 1.0)
            np.add.at(Z, (r, j), zz)
            counts[b, f] = (xu, N, Z)
    out: dict[str, list[list[str]]] = {b: [] for b in backends}
    for d in draws:
        w = np.bincount(d, minlength=len(records)).astype(float)
        for b in backends:
            disp = {}
            for f in families:
                xu, N, Z = counts[b, f]
                disp[f] = _fit_counts(xu, w @ N, w @ Z)["dispersion"] if xu.size else math.nan
            out[b].append(_best_set(disp, families))
    return out


#: Resamples of the records for the shares of the best intensity measure (at most the
#: analysis's ``n_boot``): each is one fit per backend and family.
IM_BOOT = 200


def im_efficiency(runs: pd.DataFrame, record_ims: pd.DataFrame, *,
                  measures: Sequence[str] | None = None, reference: str = "analytic",
                  n_boot: int = IM_BOOT, seed: int = 0) -> dict[str, Any]:
    """The lognormal fit (:func:`fit_lognormal`) of every backend's runs over every intensity
    measure: a run's intensity is its ``scale`` times its record's measure (``record_ims``: one
    row per ``record``, one column per key of :data:`MEASURES`; ``measures``: which, default
    every column of ``record_ims`` that is a measure). Runs not ``ok`` are left out.

    The efficiency of a measure is its dispersion beta [-]: the spread of ln(capacity) over
    the records that the measure leaves (the smaller, the fewer records a study needs). A
    dimensionless measure is a constant multiple of its base measure for one structure
    (:data:`rockbench.studies.intensity.BASE_MEASURE`): the same dispersion, so the two rank as
    one ("family"). Returns ``measures`` (key -> name, unit, definition) and per backend:
    ``fits`` (key -> median [unit], dispersion [-], note, family (its family's name), rank: 1
    the smallest dispersion,
    shared within a family and by fits at the dispersion's lower bound, which the sample
    cannot order; None without a regular fit), ``ranking`` (the families, each named by its
    first measure in ``measures``, smallest dispersion first), ``best`` (the first family;
    None without a regular fit) and ``best_set`` (the families tied with it), and for the
    backends other than ``reference``: ``same_best`` (True when the two best sets share a
    family, False when not: the engine would pick another measure; None when either has no
    best) and ``same_ranking`` (the whole order of the families), and ``sentence``.

    How sure the ranking is: on ``n_boot`` ensembles of records drawn with replacement
    (``seed``; 0: none), ``p_best`` (family -> the share of the draws in which it is the most
    efficient, a tie shared) and, per engine, ``p_same_best`` (the share of the draws in which
    its best set and the reference's share a family, on the same draw)."""
    if measures is None:
        measures = [k for k in MEASURES if k in record_ims.columns]
    for k in measures:
        if k not in MEASURES:
            raise ParameterError("intensity", k, f"one of {', '.join(MEASURES)}")
        if k not in record_ims.columns:
            raise ParameterError("record_ims", f"no column {k}", "a column per measure")
    ok = runs[runs["status"] == "ok"]
    by_record = record_ims.set_index("record")
    out: dict[str, Any] = {"measures": {k: dict(zip(("name", "unit", "definition"),
                                                    MEASURES[k])) for k in measures},
                           "reference": reference, "backends": {}}
    for b in dict.fromkeys(runs["backend"]):
        g = ok[ok["backend"] == b]
        ot = g["overturned"].astype(bool).to_numpy()
        fits: dict[str, dict[str, Any]] = {}
        for k in measures:
            x = g["scale"].to_numpy(float) * by_record.loc[g["record"], k].to_numpy(float)
            f = fit_lognormal(x, ot) if len(g) else {"median": math.nan,
                                                     "dispersion": math.nan, "note": "no run"}
            fits[k] = {"median": f["median"], "dispersion": f["dispersion"], "note": f["note"]}
        # a family is named by its first measure in ``measures``, its dispersion that one's
        rep = {k: next(m for m in measures if _family(m) == _family(k)) for k in measures}
        # fits at the dispersion's lower bound (separated by intensity) tie: the sample
        # cannot tell them apart
        fam = {rep[k]: max(fits[rep[k]]["dispersion"], AT_BOUND) for k in measures
               if math.isfinite(fits[rep[k]]["dispersion"])}
        ranking = sorted(fam, key=lambda f: (fam[f], list(measures).index(f)))
        levels = sorted(set(fam.values()))
        for k in measures:
            fits[k]["rank"] = levels.index(fam[rep[k]]) + 1 if rep[k] in fam else None
            fits[k]["family"] = rep[k]
        out["backends"][b] = {"fits": fits, "ranking": ranking,
                              "best": ranking[0] if ranking else None,
                              "best_set": [f for f in ranking if fam[f] == fam[ranking[0]]]}
    families = list(dict.fromkeys(next(m for m in measures if _family(m) == _family(k))
                                  for k in measures))
    boot = (_im_bootstrap(ok, by_record, families, list(out["backends"]), int(n_boot), seed)
            if n_boot and len(ok) else {})
    for b, sets in boot.items():
        share = dict.fromkeys(families, 0.0)
        for bs in sets:
            for f in bs:
                share[f] += 1.0 / len(bs) / len(sets)
        out["backends"][b]["p_best"] = share
        if b != reference and reference in boot:
            out["backends"][b]["p_same_best"] = float(np.mean(
                [bool(set(e) & set(r)) for e, r in zip(sets, boot[reference]) if e and r]
                or [math.nan]))
    out["n_boot"] = int(n_boot) if boot else 0
    ref = out["backends"].get(reference)
    for b, v in out["backends"].items():
        if b == reference:
            continue
        rb = ref["best"] if ref else None
        v["same_best"] = (None if rb is None or v["best"] is None
                          else bool(set(v["best_set"]) & set(ref["best_set"])))
        v["same_ranking"] = (None if v["same_best"] is None
                             else v["ranking"] == ref["ranking"])
        v["sentence"] = _im_sentence(b, v, ref, reference, out["measures"])
    return out


def _im_sentence(engine: str, v: Mapping[str, Any], ref: Mapping[str, Any] | None,
                 reference: str, measures: Mapping[str, Mapping[str, str]]) -> str:
    def named(fam: str, fits) -> str:
        return f"{measures[fam]['name']} (dispersion {_fmt(fits[fam]['dispersion'])})"
    if v["same_best"] is None:
        return f"{engine}: the intensity measures are not ranked (no regular fit)."
    order = " < ".join(measures[f]["name"] for f in v["ranking"])
    tied = (" (fits at the dispersion's bound: the runs separate by intensity, the measures "
            f"{', '.join(measures[f]['name'] for f in v['best_set'])} tie)"
            if len(v["best_set"]) > 1 else "")
    sure = (f" On {_fmt(100 * v['p_same_best'])} % of the resampled ensembles of records the "
            f"two pick the same measure." if math.isfinite(v.get("p_same_best", math.nan))
            else "")
    if v["same_best"]:
        return (f"{engine}: most efficient intensity measure {named(v['best'], v['fits'])}"
                f"{tied}, as in the {reference} model ({named(ref['best'], ref['fits'])})"
                + ("; the same order of every measure." if v["same_ranking"] else
                   f"; the order of the others differs (dispersion: {order}).") + sure)
    return (f"{engine}: most efficient intensity measure {named(v['best'], v['fits'])}, NOT the "
            f"{reference} model's ({named(ref['best'], ref['fits'])}): a study run with this "
            f"engine would pick another intensity measure (dispersion: {order})." + sure)

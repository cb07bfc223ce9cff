"""The campaign's tables, built from what the campaign hands over: comparison payloads (the
tables of :func:`rockbench.comparison.compare`), time-step rows and sweep frames
(:func:`rockbench.sweep.run_cases`). Columns and units: :data:`CAMPAIGN_COLUMNS` and
``docs/report.md``. Pure functions of data frames: nothing here runs anything."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import pandas as pd

from ..fates import FATES
from . import figures as F

__all__ = ["CAMPAIGN_COLUMNS", "metrics_table", "eta_tables",
           "engine_summary", "sweep_rows", "with_verdicts"]

#: Columns of the campaign's CSV files (beyond the METRIC_COLUMNS / ETA_COLUMNS they repeat).
CAMPAIGN_COLUMNS: dict[str, dict[str, str]] = {
    "metrics.csv": {
        "part": "-, pulse | fracture (hybrid pulse cases that fracture) | free (free rocking)",
        "case": "-, short label of the case",
        "scene": "-, built-in scene name",
        "shape": "-, symmetric | antisymmetric Ricker pulse (empty: free rocking)",
        "sign": "-, +1 | -1 sign of the pulse",
        "A": "-, a_g / (g tan alpha)",
        "W": "-, omega_g / p",
        "phi0": "rad, initial rotation",
        "band_low": "-, smallest max|phi| / alpha of the analytic model under the perturbations "
                    "of rockbench.studies.sensitivity (pulse and fracture cases; docs/records.md)",
        "band_high": "-, largest max|phi| / alpha under those perturbations",
        "within_band": "-, bool: this backend's peak lies within the band (an overturned run: "
                       "some analytic run of the band overturns too)",
        "band_distance": "-, signed distance of the backend's peak to the band, in alpha (0 "
                         "inside)",
        "(then)": "every column of rockbench.comparison.METRIC_COLUMNS",
    },
    "eta.csv": {"scene": "-, scene (free rocking)", "phi0": "rad, initial rotation",
                "(then)": "every column of rockbench.comparison.ETA_COLUMNS"},
    "eta_summary.csv": {
        "scene": "-", "backend": "-", "direction": "-, +1 counterclockwise, -1 clockwise",
        "eta_ref": "-, analytic eta", "eta_mean": "-, mean effective eta",
        "eta_std": "-, standard deviation (ddof 0)", "n_impacts": "-, impacts measured",
        "rel_error": "-, eta_mean / eta_ref - 1"},
    "engines.csv": {
        "backend": "-", "engine_version": "-",
        "n_cases": "-, pulse cases run", "n_ok": "-, of them with status ok",
        "nrmse_median": "-, median nrmse over the ok pulse cases",
        "nrmse_max": "-, largest nrmse over the ok pulse cases",
        "peak_rel_error_median": "-, median |peak_rel_error|",
        "peak_rel_error_max": "-, largest |peak_rel_error|",
        "eta_mean_rel_error": "-, free rocking: mean over scenes and directions of "
                              "|eta_mean / eta_ref - 1|",
        "verdicts_agree": "-, pulse cases and map cells whose overturning verdict agrees",
        "verdicts_total": "-, pulse cases and map cells compared",
        "energy_gained": "-, pulse cases with energy gained at an impact",
        "cpu_per_sim_s_median": "s/s, median over the ok pulse cases of the process CPU s per "
                                "simulated s of one run (the decision measures cost with "
                                "repeats: advice.csv)"},
    "map_agreement.csv": {
        "scene": "-", "backend": "-", "grid": "-, NA x NW x pulses of the engine's map",
        "cells": "-, cells compared (ok in both maps)",
        "differ": "-, of those, cells whose overturning verdict differs from the analytic one",
        "agree_fraction": "-, (cells - differ) / cells",
        "kappa": "-, Cohen's kappa of the verdicts (1: perfect, 0: chance)",
        "engine_overturns_analytic_survives": "-, cells",
        "analytic_overturns_engine_survives": "-, cells",
        "boundary_shift_mean": "-, mean over pulses and frequencies of A_min(engine) - "
                               "A_min(analytic) (negative: the engine overturns earlier)",
        "boundary_shift_max_abs": "-, largest |A_min(engine) - A_min(analytic)|",
        "not_ok": "-, cells not ok in either map (left out of cells)",
        "near_boundary": "-, compared cells within 2 % in A of the analytic boundary",
        "disagree_near_boundary": "-, differing cells near the boundary",
        "disagree_away": "-, differing cells away from it",
        "in_words": "-, the boundary's shift per pulse, in words"},
    "tradeoff.csv": {"(then)": "every column of rockbench.studies.tradeoff.TABLE_COLUMNS "
                               "(one row per engine and setting the decision's search ran)"},
    "validity_map.csv": {"(then)": "every column of rockbench.studies.validity_map."
                                   "VALIDITY_COLUMNS (one row per cell of the validity map of "
                                   "the decision's scene; docs/maps.md)"},
    "fragility.csv": {
        "frame": "-, the frame's label", "scene": "-", "backend": "-, a backend, or 'analytic "
        "(whole ladder)': the analytic fit over every step", "ensemble": "-, kind: name of the "
        "records (synthetic, bundled or real)", "intensity": "-, the intensity measure",
        "unit": "-, its unit", "median": "the IM's unit, lognormal fragility median",
        "median_low": "the IM's unit, 95 % bootstrap interval, low",
        "median_high": "the IM's unit, 95 % bootstrap interval, high",
        "dispersion": "-, lognormal dispersion beta (record to record)",
        "dispersion_low": "-, its 95 % interval, low", "dispersion_high": "-, high",
        "dispersion_numerical": "-, beta_num: RMS of ln(1 + e) over the engine's relative peak "
                                "errors at its setting (docs/fragility.md)",
        "dispersion_total": "-, sqrt(beta^2 + beta_num^2)",
        "im_best": "-, the most efficient intensity measure (smallest dispersion)",
        "runs": "-, runs fitted", "overturned": "-, of them overturned",
        "not_ok": "-, runs not ok (left out)", "statistic": "-, two-sample KS statistic",
        "p_value": "-, its smallest p over the steps",
        "median_difference": "the IM's unit, median - the analytic median",
        "median_difference_low": "the IM's unit, 95 % interval, low",
        "median_difference_high": "the IM's unit, 95 % interval, high",
        "verdict": "-, the engine's verdict against the analytic model, in words",
        "note": "-, how the fit went, in words"},
    "stress.csv": {"(then)": "every column of rockbench.studies.robustness.STRESS_COLUMNS (one "
                             "row per engine and stability point)"},
    "stress_breaking_points.csv": {
        "engine": "-", "axis": "-, the stability axis (rockbench stress)",
        "side": "-, below | above the base scene's value (all: an axis without one)",
        "value": "the axis's unit, the first value on that side where the engine is not within "
                 "5 %", "unit": "-, the axis's unit", "class": "-, off | diverged | invalid",
        "reason": "-, what was measured there"},
    "advice.csv": {
        "tolerance": "-, relative error (0.02 = 2 %)", "rank": "-, 1 = recommended when it "
        "meets the tolerance", "engine": "-",
        "status": f"-, the engine's fate (rockbench.fates: {', '.join(FATES)})",
        "recommended": "-, bool", "setting": "-, the setting (meets: the answer; otherwise the "
        "closest one)", "worst_error_choice": "-, worst error on the choice part",
        "worst_error_heldout": "-, worst error on the held-out part",
        "cpu_per_sim_s": "s/s, steady process CPU s per simulated s",
        "real_time_factor": "-, simulated s per CPU s", "erratic": "-, bool",
        "tie_with_cheapest": "-, within 25 % of the cheapest confirmed cost",
        "reason": "-, why, in words"},
    "record_peaks.csv": {
        "record": "-, file stem", "frame": "-, free-standing | hybrid", "scene": "-",
        "polarity": "-, +1 as recorded, -1 reversed", "backend": "-", "status": "-",
        "max_abs_phi_over_alpha": "-", "overturned": "-, bool",
        "overturned_ref": "-, analytic verdict", "verdict_agrees": "-, bool",
        "peak_rel_error": "-, max|phi| / max|phi_ref| - 1 (both ok and not overturned)",
        "band_low": "-, smallest max|phi| / alpha of the analytic model under the perturbations "
                    "of rockbench.studies.sensitivity (docs/records.md)",
        "band_nominal": "-, the unperturbed analytic max|phi| / alpha of the band's runs",
        "band_high": "-, largest max|phi| / alpha under those perturbations",
        "band_verdict_agreement": "-, fraction of perturbed analytic runs with the unperturbed "
                                  "overturning verdict",
        "within_band": "-, bool: the backend's peak lies in [band_low, band_high] (an overturned "
                       "run: some analytic run of the band overturns too)",
        "band_distance": "-, signed distance of the peak to the band, in alpha (0 inside)"},
    "runtime.csv": {
        "part": "-, a part of the campaign (comparisons, maps, choice, records, "
                "fragility, validity map, report = the page and its figures), or total",
        "wall_s": "s, wall-clock seconds of the part in this run",
        "cpu_s": "s, CPU seconds (user + system) of the process and its workers during the "
                 "part (rockbench.machine.tree_cpu_s); cases reused from the store cost nothing",
        "workers": "-, worker processes the campaign used",
        "processor": "-, the machine's processor (rockbench.machine.cpu_name)"},
}


def _bool(v: Any) -> bool | None:
    if v is None or v is pd.NA:
        return None
    if isinstance(v, float) and math.isnan(v):
        return None
    return bool(v)


# ==========================================================================================
# Sweep frames: the overturning map and the records
# ==========================================================================================
def with_verdicts(df: pd.DataFrame, keys: Sequence[str]) -> pd.DataFrame:
    """Add overturned_ref (the analytic verdict of the same keys) and verdict_agrees."""
    df = df.copy()
    ref = df[(df["backend"] == "analytic") & (df["status"] == "ok")]
    verdict = {tuple(r[k] for k in keys): _bool(r["overturned"]) for _, r in ref.iterrows()}
    peak = {tuple(r[k] for k in keys): r["max_abs_phi_over_alpha"] for _, r in ref.iterrows()}
    refs, agree, rel = [], [], []
    for _, r in df.iterrows():
        k = tuple(r[c] for c in keys)
        v = verdict.get(k)
        mine = _bool(r["overturned"]) if r["status"] == "ok" else None
        refs.append(v)
        agree.append(None if v is None or mine is None else v == mine)
        p = peak.get(k)
        rel.append(r["max_abs_phi_over_alpha"] / p - 1.0
                   if mine is False and v is False and p and p > 0 else math.nan)
    df["overturned_ref"] = pd.array(refs, dtype="boolean")
    df["verdict_agrees"] = pd.array(agree, dtype="boolean")
    df["peak_rel_error"] = rel
    return df


def sweep_rows(df: pd.DataFrame) -> pd.DataFrame:
    """run_cases rows -> campaign columns (backend, shape, sign, A, W, record, polarity)."""
    if df.empty:
        return df
    out = pd.DataFrame({"backend": df["engine"].astype(str), "scene": df["scene"].astype(str)})
    for src, dst in (("motion.shape", "shape"), ("motion.sign", "sign"), ("motion.A", "A"),
                     ("motion.W", "W"), ("motion.scale", "polarity"), ("motion.path", "path")):
        if src in df:
            out[dst] = df[src].to_numpy()
    for c in ("status", "reason", "max_abs_phi_over_alpha", "overturned", "t_overturn",
              "n_impacts", "fractured", "max_penetration", "max_sliding", "wall_s",
              "real_time_factor", "run_s", "engine_version"):
        if c in df:
            out[c] = df[c].to_numpy()
    out["overturned"] = pd.array([_bool(v) for v in out["overturned"]], dtype="boolean") \
        if "overturned" in out else pd.array([None] * len(out), dtype="boolean")
    return out


# ==========================================================================================
# Comparison payloads: {"job", "label", "table", "eta", "phi0", ...}
# ==========================================================================================
def _case_columns(job: Mapping[str, Any], label: str, phi0: float) -> dict[str, Any]:
    m = job.get("motion")
    if job["kind"] == "free":
        return {"part": "free", "case": label, "scene": job["scene"], "shape": "",
                "sign": pd.NA, "A": math.nan, "W": math.nan, "phi0": phi0}
    part = "fracture" if job["kind"] == "fracture" else "pulse"
    return {"part": part, "case": label, "scene": job["scene"], "shape": m["shape"],
            "sign": int(m["sign"]), "A": float(m["A"]), "W": float(m["W"]), "phi0": phi0}


def metrics_table(payloads: Iterable[Mapping[str, Any]]) -> pd.DataFrame:
    """``metrics.csv``: one row per (case, backend), the case's columns then the metrics."""
    frames = []
    for p in payloads:
        if "table" not in p:
            continue
        cols = _case_columns(p["job"], p["label"], p["phi0"])
        t = p["table"].copy()
        band = p.get("band") or {}
        judged = p.get("band_judged") or {}
        pos = 0
        for k, v in cols.items():
            t.insert(pos, k, v)
            pos += 1
        t.insert(pos, "band_low", float(band.get("low", math.nan)))
        t.insert(pos + 1, "band_high", float(band.get("high", math.nan)))
        t.insert(pos + 2, "within_band", pd.array(
            [judged.get(b, (None, math.nan))[0] for b in t["backend"]], dtype="boolean"))
        t.insert(pos + 3, "band_distance",
                 [float(judged.get(b, (None, math.nan))[1]) for b in t["backend"]])
        frames.append(t)
    if not frames:
        return pd.DataFrame()
    df = pd.concat(frames, ignore_index=True)
    df["sign"] = pd.array([None if pd.isna(v) else int(v) for v in df["sign"]], dtype="Int64")
    return df


def eta_tables(payloads: Iterable[Mapping[str, Any]]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``eta.csv`` (every impact of the free-rocking runs) and ``eta_summary.csv``."""
    per_impact, summary = [], []
    for p in payloads:
        if "eta" not in p or p["job"]["kind"] != "free":
            continue
        scene = p["job"]["scene"]
        e = p["eta"].copy()
        e.insert(0, "phi0", p["phi0"])
        e.insert(0, "scene", scene)
        per_impact.append(e)
        t = p["table"]
        for _, r in t.iterrows():
            for d, tag in ((1, "ccw"), (-1, "cw")):
                sub = e[(e["backend"] == r["backend"]) & (e["direction"] == d)]
                ref = r[f"eta_{tag}_ref"]
                mean = r[f"eta_{tag}_mean"]
                summary.append({"scene": scene, "backend": r["backend"], "direction": d,
                                "eta_ref": ref, "eta_mean": mean, "eta_std": r[f"eta_{tag}_std"],
                                "n_impacts": int(sub["eta"].notna().sum()),
                                "rel_error": mean / ref - 1.0 if pd.notna(mean) and ref
                                else math.nan})
    eta = pd.concat(per_impact, ignore_index=True) if per_impact else pd.DataFrame()
    return eta, pd.DataFrame(summary)


def engine_summary(metrics: pd.DataFrame, eta_summary: pd.DataFrame,
                   agreement: pd.DataFrame | None = None) -> pd.DataFrame:
    """``engines.csv``: one row per backend (columns: :data:`CAMPAIGN_COLUMNS`): the pulse
    cases' errors and verdicts, and, from ``agreement`` (``map_agreement.csv``), the cells of
    its maps whose verdict differs from the analytic one."""
    rows = []
    pulses = metrics[metrics["part"] == "pulse"] if len(metrics) else metrics
    backends = F._order(pulses["backend"]) if len(pulses) else []
    for b in backends:
        s = pulses[pulses["backend"] == b]
        ok = s[s["status"] == "ok"]
        nr = ok["nrmse"].astype(float).dropna()
        pk = ok["peak_rel_error"].astype(float).abs().dropna()
        es = eta_summary[eta_summary["backend"] == b] if len(eta_summary) else eta_summary
        er = es["rel_error"].astype(float).abs().dropna() if len(es) else pd.Series(dtype=float)
        va = ok["verdict_agrees"].dropna().astype(bool)
        n_agree, n_total = int(va.sum()), len(va)
        if agreement is not None and len(agreement):
            a = agreement[agreement["backend"] == b]
            n_total += int(a["cells"].sum())
            n_agree += int(a["cells"].sum() - a["differ"].sum()) if "differ" in a else int(
                round((a["cells"] * a["agree_fraction"]).sum()))
        versions = s["engine_version"].dropna().astype(str)
        rows.append({
            "backend": b, "engine_version": versions.iloc[0] if len(versions) else "",
            "n_cases": len(s), "n_ok": len(ok),
            "nrmse_median": float(nr.median()) if len(nr) else math.nan,
            "nrmse_max": float(nr.max()) if len(nr) else math.nan,
            "peak_rel_error_median": float(pk.median()) if len(pk) else math.nan,
            "peak_rel_error_max": float(pk.max()) if len(pk) else math.nan,
            "eta_mean_rel_error": float(er.mean()) if len(er) else math.nan,
            "verdicts_agree": n_agree, "verdicts_total": n_total,
            "energy_gained": int(ok["energy_gained_at_impact"].fillna(False).astype(bool).sum()),
            "cpu_per_sim_s_median": float(ok["cpu_per_sim_s"].astype(float).median())
            if len(ok) and "cpu_per_sim_s" in ok else math.nan,
        })
    return pd.DataFrame(rows)

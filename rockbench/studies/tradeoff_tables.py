"""The tables of the work-precision (:mod:`rockbench.studies.tradeoff`): the error of one case against
the analytic model (:func:`case_error`) and its class (:data:`VERDICTS`,
:func:`classify_error`), the run and summary tables (:data:`RUN_COLUMNS`,
:data:`TABLE_COLUMNS`, :func:`summarize`, :class:`Tradeoff`), each backend's precision curves
(:func:`precision_sweeps`) and the machine a measurement ran on (:func:`machine_info`).
Pure functions over tables; :mod:`rockbench.studies.tradeoff` runs the cases and re-exports these names.
Errors are relative (0.02 = 2 %); costs in process CPU s per simulated s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np
import pandas as pd

from ..constants import DT_LADDER

if TYPE_CHECKING:
    from .validation import ValidationCase

__all__ = ["DT_LADDER", "VERDICTS", "precision_sweeps", "case_error", "classify_error", "RUN_COLUMNS",
           "runs_frame", "add_self_consistency", "curve_of",
           "TABLE_COLUMNS", "summarize", "Tradeoff", "machine_info"]


#: Classes of agreement with the analytic model, best first (``verdict`` columns of the
#: tradeoff, advise and stress tables). "outside model" is used by :mod:`rockbench.studies.robustness` only.
VERDICTS = ("within 1%", "within 5%", "off", "diverged", "invalid", "outside model")


def precision_sweeps(engine: str) -> tuple:
    """The work-precision curves of ``engine``: its backend class's ``precision_sweeps``, a
    tuple of (knob, values or None, fixed overrides) - the setting that trades accuracy for
    cost, the values to sweep coarse to fine (None: the sweep's time steps) and the settings
    held with it (e.g. Drake: CENIC's ``accuracy``, and ``dt`` with a fixed-step solver);
    ``(("dt", None, {}),)`` for a backend that declares none."""
    from ..engines import get_backend

    try:
        return tuple(get_backend(engine).precision_sweeps)
    except Exception:      # an unavailable engine: the runs report it
        return (("dt", None, {}),)


# =========================================================================================
# Errors and classes
# =========================================================================================
def case_error(row: Mapping[str, Any]) -> float:
    """The validation error [-] of one run row (see the module docstring), by the case's
    well-conditioned measure (``measure``, :data:`rockbench.studies.validation.MEASURES`):
    |peak error| of a surviving pulse, the largest eta error of a free-rocking run without
    devices, the RMS of (phi - phi_ref) / alpha over |phi0| / alpha (``peak_ref``) of one with
    devices, for a record the relative
    distance of its peak to the analytic model's own sensitivity band (0 inside it: the model
    cannot claim a peak better than that; a record outside its band by more than the tolerance
    is not ok), 0 for an overturning case; infinite when the run is not ok or gets the
    overturning verdict wrong away from the boundary; NaN (not counted, reported) for a cell
    near the boundary: its verdict is a coin toss for every model there, and its peak a steep
    function of A."""
    if row.get("status") != "ok":
        return math.inf
    near = bool(row.get("near_boundary") or False)
    va = row.get("verdict_agrees")
    if va is not None and va is not pd.NA and not (isinstance(va, float) and math.isnan(va)) \
            and not bool(va):
        return math.nan if near else math.inf
    if near:
        return math.nan
    kind = row.get("kind")
    measure = row.get("measure")
    if measure == "history":
        # free rocking with devices: the history, relative to the initial amplitude (the eta
        # of a damped impact measures the damper's timing, not the engine)
        amp = float(row.get("peak_ref") or math.nan)
        v = abs(float(row.get("nrmse", math.nan))) / amp if amp > 0 else math.nan
        return v if math.isfinite(v) else math.inf
    if kind == "record":
        # beyond the analytic model's own sensitivity band: the relative distance of the peak
        # to the band's nearest edge (0 inside); without a band, the peak error
        bd = row.get("band_distance")
        bd = math.nan if bd is None else float(bd)
        v = abs(bd) if math.isfinite(bd) else abs(float(row.get("peak_rel_error", math.nan)))
    elif kind == "survive":
        v = abs(float(row.get("peak_rel_error", math.nan)))
    elif kind == "free":
        v = abs(float(row.get("eta_max_rel_error", math.nan)))
    else:
        return 0.0
    return v if math.isfinite(v) else math.inf


def classify_error(err: float, status: str = "ok") -> str:
    """The :data:`VERDICTS` class of a relative error ``err`` [-] of a run with ``status``:
    "within 1%", "within 5%", "off" (> 5 % or a wrong overturning verdict: infinite),
    "diverged" or "invalid" (status)."""
    if status in ("diverged", "invalid"):
        return status
    if status != "ok":
        return "invalid"
    if err <= 0.01:
        return "within 1%"
    if err <= 0.05:
        return "within 5%"
    return "off"


# =========================================================================================
# Tables
# =========================================================================================
#: Columns of :attr:`Tradeoff.runs` (one row per engine, setting and case).
RUN_COLUMNS: dict[str, str] = {
    "engine": "-, backend name",
    "setting": "-, setting label (dt first, then other overrides)",
    "dt": "s, engine time step",
    "case": "-, validation case (free rocking +-phi0/alpha, or the pulse's label)",
    "kind": "-, free | survive | overturn | record",
    "part": "-, choice | held-out (the case's part of the evidence)",
    "group": "-, the case's group: free | away:<pulse> | near | overturn | record",
    "near_boundary": "-, a pulse cell within NEAR_MARGIN of the analytic overturning "
                     "threshold, or a case whose analytic verdict flips within its band",
    "measure": "-, the case's measure: eta | history | peak | band | verdict",
    "peak_ref": "-, analytic max|phi| / alpha of the case (free rocking: phi0 / alpha)",
    "status": "-, ok | diverged | invalid | error (error: an exception, see reason)",
    "reason": "-, why a run is not ok",
    "peak_rel_error": "-, max|phi| / max|phi_ref| - 1 against the analytic reference",
    "nrmse": "-, RMS of (phi - phi_ref) / alpha over the common time grid",
    "eta_max_rel_error": "-, largest |eta / eta_ref - 1| over the run's impacts",
    "verdict_agrees": "-, same overturning verdict as the analytic reference",
    "in_band": "-, a record's peak within the analytic model's sensitivity band",
    "band_distance": "-, a record's peak / nearest band edge - 1 (0 inside)",
    "error": "-, the case's validation error (case_error): inf when not ok, a wrong verdict "
             "away from the boundary or a record outside its band; NaN near the boundary",
    "verdict": "-, class of the error (VERDICTS)",
    "self_peak_error": "-, max|phi| / max|phi_fine| - 1 against the same engine at dt / 4 "
                       "(NaN when that run is not in the sweep)",
    "self_nrmse": "-, RMS of (phi - phi_fine) / alpha against the same engine at dt / 4",
    "max_sliding": "m, largest slip of a contact point",
    "contact_opened": "-, a contact the analytic model keeps closed opened",
    "sim_time": "s, simulated time of the run",
    "cpu_s_median": "s, median over the repeats of the run's process CPU time",
    "cpu_s_min": "s, smallest CPU time of the repeats",
    "cpu_s_max": "s, largest CPU time of the repeats",
    "build_cpu_s": "s, CPU time of building the engine's model once (apart from cpu_s)",
    "warmup_cpu_s": "s, CPU time of the process's one-off warm-up run for this setting (NaN: "
                    "the process had warmed up already)",
}

#: Columns of :attr:`Tradeoff.table` (one row per engine and setting).
TABLE_COLUMNS: dict[str, str] = {
    "engine": "-, backend name",
    "setting": "-, setting label",
    "dt": "s, engine time step",
    "n_cases": "-, validation runs",
    "n_ok": "-, runs with status ok",
    "peak_error_worst": "-, largest |peak_rel_error| over the surviving pulses away from the "
                        "boundary and the records",
    "peak_error_median": "-, median of the same",
    "nrmse_worst": "-, largest nrmse over the free-rocking and surviving runs",
    "nrmse_median": "-, median nrmse over the free-rocking and surviving runs",
    "eta_error_worst": "-, largest eta error over the free-rocking runs",
    "eta_error_median": "-, median of the free-rocking runs' largest eta errors",
    "verdicts_agree": "-, fraction of ok runs with the analytic overturning verdict",
    "worst_error": "-, the worst validation error over every case (inf: a run not ok, a wrong "
                   "verdict away from the boundary, a record outside its band)",
    "worst_error_choice": "-, the same over the choice part of the evidence",
    "worst_error_heldout": "-, the same over the held-out part",
    "n_choice": "-, runs of the choice part", "n_heldout": "-, runs of the held-out part",
    "near_disagree": "-, near-boundary cells whose overturning verdict differs (not counted)",
    "outside_band": "-, record runs whose peak is outside the analytic sensitivity band (by "
                    "any amount; the error counts the distance)",
    "verdict": "-, class of worst_error (VERDICTS)",
    "self_peak_error_worst": "-, largest |self_peak_error| (against dt / 4; NaN: not run)",
    "self_nrmse_worst": "-, largest self_nrmse (against dt / 4)",
    "max_sliding": "m, largest slip over the ok runs",
    "any_contact_opened": "-, a contact the analytic model keeps closed opened in some run",
    "cpu_per_sim_s": "s/s, steady-state process CPU s per simulated s over the whole set "
                     "(median of repeats; the model build and the warm-up apart)",
    "cpu_per_sim_s_min": "s/s, the same for the fastest repeat",
    "cpu_per_sim_s_max": "s/s, the same for the slowest repeat",
    "real_time_factor": "-, simulated s per CPU s (1 / cpu_per_sim_s)",
    "repeats": "-, runs of every case (cost spread over them)",
    "curve": "-, the work-precision curve of the setting: the engine, and the overrides held "
             "along it (precision_sweeps)",
    "knob": "-, the setting that moves along the curve (dt, or the engine's own knob)",
    "knob_value": "the knob's value (s for dt)",
    "build_cpu_s": "s, median CPU time of building the engine's model for one run (one-off)",
    "warmup_cpu_s": "s, largest one-off warm-up CPU time of a worker process (first run: "
                    "imports, JIT compile)",
}


def add_self_consistency(runs: list[dict[str, Any]]) -> None:
    """Add self_peak_error and self_nrmse to every run whose dt / 4 partner is among ``runs``."""
    by = {(r["engine"], r["setting"], r["case"]): r for r in runs}
    for r in runs:
        r["self_peak_error"] = r["self_nrmse"] = math.nan
        s = r.get("_setting")
        if s is None or r.get("status") != "ok":
            continue
        fine = by.get((r["engine"], s.refined().label, r["case"]))
        if fine is None or fine.get("status") != "ok":
            continue
        t, phi, tf, pf = r["t"], r["phi"], fine["t"], fine["phi"]
        lo, hi = max(t[0], tf[0]), min(t[-1], tf[-1])
        m = (tf >= lo - 1e-9) & (tf <= hi + 1e-9)
        if not m.any():
            continue
        e = (np.interp(tf[m], t, phi) - pf[m]) / r["alpha"]
        r["self_nrmse"] = float(np.sqrt(np.mean(e * e)))
        pk = float(np.max(np.abs(pf)))
        r["self_peak_error"] = float(np.max(np.abs(phi)) / pk - 1.0) if pk > 0 else math.nan


def runs_frame(runs: list[dict[str, Any]]) -> pd.DataFrame:
    rows = []
    for r in runs:
        cpu = np.asarray(r.get("cpu_s") or [], dtype=float)
        row = {c: r.get(c, math.nan) for c in RUN_COLUMNS}
        row["error"] = case_error(r)
        row["verdict"] = ("near boundary" if math.isnan(row["error"]) else
                          classify_error(row["error"], r.get("status", "error")))
        row["cpu_s_median"] = float(np.median(cpu)) if cpu.size else math.nan
        row["cpu_s_min"] = float(cpu.min()) if cpu.size else math.nan
        row["cpu_s_max"] = float(cpu.max()) if cpu.size else math.nan
        row["_cpu"] = cpu
        rows.append(row)
    df = pd.DataFrame(rows, columns=list(RUN_COLUMNS) + ["_cpu"])
    for c in ("reason",):
        df[c] = df[c].fillna("").astype(str)
    return df


def curve_of(engine: str, label: str) -> dict[str, Any]:
    """The curve, knob and knob value of a setting label (``"dt=0.001,accuracy=1e-05"``):
    the knob is the engine's own (:func:`precision_sweeps`) when the label sets it, else dt;
    the curve is the engine with the label's other overrides but dt."""
    parts = dict(p.split("=", 1) for p in label.split(",") if "=" in p)
    knobs = [k for k, _, _ in precision_sweeps(engine) if k != "dt" and k in parts]
    knob = knobs[0] if knobs else "dt"
    rest = ",".join(f"{k}={v}" for k, v in parts.items() if k not in (knob, "dt"))
    return {"curve": f"{engine} {rest}" if rest else engine, "knob": knob,
            "knob_value": float(parts.get(knob, "nan"))}


def summarize(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per (engine, setting) of a runs frame (:data:`RUN_COLUMNS`), columns
    :data:`TABLE_COLUMNS`. Cost: total CPU over total simulated time of the set, per repeat
    (``_cpu`` lists of the runs; without them the runs' median CPU seconds)."""
    out = []
    for (eng, label), g in runs.groupby(["engine", "setting"], sort=False):
        ok = g[g["status"] == "ok"]
        far = ~ok["near_boundary"].fillna(False).astype(bool)
        surv = ok[ok["kind"].isin(["survive", "record"]) & far]
        free = ok[ok["kind"] == "free"]
        fr = ok[ok["kind"].isin(["free", "survive"])]

        def stat(s: pd.Series, f) -> float:
            v = np.abs(pd.to_numeric(s, errors="coerce").to_numpy(dtype=float))
            v = v[np.isfinite(v)]
            return float(f(v)) if v.size else math.nan

        def worst_of(rows: pd.DataFrame) -> float:
            e = rows["error"].to_numpy(dtype=float)
            e = e[~np.isnan(e)]
            return float(e.max()) if e.size else (math.inf if len(rows) and not
                                                   rows["near_boundary"].astype(bool).all()
                                                   else math.nan)

        worst = worst_of(g) if len(g) else math.inf
        part = g["part"] if "part" in g else pd.Series(["choice"] * len(g), index=g.index)
        choice, held = g[part != "held-out"], g[part == "held-out"]
        status = "ok" if (g["status"] == "ok").all() else (
            "diverged" if (g["status"] == "diverged").any() else
            "invalid" if (g["status"] == "invalid").any() else "error")
        sim = g["sim_time"].to_numpy(dtype=float)
        cpus = [c for c in g.get("_cpu", pd.Series([None] * len(g)))]
        per_rep = []
        if cpus and all(isinstance(c, np.ndarray) and c.size for c in cpus):
            n = min(c.size for c in cpus)
            tot_sim = float(np.nansum(sim))
            per_rep = [float(sum(c[k] for c in cpus)) / tot_sim for k in range(n)]
        elif "cpu_s_median" in g and np.isfinite(sim).all():
            per_rep = [float(g["cpu_s_median"].sum() / sim.sum())]
        va = ok["verdict_agrees"].dropna().astype(bool)
        opened = g["contact_opened"].dropna()
        row = {
            "engine": eng, "setting": label, "dt": float(g["dt"].iloc[0]),
            "n_cases": int(len(g)), "n_ok": int(len(ok)),
            "peak_error_worst": stat(surv["peak_rel_error"], np.max),
            "peak_error_median": stat(surv["peak_rel_error"], np.median),
            "nrmse_worst": stat(fr["nrmse"], np.max),
            "nrmse_median": stat(fr["nrmse"], np.median),
            "eta_error_worst": stat(free["eta_max_rel_error"], np.max),
            "eta_error_median": stat(free["eta_max_rel_error"], np.median),
            "verdicts_agree": float(va.mean()) if len(va) else math.nan,
            "worst_error": worst,
            "worst_error_choice": worst_of(choice) if len(choice) else math.nan,
            "worst_error_heldout": worst_of(held) if len(held) else math.nan,
            "n_choice": int(len(choice)), "n_heldout": int(len(held)),
            "near_disagree": int((ok["near_boundary"].astype(bool)
                                  & ~ok["verdict_agrees"].fillna(True).astype(bool)).sum()),
            "outside_band": int((ok["kind"].eq("record")
                                 & ok["in_band"].eq(False)).sum()),
            "verdict": classify_error(worst, status if status != "error" else "invalid"),
            "self_peak_error_worst": stat(ok.loc[ok["kind"] == "survive", "self_peak_error"],
                                          np.max),
            "self_nrmse_worst": stat(fr["self_nrmse"], np.max),
            "max_sliding": stat(ok["max_sliding"], np.max),
            "any_contact_opened": bool(opened.astype(bool).any()) if len(opened) else False,
            "cpu_per_sim_s": float(np.median(per_rep)) if per_rep else math.nan,
            "cpu_per_sim_s_min": float(np.min(per_rep)) if per_rep else math.nan,
            "cpu_per_sim_s_max": float(np.max(per_rep)) if per_rep else math.nan,
            "repeats": len(per_rep),
            **curve_of(eng, label),
            "build_cpu_s": stat(g["build_cpu_s"], np.median),
            "warmup_cpu_s": stat(g["warmup_cpu_s"], np.max),
        }
        c = row["cpu_per_sim_s"]
        row["real_time_factor"] = 1.0 / c if c and math.isfinite(c) and c > 0 else math.nan
        out.append(row)
    df = pd.DataFrame(out, columns=list(TABLE_COLUMNS))
    return df.sort_values(["engine", "dt"], ascending=[True, False]).reset_index(drop=True)


@dataclass
class Tradeoff:
    """The work-precision measurements of one scene.

    scene : str (scene name); cases : the validation set; runs : one row per engine, setting
    and case (:data:`RUN_COLUMNS`); table : one row per engine and setting
    (:data:`TABLE_COLUMNS`); unavailable : engine -> why it could not run here;
    machine : where the cost was measured (processor, Python, engine versions).
    """

    scene: str
    cases: list[ValidationCase]
    runs: pd.DataFrame
    table: pd.DataFrame
    unavailable: dict[str, str] = field(default_factory=dict)
    machine: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        from ..result import jsonable

        return jsonable({"scene": self.scene, "machine": self.machine,
                          "unavailable": self.unavailable,
                          "cases": [c.to_dict() for c in self.cases],
                          "table": self.table.to_dict("records"),
                          "columns": TABLE_COLUMNS})

    def to_csv(self, directory) -> list[Path]:
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        a, b = d / "tradeoff.csv", d / "tradeoff_runs.csv"
        self.table.to_csv(a, index=False)
        self.runs.drop(columns=["_cpu"], errors="ignore").to_csv(b, index=False)
        return [a, b]


def machine_info() -> dict[str, Any]:
    """Where the cost was measured: :func:`rockbench.machine.describe` (processor, cores,
    Python, platform) and the versions of the engines."""
    from ..engines import engine_info
    from ..machine import describe

    return {**describe(),
            "engines": {r["name"]: r.get("version", r.get("reason")) for r in engine_info()}}



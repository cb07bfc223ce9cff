"""Work-precision: how accurate each engine is on a scene, at each setting, and at what cost.

:func:`tradeoff` runs a fixed **validation set** of a scene
(:func:`rockbench.validation.validation_set`, re-exported here) with every selected engine at
every setting (by default the time steps :data:`DEFAULT_DTS`), with
repeats, and measures

* **accuracy against the analytic reference** (:func:`rockbench.compare.metrics` on every run):
  worst and median |peak error| over the surviving pulses, worst and median nrmse, worst and
  median eta error over the free-rocking runs, overturning-verdict agreement;
* **self-consistency** (Erez, Tassa & Todorov 2015, "Simulation tools for model-based robotics"):
  every setting against the same engine at a step four times smaller (``dt / 4``), on the same
  cases. The difference is the engine's *discretisation* error; what remains of the error against
  the analytic model once that is small is *model* error (the engine converges to something
  else than the rigid-impact model);
* **cost** as process CPU time (:func:`time.process_time`, user + system time of the worker
  process, all threads: the engines run on one thread) of the whole run (building the model,
  stepping, the Python loop and the post-processing into a Result), divided by the simulated
  time: CPU seconds per simulated second, the median of ``repeat`` runs with its min-max spread,
  and the CPU real-time factor (simulated seconds per CPU second, the inverse). CPU time, unlike
  wall time, does not change with the load of a shared machine, so the ranking is stable.

Output: a :class:`Tradeoff` with ``runs`` (one row per engine, setting and case:
:data:`RUN_COLUMNS`) and ``table`` (one row per engine and setting: :data:`TABLE_COLUMNS`);
``rockbench.report.tradeoff_figures.plot_work_precision(t.table)`` draws the work-precision
diagram.

The **worst validation error** (``worst_error``, what ``rockbench advise`` compares with a
tolerance) of a setting is the largest of: |peak error| of every surviving pulse, the eta error
of every free-rocking impact (:func:`rockbench.compare.metrics`' ``eta_max_rel_error``); it is
infinite when a run is not ``ok`` or gets the overturning verdict wrong. Errors are relative
(0.02 = 2 %).

Runs go through :func:`rockbench.runner.run` and the one executor
(:func:`rockbench.sweep.executors.execute`: serial, process pool or Dask); finished runs are kept
in the one store (:mod:`rockbench.sweep.store`) under ``<store>/<code fingerprint>/tradeoff/``,
keyed by the scene's data, the case, the engine and its settings, and the repeat count.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from .errors import ParameterError
from .validation import (ValidationCase, _analytic, _scene_from_key,
                         _scene_key, overturn_threshold, validation_set)

__all__ = ["DEFAULT_DTS", "precision_sweeps", "ValidationCase", "validation_set",
           "overturn_threshold", "Setting", "settings_grid", "tradeoff", "Tradeoff", "summarize",
           "classify_error", "RUN_COLUMNS", "TABLE_COLUMNS", "VERDICTS", "case_error"]

#: Default time steps [s] of the work-precision sweep.
DEFAULT_DTS: tuple[float, ...] = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)

#: Classes of agreement with the analytic model, best first (``verdict`` columns of the
#: tradeoff, advise and stress tables). "outside model" is used by :mod:`rockbench.stress` only.
VERDICTS = ("within 1%", "within 5%", "off", "diverged", "invalid", "outside model")

#: The clock of the cost: process CPU time (user + system) [s]. A module attribute so that a
#: test can replace it.
cpu_clock = time.process_time

#: Self-consistency partner: each setting is compared with the same engine at dt / this.
REFINEMENT = 4



# =========================================================================================
# Settings
# =========================================================================================
@dataclass(frozen=True)
class Setting:
    """One engine setting: ``engine`` and a tuple of (name, value) setting overrides."""

    engine: str
    overrides: tuple[tuple[str, Any], ...]

    @property
    def dt(self) -> float:
        from .engines import get_backend

        d = dict(self.overrides)
        if "dt" in d:
            return float(d["dt"])
        return float(getattr(get_backend(self.engine).Settings(), "dt", math.nan))

    @property
    def label(self) -> str:
        """``"dt=0.001"`` or ``"dt=0.001,iterations=50"`` (dt first, then sorted names)."""
        d = dict(self.overrides)
        parts = [f"dt={self.dt:g}"] + [f"{k}={d[k]:g}" if isinstance(d[k], float)
                                       else f"{k}={d[k]}" for k in sorted(d) if k != "dt"]
        return ",".join(parts)

    def refined(self, factor: int = REFINEMENT) -> "Setting":
        """The same setting at dt / factor (or, for a setting of a backend's own precision
        knob, :func:`precision_sweeps`, that knob / factor)."""
        d = dict(self.overrides)
        knob = next((k for k, _, _ in precision_sweeps(self.engine) if k != "dt" and k in d),
                    "dt")
        d[knob] = (self.dt if knob == "dt" else float(d[knob])) / factor
        return Setting(self.engine, tuple(sorted(d.items())))


def precision_sweeps(engine: str) -> tuple:
    """The work-precision curves of ``engine``: its backend class's ``precision_sweeps``, a
    tuple of (knob, values or None, fixed overrides) - the setting that trades accuracy for
    cost, the values to sweep coarse to fine (None: the sweep's time steps) and the settings
    held with it (e.g. Drake: CENIC's ``accuracy``, and ``dt`` with a fixed-step solver);
    ``(("dt", None, {}),)`` for a backend that declares none."""
    from .engines import get_backend

    try:
        return tuple(getattr(get_backend(engine), "precision_sweeps", None)
                     or (("dt", None, {}),))
    except Exception:      # an unavailable engine: the runs report it
        return (("dt", None, {}),)


def _parse_value(text: str) -> Any:
    t = text.strip()
    for conv in (int, float):
        try:
            return conv(t)
        except ValueError:
            pass
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    return t


def parse_setting(text: str) -> dict[str, Any]:
    """``"iterations=50"`` or ``"pymunk:iterations=50,collision_slop=1e-4"`` -> overrides
    (an optional ``engine:`` prefix is returned under the key ``"__engine__"``)."""
    out: dict[str, Any] = {}
    if ":" in text.split("=", 1)[0]:
        eng, text = text.split(":", 1)
        out["__engine__"] = eng.strip()
    for part in text.split(","):
        if not part.strip():
            continue
        if "=" not in part:
            raise ParameterError("setting", part, "name=value (e.g. iterations=50)")
        k, v = part.split("=", 1)
        out[k.strip()] = _parse_value(v)
    return out


def settings_grid(engines: Sequence[str], dts: Iterable[float] | None = None,
                  extra: Sequence[Mapping[str, Any] | str] | None = None) -> list[Setting]:
    """Every (engine, setting) of a sweep: each engine at each ``dt`` [s] (default
    :data:`DEFAULT_DTS`), and each ``extra`` override set (a dict or ``"name=value,..."``,
    optionally ``"engine:name=value"`` for one engine only) at each dt, unless it sets dt
    itself. Settings are validated by the engines when they run."""
    dts = [float(d) for d in (DEFAULT_DTS if dts is None else dts)]
    for d in dts:
        if not (d > 0 and math.isfinite(d)):
            raise ParameterError("dt", d, "> 0 [s]")
    extras: list[dict[str, Any]] = [{}]
    for e in extra or []:
        extras.append(parse_setting(e) if isinstance(e, str) else dict(e))
    out: list[Setting] = []
    for eng in engines:
        for ex in extras:
            ex = dict(ex)
            only = ex.pop("__engine__", None)
            if only is not None and only != eng:
                continue
            # each of the engine's curves (precision_sweeps: dt for every engine but those
            # whose class declares its own knob); an extra that sets the knob is run as given
            for knob, values, fixed in (precision_sweeps(eng) if not ex else
                                        (("dt", None, {}),)):
                vals = [ex[knob]] if knob in ex else (dts if values is None else values)
                for v in vals:
                    o = {**fixed, **ex, knob: float(v)}
                    if knob == "dt" or "dt" in ex:
                        o["dt"] = float(o.get("dt", v))
                    s = Setting(eng, tuple(sorted(o.items())))
                    if s not in out:
                        out.append(s)
    return out


# =========================================================================================
# One run (what the executor runs; picklable, top level)
# =========================================================================================
@functools.lru_cache(maxsize=64)
def _reference(key: str, case: ValidationCase):
    scene = _scene_from_key(key)
    sc, motion = case.load(scene)
    # records: the compiled analytic path (the default of record comparisons; same answers)
    return _analytic(sc, motion, case.duration, case.phi0, compiled=case.kind == "record"
                     or (case.motion is not None and dict(case.motion).get("kind") == "record"))


@functools.lru_cache(maxsize=64)
def _band(key: str, case: ValidationCase):
    """The analytic model's own sensitivity band of a record case (:mod:`rockbench.sensitivity`)."""
    from .sensitivity import band

    sc, motion = case.load(_scene_from_key(key))
    return band(sc, motion, duration=case.duration, phi0=case.phi0)


#: (engine, setting label) already warmed up in this process, with the warm-up's CPU time [s].
_WARMED: dict[tuple[str, str], float] = {}

#: Simulated time [s] of the warm-up run (free rocking from 0.3 alpha).
WARMUP_DURATION = 0.5


def _warm(setting: "Setting", scene, over: dict[str, Any]) -> float:
    """Run one short case of ``setting`` on ``scene`` before anything is timed, once per process
    (the one-off costs: imports, numba's compile of the stepping loop, the engine's first-run
    allocations). Returns its CPU time [s] the first time, NaN after."""
    from .runner import run

    k = (setting.engine, setting.label)
    if k in _WARMED:
        return math.nan
    c0 = cpu_clock()
    try:
        run(scene, None, engine=setting.engine, duration=WARMUP_DURATION,
            phi0=0.3 * scene.alpha, **over)
    except Exception:   # the timed run reports the failure
        pass
    _WARMED[k] = cpu_clock() - c0
    return _WARMED[k]


def _build_cpu(setting: "Setting", scene, phi0: float, over: dict[str, Any]) -> float:
    """CPU time [s] of building the engine's model of ``scene`` (a one-off cost per run,
    measured apart: :meth:`EngineBackend.build` then release), or 0 for a backend without one."""
    from .engines import get_backend

    cls = get_backend(setting.engine)
    if not hasattr(cls, "build"):
        return 0.0
    b = cls(scene, None, **over)
    c0 = cpu_clock()
    try:
        b.build(phi0)
    finally:
        try:
            b._close()
        except Exception:
            pass
    return cpu_clock() - c0


def _run_overrides(setting: Setting) -> dict[str, Any]:
    """The setting's overrides, with ``output_dt`` raised to dt when dt exceeds the engine's
    default output interval (1 ms): histories stay sampled at 1 ms or at every step."""
    from .engines import get_backend

    over = dict(setting.overrides)
    if "output_dt" not in over:
        od = float(get_backend(setting.engine).Settings().output_dt)
        if setting.dt > od:
            over["output_dt"] = setting.dt
    return over


def _run_item(item: dict[str, Any]) -> dict[str, Any]:
    """Run one (engine, setting, case) ``repeat`` times; return its row (metrics against the
    analytic reference; for a record, its place in the reference's sensitivity band; CPU times:
    the steady-state part of every repeat, the model build and the process's one-off warm-up
    apart) and the thinned history (t, phi) for self-consistency.
    Never raises for a failure of the run: it becomes status "error"."""
    from .compare import metrics
    from .runner import run

    case: ValidationCase = item["case"]
    setting: Setting = item["setting"]
    row: dict[str, Any] = {"engine": setting.engine, "setting": setting.label,
                           "dt": setting.dt, "case": case.name, "kind": case.kind,
                           "part": case.part, "group": case.group,
                           "near_boundary": bool(case.near_boundary)}
    try:
        scene = _scene_from_key(item["scene"])
        sc, motion = case.load(scene)
        ref = _reference(item["scene"], case)
        over = _run_overrides(setting)
        row["warmup_cpu_s"] = _warm(setting, sc, over)
        build = _build_cpu(setting, sc, case.phi0, over)
        cpu: list[float] = []
        result = None
        for _ in range(int(item["repeat"])):
            c0 = cpu_clock()
            result = run(sc, motion, engine=setting.engine, duration=case.duration,
                         phi0=case.phi0, **over)
            cpu.append(max(cpu_clock() - c0 - build, 0.0))
        m = metrics(result, ref)
        row.update({k: m[k] for k in ("status", "reason", "peak_rel_error", "nrmse",
                                      "eta_max_rel_error", "verdict_agrees", "overturned",
                                      "overturned_ref", "energy_gained_at_impact",
                                      "max_sliding", "max_penetration", "contact_opened")})
        if case.kind == "record" and row["status"] == "ok":
            j = _band(item["scene"], case).judge(result)
            row["in_band"], row["band_distance"] = bool(j.inside), float(j.relative)
        row["sim_time"] = float(result.cost.sim_time)
        row["cpu_s"] = [float(c) for c in cpu]
        row["build_cpu_s"] = float(build)
        row["t"] = result.history["t"].to_numpy(dtype=float)
        row["phi"] = result.history["phi"].to_numpy(dtype=float)
        row["alpha"] = float(sc.alpha)
    except Exception as e:  # a failing run is data
        row.update(status="error", reason=f"{type(e).__name__}: {e}", cpu_s=[],
                   sim_time=math.nan)
    return row


def _crashed(item: dict[str, Any], reason: str) -> dict[str, Any]:
    s, c = item["setting"], item["case"]
    return {"engine": s.engine, "setting": s.label, "dt": s.dt, "case": c.name,
            "kind": c.kind, "part": c.part, "group": c.group,
            "near_boundary": bool(c.near_boundary), "status": "error", "reason": reason,
            "cpu_s": [], "sim_time": math.nan}


# =========================================================================================
# Errors and classes
# =========================================================================================
def case_error(row: Mapping[str, Any]) -> float:
    """The validation error [-] of one run row (see the module docstring): |peak error| of a
    surviving pulse, the largest eta error of a free-rocking run, for a record the relative
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
    "near_boundary": "-, a pulse cell within NEAR_MARGIN of the analytic overturning threshold",
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


def _self_consistency(runs: list[dict[str, Any]]) -> None:
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


def _runs_frame(runs: list[dict[str, Any]]) -> pd.DataFrame:
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


def _curve(engine: str, label: str) -> dict[str, Any]:
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
            **_curve(eng, label),
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
        from .result import _jsonable

        return _jsonable({"scene": self.scene, "machine": self.machine,
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
    """Where the cost was measured: processor, cores, Python, engine versions."""
    import os
    import platform

    from .engines import engine_info

    proc = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    proc = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"processor": proc, "cores": os.cpu_count(), "python": platform.python_version(),
            "engines": {r["name"]: r.get("version", r.get("reason")) for r in engine_info()}}


# =========================================================================================
# The store
# =========================================================================================
def _item_key(item: dict[str, Any]) -> str:
    from .sweep.store import code_fingerprint, key

    s, c = item["setting"], item["case"]
    return key({"scene": item["scene"], "case": c.physics(), "engine": s.engine,
                "settings": dict(s.overrides), "repeat": int(item["repeat"]),
                "code": code_fingerprint()})


def _store_dir(store) -> Path:
    from .sweep.store import code_fingerprint, store_dir

    return store_dir(store) / code_fingerprint() / "tradeoff"


def _load_stored(directory: Path, k: str) -> dict[str, Any] | None:
    from .sweep.store import load_payload

    return load_payload(directory, k)


# =========================================================================================
# The sweep
# =========================================================================================
def tradeoff(scene, engines: Sequence[str] | None = None, *, dts: Iterable[float] | None = None,
             settings: Sequence[Mapping[str, Any] | str] | None = None, repeat: int = 3,
             quick: bool = False, self_consistency: str = "grid",
             executor: str = "process", workers: int | None = None, store=None,
             progress: bool = False, cases: Sequence[ValidationCase] | None = None,
             exact: Sequence[Mapping[str, Any]] | None = None) -> Tradeoff:
    """Measure work-precision on ``scene`` (a Scene, a built-in name or a scene file).

    Parameters
    ----------
    engines : backend names (default: every available engine, the analytic model excluded).
    dts : time steps [s] (default :data:`DEFAULT_DTS`).
    settings : extra override sets (:func:`settings_grid`), e.g. ``["iterations=50"]``.
    repeat : runs of each case (>= 1); the cost is the median over them, with min-max spread.
    quick : the reduced validation set (:func:`validation_set`).
    self_consistency : ``"grid"`` (compare with dt / 4 where that dt is in the sweep),
        ``"run"`` (run the missing dt / 4 settings too, once, not shown as settings) or
        ``"none"``.
    executor, workers : :func:`rockbench.sweep.executors.execute` (``"process"`` by default:
        each worker is one process on one core; CPU time is per process, so parallel runs do
        not inflate each other's cost as long as no core is oversubscribed).
    store : a directory: runs already there (same scene data, case, engine, settings, repeat
        count and code fingerprint) are not run again; new ones are written there.
    cases : a validation set to use instead of :func:`validation_set`.
    exact : override sets run as they are, instead of the grid of ``dts`` x ``settings``
        (each for every engine; without dt an engine runs at its default step).
    """
    from .runner import REFERENCE, resolve_engines
    from .scene.scene import load_scene
    from .sweep.executors import execute

    scene = load_scene(scene)          # a name, a file or a Scene: the one resolver
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ParameterError("repeat", repeat, "an integer >= 1")
    if self_consistency not in ("grid", "run", "none"):
        raise ParameterError("self_consistency", self_consistency, "grid, run or none")
    names = [n for n in resolve_engines(engines) if n != REFERENCE]
    from .engines import get_backend

    unavailable: dict[str, str] = {}
    usable = []
    for n in names:
        ok, why = get_backend(n).available()
        if ok:
            usable.append(n)
        else:
            unavailable[n] = why
    if exact is not None:
        grid = [Setting(e, tuple(sorted(dict(o).items()))) for e in usable for o in exact]
    else:
        grid = settings_grid(usable, dts, settings)
    shown = set(grid)
    if self_consistency == "run":
        for s in list(grid):
            f = s.refined()
            if f not in shown and f.dt >= 1e-6:
                grid.append(f)
    vset = list(cases) if cases is not None else validation_set(scene, quick=quick)
    key = _scene_key(scene)
    items = []
    for s in grid:
        for c in vset:
            # refinement-only runs need no repeats: their cost is not reported
            items.append({"scene": key, "case": c, "setting": s,
                          "repeat": repeat if s in shown else 1})
    keyed = [(_item_key(it), it) for it in items]
    done: dict[str, dict[str, Any]] = {}
    directory = None
    if store is not None:
        directory = _store_dir(store)
        for k, _ in keyed:
            row = _load_stored(directory, k)
            if row is not None and row.get("status") != "error":
                done[k] = row
    todo = [(k, it) for k, it in keyed if k not in done]

    def on_result(k: str, row: dict[str, Any]) -> None:
        done[k] = row
        if directory is not None and row.get("status") != "error":
            from .sweep.store import write_payload
            write_payload(directory, k, row)

    # TODO(pymunk/mujoco threads): every engine here steps on one thread.
    execute(_run_item, todo, on_result=on_result, crashed=_crashed,
            label=lambda it: f"{it['setting'].engine} {it['setting'].label} {it['case'].name}",
            is_error=lambda r: r.get("status") not in ("ok",), executor=executor,
            workers=workers, progress=progress, desc="tradeoff", unit="run")
    runs = []
    for k, it in keyed:
        r = dict(done[k])
        c = it["case"]        # its place in this split (the store keys the physics only)
        r.update(part=c.part, group=c.group, near_boundary=bool(c.near_boundary))
        r["_setting"] = it["setting"]
        r["_shown"] = it["setting"] in shown
        runs.append(r)
    _self_consistency(runs)
    frame = _runs_frame([r for r in runs if r["_shown"]])
    table = summarize(frame)
    return Tradeoff(scene=scene.name, cases=vset, runs=frame, table=table,
                    unavailable=unavailable, machine=machine_info())

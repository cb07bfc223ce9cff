"""The default campaign: what ``rockbench report`` (and ``make report``) runs.

:func:`run_campaign` runs every available backend against the analytic reference on the
paper's frames and writes one self-contained page, the tables as CSV and the figures as PNG.
Its parts (``docs/report.md`` describes the page and every table):

1. **Pulse cases** - the paper's symmetric and asymmetric frames, free-standing and hybrid
   (scenes :data:`SCENES`), under symmetric and antisymmetric Ricker pulses of both signs at the
   (A, W) points :data:`PULSE_POINTS`: one :func:`rockbench.compare.compare` per case (rotation
   histories, nrmse, peak error, eta, verdicts, cost).
2. **Free rocking** - every scene released from phi0 = :data:`FREE_PHI0_OVER_ALPHA` alpha: the
   effective eta of each engine per rocking direction against the analytic eta.
3. **Overturning map** - ``paper-asymmetric`` under positive symmetric pulses on the coarse
   grid :data:`MAP_A` x :data:`MAP_W`, every backend (via :func:`rockbench.sweep.run_cases`):
   where an engine's verdict differs from the analytic one.
4. **Speed against accuracy** - one pulse case per engine at the time steps :data:`DT_SWEEP`:
   nrmse and peak error against the real-time factor.
5. **Records** (only with ``records_dir``) - peak rotation per record for the free-standing and
   the hybrid (eps_f = 1 %) asymmetric frame, both polarities, as in the paper's Fig. 9 (via
   :func:`rockbench.sweep.run_cases`).

Everything finished is kept in a store (default ``out_dir/store``): the comparisons as small
pickles, the sweep cases in the sweep's Parquet store, both under a fingerprint of the physics
code (:func:`code_fingerprint`). A rerun, e.g. after Ctrl-C, reuses what finished; after a
change to a backend, the scene model or an engine version, everything runs again.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import pickle
import time
import uuid
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import ParameterError
from ..scene.records import find_records
from . import figures as F
from . import html as H

__all__ = [
    "CAMPAIGN_COLUMNS",
    "DT_SWEEP",
    "FREE_PHI0_OVER_ALPHA",
    "MAP_A",
    "MAP_W",
    "PULSE_POINTS",
    "PULSE_SHAPES",
    "RECORD_FRAMES",
    "SCENES",
    "campaign_plan",
    "code_fingerprint",
    "find_records",
    "run_campaign",
]

#: The paper's frames (built-in scenes).
SCENES = ("paper-symmetric", "paper-asymmetric", "paper-symmetric-hybrid",
          "paper-asymmetric-hybrid", "paper-asymmetric-hybrid-eps2",
          "paper-asymmetric-hybrid-eps1")
#: (A, W) points of the pulse cases: A = a_g / (g tan alpha), W = omega_g / p.
PULSE_POINTS = ((2.0, 3.0), (4.0, 4.0))
#: (shape, sign) of the pulse cases.
PULSE_SHAPES = (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1),
                ("antisymmetric", -1))
#: Free rocking after each pulse [s] (the pulse itself lasts 6 T_g).
PULSE_TAIL = 6.0
#: Overturning map grid (paper-asymmetric, positive symmetric pulse).
MAP_SCENE = "paper-asymmetric"
MAP_A = (1.5, 2.5, 3.5, 5.0, 7.0)
MAP_W = (1.5, 2.0, 3.0, 4.0, 6.0)
#: Time steps [s] of the speed-against-accuracy sweep, and its case.
DT_SWEEP = (2e-3, 1e-3, 5e-4, 2e-4)
DT_CASE = {"scene": "paper-asymmetric", "shape": "symmetric", "sign": 1, "A": 3.0, "W": 4.0}
#: Free rocking: initial rotation phi0 / alpha [-] and duration [s].
FREE_PHI0_OVER_ALPHA = 0.3
FREE_DURATION = 8.0
#: Frames of the record part (label -> scene), as in the paper's Fig. 9.
RECORD_FRAMES = {"free-standing": "paper-asymmetric",
                 "hybrid, eps_f = 1 %": "paper-asymmetric-hybrid-eps1"}

#: Columns of the campaign's CSV files (beyond the METRIC_COLUMNS / ETA_COLUMNS they repeat).
CAMPAIGN_COLUMNS: dict[str, dict[str, str]] = {
    "metrics.csv": {
        "part": "-, pulse | free (free rocking)",
        "case": "-, short label of the case",
        "scene": "-, built-in scene name",
        "shape": "-, symmetric | antisymmetric Ricker pulse (empty: free rocking)",
        "sign": "-, +1 | -1 sign of the pulse",
        "A": "-, a_g / (g tan alpha)",
        "W": "-, omega_g / p",
        "phi0": "rad, initial rotation",
        "(then)": "every column of rockbench.compare.METRIC_COLUMNS",
    },
    "eta.csv": {"scene": "-, scene (free rocking)", "phi0": "rad, initial rotation",
                "(then)": "every column of rockbench.compare.ETA_COLUMNS"},
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
        "verdicts_agree": "-, pulse cases and map points whose overturning verdict agrees",
        "verdicts_total": "-, pulse cases and map points compared",
        "energy_gained": "-, pulse cases with energy gained at an impact",
        "real_time_factor_median": "-, median real-time factor (stepping only)",
        "run_real_time_factor_median": "-, median real-time factor of the whole run (speed "
                                       "sweep)"},
    "speed_accuracy.csv": {
        "backend": "-", "dt": "s, time step", "output_dt": "s, output interval",
        "status": "-", "nrmse": "-", "peak_rel_error": "-", "max_abs_error_over_alpha": "-",
        "real_time_factor": "-, simulated s per wall s of stepping",
        "run_s": "s, whole run (model building and per-step work included)",
        "run_real_time_factor": "-, simulated s per wall s of the whole run",
        "sim_time": "s, simulated time",
        "ref_real_time_factor": "-, the analytic reference on the same case (integration only)",
        "ref_run_real_time_factor": "-, the analytic reference, whole run"},
    "overturning_map.csv": {
        "backend": "-", "scene": "-", "shape": "-", "sign": "-", "A": "-", "W": "-",
        "status": "-", "overturned": "-, bool", "overturned_ref": "-, analytic verdict",
        "verdict_agrees": "-, bool", "max_abs_phi_over_alpha": "-",
        "real_time_factor": "-"},
    "record_peaks.csv": {
        "record": "-, file stem", "frame": "-, free-standing | hybrid", "scene": "-",
        "polarity": "-, +1 as recorded, -1 reversed", "backend": "-", "status": "-",
        "max_abs_phi_over_alpha": "-", "overturned": "-, bool",
        "overturned_ref": "-, analytic verdict", "verdict_agrees": "-, bool",
        "peak_rel_error": "-, max|phi| / max|phi_ref| - 1 (both ok and not overturned)",
        "real_time_factor": "-"},
}


# ==========================================================================================
# The plan
# ==========================================================================================
def campaign_plan(quick: bool = False) -> dict[str, Any]:
    """The grid of the campaign: scenes, pulse points, map grid, dt sweep, free rocking.

    ``quick``: a few cases (two scenes, one pulse, a 2 x 2 map, two time steps, shorter
    runs) for tests and a first look; the full plan is the module's constants.
    """
    if quick:
        return {"scenes": ("paper-asymmetric", "paper-asymmetric-hybrid-eps1"),
                "pulse_points": ((3.0, 4.0),), "pulse_shapes": (("symmetric", 1),),
                "pulse_tail": 2.0, "map_A": (2.0, 5.0), "map_W": (3.0,),
                "map_duration_tail": 2.0, "dt_sweep": (1e-3, 5e-4),
                "dt_case": dict(DT_CASE, A=3.0, W=4.0), "dt_tail": 2.0,
                "free_phi0": FREE_PHI0_OVER_ALPHA, "free_duration": 3.0,
                "max_records": 1, "record_tail": 2.0}
    return {"scenes": SCENES, "pulse_points": PULSE_POINTS, "pulse_shapes": PULSE_SHAPES,
            "pulse_tail": PULSE_TAIL, "map_A": MAP_A, "map_W": MAP_W,
            "map_duration_tail": None, "dt_sweep": DT_SWEEP, "dt_case": dict(DT_CASE),
            "dt_tail": PULSE_TAIL, "free_phi0": FREE_PHI0_OVER_ALPHA,
            "free_duration": FREE_DURATION, "max_records": None, "record_tail": None}


def _pulse_duration(scene_name: str, A: float, W: float, shape: str, tail: float | None):
    """Duration [s] of a pulse run: the pulse window (6 T_g) plus ``tail`` s (None: the
    package default, pulse + 10 s)."""
    if tail is None:
        return None
    from ..scene import load_scene
    from ..scene.motion import RickerPulse

    sc = load_scene(scene_name)
    p = RickerPulse.dimensionless(A, W, sc.structure, shape, 1)
    return float(p.t_end - p.t_start + tail)


# ==========================================================================================
# Records
# ==========================================================================================
# ==========================================================================================
# Comparison jobs (histories needed): run in worker processes, cached as small pickles
# ==========================================================================================
@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """A short hash of what decides a run's physics: rockbench's source files (modules and
    scenarios, except the report, command-line and testing layers) and the versions of the
    installed engines. The campaign keeps its store under it, so that results computed by
    other code are never mixed into a page."""
    import rockbench

    from ..engines import engine_info

    root = Path(rockbench.__file__).resolve().parent
    h = hashlib.sha256()
    for f in sorted(root.rglob("*")):
        rel = f.relative_to(root).as_posix()
        if (not f.is_file() or f.suffix not in (".py", ".toml")
                or rel.split("/")[0] in ("report", "testing") or rel in ("cli.py",
                                                                       "__main__.py")):
            continue
        h.update(rel.encode())
        h.update(f.read_bytes())
    h.update(json.dumps(engine_info(), sort_keys=True, default=str).encode())
    return h.hexdigest()[:12]


def _job_key(job: Mapping[str, Any]) -> str:
    text = json.dumps(job, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _job_label(job: Mapping[str, Any]) -> str:
    if job["kind"] == "dt":
        return f"{job['engine']} dt={job['dt']:g} s"
    if job["kind"] == "free":
        return f"{job['scene']} free rocking"
    m = job["motion"]
    return (f"{job['scene']} {m['shape'][:4]}{'+' if m['sign'] == 1 else '-'} "
            f"A={m['A']:g} W={m['W']:g}")


def _motion_of(m: Mapping[str, Any] | None, structure):
    if m is None:
        return None
    from ..scene.motion import make_pulse

    return make_pulse(m["shape"], m["sign"], structure=structure, A=m["A"], W=m["W"])


def _run_job(job: dict[str, Any]) -> dict[str, Any]:
    """One comparison job (in a worker): returns a small, picklable payload."""
    from ..compare import compare, eta_rows, metrics
    from ..engines import get_backend
    from ..scene import load_scene

    scene = load_scene(job["scene"])
    motion = _motion_of(job.get("motion"), scene.structure)
    phi0 = float(job.get("phi0_over_alpha", 0.0)) * scene.alpha
    t0 = time.perf_counter()
    c0 = time.process_time()
    if job["kind"] == "dt":
        tr = time.perf_counter()
        ref = get_backend("analytic")(scene).run(motion, duration=job["duration"], phi0=phi0)
        ref_run_s = time.perf_counter() - tr
        eng = job["engine"]
        ts = time.perf_counter()
        try:
            res = get_backend(eng)(scene, None, dt=job["dt"],
                                   output_dt=max(job["dt"], 1e-3)).run(
                motion, duration=job["duration"], phi0=phi0)
        except Exception as e:  # bad settings for this engine: a row, not a crash
            return {"job": job, "error": f"{type(e).__name__}: {e}"}
        run_s = time.perf_counter() - ts
        row = metrics(res, ref)
        row.update(dt=job["dt"], output_dt=max(job["dt"], 1e-3), run_s=run_s,
                   sim_time=float(res.cost.sim_time),
                   run_real_time_factor=float(res.cost.sim_time) / run_s if run_s > 0
                   else math.inf,
                   ref_real_time_factor=float(ref.cost.real_time_factor),
                   ref_run_real_time_factor=float(ref.cost.sim_time) / ref_run_s
                   if ref_run_s > 0 else math.inf)
        return {"job": job, "row": row, "n_eta": len(eta_rows(res, ref)),
                "elapsed_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    c = compare(scene, motion, engines=job["engines"], phi0=phi0, duration=job["duration"])
    traces = {k: F.Trace.from_result(r, max_points=job.get("max_points", 2500)).to_dict()
              for k, r in c.results.items()}
    return {"job": job, "table": c.table, "eta": c.eta, "traces": traces,
            "alpha": float(scene.alpha), "motion": c.motion, "phi0": phi0,
            "settings": {k: dict(v) for k, v in c.settings.items()},
            "elapsed_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        return os.cpu_count() or 1


def _save(path: Path, payload: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".tmp-{path.name}-{uuid.uuid4().hex[:8]}")
    with open(tmp, "wb") as f:
        pickle.dump(payload, f, protocol=pickle.HIGHEST_PROTOCOL)
    os.replace(tmp, path)


def _load(path: Path) -> Any:
    try:
        with open(path, "rb") as f:
            return pickle.load(f)
    except Exception:  # unreadable: run it again
        return None


def _run_jobs(jobs: Sequence[dict[str, Any]], *, cache: Path | None, executor: str,
              dask_address: str | None, progress: bool, desc: str,
              workers: int | None = None) -> list[dict[str, Any]]:
    """Run the comparison jobs (cached ones are loaded), in input order. A finished job is
    written to ``cache`` at once (atomic rename), so an interruption loses nothing that
    finished."""
    out: dict[str, dict[str, Any]] = {}
    todo = []
    for job in jobs:
        key = _job_key(job)
        hit = _load(cache / f"{key}.pkl") if cache is not None else None
        if hit is not None and "error" not in hit:
            out[key] = hit
        elif key not in {k for k, _ in todo}:
            todo.append((key, job))
    bar = None
    if todo and progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(todo), desc=desc, unit="case", dynamic_ncols=True)

    def done(key: str, payload: dict[str, Any]) -> None:
        out[key] = payload
        if cache is not None and "error" not in payload:
            _save(cache / f"{key}.pkl", payload)
        if bar is not None:
            bar.set_postfix_str(_job_label(payload["job"]), refresh=False)
            bar.update(1)

    try:
        if not todo:
            pass
        elif executor == "serial" or len(todo) == 1:
            for key, job in todo:
                if bar is not None:
                    bar.set_postfix_str(_job_label(job), refresh=True)
                done(key, _run_job_safe(job))
        elif executor == "process":
            from concurrent.futures import ProcessPoolExecutor, as_completed
            # longest jobs first (hybrid frames and small time steps) for a balanced pool
            order = sorted(todo, key=lambda kj: -_job_weight(kj[1]))
            from concurrent.futures.process import BrokenProcessPool

            jobs_of = dict(order)
            broken: list[str] = []
            ex = ProcessPoolExecutor(max_workers=min(workers or _cpu_count(), len(order)))
            try:
                futs = {ex.submit(_run_job_safe, job): key for key, job in order}
                for f in as_completed(futs):
                    try:
                        payload = f.result()
                    except BrokenProcessPool:   # a worker died (engine crash): retry alone
                        broken.append(futs[f])
                        continue
                    done(futs[f], payload)
            finally:
                # on Ctrl-C: drop the queued jobs at once (finished ones are already stored)
                ex.shutdown(wait=False, cancel_futures=True)
            for key in broken:
                done(key, _isolated(jobs_of[key]))
        else:
            try:
                from distributed import Client, LocalCluster
                from distributed import as_completed as das_completed
            except ImportError:
                from ..errors import RockbenchError
                raise RockbenchError("executor='dask' needs dask.distributed: pip install "
                                     "'rockbench[dask]'") from None
            cluster = None
            if dask_address:
                client = Client(dask_address)
            else:
                cluster = LocalCluster(n_workers=workers or _cpu_count(), threads_per_worker=1,
                                       processes=True, dashboard_address=None)
                client = Client(cluster)
            try:
                futs = {client.submit(_run_job_safe, job, pure=False): key for key, job in todo}
                for f in das_completed(list(futs)):
                    done(futs[f], f.result())
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
    finally:
        if bar is not None:
            bar.close()
    return [out[_job_key(j)] for j in jobs if _job_key(j) in out]


def _isolated(job: dict[str, Any]) -> dict[str, Any]:
    """Run one job in a fresh one-worker pool; a dying worker gives an error payload."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    with ProcessPoolExecutor(max_workers=1) as ex:
        try:
            return ex.submit(_run_job_safe, job).result()
        except BrokenProcessPool as e:
            return {"job": job, "error": f"worker process died (engine crash or out of "
                                         f"memory?): {e}"}


def _run_job_safe(job: dict[str, Any]) -> dict[str, Any]:
    try:
        return _run_job(job)
    except Exception as e:  # a failing job is data, not a crash of the campaign
        return {"job": job, "error": f"{type(e).__name__}: {e}"}


def _job_weight(job: Mapping[str, Any]) -> float:
    w = 1.0
    if "hybrid" in job["scene"]:
        w *= 2.5
    if job["kind"] == "dt":
        w *= 1e-3 / job["dt"]
        w *= {"pybullet": 2.5}.get(job["engine"], 1.0)
    return w


# ==========================================================================================
# Sweep cases (summaries only): maps and records
# ==========================================================================================
def _sweep(cases: list[dict[str, Any]], *, store: Path | None, executor: str,
           dask_address: str | None, progress: bool, workers: int | None) -> pd.DataFrame:
    from ..sweep import run_cases

    if not cases:
        return pd.DataFrame()
    return run_cases(cases, store=store, executor=executor, dask_address=dask_address,
                     progress=progress, workers=workers)


def _have_pyarrow() -> bool:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True


def _bool(v: Any) -> bool | None:
    if v is None or v is pd.NA:
        return None
    if isinstance(v, float) and math.isnan(v):
        return None
    return bool(v)


def _with_verdicts(df: pd.DataFrame, keys: Sequence[str]) -> pd.DataFrame:
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


def _sweep_rows(df: pd.DataFrame) -> pd.DataFrame:
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
# Tables from the comparison payloads
# ==========================================================================================
def _case_columns(job: Mapping[str, Any], phi0: float) -> dict[str, Any]:
    m = job.get("motion")
    if job["kind"] == "free":
        return {"part": "free", "case": f"{job['scene']} free rocking", "scene": job["scene"],
                "shape": "", "sign": pd.NA, "A": math.nan, "W": math.nan, "phi0": phi0}
    label = (f"{job['scene']} {m['shape'][:4]}{'+' if m['sign'] == 1 else '-'} "
             f"A={m['A']:g} W={m['W']:g}")
    return {"part": "pulse", "case": label, "scene": job["scene"], "shape": m["shape"],
            "sign": int(m["sign"]), "A": float(m["A"]), "W": float(m["W"]), "phi0": phi0}


def _metrics_table(payloads: Iterable[dict[str, Any]]) -> pd.DataFrame:
    frames = []
    for p in payloads:
        if "table" not in p:
            continue
        cols = _case_columns(p["job"], p["phi0"])
        t = p["table"].copy()
        for k, v in reversed(list(cols.items())):
            t.insert(0, k, v)
        frames.append(t)
    if not frames:
        return pd.DataFrame()
    df = pd.concat(frames, ignore_index=True)
    df["sign"] = pd.array([None if pd.isna(v) else int(v) for v in df["sign"]], dtype="Int64")
    return df


def _eta_tables(payloads: Iterable[dict[str, Any]]) -> tuple[pd.DataFrame, pd.DataFrame]:
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


def _engine_summary(metrics: pd.DataFrame, eta_summary: pd.DataFrame, speed: pd.DataFrame,
                    omap: pd.DataFrame) -> pd.DataFrame:
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
        if len(omap):
            m = omap[(omap["backend"] == b)]["verdict_agrees"].dropna().astype(bool)
            n_agree += int(m.sum())
            n_total += len(m)
        sp = speed[speed["backend"] == b] if len(speed) else speed
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
            "real_time_factor_median": float(ok["real_time_factor"].astype(float).median())
            if len(ok) else math.nan,
            "run_real_time_factor_median": float(sp["run_real_time_factor"].astype(float)
                                                 .median()) if len(sp) and
            "run_real_time_factor" in sp else math.nan,
        })
    return pd.DataFrame(rows)


# ==========================================================================================
# The conclusion
# ==========================================================================================
def _pct(x: float) -> str:
    """A percentage with 2 decimals, "n/a" when missing."""
    return "n/a" if x is None or pd.isna(x) else f"{100.0 * x:.2f} %"


def _is_hybrid(scene_name: str) -> bool:
    """Whether a scene has devices (tendons, dampers)."""
    try:
        from ..scene import load_scene
        return load_scene(scene_name).devices is not None
    except Exception:  # not loadable here: judge by the name
        return "hybrid" in str(scene_name)


def _groups(df: pd.DataFrame) -> list[tuple[str, pd.DataFrame]]:
    """(label, rows) for the free-standing and the hybrid scenes of ``df`` (column scene)."""
    if not len(df):
        return []
    hyb = df["scene"].map({s: _is_hybrid(s) for s in df["scene"].unique()}).astype(bool)
    out = [("free-standing frames", df[~hyb]), ("hybrid frames", df[hyb])]
    return [(k, v) for k, v in out if len(v)]


def campaign_conclusion(engines: pd.DataFrame, metrics: pd.DataFrame, eta_summary: pd.DataFrame,
                        speed: pd.DataFrame, omap: pd.DataFrame,
                        records: pd.DataFrame) -> list[str]:
    """Plain-language findings computed from the campaign's tables (numbers: nrmse and
    real-time factors ``.3g``, relative errors in percent with 2 decimals)."""
    lines: list[str] = []
    eng = engines[engines["backend"] != "analytic"] if len(engines) else engines
    ranked = eng[eng["n_ok"] > 0].sort_values("nrmse_median") if len(eng) else eng
    pulses = metrics[(metrics["part"] == "pulse") & (metrics["backend"] != "analytic")] \
        if len(metrics) else metrics
    order = list(ranked["backend"]) if len(ranked) else []
    if not len(eng):
        lines.append("Only the analytic reference ran: there is no engine to compare.")
    elif not len(ranked):
        lines.append("No engine finished a pulse case cleanly: nothing to compare with the "
                     "analytic model.")
    else:
        b = ranked.iloc[0]
        lines.append(
            f"Closest to the analytic model: {b['backend']}, median nrmse "
            f"{b['nrmse_median']:.3g} over {int(b['n_ok'])} pulse cases (largest "
            f"{b['nrmse_max']:.3g}), median peak rotation error "
            f"{_pct(b['peak_rel_error_median'])} (largest {_pct(b['peak_rel_error_max'])}).")
        for _, r in ranked.iloc[1:].iterrows():
            ratio = r["nrmse_median"] / b["nrmse_median"] if b["nrmse_median"] > 0 \
                else math.inf
            lines.append(
                f"{r['backend']}: median nrmse {r['nrmse_median']:.3g} ({ratio:.3g} times "
                f"that of {b['backend']}), median peak rotation error "
                f"{_pct(r['peak_rel_error_median'])} (largest "
                f"{_pct(r['peak_rel_error_max'])}).")
        ok = pulses[pulses["status"] == "ok"]
        for label, g in _groups(ok):
            parts = []
            for name in order:
                s = g[g["backend"] == name]
                if len(s):
                    parts.append(f"{name} {s['nrmse'].median():.3g} / "
                                 f"{_pct(s['peak_rel_error'].abs().median())}")
            if parts:
                lines.append(f"Pulse cases on {label}, median nrmse / median |peak error|: "
                             + ", ".join(parts) + ".")
    if len(eng):
        f = eng.loc[eng["real_time_factor_median"].astype(float).fillna(-1).idxmax()]
        sent = (f"Fastest engine: {f['backend']}, median real-time factor "
                f"{f['real_time_factor_median']:.3g} counting the engine's stepping only")
        if pd.notna(f.get("run_real_time_factor_median")):
            sent += (f" ({f['run_real_time_factor_median']:.3g} for the whole run in the speed "
                     f"sweep, rockbench's per-step work included)")
        ref = engines[engines["backend"] == "analytic"]
        if len(ref):
            sent += (f"; the analytic reference: "
                     f"{ref.iloc[0]['real_time_factor_median']:.3g}")
        lines.append(sent + ".")
    if len(eta_summary):
        es = eta_summary[eta_summary["backend"] != "analytic"].dropna(subset=["rel_error"])
        for b, g in es.groupby("backend", sort=False):
            worst = g.loc[g["rel_error"].abs().idxmax()]
            per = "; ".join(f"{label} {_pct(x['rel_error'].abs().mean())}"
                            for label, x in _groups(g))
            lines.append(
                f"Free rocking: the effective eta of {b} is off the analytic eta by "
                f"{_pct(g['rel_error'].abs().mean())} on average over scenes and directions "
                f"({per}); worst {worst['scene']} "
                f"({'counterclockwise' if worst['direction'] == 1 else 'clockwise'}): "
                f"{worst['eta_mean']:.4f} against {worst['eta_ref']:.4f} "
                f"({100 * worst['rel_error']:+.2f} %).")
    if len(omap):
        n_pts = int((omap["backend"] == "analytic").sum())
        for b in [x for x in F._order(omap["backend"]) if x != "analytic"]:
            s = omap[omap["backend"] == b]
            dis = s[s["verdict_agrees"].fillna(True).astype(bool) == False]
            nok = s[s["status"] != "ok"]
            if len(dis):
                pts = ", ".join(f"(A={a:g}, W={w:g}: {'overturns' if bool(o) else 'survives'})"
                                for a, w, o in zip(dis["A"], dis["W"], dis["overturned"]))
                lines.append(f"Overturning map ({MAP_SCENE}, {n_pts} points): {b} disagrees "
                             f"with the analytic verdict at {len(dis)} point"
                             f"{'s' if len(dis) > 1 else ''}: {pts}.")
            else:
                lines.append(f"Overturning map ({MAP_SCENE}, {n_pts} points): {b} agrees with "
                             f"every analytic verdict"
                             + (f" it could give ({len(nok)} run{'s' if len(nok) > 1 else ''} "
                                f"not ok)." if len(nok) else "."))
    if len(metrics):
        dis = pulses[pulses["verdict_agrees"].fillna(True).astype(bool) == False]
        for _, r in dis.iterrows():
            what = "overturns" if bool(r["overturned"]) else "survives"
            lines.append(f"{r['backend']} {what} under {r['case']}, unlike the analytic "
                         f"model.")
        bad = metrics[~metrics["status"].isin(["ok", "unavailable"])]
        for case, g in bad.groupby("case", sort=False):
            refrow = metrics[(metrics["case"] == case) & (metrics["backend"] == "analytic")]
            verdict = ""
            if len(refrow) and pd.notna(refrow.iloc[0]["overturned"]):
                verdict = (" (the analytic model overturns there)"
                           if bool(refrow.iloc[0]["overturned"]) else
                           " (the analytic model survives there)")
            who = ", ".join(f"{r['backend']} ({r['status']}: {r['reason'] or 'no reason'})"
                            for _, r in g.iterrows())
            lines.append(f"{case}: not finished cleanly by {who}{verdict}.")
        if not len(bad):
            lines.append("No pulse or free-rocking run diverged.")
        flags = pulses[pulses["status"] == "ok"]
        if len(flags) and not flags["energy_gained_at_impact"].fillna(False).astype(bool).any():
            lines.append("No engine gained energy at an impact in any pulse case.")
            order_flags: list[str] = []
        else:
            order_flags = order
        for b in order_flags:
            parts = []
            for label, g in _groups(flags[flags["backend"] == b]):
                n = int(g["energy_gained_at_impact"].fillna(False).astype(bool).sum())
                parts.append(f"{n} of {len(g)} on {label}")
            if parts:
                lines.append(f"Energy gained at an impact (an effective eta >= 1, or kinetic "
                             f"energy that grows across an impact), {b}: " + ", ".join(parts)
                             + " (pulse cases).")
    if len(speed):
        for b in [x for x in F._order(speed["backend"]) if x != "analytic"]:
            s = speed[(speed["backend"] == b)].sort_values("dt")
            okk = s[s["status"] == "ok"]
            if len(okk) >= 2:
                lo, hi = okk.iloc[0], okk.iloc[-1]
                best = okk.loc[okk["nrmse"].astype(float).idxmin()]
                lines.append(f"Time step ({b}): dt = {hi['dt']:g} s gives nrmse "
                             f"{hi['nrmse']:.3g} at a real-time factor of "
                             f"{hi['real_time_factor']:.3g}; dt = {lo['dt']:g} s gives "
                             f"{lo['nrmse']:.3g} at {lo['real_time_factor']:.3g}; the smallest "
                             f"nrmse, {best['nrmse']:.3g}, at dt = {best['dt']:g} s.")
            for _, r in s[s["status"] == "error"].iterrows():
                lines.append(f"{b} at dt = {r['dt']:g} s was not run: {r.get('reason') or ''}.")
            for _, r in s[~s["status"].isin(["ok", "error"])].iterrows():
                lines.append(f"{b} at dt = {r['dt']:g} s did not finish cleanly "
                             f"({r['status']}): {r.get('reason') or ''}.")
    if len(records):
        ref = records[records["backend"] == "analytic"]
        for frame, g in ref.groupby("frame", sort=False):
            ot = g["overturned"].fillna(False).astype(bool)
            rest = g.loc[~ot, "max_abs_phi_over_alpha"]
            lines.append(f"Records, {frame} frame: the analytic model overturns in "
                         f"{int(ot.sum())} of {len(g)} record runs (both polarities)"
                         + (f"; largest peak max |phi| / alpha of the others "
                            f"{rest.max():.3g}." if len(rest) else "."))
        for b in [x for x in F._order(records["backend"]) if x != "analytic"]:
            s = records[records["backend"] == b]
            v = s["verdict_agrees"].dropna().astype(bool)
            pk = s["peak_rel_error"].astype(float).abs().dropna()
            nok = int((s["status"] != "ok").sum())
            lines.append(f"Records, {b}: {int(v.sum())} of {len(v)} verdicts agree with the "
                         f"analytic model; median |peak error| "
                         f"{_pct(pk.median()) if len(pk) else 'n/a'}"
                         + (f"; {nok} run{'s' if nok > 1 else ''} not ok." if nok else "."))
    return lines


# ==========================================================================================
# run_campaign
# ==========================================================================================
def _check_args(engines, executor) -> list[str]:
    from ..engines import REGISTRY, available_backends

    if executor not in ("process", "serial", "dask"):
        raise ParameterError("executor", executor, "one of 'process', 'serial', 'dask'")
    avail = available_backends()
    if engines is None:
        names = avail
    else:
        if isinstance(engines, str):
            engines = [engines]
        names = list(dict.fromkeys(engines))
        for n in names:
            if n not in REGISTRY:
                raise ParameterError("engines", n, f"registered backend names: "
                                                   f"{', '.join(REGISTRY)}")
    return ["analytic"] + [n for n in names if n != "analytic"]


def run_campaign(out_dir: str | os.PathLike = "reports", *, engines: Sequence[str] | None = None,
                 records_dir: str | os.PathLike | None = None, quick: bool = False,
                 progress: bool = True, store: str | os.PathLike | None = None,
                 executor: str = "process", dask_address: str | None = None,
                 workers: int | None = None) -> Path:
    """Run the default campaign (module docstring) and write its report; return the path of
    ``out_dir/index.html``.

    Parameters
    ----------
    out_dir : folder written: ``index.html``, the CSV tables (``docs/report.md``), the figures
        as PNG under ``figures/``.
    engines : backend names (default: every available backend; the analytic reference always
        runs). Unavailable ones are listed on the page and skipped.
    records_dir : a folder of records (``.AT2`` files, or headerless files listed in a
        ``records.csv`` with their dt): adds the peak rotation per record (paper Fig. 9).
    quick : a few cases only (tests, a first look; well under a minute).
    progress : tqdm progress bars naming what runs.
    store : folder of the resumable store (default ``out_dir/store``); finished cases are
        reused on a rerun.
    executor : "process" (local process pool, one worker per core), "serial", or "dask"
        (``dask_address``: a running scheduler; none: a local cluster).
    workers : worker processes (default: one per available core).
    """
    from ..engines import available_backends, engine_info

    t_start = time.perf_counter()
    names = _check_args(engines, executor)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ParameterError("workers", workers, "an integer >= 1 or None")
    if dask_address is not None and executor != "dask":
        raise ParameterError("dask_address", dask_address, "given only with executor='dask'")
    if records_dir is not None:
        find_records(records_dir)          # a bad folder fails now, not after the pulses
    avail = set(available_backends())
    missing = [n for n in names if n not in avail]
    names = [n for n in names if n in avail]
    plan = campaign_plan(quick)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    store_dir = Path(store) if store is not None else out / "store"
    fingerprint = code_fingerprint()
    cache = store_dir / fingerprint / "comparisons"
    notes: list[str] = []
    sweep_store = store_dir / fingerprint / "cases" if _have_pyarrow() else None
    if sweep_store is None:
        notes.append("pyarrow is not installed: the sweep cases (map, records) are not kept "
                     "between runs (pip install 'rockbench[parquet]').")
    run = dict(executor=executor, dask_address=dask_address, progress=progress,
               workers=workers)
    jobrun = dict(executor=executor, dask_address=dask_address, workers=workers)
    timings: dict[str, float] = {}

    # 1 + 2: comparisons (pulse cases, free rocking) ------------------------------------
    t = time.perf_counter()
    jobs = []
    for scene in plan["scenes"]:
        for (A, W) in plan["pulse_points"]:
            for shape, sign in plan["pulse_shapes"]:
                jobs.append({"kind": "pulse", "scene": scene, "engines": names,
                             "motion": {"shape": shape, "sign": int(sign), "A": float(A),
                                        "W": float(W)},
                             "duration": _pulse_duration(scene, A, W, shape, plan["pulse_tail"])})
    for scene in plan["scenes"]:
        jobs.append({"kind": "free", "scene": scene, "engines": names, "motion": None,
                     "phi0_over_alpha": plan["free_phi0"], "duration": plan["free_duration"]})
    payloads = _run_jobs(jobs, cache=cache, progress=progress, desc="comparisons", **jobrun)
    timings["comparisons"] = time.perf_counter() - t
    failed = [p for p in payloads if "error" in p]
    for p in failed:
        notes.append(f"{_job_label(p['job'])} failed: {p['error']}")
    payloads = [p for p in payloads if "error" not in p]

    # 4: speed against accuracy ------------------------------------------------------------
    t = time.perf_counter()
    dc = plan["dt_case"]
    dur = _pulse_duration(dc["scene"], dc["A"], dc["W"], dc["shape"], plan["dt_tail"])
    dt_jobs = [{"kind": "dt", "scene": dc["scene"], "engine": e, "dt": float(dt),
                "motion": {k: dc[k] for k in ("shape", "sign", "A", "W")}, "duration": dur}
               for e in names if e != "analytic" for dt in plan["dt_sweep"]]
    dt_payloads = _run_jobs(dt_jobs, cache=cache, progress=progress, desc="time steps",
                            **jobrun)
    speed_rows = []
    for p in dt_payloads:
        if "error" in p:
            speed_rows.append({"backend": p["job"]["engine"], "dt": p["job"]["dt"],
                               "status": "error", "reason": p["error"]})
        else:
            speed_rows.append(p["row"])
    speed_cols = ["backend", "dt", "output_dt", "status", "reason", "nrmse", "peak_rel_error",
                  "max_abs_error_over_alpha", "n_impacts", "n_impacts_ref", "eta_max_rel_error",
                  "verdict_agrees", "real_time_factor", "wall_s", "steps", "run_s",
                  "run_real_time_factor", "sim_time", "engine_version",
                  "ref_real_time_factor", "ref_run_real_time_factor"]
    speed = pd.DataFrame(speed_rows)
    for c in speed_cols:
        if c not in speed:
            speed[c] = math.nan
    speed = speed[speed_cols]
    timings["speed"] = time.perf_counter() - t

    # 3: overturning map -----------------------------------------------------------------
    t = time.perf_counter()
    from ..sweep import pulse_grid

    tail = plan["map_duration_tail"]
    map_cases = []
    for A in plan["map_A"]:
        for W in plan["map_W"]:
            d = _pulse_duration(MAP_SCENE, A, W, "symmetric", tail)
            map_cases += pulse_grid(MAP_SCENE, "symmetric", 1, [A], [W], names, duration=d)
    omap = _sweep_rows(_sweep(map_cases, store=sweep_store, **run))
    if len(omap):
        omap = _with_verdicts(omap, ("A", "W"))
    timings["map"] = time.perf_counter() - t

    # 5: records ----------------------------------------------------------------------------
    t = time.perf_counter()
    records = pd.DataFrame()
    if records_dir is not None:
        recs, rnotes = find_records(records_dir)
        notes.extend(rnotes)
        if plan["max_records"]:
            recs = recs[: plan["max_records"]]
        rec_cases = []
        for rec in recs:
            rec_duration = None
            if plan["record_tail"] is not None:
                from ..scene.records import load_record
                r = load_record(rec["path"], dt=rec["dt"], units=rec["units"])
                rec_duration = float(r.t_end - r.t_start + plan["record_tail"])
            for frame, scene in RECORD_FRAMES.items():
                for pol in (1.0, -1.0):
                    m = {"kind": "record", "path": rec["path"], "scale": pol}
                    if rec["dt"] is not None:
                        m.update(dt=rec["dt"], units=rec["units"])
                    for e in names:
                        rec_cases.append({"scene": scene, "engine": e, "motion": m,
                                          "duration": rec_duration})
        rows = _sweep_rows(_sweep(rec_cases, store=sweep_store, **run))
        if len(rows):
            byscene = {v: k for k, v in RECORD_FRAMES.items()}
            rows["record"] = [Path(p).stem for p in rows["path"]]
            rows["frame"] = [byscene.get(s, s) for s in rows["scene"]]
            rows["polarity"] = [int(round(float(v))) for v in rows["polarity"]]
            rows = _with_verdicts(rows, ("record", "frame", "polarity"))
            first = ["record", "frame", "scene", "polarity", "backend"]
            records = rows[first + [c for c in rows.columns if c not in first + ["path"]]]
        if not recs:
            notes.append(f"no record files found under {records_dir}")
    timings["records"] = time.perf_counter() - t

    # tables -----------------------------------------------------------------------------
    t = time.perf_counter()
    metrics = _metrics_table(payloads)
    eta, eta_summary = _eta_tables(payloads)
    engines_tab = _engine_summary(metrics, eta_summary, speed, omap)
    files = {"metrics.csv": metrics, "eta.csv": eta, "eta_summary.csv": eta_summary,
             "engines.csv": engines_tab, "speed_accuracy.csv": speed,
             "overturning_map.csv": omap}
    if len(records):
        files["record_peaks.csv"] = records
    for name, df in files.items():
        df.to_csv(out / name, index=False)
    lines = campaign_conclusion(engines_tab, metrics, eta_summary, speed, omap, records)

    # page -------------------------------------------------------------------------------
    figdir = out / "figures"
    sections = _page_sections(plan, names, missing, payloads, metrics, eta, eta_summary,
                              engines_tab, speed, omap, records, lines, notes, figdir,
                              quick=quick, records_dir=records_dir, store_dir=store_dir,
                              engine_rows=engine_info(), files=list(files))
    timings["report"] = time.perf_counter() - t
    total = time.perf_counter() - t_start
    cpu = sum(float(p.get("cpu_s", 0.0)) for p in payloads + dt_payloads)
    sections.append(("runtime-section", "Run time",
                     _runtime_html(timings, total, workers or _cpu_count(), cpu)))
    page = H.render_page("rockbench: physics engines against the analytic rocking model",
                         sections, subtitle="The paper's rocking frames, free-standing and "
                         "hybrid, under Ricker pulses" + (" and records" if len(records) else "")
                         + ": how far each engine stands from the analytic model, and at what "
                         "cost." + (" (quick campaign)" if quick else ""))
    path = out / "index.html"
    path.write_text(page, encoding="utf-8")
    return path


def _runtime_html(timings: Mapping[str, float], total: float, workers: int,
                  cpu_s: float) -> str:
    items = [(f"{k} [s]", f"{v:.1f}") for k, v in timings.items()]
    items.append(("total [s]", f"{total:.1f}"))
    items.append(("workers", str(workers)))
    items.append(("CPU time of the comparisons [s]", f"{cpu_s:.1f}"))
    return (H._dl(items) + "<p>Wall-clock seconds of this run of the campaign (cases reused "
            "from the store cost nothing here); CPU time summed over the comparison and "
            "time-step cases, reused ones included.</p>")


# ==========================================================================================
# The page
# ==========================================================================================
def _page_sections(plan, names, missing, payloads, metrics, eta, eta_summary, engines_tab,
                   speed, omap, records, lines, notes, figdir, *, quick, records_dir,
                   store_dir, engine_rows, files) -> list[tuple[str, str, str]]:
    from ..compare import METRIC_COLUMNS

    units = {**METRIC_COLUMNS, **H.DERIVED_COLUMNS}
    for tab in CAMPAIGN_COLUMNS.values():
        for k, v in tab.items():
            units.setdefault(k, v)
    sections: list[tuple[str, str, str]] = []

    # conclusion
    conc = H.conclusion_html(lines)
    if notes:
        conc += "<h3>Notes</h3><ul>" + "".join(f"<li>{H.escape(n)}</li>" for n in notes) + \
            "</ul>"
    sections.append(("conclusion-section", "Conclusion", conc))

    # engine summary
    eng_cols = list(CAMPAIGN_COLUMNS["engines.csv"])
    grade_as = {"nrmse_median": "nrmse", "nrmse_max": "nrmse",
                "peak_rel_error_median": "peak_rel_error", "peak_rel_error_max": "peak_rel_error",
                "eta_mean_rel_error": "eta_mean_rel_error"}
    summ = H.grade_legend() + H.html_table(engines_tab, eng_cols, units=units, grade_as=grade_as,
                                           table_id="engines")
    if len(engines_tab):
        summ += H.figure_html(
            F.plot_summary_table(engines_tab, [c for c in eng_cols if c != "engine_version"],
                                 grade_as=grade_as,
                                 title="Every engine against the analytic model"),
            "The summary table as a figure (same colours): medians and extremes over the "
            "pulse cases, free-rocking eta error, verdict agreement (pulse cases + overturning "
            "map), real-time factors.", name="summary_table", png_dir=figdir)
    sections.append(("summary-section", "Summary per engine", summ))

    # histories
    hist = []
    pulses = [p for p in payloads if p["job"]["kind"] == "pulse"]
    for scene in plan["scenes"]:
        ps = [p for p in pulses if p["job"]["scene"] == scene]
        if not ps:
            continue
        panels = [(_job_label(p["job"]).replace(scene + " ", ""),
                   {k: F.as_trace(v) for k, v in p["traces"].items()}) for p in ps]
        fig = F.plot_history_grid(panels, alpha=ps[0]["alpha"], ncols=min(4, len(panels)),
                                  title=f"{scene}: rotation histories under Ricker pulses")
        hist.append(H.figure_html(
            fig, f"{scene}: phi / alpha [-] against t [s] for every pulse case (analytic "
                 f"reference bold black; impacts marked), alpha = {ps[0]['alpha']:.4f} rad. "
                 f"Panel titles: pulse shape and sign, A = a_g / (g tan alpha), W = omega_g / p.",
            name=f"histories_{scene}", png_dir=figdir))
    sections.append(("histories-section", "Rotation histories", "\n".join(hist) or
                     "<p>No pulse case finished.</p>"))

    # pulse table
    shown = H.with_derived(metrics) if len(metrics) else metrics
    cols = ["case", "backend", "status", "max_abs_phi_over_alpha", "peak_rel_error", "nrmse",
            "max_abs_error_over_alpha", "t_first_impact_error", "n_impacts", "n_impacts_ref",
            "eta_mean_rel_error", "overturned", "overturned_ref", "verdict_agrees",
            "energy_gained_at_impact", "max_penetration", "max_sliding", "real_time_factor"]
    tab = H.html_table(shown[shown["part"] == "pulse"] if len(shown) else shown, cols,
                       units=units, table_id="cases", scroll=True)
    sections.append(("cases-section", "Every pulse case", H.grade_legend() + tab +
                     '<p>All columns: <a href="metrics.csv">metrics.csv</a>.</p>'))

    # eta
    etah = []
    if len(eta_summary):
        etah.append(H.figure_html(
            F.plot_eta_summary(eta_summary, title="Free rocking: effective eta against the "
                                                  "analytic eta"),
            f"Free rocking from phi0 = {plan['free_phi0']:g} alpha for "
            f"{plan['free_duration']:g} s: each engine's mean effective coefficient of "
            f"restitution relative to the analytic eta, 100 (eta_mean / eta_ref - 1) [%], "
            f"error bars one standard deviation over the impacts, per rocking direction after "
            f"the impact. Free-standing frames: the engines measure eta from the energy of "
            f"successive rocking peaks. Hybrid frames: from the angular velocities fitted just "
            f"before and after each impact (docs/metrics.md), which the tendon and damper "
            f"forces bend, so part of a hybrid frame's deviation may be the measurement's.",
            name="eta_free_rocking", png_dir=figdir))
        etah.append(H.html_table(eta_summary, list(CAMPAIGN_COLUMNS["eta_summary.csv"]),
                                 units=units, grade_as={"rel_error": "eta_mean_rel_error"},
                                 scroll=True))
    first = next((p for p in payloads if p["job"]["kind"] == "free"), None)
    if first is not None and len(first["eta"]):
        etah.append(H.figure_html(
            F.plot_eta(first["eta"], title=f"{first['job']['scene']}, free rocking: eta per "
                                           f"impact"),
            "eta [-] of every impact of one free-rocking run (engines: measured from their "
            "motion; analytic dashed), per direction; right: mean +- standard deviation.",
            name="eta_per_impact", png_dir=figdir))
    sections.append(("eta-section", "Coefficient of restitution", "\n".join(etah) or
                     "<p>No free-rocking run finished.</p>"))

    # speed
    sp = []
    if len(speed):
        okk = speed[speed["status"] == "ok"]
        rows = okk
        ref = okk[["ref_real_time_factor", "ref_run_real_time_factor"]].astype(float).median()
        if len(okk) and ref.notna().all():
            rows = pd.concat([okk, pd.DataFrame([{
                "backend": "analytic", "dt": math.nan,
                "real_time_factor": float(ref["ref_real_time_factor"]),
                "run_real_time_factor": float(ref["ref_run_real_time_factor"])}])],
                ignore_index=True)
        dc = plan["dt_case"]
        sp.append(H.figure_html(
            F.plot_speed_accuracy(rows, error="nrmse",
                                  speeds=("real_time_factor", "run_real_time_factor"),
                                  title=f"Speed against accuracy: {dc['scene']}, {dc['shape']} "
                                        f"pulse {dc['sign']:+d}, A = {dc['A']:g}, "
                                        f"W = {dc['W']:g}"),
            "nrmse [-] against the real-time factor [-] for each engine at the time steps "
            f"{', '.join(f'{d:g}' for d in plan['dt_sweep'])} s. Left: engine stepping only "
            "(the Cost of the Result); right: the whole run, including model building and "
            "rockbench's per-step work (ground motion, device forces, sampling, contact "
            "diagnostics). Dotted line: the analytic reference on the same case (median "
            "over its runs in the sweep).", name="speed_accuracy", png_dir=figdir))
        sp.append(H.html_table(speed, list(CAMPAIGN_COLUMNS["speed_accuracy.csv"]),
                               units=units, scroll=True))
    sections.append(("speed-section", "Speed against accuracy", "\n".join(sp) or
                     "<p>No engine besides the analytic reference.</p>"))

    # map
    mp = []
    if len(omap):
        mp.append(H.figure_html(
            F.plot_overturn_maps(omap, title=f"Overturning map: {MAP_SCENE}, positive "
                                             f"symmetric Ricker pulses"),
            "Overturning verdicts on the (W, A) plane, W = omega_g / p [-], "
            "A = a_g / (g tan alpha) [-]: filled squares overturn, open circles survive; a "
            "black ring marks an engine verdict that differs from the analytic one.",
            name="overturning_map", png_dir=figdir))
        mp.append("<details><summary>map points (table)</summary>" + H.html_table(
            omap, list(CAMPAIGN_COLUMNS["overturning_map.csv"]), units=units, scroll=True)
            + "</details>")
    sections.append(("map-section", "Overturning map", "\n".join(mp) or "<p>No map.</p>"))

    # records
    if len(records):
        sections.append(("records-section", "Records (paper Fig. 9)", H.figure_html(
            F.plot_record_peaks(records, title="Peak rotation per record"),
            "Peak rotation max |phi| / alpha [-] of the free-standing and the hybrid "
            "(eps_f = 1 %) asymmetric frame under each record, as recorded (filled) and "
            "reversed (open); triangles at the top: overturned.", name="record_peaks",
            png_dir=figdir) + "<details><summary>record runs (table)</summary>" + H.html_table(
                records, list(CAMPAIGN_COLUMNS["record_peaks.csv"]), units=units,
                scroll=True) + "</details>"))

    # settings
    items = [("engines", ", ".join(names)),
             ("engines not available", ", ".join(missing) or "none"),
             ("scenes", ", ".join(plan["scenes"])),
             ("pulse (A, W) points", ", ".join(f"({a:g}, {w:g})"
                                               for a, w in plan["pulse_points"])),
             ("pulse shapes", ", ".join(f"{s} {g:+d}" for s, g in plan["pulse_shapes"])),
             ("pulse run length", f"pulse window (6 T_g) + {plan['pulse_tail']:g} s"),
             ("free rocking", f"phi0 = {plan['free_phi0']:g} alpha, "
                              f"{plan['free_duration']:g} s"),
             ("overturning map", f"{MAP_SCENE}, symmetric +1, A in "
                                 f"{list(plan['map_A'])}, W in {list(plan['map_W'])}"),
             ("time steps [s]", ", ".join(f"{d:g}" for d in plan["dt_sweep"])),
             ("records folder", str(records_dir) if records_dir else "none"),
             ("quick", str(bool(quick))), ("store", str(store_dir)),
             ("code fingerprint", code_fingerprint())]
    default_settings = {}
    for p in payloads:
        for k, v in p.get("settings", {}).items():
            default_settings.setdefault(k, v)
    sett = (H._dl(items) + "<h3>Backend settings (defaults, all cases but the time-step sweep)"
            "</h3>" + H._dl((f"settings {k}", v) for k, v in default_settings.items())
            + "<h3>Versions</h3>" + H.versions_html())
    sections.append(("settings-section", "Settings and versions", sett))
    links = ", ".join(f'<a href="{f}">{f}</a>' for f in files)
    sections.append(("files-section", "Tables", f"<p>{links}. Columns and units: "
                     f"docs/report.md.</p>"))
    return sections

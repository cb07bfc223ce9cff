"""Many runs: grids of cases, parallel execution and a resumable result store.

A *case* is a plain dict (picklable, JSON-able, so it travels to worker processes and Dask
workers and can be hashed)::

    {"scene": "paper-asymmetric",          # built-in name or path to a .toml file
     "overrides": {"span": 9.0},           # scene overrides (load_scene), optional
     "engine": "pymunk",                   # backend name (default "analytic")
     "settings": {"dt": 2e-4},             # backend setting overrides, optional
     "motion": {"kind": "ricker", "shape": "symmetric", "sign": 1, "A": 3.0, "W": 4.0},
               # or {"kind": "ricker", ..., "amplitude": a_g [m/s^2], "period": T_g [s]}
               # or {"kind": "record", "path": ..., "dt": ..., "units": ..., "scale": ...}
               # or None (free rocking from phi0)
     "phi0": 0.0,                          # rad
     "duration": None}                     # s (None: the motion's length + 10 s)

:func:`run_cases` runs a list of cases and returns one row per case (the case's keys flattened,
the Result's summary and cost). With ``store=DIR`` every finished case is written at once to
``DIR`` as one small Parquet file named by the case's hash (written to a temporary name, then
renamed: a file in the store is always complete); a rerun loads the store and runs only the
cases not in it, so an interrupted sweep (crash, Ctrl-C, lost node) loses nothing that
finished. At the end of a sweep the small files are merged into one ``compact-*.parquet``.
A case that raises is recorded with status ``"error"`` and the message; it never stops the
sweep. Why Parquet parts and not one appended CSV: cases of one sweep may have different keys
(overrides, record vs pulse), which a fixed CSV header cannot hold; a killed process can leave a
half-written CSV line, while an atomic rename cannot leave a half-written part; and types (bool,
int, None) survive.

Executors: ``"process"`` (default: a local process pool, ``workers`` = ``os.cpu_count()``),
``"serial"`` (in this process) and ``"dask"`` (``dask.distributed``: a ``Client`` to
``dask_address``, or a ``LocalCluster``; ``pip install 'rockbench[dask]'``).

:func:`pulse_grid` builds the cases of a Ricker-pulse map, :func:`overturn_map` pivots a sweep
frame into an A x W table for overturning maps (paper Figs. 4-8).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import time
import uuid
from collections import deque
from itertools import product
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from .errors import ParameterError, RockbenchError

__all__ = ["run_cases", "run_case", "normalize_case", "case_id", "load_store", "pulse_grid",
           "overturn_map", "CASE_KEYS", "TIMING_COLUMNS", "EXECUTORS"]

#: The keys a case may have (every other key is an error).
CASE_KEYS = ("scene", "overrides", "engine", "settings", "motion", "phi0", "duration")

#: Executors accepted by :func:`run_cases`.
EXECUTORS = ("process", "serial", "dask")

#: Row columns that depend on the machine and the moment, not on the physics (leave them out
#: when comparing two sweeps).
TIMING_COLUMNS = ("wall_s", "real_time_factor", "run_s", "finished_at")

_MOTION_KINDS = ("ricker", "record", "none")
_RICKER_KEYS = {"kind", "shape", "sign", "A", "W", "amplitude", "period"}
_RECORD_KEYS = {"kind", "path", "dt", "units", "scale"}


# =========================================================================================
# Cases: normalization and hashing
# =========================================================================================
def _plain(x: Any, name: str) -> Any:
    """``x`` as plain JSON-able Python (numpy scalars -> Python, Path -> str)."""
    if isinstance(x, Mapping):
        return {str(k): _plain(v, f"{name}.{k}") for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v, name) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        v = float(x)
        if not math.isfinite(v):
            raise ParameterError(name, x, "a finite number")
        return v
    if x is None or isinstance(x, str):
        return x
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    raise ParameterError(name, x, "a number, string, bool, None, list or dict (cases are data)")


def normalize_case(case: Mapping[str, Any]) -> dict[str, Any]:
    """The case with every key of :data:`CASE_KEYS` present (defaults filled), plain Python
    values, checked for shape (unknown keys, motion kind and its keys, engine name). Physics
    validation (ranges) happens when the case runs."""
    from .engines import REGISTRY

    if not isinstance(case, Mapping):
        raise ParameterError("case", type(case).__name__,
                             "a dict with keys " + ", ".join(CASE_KEYS))
    bad = sorted(set(case) - set(CASE_KEYS))
    if bad:
        raise ParameterError(f"case key {bad[0]!r}", case[bad[0]], f"one of {', '.join(CASE_KEYS)}")
    c = _plain(dict(case), "case")
    scene = c.get("scene")
    if not isinstance(scene, str) or not scene:
        raise ParameterError("scene", scene, "a built-in scene name or a path to a .toml file")
    engine = c.get("engine", "analytic")
    if engine not in REGISTRY:
        raise ParameterError("engine", engine, f"one of {', '.join(REGISTRY)}")
    out: dict[str, Any] = {"scene": scene}
    for key in ("overrides", "settings"):
        v = c.get(key) or {}
        if not isinstance(v, dict):
            raise ParameterError(key, v, "a dict (or None)")
        out[key] = {k: v[k] for k in sorted(v)}
    out["engine"] = engine
    out["motion"] = _normalize_motion(c.get("motion"))
    phi0 = c.get("phi0", 0.0)
    if isinstance(phi0, bool) or not isinstance(phi0, (int, float)):
        raise ParameterError("phi0", phi0, "a finite number [rad]")
    out["phi0"] = float(phi0)
    dur = c.get("duration")
    if dur is not None:
        if isinstance(dur, bool) or not isinstance(dur, (int, float)) or dur <= 0:
            raise ParameterError("duration", dur, "> 0 [s] or None")
        dur = float(dur)
    out["duration"] = dur
    return out


def _normalize_motion(m: Any) -> dict[str, Any] | None:
    if m is None:
        return None
    if not isinstance(m, dict):
        raise ParameterError("motion", m, "a dict with 'kind' in ricker, record, none (or None)")
    kind = m.get("kind")
    if kind not in _MOTION_KINDS:
        raise ParameterError("motion.kind", kind, f"one of {', '.join(_MOTION_KINDS)}")
    if kind == "none":
        if set(m) != {"kind"}:
            raise ParameterError("motion", m, "{'kind': 'none'} with no other key")
        return None
    allowed = _RICKER_KEYS if kind == "ricker" else _RECORD_KEYS
    bad = sorted(set(m) - allowed)
    if bad:
        raise ParameterError(f"motion.{bad[0]}", m[bad[0]],
                             f"a key among {', '.join(sorted(allowed))} for a {kind} motion")
    out = {k: m[k] for k in sorted(m)}
    if kind == "ricker":
        out.setdefault("shape", "symmetric")
        out.setdefault("sign", 1)
        if isinstance(out["sign"], (int, float)) and out["sign"] in (1, -1):
            out["sign"] = int(out["sign"])
        has_dimless = "A" in out and "W" in out
        has_dim = "amplitude" in out and "period" in out
        if has_dimless == has_dim or len(set(out) & {"A", "W", "amplitude", "period"}) != 2:
            raise ParameterError("motion", m, "a ricker motion with either A and W, or amplitude "
                                              "[m/s^2] and period [s]")
    else:
        if not isinstance(out.get("path"), str):
            raise ParameterError("motion.path", out.get("path"), "a path to a record file")
        out.setdefault("scale", 1.0)
    return {k: out[k] for k in sorted(out)}


def _canonical(x: Any) -> Any:
    """Numbers as floats (so that 3 and 3.0 hash alike), recursively."""
    if isinstance(x, dict):
        return {k: _canonical(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_canonical(v) for v in x]
    if isinstance(x, bool) or x is None or isinstance(x, str):
        return x
    return float(x)


def case_id(case: Mapping[str, Any]) -> str:
    """A stable 16-hex-digit hash of the normalized case (SHA-256 of its canonical JSON):
    the same case gets the same id in any process, on any machine, in any key order."""
    text = json.dumps(_canonical(normalize_case(case)), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _flatten(case: dict[str, Any]) -> dict[str, Any]:
    """scene, overrides.<k>, engine, settings.<k>, motion.kind, motion.<k>, phi0, duration."""
    out: dict[str, Any] = {"scene": case["scene"]}
    for k, v in case["overrides"].items():
        out[f"overrides.{k}"] = v
    out["engine"] = case["engine"]
    for k, v in case["settings"].items():
        out[f"settings.{k}"] = v
    m = case["motion"]
    out["motion.kind"] = "none" if m is None else m["kind"]
    for k, v in (m or {}).items():
        if k != "kind":
            out[f"motion.{k}"] = v
    out["phi0"] = case["phi0"]
    out["duration"] = case["duration"]
    return out


def _label(case: dict[str, Any]) -> str:
    """A short human label for progress bars."""
    m = case["motion"]
    if m is None:
        mot = f"free phi0={case['phi0']:.3g} rad"
    elif m["kind"] == "ricker":
        amp = (f"A={m['A']:.3g} W={m['W']:.3g}" if "A" in m
               else f"a={m['amplitude']:.3g} m/s2 T={m['period']:.3g} s")
        mot = f"{m['shape'][:4]}{'+' if m['sign'] == 1 else '-'} {amp}"
    else:
        mot = f"{Path(m['path']).name} x{m['scale']:g}"
    return f"{case['engine']} {Path(case['scene']).stem} {mot}"


# =========================================================================================
# Running one case
# =========================================================================================
def _motion_of(m: dict[str, Any] | None, structure):
    if m is None:
        return None
    if m["kind"] == "ricker":
        from .scene.motion import make_pulse
        if "A" in m:
            return make_pulse(m["shape"], m["sign"], structure=structure, A=m.get("A"),
                              W=m.get("W"))
        return make_pulse(m["shape"], m["sign"], amplitude=m.get("amplitude"),
                          period=m.get("period"))
    from .scene.records import load_record
    return load_record(m["path"], dt=m.get("dt"), units=m.get("units"), scale=m["scale"])


def _result_fields(result) -> dict[str, Any]:
    s, c = result.summary, result.cost
    imp = result.impacts()
    row: dict[str, Any] = {"status": s.status, "reason": s.reason or ""}
    for k in ("max_abs_phi", "max_abs_phi_over_alpha", "overturned", "t_overturn",
              "exceeded_critical", "uplifted", "t_uplift", "n_impacts", "fractured",
              "t_fracture", "max_penetration", "max_sliding", "contact_opened"):
        v = getattr(s, k)
        row[k] = v.item() if isinstance(v, np.generic) else v
    for d, tag in ((1, "ccw"), (-1, "cw")):
        e = imp.loc[imp["direction"] == d, "eta"].to_numpy(dtype=float)
        e = e[np.isfinite(e)]
        row[f"eta_{tag}_mean"] = float(e.mean()) if e.size else math.nan
    row.update(wall_s=float(c.wall_s), sim_time=float(c.sim_time), steps=int(c.steps),
               rhs_calls=int(c.rhs_calls), real_time_factor=float(c.real_time_factor))
    version = result.settings.get("engine_version") if isinstance(result.settings, dict) else None
    if not version:
        from .engines import get_backend
        ok, info = get_backend(result.backend).available()
        version = info if ok else ""
    row["engine_version"] = str(version)
    return row


def run_case(case: Mapping[str, Any]) -> dict[str, Any]:
    """Run one case; return its row (never raises for a failure of the run itself: an
    exception becomes status ``"error"`` with ``reason`` = the exception's type and message).

    Row keys: ``case_id``, the flattened case, ``status``, ``reason``, the Result's summary
    (``max_abs_phi`` [rad], ``max_abs_phi_over_alpha``, ``overturned``, ``t_overturn`` [s], ...),
    mean eta per direction, cost (``wall_s`` [s], ``sim_time`` [s], ``steps``, ``rhs_calls``,
    ``real_time_factor``), ``engine_version``, ``run_s`` [s] (the whole case, building
    included), ``finished_at`` (UTC, ISO 8601) and ``case`` (the normalized case as JSON).
    """
    norm = normalize_case(case)
    row = _base_row(norm)
    t = time.perf_counter()
    try:
        from . import run
        from .scene.scene import load_scene

        scene = load_scene(norm["scene"], norm["overrides"] or None)
        motion = _motion_of(norm["motion"], scene.structure)
        result = run(scene, motion, engine=norm["engine"], duration=norm["duration"],
                     phi0=norm["phi0"], **norm["settings"])
        row.update(_result_fields(result))
    except Exception as e:  # a failing case is data, not a crash of the sweep
        row.update(status="error", reason=f"{type(e).__name__}: {e}")
    row["run_s"] = time.perf_counter() - t
    row["finished_at"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    return row


def _base_row(norm: dict[str, Any]) -> dict[str, Any]:
    row = {"case_id": case_id(norm)}
    row.update(_flatten(norm))
    row["case"] = json.dumps(norm, sort_keys=True)
    return row


def _error_row(norm: dict[str, Any], reason: str) -> dict[str, Any]:
    row = _base_row(norm)
    row.update(status="error", reason=reason, run_s=math.nan,
               finished_at=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"))
    return row


# =========================================================================================
# The store: a directory of small Parquet files
# =========================================================================================
def _need_pyarrow() -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise RockbenchError("a sweep store is written in Parquet and needs pyarrow: "
                             "pip install 'rockbench[parquet]'") from None


def _store_dir(store: str | Path) -> Path:
    p = Path(store)
    if p.exists() and not p.is_dir():
        raise ParameterError("store", str(store), "a directory (created if missing)")
    return p


def _parquet_safe(df: pd.DataFrame) -> pd.DataFrame:
    """Object columns that mix Python types (e.g. an override given as 0.01 in one case and
    "none" in another) become strings, so that Arrow can write them."""
    df = df.copy()
    for c in df.columns:
        if df[c].dtype == object:
            kinds = {type(v) for v in df[c] if v is not None and not (isinstance(v, float)
                                                                        and math.isnan(v))}
            if {int, float} >= kinds:
                continue
            if len(kinds) > 1:
                df[c] = [None if v is None or (isinstance(v, float) and math.isnan(v)) else str(v)
                         for v in df[c]]
    return df


def _write_part(directory: Path, row: dict[str, Any]) -> Path:
    """Write one row to ``directory/part-<case_id>.parquet`` atomically."""
    directory.mkdir(parents=True, exist_ok=True)
    final = directory / f"part-{row['case_id']}.parquet"
    tmp = directory / f".tmp-{row['case_id']}-{os.getpid()}-{uuid.uuid4().hex[:8]}.parquet"
    _parquet_safe(pd.DataFrame([row])).to_parquet(tmp, index=False)
    os.replace(tmp, final)
    return final


def _store_files(directory: Path) -> list[Path]:
    if not directory.is_dir():
        return []
    compact = sorted(directory.glob("compact-*.parquet"), key=lambda p: p.stat().st_mtime)
    parts = sorted(directory.glob("part-*.parquet"), key=lambda p: p.stat().st_mtime)
    return compact + parts


def load_store(store: str | Path) -> pd.DataFrame:
    """Every row of a sweep store (one per case id; the latest wins), or an empty frame."""
    _need_pyarrow()
    d = _store_dir(store)
    frames = []
    for f in _store_files(d):
        try:
            frames.append(pd.read_parquet(f))
        except Exception:  # an unreadable file: its cases simply run again
            continue
    frames = [f for f in frames if len(f)]
    if not frames:
        return pd.DataFrame(columns=["case_id"])
    df = pd.concat(frames, ignore_index=True)
    return df.drop_duplicates("case_id", keep="last").reset_index(drop=True)


def _compact(directory: Path) -> None:
    """Merge the store's files into one ``compact-<uuid>.parquet`` (written atomically before
    the merged files are removed; an interruption leaves duplicates, which loading drops)."""
    files = _store_files(directory)
    if len(files) < 2:
        return
    df = load_store(directory)
    final = directory / f"compact-{uuid.uuid4().hex[:12]}.parquet"
    tmp = directory / f".tmp-{final.name}"
    try:
        _parquet_safe(df).to_parquet(tmp, index=False)
    except Exception:  # keep the parts: correct, only slower to load
        tmp.unlink(missing_ok=True)
        return
    os.replace(tmp, final)
    for f in files:
        f.unlink(missing_ok=True)


# =========================================================================================
# Executors
# =========================================================================================
def _serial(items, on_row, bar) -> None:
    for cid, norm in items:
        if bar is not None:
            bar.set_postfix_str(_label(norm), refresh=True)
        on_row(cid, run_case(norm))


def _pool(items, workers: int, on_row, bar) -> None:
    """A process pool with at most ``workers`` cases in flight (so the bar can name them, and so
    that a worker that dies - segfault, out of memory - implicates only those cases, which are
    then rerun one by one, each in its own process, to find and record the culprit)."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    queue = deque(items)
    inflight: dict[Any, tuple[str, dict]] = {}
    ex = ProcessPoolExecutor(max_workers=workers)
    try:
        while queue or inflight:
            while queue and len(inflight) < workers:
                cid, norm = queue.popleft()
                inflight[ex.submit(run_case, norm)] = (cid, norm)
            if bar is not None:
                bar.set_postfix_str(" | ".join(_label(n) for _, n in inflight.values()),
                                    refresh=True)
            done, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
            suspects: list[tuple[str, dict]] = []
            for f in done:
                cid, norm = inflight.pop(f)
                try:
                    row = f.result()
                except BrokenProcessPool:
                    suspects.append((cid, norm))
                    continue
                on_row(cid, row)
            if suspects:
                # the pool is dead: every case still in flight is a suspect
                suspects.extend(inflight.values())
                inflight.clear()
                ex.shutdown(wait=True, cancel_futures=True)
                for cid, norm in suspects:
                    if bar is not None:
                        bar.set_postfix_str(f"isolating {_label(norm)}", refresh=True)
                    on_row(cid, _isolated(norm))
                ex = ProcessPoolExecutor(max_workers=workers)
    finally:
        ex.shutdown(wait=False, cancel_futures=True)


def _isolated(norm: dict[str, Any]) -> dict[str, Any]:
    """Run one case in a fresh single-worker process pool; a dying worker -> an error row."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    with ProcessPoolExecutor(max_workers=1) as ex:
        try:
            return ex.submit(run_case, norm).result()
        except BrokenProcessPool as e:
            return _error_row(norm, f"worker process died while running this case "
                                    f"(segfault or out of memory?): {e}")


def _dask(items, workers: int | None, address: str | None, on_row, bar) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise RockbenchError("executor='dask' needs dask.distributed: "
                             "pip install 'rockbench[dask]'") from None
    cluster = None
    if address:
        client = Client(address)
    else:
        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        futs = {}
        for cid, norm in items:
            futs[client.submit(run_case, norm, key=f"rockbench-case-{cid}", pure=False)] = \
                (cid, norm)
        for f in as_completed(list(futs)):
            cid, norm = futs[f]
            try:
                row = f.result()
            except Exception as e:  # e.g. KilledWorker: the case killed its worker
                row = _error_row(norm, f"{type(e).__name__}: {e}")
            if bar is not None:
                bar.set_postfix_str(f"done {_label(norm)}", refresh=False)
            on_row(cid, row)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


# =========================================================================================
# run_cases
# =========================================================================================
_FIRST = ["case_id"]
_RESULT_ORDER = ["status", "reason", "max_abs_phi", "max_abs_phi_over_alpha", "overturned",
                 "t_overturn", "exceeded_critical", "uplifted", "t_uplift", "n_impacts",
                 "fractured", "t_fracture", "eta_ccw_mean", "eta_cw_mean", "max_penetration",
                 "max_sliding", "contact_opened", "wall_s", "sim_time", "steps", "rhs_calls",
                 "real_time_factor", "engine_version", "run_s", "finished_at", "case"]


_INT_COLS = ("n_impacts", "steps", "rhs_calls", "motion.sign")
_BOOL_COLS = ("overturned", "exceeded_critical", "uplifted", "fractured", "contact_opened")
_FLOAT_COLS = ("phi0", "duration", "max_abs_phi", "max_abs_phi_over_alpha", "t_overturn",
               "t_uplift", "t_fracture", "eta_ccw_mean", "eta_cw_mean", "max_penetration",
               "max_sliding", "wall_s", "sim_time", "real_time_factor", "run_s")


def _missing(v: Any) -> bool:
    return v is None or v is pd.NA or (isinstance(v, float) and math.isnan(v))


def _tidy(df: pd.DataFrame) -> pd.DataFrame:
    """Column dtypes that survive missing values: counts Int64, flags boolean, times float64
    (missing = <NA> / NaN, e.g. on an error row)."""
    for c in df.columns:
        vals = [v for v in df[c].tolist() if not _missing(v)]
        if c in _INT_COLS and all(float(v) == int(v) for v in vals):
            df[c] = pd.array([None if _missing(v) else int(v) for v in df[c]], dtype="Int64")
        elif c in _BOOL_COLS:
            df[c] = pd.array([None if _missing(v) else bool(v) for v in df[c]],
                             dtype="boolean")
        elif c in _FLOAT_COLS:
            df[c] = pd.to_numeric(pd.Series([math.nan if _missing(v) else v for v in df[c]],
                                            index=df.index), errors="coerce").astype("float64")
    return df


def _frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    df = pd.DataFrame(rows)
    if df.empty:
        return df
    case_cols = [c for c in df.columns if c not in _FIRST and c not in _RESULT_ORDER]
    order = _FIRST + case_cols + [c for c in _RESULT_ORDER if c in df.columns]
    return _tidy(df[order].reset_index(drop=True))


def run_cases(cases: Iterable[Mapping[str, Any]], *, store: str | Path | None = None,
              executor: str = "process", workers: int | None = None,
              dask_address: str | None = None, progress: bool = True,
              retry_errors: bool = False) -> pd.DataFrame:
    """Run every case (see the module docstring) and return one row per case, in input order.

    Parameters
    ----------
    cases : list of dict
    store : path of a directory, optional
        Resumable store: cases already in it are not run again, each newly finished case is
        written to it at once (see the module docstring).
    executor : {"process", "serial", "dask"}
    workers : int, optional
        Worker processes (default ``os.cpu_count()``); for ``"dask"`` without an address, the
        LocalCluster's workers.
    dask_address : str, optional
        Scheduler address of a running Dask cluster (``executor="dask"`` only).
    progress : bool
        Show a tqdm bar naming the running cases.
    retry_errors : bool
        Run again the cases the store holds with status ``"error"``.

    Columns: ``case_id``, the flattened case (``scene``, ``overrides.<k>``, ``engine``,
    ``settings.<k>``, ``motion.kind``, ``motion.<k>``, ``phi0`` [rad], ``duration`` [s]), then
    the run's fields (see :func:`run_case`). :data:`TIMING_COLUMNS` vary from run to run.
    """
    if executor not in EXECUTORS:
        raise ParameterError("executor", executor, f"one of {', '.join(EXECUTORS)}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ParameterError("workers", workers, "an integer >= 1 or None")
    if dask_address is not None and executor != "dask":
        raise ParameterError("dask_address", dask_address, "given only with executor='dask'")
    norms = [normalize_case(c) for c in cases]
    ids = [case_id(n) for n in norms]

    done: dict[str, dict[str, Any]] = {}
    directory = None
    if store is not None:
        _need_pyarrow()
        directory = _store_dir(store)
        stored = load_store(directory)
        for rec in stored.to_dict("records"):
            if retry_errors and rec.get("status") == "error":
                continue
            done[rec["case_id"]] = rec

    todo: dict[str, dict[str, Any]] = {}
    for cid, n in zip(ids, norms, strict=True):
        if cid not in done and cid not in todo:
            todo[cid] = n
    items = list(todo.items())

    def on_row(cid: str, row: dict[str, Any]) -> None:
        done[cid] = row
        if directory is not None:
            _write_part(directory, row)
        if bar is not None:
            bar.update(1)
            if row.get("status") == "error":
                n_err[0] += 1
                bar.set_description(f"sweep ({n_err[0]} error{'s' if n_err[0] > 1 else ''})")

    n_err = [0]
    bar = None
    if items and progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(items), desc="sweep", unit="case", dynamic_ncols=True)
    try:
        if items:
            n_workers = workers or os.cpu_count() or 1
            if executor == "serial":
                _serial(items, on_row, bar)
            elif executor == "process":
                _pool(items, min(n_workers, len(items)), on_row, bar)
            else:
                _dask(items, workers, dask_address, on_row, bar)
    finally:
        if bar is not None:
            bar.close()
    if directory is not None and items:
        _compact(directory)
    return _frame([done[cid] for cid in ids])


# =========================================================================================
# Grids and maps
# =========================================================================================
def _as_list(x: Any, name: str) -> list:
    if isinstance(x, (str, int, float, np.number)):
        return [x]
    try:
        out = list(x)
    except TypeError:
        raise ParameterError(name, x, "a value or a list of values") from None
    if not out:
        raise ParameterError(name, x, "at least one value")
    return out


def pulse_grid(scene: str | Path, shapes, signs, A_values, W_values, engines, *,
               overrides: Mapping[str, Any] | None = None,
               settings: Mapping[str, Mapping[str, Any]] | None = None, phi0: float = 0.0,
               duration: float | None = None) -> list[dict[str, Any]]:
    """Cases of a Ricker-pulse map: every engine x shape x sign x A x W.

    ``scene`` a built-in name or a .toml path; ``shapes`` "symmetric"/"antisymmetric" (or a list);
    ``signs`` +1/-1 (or a list); ``A_values`` = a_g / (g tan alpha) > 0 and ``W_values`` =
    omega_g / p > 0 (lists, alpha and p of the taller column); ``engines`` a name or a list;
    ``settings`` maps an engine name to its setting overrides; ``duration`` [s] (None: pulse
    length + 10 s).
    """
    if not isinstance(scene, (str, os.PathLike)):
        raise ParameterError("scene", scene, "a built-in scene name or a path (cases are data)")
    engines_l = _as_list(engines, "engines")
    settings = dict(settings or {})
    unknown = set(settings) - set(engines_l)
    if unknown:
        raise ParameterError("settings", sorted(unknown)[0], f"keyed by one of the engines "
                                                            f"{engines_l}")
    for a in _as_list(A_values, "A_values"):
        if not float(a) > 0:
            raise ParameterError("A_values", a, "> 0")
    for w in _as_list(W_values, "W_values"):
        if not float(w) > 0:
            raise ParameterError("W_values", w, "> 0")
    cases = []
    for eng, shape, sign, A, W in product(engines_l, _as_list(shapes, "shapes"),
                                          _as_list(signs, "signs"), _as_list(A_values, "A_values"),
                                          _as_list(W_values, "W_values")):
        case = {"scene": os.fspath(scene), "overrides": dict(overrides or {}), "engine": eng,
                "settings": dict(settings.get(eng, {})),
                "motion": {"kind": "ricker", "shape": shape, "sign": int(sign), "A": float(A),
                           "W": float(W)},
                "phi0": float(phi0), "duration": duration}
        cases.append(normalize_case(case))
    return cases


def overturn_map(frame: pd.DataFrame, *, engine: str | None = None, scene: str | None = None,
                 shape: str | None = None, sign: int | None = None,
                 value: str = "overturned") -> pd.DataFrame:
    """Pivot a sweep frame of Ricker cases into a map: index ``A`` (rows, a_g / (g tan alpha)),
    columns ``W`` (omega_g / p), cells ``value`` (default ``overturned`` as 1.0 / 0.0; NaN where
    the case is not ``ok``). Filters select one engine / scene / shape / sign; a map that would
    still hold two cases in one cell raises ParameterError naming the column that differs."""
    if not isinstance(frame, pd.DataFrame) or "motion.A" not in frame or "motion.W" not in frame:
        raise ParameterError("frame", type(frame).__name__,
                             "a run_cases frame of Ricker cases given by A and W")
    if value not in frame:
        raise ParameterError("value", value, "a column of the frame, e.g. overturned, "
                                             "max_abs_phi_over_alpha")
    df = frame[frame["motion.kind"] == "ricker"]
    for col, want in (("engine", engine), ("scene", scene), ("motion.shape", shape),
                      ("motion.sign", sign)):
        if want is not None:
            df = df[df[col] == want]
    if df.empty:
        raise ParameterError("frame", "no matching rows",
                             "rows for the selected engine/scene/shape/sign")
    keys = df[["motion.A", "motion.W"]]
    if keys.duplicated().any():
        varying = [c for c in ("engine", "scene", "motion.shape", "motion.sign", "case_id")
                   if c in df and df[c].nunique() > 1]
        raise ParameterError(varying[0] if varying else "frame", "several values",
                             "one value: select it with the matching argument "
                             "(engine=, scene=, shape=, sign=)")
    def num(v: Any) -> float:
        try:
            return math.nan if v is None else float(v)
        except (TypeError, ValueError):
            return math.nan

    vals = pd.Series([num(v) for v in df[value]], index=df.index)
    vals = vals.where(df["status"] == "ok")
    out = pd.DataFrame({"A": df["motion.A"].astype(float), "W": df["motion.W"].astype(float),
                        "v": vals.astype(float)})
    table = out.pivot(index="A", columns="W", values="v").sort_index().sort_index(axis=1)
    table.columns.name = "W"
    table.index.name = "A"
    return table


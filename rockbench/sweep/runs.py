"""Running cases: one case -> one row (:func:`run_case`), many -> a frame (:func:`run_cases`),
through the one executor and the one store."""

from __future__ import annotations

import datetime as _dt
import json
import math
import time
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np
import pandas as pd

from . import store as S
from .cases import case_id, case_label, flatten_case, load_case_scene, normalize_case
from .executors import check_options, execute

__all__ = ["run_case", "run_cases", "TIMING_COLUMNS"]

#: Row columns that depend on the machine and the moment, not on the physics (leave them out
#: when comparing two sweeps).
TIMING_COLUMNS = ("wall_s", "real_time_factor", "cpu_s", "run_s", "finished_at")


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def _result_fields(result) -> dict[str, Any]:
    """The row fields of a Result, or of an :class:`~rockbench.engines.loop.Outcome` (what a
    map keeps: the same summary and cost but no eta measured, so its eta means are NaN)."""
    s, c = result.summary, result.cost
    if isinstance(result.impacts, list):          # an Outcome
        direction = np.array([r.get("direction") or 0 for r in result.impacts], dtype=np.int64)
        eta = np.array([r.get("eta") for r in result.impacts], dtype=float)
    else:
        imp = result.impacts()
        direction, eta = imp["direction"].to_numpy(), imp["eta"].to_numpy(dtype=float)
    row: dict[str, Any] = {"status": s.status, "reason": s.reason or ""}
    for k in ("max_abs_phi", "max_abs_phi_over_alpha", "overturned", "t_overturn",
              "exceeded_critical", "uplifted", "t_uplift", "n_impacts", "fractured",
              "t_fracture", "max_penetration", "max_sliding", "contact_opened"):
        v = getattr(s, k)
        row[k] = v.item() if isinstance(v, np.generic) else v
    for d, tag in ((1, "ccw"), (-1, "cw")):
        e = eta[direction == d]
        e = e[np.isfinite(e)]
        row[f"eta_{tag}_mean"] = float(e.mean()) if e.size else math.nan
    row.update(wall_s=float(c.wall_s), sim_time=float(c.sim_time), steps=int(c.steps),
               rhs_calls=int(c.rhs_calls), real_time_factor=float(c.real_time_factor),
               cpu_s=float(c.cpu_s))
    version = result.settings.get("engine_version") if isinstance(result.settings, dict) else None
    if not version:
        from ..engines import get_backend
        ok, info = get_backend(result.backend).available()
        version = info if ok else ""
    row["engine_version"] = str(version)
    return row


def _base_row(norm: dict[str, Any]) -> dict[str, Any]:
    row = {"case_id": case_id(norm)}
    row.update(flatten_case(norm))
    row["case"] = json.dumps(norm, sort_keys=True)
    return row


def case_columns(case: Mapping[str, Any]) -> dict[str, Any]:
    """The columns of a store row that say which case it is: ``case_id``, the flattened case
    and the case as JSON (what :func:`run_cases` writes beside a run's fields)."""
    return _base_row(normalize_case(case))


def _error_row(norm: dict[str, Any], reason: str) -> dict[str, Any]:
    row = _base_row(norm)
    row.update(status="error", reason=reason, run_s=math.nan, finished_at=_now())
    return row


#: Scenes loaded in this process, by case scene and overrides (a scene file: and its
#: modification time): loading validates the mechanism (its geometric limits, ~20 ms of CPU
#: for a frame), which a map would otherwise pay in every cell. Scenes are frozen.
_SCENES: dict[str, Any] = {}


def _case_scene(norm: dict[str, Any]):
    """:func:`load_case_scene`, loaded once per process for each scene (and file version)."""
    sc = norm["scene"]
    stamp = None
    if isinstance(sc, str):
        try:
            stamp = Path(sc).stat().st_mtime_ns
        except (OSError, ValueError):
            stamp = None
    key = json.dumps([sc, norm["overrides"], stamp], sort_keys=True, default=str)
    if key not in _SCENES:
        if len(_SCENES) >= 16:
            _SCENES.clear()
        _SCENES[key] = load_case_scene(norm)
    return _SCENES[key]


KEEP = ("all", "summary")


def run_case(case: Mapping[str, Any], keep: str = "all") -> dict[str, Any]:
    """Run one case; return its row (never raises for a failure of the run itself: an
    exception becomes status ``"error"`` with ``reason`` = the exception's type and message).
    ``keep="summary"`` (engines; what maps use): the run keeps only its summary
    (:func:`rockbench.engines.loop.finish`): the same row but for the eta means (NaN: a map
    does not measure eta).

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
        from ..runner import run
        from ..scene.motion import motion_from_spec

        scene = _case_scene(norm)
        motion = motion_from_spec(norm["motion"], scene.structure)
        result = run(scene, motion, engine=norm["engine"], duration=norm["duration"],
                     phi0=norm["phi0"], keep=keep, **norm["settings"])
        row.update(_result_fields(result))
    except Exception as e:  # a failing case is data, not a crash of the sweep
        row.update(status="error", reason=f"{type(e).__name__}: {e}")
    row["run_s"] = time.perf_counter() - t
    row["finished_at"] = _now()
    return row


def _run_normalized(norm: dict[str, Any], keep: str = "all") -> dict[str, Any]:
    """What the executor runs: :func:`run_case` looked up at call time (so that it can be
    replaced, e.g. by a test)."""
    return run_case(norm) if keep == "all" else run_case(norm, keep=keep)


#: Cases of a batched backend (``batched`` capability, e.g. MuJoCo's ``mujoco.rollout``) run
#: together in one ``run_batch`` call (one executor item).
BATCH_SIZE = 16


def _batched(engine: str) -> bool:
    """The backend ``engine`` declares batched runs (its class attribute ``batched``; reading
    it imports the adapter module, never the engine)."""
    from ..engines import get_backend
    from ..errors import BackendUnavailable

    try:
        return bool(get_backend(engine).batched)
    except BackendUnavailable:
        return False


def _batch_key(norm: dict[str, Any]) -> str | None:
    """The group of a case that a batched backend (``batched``) can run with others (same
    engine, scene, overrides, settings and duration, from rest under a ground motion), or
    None."""
    if norm["motion"] is None or norm["phi0"] != 0.0 or not _batched(norm["engine"]):
        return None
    return json.dumps([norm["engine"], norm["scene"], norm["overrides"], norm["settings"], norm["duration"]],
                      sort_keys=True)


def run_batch_cases(norms: list[dict[str, Any]], nthread: int | None = 1,
                    keep: str = "all") -> list[dict]:
    """Rows of the cases of one batch group (:func:`_batch_key`: one batched backend, scene
    and settings) run together by the backend's ``run_batch`` (e.g.
    :func:`rockbench.engines.mujoco_batch.run_batch`); a scene its ``batch_refusal`` refuses
    (dampers, fracture) falls back to :func:`run_case` one by one. ``run_s`` of each row is its
    share of the batch."""
    from ..engines import get_backend
    from ..scene.motion import motion_from_spec

    t = time.perf_counter()
    first = norms[0]
    try:
        backend = get_backend(first["engine"])
        scene = _case_scene(first)
        why = backend.batch_refusal(scene, backend(scene, **first["settings"]).settings)
        if why is not None:
            return [_run_normalized(n, keep) for n in norms]
        motions = [motion_from_spec(n["motion"], scene.structure) for n in norms]
        results = backend.run_batch(scene, motions, duration=first["duration"], nthread=nthread,
                            keep=keep, **first["settings"])
    except Exception:  # anything the batch cannot do: the plain path, case by case
        return [_run_normalized(n, keep) for n in norms]
    share = (time.perf_counter() - t) / len(norms)
    rows = []
    for n, r in zip(norms, results):
        row = _base_row(n)
        row.update(_result_fields(r))
        row["run_s"] = share
        row["finished_at"] = _now()
        rows.append(row)
    return rows


def _run_item(item: tuple) -> Any:
    """An executor item: ("case", norm, keep) -> row, ("batch", [norm, ...], keep) -> rows."""
    kind, payload, keep = item
    return (run_batch_cases(payload, keep=keep) if kind == "batch"
            else _run_normalized(payload, keep))


# =========================================================================================
# The frame
# =========================================================================================
_FIRST = ["case_id"]
_RESULT_ORDER = ["status", "reason", "max_abs_phi", "max_abs_phi_over_alpha", "overturned",
                 "t_overturn", "exceeded_critical", "uplifted", "t_uplift", "n_impacts",
                 "fractured", "t_fracture", "eta_ccw_mean", "eta_cw_mean", "max_penetration",
                 "max_sliding", "contact_opened", "wall_s", "sim_time", "steps", "rhs_calls",
                 "real_time_factor", "cpu_s", "engine_version", "run_s", "finished_at", "case"]
_INT_COLS = ("n_impacts", "steps", "rhs_calls", "motion.sign")
_BOOL_COLS = ("overturned", "exceeded_critical", "uplifted", "fractured", "contact_opened")
_FLOAT_COLS = ("phi0", "duration", "max_abs_phi", "max_abs_phi_over_alpha", "t_overturn",
               "t_uplift", "t_fracture", "eta_ccw_mean", "eta_cw_mean", "max_penetration",
               "max_sliding", "wall_s", "sim_time", "real_time_factor", "cpu_s", "run_s")


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


# =========================================================================================
# run_cases
# =========================================================================================
def run_cases(cases: Iterable[Mapping[str, Any]], *, store: str | Path | None = None,
              executor: str = "process", workers: int | None = None,
              dask_address: str | None = None, progress: bool = True,
              retry_errors: bool = False, batch: bool = True,
              on_rows: Callable[[list[dict[str, Any]]], None] | None = None,
              keep: str = "all") -> pd.DataFrame:
    """Run every case and return one row per case, in input order (``docs/sweeps.md``).

    Parameters
    ----------
    cases : list of dict (:mod:`rockbench.sweep.cases`)
    store : path of a directory, optional
        Resumable store (:mod:`rockbench.sweep.store`): cases already in it are not run again,
        each newly finished case is written to it at once.
    executor : {"process", "serial", "dask"} (:mod:`rockbench.sweep.executors`)
    workers : int, optional
        Worker processes (default: the available cores); for ``"dask"`` without an address,
        the LocalCluster's workers.
    dask_address : str, optional
        Scheduler address of a running Dask cluster (``executor="dask"`` only).
    progress : bool
        Show a tqdm bar naming the running cases.
    retry_errors : bool
        Run again the cases the store holds with status ``"error"``.
    batch : bool
        Run MuJoCo cases of one scene and settings together in ``mujoco.rollout``
        (:func:`run_batch_cases`; default True); scenes the batched path refuses fall back to
        the plain path.
    on_rows : callable, optional
        Called in this process with the rows of each finished executor item (one case, or a
        MuJoCo batch) as it finishes, after the store has them (e.g. to keep them elsewhere).
    keep : {"all", "summary"}
        "summary" (engine cases only; what maps use): each run keeps only its summary - the
        same rows but for the eta means (NaN), without building a history frame or measuring
        the impacts' eta (:func:`rockbench.engines.loop.finish`).

    Columns: ``case_id``, the flattened case (``scene``, ``overrides.<k>``, ``engine``,
    ``settings.<k>``, ``motion.kind``, ``motion.<k>``, ``phi0`` [rad], ``duration`` [s]), then
    the run's fields (see :func:`run_case`). :data:`TIMING_COLUMNS` vary from run to run.
    """
    check_options(executor, workers, dask_address)
    if keep not in KEEP:
        from ..errors import ParameterError
        raise ParameterError("keep", keep, "'all' or 'summary'")
    norms = [normalize_case(c) for c in cases]
    ids = [case_id(n) for n in norms]

    directory = None
    if store is not None:
        S.need_pyarrow()
        directory = S.store_dir(store)
    done, todo = _stored(directory, ids, norms, retry_errors, damaged="quiet")
    if directory is not None and not todo:   # nothing to write: a read-only store will do
        done, todo = _stored(directory, ids, norms, retry_errors, damaged="warn")
    if directory is None or not todo:
        return _run_todo(directory, done, todo, ids, dict(
            executor=executor, workers=workers, dask_address=dask_address, progress=progress,
            batch=batch, on_rows=on_rows, keep=keep))
    with S.writer_lock(directory, "store"):  # one writer; a second one is refused, named
        done, todo = _stored(directory, ids, norms, retry_errors, damaged="move")
        return _run_todo(directory, done, todo, ids, dict(
            executor=executor, workers=workers, dask_address=dask_address, progress=progress,
            batch=batch, on_rows=on_rows, keep=keep))


def _stored(directory: Path | None, ids: list[str], norms: list[dict[str, Any]],
            retry_errors: bool, *, damaged: str) -> tuple[dict, dict]:
    """(rows already in the store by case id, the cases still to run by case id)."""
    done: dict[str, dict[str, Any]] = {}
    if directory is not None:
        for rec in S.load_store(directory, damaged=damaged).to_dict("records"):
            if retry_errors and rec.get("status") == "error":
                continue
            done[rec["case_id"]] = rec
    todo: dict[str, dict[str, Any]] = {}
    for cid, n in zip(ids, norms, strict=True):
        if cid not in done and cid not in todo:
            todo[cid] = n
    return done, todo


def _run_todo(directory: Path | None, done: dict, todo: dict, ids: list[str],
              how: dict[str, Any]) -> pd.DataFrame:
    """Run ``todo`` (each row written to the store as it finishes) and return every row of
    ``ids``; ``how``: run_cases's executor, workers, dask_address, progress, batch, on_rows
    and keep."""
    executor, workers, dask_address = how["executor"], how["workers"], how["dask_address"]
    progress, batch, on_rows, keep = how["progress"], how["batch"], how["on_rows"], how["keep"]

    def on_result(cid: str, row: dict[str, Any]) -> None:
        done[cid] = row
        if directory is not None:
            S.write_row(directory, row)

    # MuJoCo cases of one scene and settings run batched (mujoco.rollout), BATCH_SIZE a batch
    items: list[tuple[str, tuple]] = []
    groups: dict[str, list[tuple[str, dict]]] = {}
    for cid, n in todo.items():
        key = _batch_key(n) if batch else None
        if key is None:
            items.append((cid, ("case", n, keep)))
        else:
            groups.setdefault(key, []).append((cid, n))
    ids_of: dict[str, list[str]] = {}
    for members in groups.values():
        for i in range(0, len(members), BATCH_SIZE):
            chunk = members[i:i + BATCH_SIZE]
            key = f"batch-{chunk[0][0]}-{len(chunk)}"
            ids_of[key] = [c for c, _ in chunk]
            items.append((key, ("batch", [n for _, n in chunk], keep)))

    def on_item(key: str, out: Any) -> None:
        if key in ids_of:
            for cid, row in zip(ids_of[key], out):
                on_result(cid, row)
        else:
            on_result(key, out)
        if on_rows is not None:
            on_rows(list(out) if key in ids_of else [out])

    def crashed(item: tuple, reason: str) -> Any:
        kind, payload = item[:2]
        if kind == "batch":
            return [_error_row(n, reason) for n in payload]
        return _error_row(payload, reason)

    execute(_run_item, items, on_result=on_item, crashed=crashed,
            label=lambda item: (case_label(item[1]) if item[0] == "case"
                                else f"{len(item[1])} {item[1][0]['engine']} cases (batched)"),
            is_error=lambda out: (isinstance(out, dict) and out.get("status") == "error"),
            executor=executor, workers=workers, dask_address=dask_address, progress=progress,
            desc="sweep", unit="item")
    if directory is not None and todo:
        S.compact(directory)
    return _frame([done[cid] for cid in ids])

"""The map store (``docs/maps.md``): a Parquet dataset folder ``NAME.parquet`` holding
``_inputs.json`` (what the map was computed for) and part files of map rows
(:data:`MAP_COLUMNS`), written by one process at a time
(:class:`rockbench.sweep.store.writer_lock`).

Every file is written to a temporary name and renamed; a part that cannot be read as map rows
is moved to ``_quarantine/`` by the writer (its cells are computed again) and skipped with a
warning by a reader; the writer merges the parts into one (:func:`compact_map_store`).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

import pandas as pd

from ..errors import ParameterError, RockbenchError, RockbenchWarning

__all__ = ["MAP_COLUMNS", "MAP_KEY", "COMPACT_EVERY", "tidy_map", "simulated_rows",
           "cell_key", "store_inputs", "INPUT_DEFAULTS", "input_differences",
           "describe_differences", "read_inputs", "part_files", "open_map_store", "write_part",
           "compact_map_store", "load_map_parts", "load_map", "store_error", "map_rows",
           "error_rows", "map_store_path"]

#: Columns of a map, with unit and meaning.
MAP_COLUMNS: dict[str, str] = {
    "amplitude": "-, A = a_g / (g tan alpha), alpha of the taller column",
    "frequency": "-, W = omega_g / p, p of the taller column",
    "pulse": "-, symmetric | antisymmetric Ricker pulse (paper Eqs. 29, 30)",
    "sign": "-, +1 the pulse as printed, -1 mirrored",
    "overturned": "-, |phi| reached the fall angle, or the run ended after the ground motion "
                  "beyond the critical angle (the analytic reference: the run is extended until "
                  "the fall is finished)",
    "exceeded_critical": "-, |phi| exceeded the critical angle of its potential",
    "max_abs_phi_over_alpha": "-, max |phi| / alpha",
    "n_impacts": "-, impacts of the run",
    "fractured": "-, tendons fractured",
    "status": "-, ok | diverged | invalid | error",
    "cpu_s": "s, process CPU time of the cell's run (batched or threaded: its share)",
}

MAP_KEY: tuple[str, ...] = ("pulse", "sign", "amplitude", "frequency")


def tidy_map(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with the map's columns and dtypes (nullable where a cell may lack a value). A
    store written before maps kept CPU time has a ``wall_s`` column instead: its cells' cost is
    not known (NaN), never a wall time read as CPU time."""
    df = df.copy()
    if "cpu_s" not in df.columns:
        df["cpu_s"] = math.nan
    for c in ("amplitude", "frequency", "max_abs_phi_over_alpha", "cpu_s"):
        df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
    df["sign"] = df["sign"].astype("int64")
    df["n_impacts"] = pd.to_numeric(df["n_impacts"], errors="coerce").astype("Int64")
    for c in ("overturned", "exceeded_critical", "fractured"):
        col = df[c]
        if col.dtype == bool or str(col.dtype) == "boolean":
            df[c] = col.astype("boolean")
        else:
            df[c] = pd.array([None if v is None or v is pd.NA or (isinstance(v, float)
                                                                  and math.isnan(v))
                              else bool(v) for v in col], dtype="boolean")
    df["pulse"] = df["pulse"].astype(str)
    df["status"] = df["status"].astype(str)
    if "inferred" in df.columns:            # an adaptive map's cells that were not simulated
        df["inferred"] = df["inferred"].astype("boolean").fillna(False).astype(bool)
        return df[list(MAP_COLUMNS) + ["inferred"]]
    return df[list(MAP_COLUMNS)]


def simulated_rows(df: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``df`` that were simulated (an adaptive map's inferred rows left out)."""
    if "inferred" not in df.columns:
        return df
    return df[~df["inferred"].astype("boolean").fillna(False).astype(bool)]


def cell_key(p: str, s: Any, a: Any, w: Any) -> tuple[str, int, float, float]:
    return (p, int(s), round(float(a), 9), round(float(w), 9))


#: A writer merges the store's part files into one when it holds more than this many (and at
#: the end of every run), so that a 100 x 100 x 4 map is not 40 000 files.
COMPACT_EVERY = 64


def map_rows(rows: Sequence[dict]) -> pd.DataFrame:
    """Map rows (:data:`MAP_COLUMNS`) of sweep rows (:func:`rockbench.sweep.run_case`); a row
    of a case that failed before it ran (status error) has no result fields: they are empty."""
    return pd.DataFrame([{
        "amplitude": r["motion.A"], "frequency": r["motion.W"], "pulse": r["motion.shape"],
        "sign": r["motion.sign"], "overturned": r.get("overturned"),
        "exceeded_critical": r.get("exceeded_critical"),
        "max_abs_phi_over_alpha": r.get("max_abs_phi_over_alpha", math.nan),
        "n_impacts": r.get("n_impacts"), "fractured": r.get("fractured"),
        "status": r.get("status", "error"), "cpu_s": r.get("cpu_s", math.nan)}
        for r in rows], columns=list(MAP_COLUMNS))


def error_rows(cells, why: str) -> pd.DataFrame:
    """Map rows with status error (reason ``why``, not kept) for ``cells`` (shape, sign, A, W)."""
    return pd.DataFrame([{"amplitude": A, "frequency": W, "pulse": sh, "sign": sg,
                          "overturned": None, "exceeded_critical": None,
                          "max_abs_phi_over_alpha": math.nan, "n_impacts": None,
                          "fractured": None, "status": "error", "cpu_s": math.nan}
                         for sh, sg, A, W in cells], columns=list(MAP_COLUMNS))


def map_store_path(folder: str | os.PathLike, scene: str, engine: str, *tags: str) -> Path:
    """The map store of ``scene``'s map by ``engine`` in ``folder``:
    ``<folder>/<scene>_<engine>[_<tag>...].parquet`` (a tag: the grid, ``"12x12"``, or what
    else sets the map apart, ``"vertical0.5"``)."""
    return Path(folder) / ("_".join([scene, engine, *tags]) + ".parquet")


def store_inputs(scene, scene_ref: str, engine: str, settings: dict, method: str,
                 tail: float | None, keyed_by_code: bool = True,
                 vertical_ratio: float = 0.0) -> dict[str, Any]:
    """What a store was written for. ``keyed_by_code``: include rockbench's code fingerprint
    (a store written by other code is refused); without it the store is keyed by the inputs
    and the engine's version only, and its reuse must be verified by re-running sample cells
    (:func:`reuse_map`). ``vertical_ratio`` r > 0 (every pulse's a_v = r u_g'') is an input
    too; a map without one has no such key (:data:`INPUT_DEFAULTS`: it reads as 0)."""
    from ..engines import engine_info
    from ..run_length import describe
    from .store import code_fingerprint

    out = {"scene": scene.to_dict(), "scene_ref": scene_ref, "engine": engine,
           "engine_version": next((str(r.get("version", r.get("reason")))
                                   for r in engine_info([engine])), ""),
           "settings": {k: settings[k] for k in sorted(settings)}, "method": method,
           "duration": describe("pulse", tail)}
    if vertical_ratio:
        out["vertical_ratio"] = float(vertical_ratio)
    if keyed_by_code:
        out["code"] = code_fingerprint()
    return out


#: Inputs a store's ``_inputs.json`` holds only when they differ from their default (stores
#: written before them keep their identity): their value when absent.
INPUT_DEFAULTS: dict[str, Any] = {"vertical_ratio": 0.0}


def input_differences(old: dict[str, Any], inputs: dict[str, Any]) -> list[str]:
    """The keys whose values differ between a store's ``old`` inputs and ``inputs``: every key
    of ``inputs``, and those of :data:`INPUT_DEFAULTS` either way (absent = the default)."""
    keys = list(inputs) + [k for k in INPUT_DEFAULTS if k not in inputs]
    return [k for k in keys if old.get(k, INPUT_DEFAULTS.get(k)) !=
            inputs.get(k, INPUT_DEFAULTS.get(k))]


def describe_differences(old: dict[str, Any], inputs: dict[str, Any],
                         diff: list[str]) -> str:
    """``k=OLD (now NEW)`` for each differing key but the scene's table."""
    return ", ".join(f"{k}={old.get(k, INPUT_DEFAULTS.get(k))!r} (now "
                     f"{inputs.get(k, INPUT_DEFAULTS.get(k))!r})" for k in diff if k != "scene")


def store_error(path: Path, e: OSError, doing: str) -> RockbenchError:
    """:func:`rockbench.sweep.store.store_error` for a map store."""
    from .store import store_error as _error

    return _error(path, e, doing, what="map store")


def read_inputs(path: Path) -> dict[str, Any] | str:
    """The store's ``_inputs.json`` as a dict, or why it cannot be read (a string)."""
    try:
        old = json.loads((path / "_inputs.json").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as e:
        return f"{type(e).__name__}: {' '.join(str(e).split())[:120]}"
    if not isinstance(old, dict):
        return f"holds a {type(old).__name__}, not a table of inputs"
    return old


def part_files(path: Path) -> list[Path]:
    """The store's part files, oldest first (a later row of a cell wins)."""
    def mtime(p: Path) -> float:
        try:
            return p.stat().st_mtime
        except OSError:
            return math.inf
    return sorted(path.glob("part-*.parquet"), key=lambda p: (mtime(p), p.name))


def open_map_store(path: Path, inputs: dict[str, Any]) -> pd.DataFrame:
    """Rows already in the store at ``path`` (``_inputs.json`` written if missing); refuse a
    store written for other inputs (scene, engine, settings, method or code) or one whose
    ``_inputs.json`` is unreadable while it holds cells. The caller holds the writer lock."""
    meta = path / "_inputs.json"
    if meta.exists():
        old = read_inputs(path)
        if isinstance(old, str):
            if part_files(path):
                raise RockbenchError(
                    f"map store {path}: {meta.name} is unreadable ({old}), so the cells it "
                    f"holds cannot be matched to these inputs; delete the folder {path} to "
                    f"compute the map again, or give another --store")
        else:
            diff = input_differences(old, inputs)
            if diff:
                raise RockbenchError(
                    f"map store {path} was written for other inputs ({', '.join(diff)} "
                    f"differ: {describe_differences(old, inputs, diff)}); use another "
                    f"--store, or delete it to start again")
            return load_map_parts(path, quarantine=True)
    elif part_files(path):
        raise RockbenchError(
            f"map store {path} holds part files but no {meta.name}, so its cells cannot be "
            f"matched to these inputs; delete the folder {path} to compute the map again, or "
            f"give another --store")
    tmp = path / f".tmp-inputs-{os.getpid()}"
    try:
        tmp.write_text(json.dumps(inputs, indent=1, sort_keys=True), encoding="utf-8")
        os.replace(tmp, meta)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise store_error(path, e, "write") from None
    return pd.DataFrame(columns=list(MAP_COLUMNS))


def write_part(path: Path, rows: pd.DataFrame) -> None:
    """Write ``rows`` as a new part file (temporary name, then an atomic rename)."""
    import uuid

    name = f"part-{uuid.uuid4().hex[:16]}.parquet"
    tmp = path / f".tmp-{name}"
    try:
        rows.to_parquet(tmp, index=False)
        os.replace(tmp, path / name)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise store_error(path, e, "write") from None


def compact_map_store(path: Path) -> None:
    """Merge the part files of the store into one (written before the merged parts are
    removed: an interruption between the two leaves duplicate rows, which :func:`load_map`
    drops and the next writer's compaction removes). Only the writer (lock holder) calls it."""
    parts = part_files(path)
    if len(parts) < 2:
        return
    df = load_map_parts(path, quarantine=True)
    parts = [p for p in parts if p.exists()]
    write_part(path, tidy_map(df))
    for p in parts:
        try:
            p.unlink()
        except FileNotFoundError:
            pass
        except OSError as e:
            raise store_error(path, e, "write") from None


def _warn(message: str) -> None:
    import warnings

    warnings.warn(message, RockbenchWarning, stacklevel=3)


def _read_part(p: Path) -> pd.DataFrame | str:
    """A part file's rows, or why it is not a part of a map (a string)."""
    try:
        df = pd.read_parquet(p)
    except ImportError:
        raise
    except Exception as e:  # ArrowInvalid, OSError, ...: truncated, corrupted, empty, foreign
        return f"{type(e).__name__}: {' '.join(str(e).split())[:120]}"
    # a part written before maps kept CPU time has wall_s instead of cpu_s (tidy_map: NaN)
    missing = [c for c in MAP_COLUMNS if c not in df.columns
               and not (c == "cpu_s" and "wall_s" in df.columns)]
    if missing:
        return f"not a map part: no column {', '.join(missing[:3])}"
    try:
        return tidy_map(df)
    except (TypeError, ValueError) as e:
        return f"not a map part: {type(e).__name__}: {' '.join(str(e).split())[:120]}"


def load_map_parts(path: Path, *, quarantine: bool) -> pd.DataFrame:
    """Every cell of the store at ``path`` (a cell written twice keeps its last row). A part
    file that cannot be read as map rows is skipped with a warning; with ``quarantine`` (the
    writer) it is moved to ``path/_quarantine/`` so that its cells are computed again."""
    from .store import need_pyarrow

    need_pyarrow()
    frames = []
    for p in part_files(path):
        df = _read_part(p)
        if isinstance(df, str):
            if quarantine:
                q = path / "_quarantine"
                try:
                    q.mkdir(exist_ok=True)
                    os.replace(p, q / p.name)
                except OSError as e:
                    raise store_error(path, e, "write") from None
                _warn(f"map store {path}: part file {p.name} is unreadable ({df}); moved it "
                      f"to {q} and its cells are computed again")
            else:
                _warn(f"map store {path}: skipped part file {p.name}, which is unreadable "
                      f"({df}); run the map again with this store to compute its cells "
                      f"(the bad file is then moved to _quarantine/)")
            continue
        if len(df):
            frames.append(df)
    if not frames:
        return pd.DataFrame(columns=list(MAP_COLUMNS))
    df = pd.concat(frames, ignore_index=True)
    return df.drop_duplicates(list(MAP_KEY), keep="last").reset_index(drop=True)


def load_map(store: str | os.PathLike) -> pd.DataFrame:
    """Every cell of a map store (columns :data:`MAP_COLUMNS`, one row per cell; a cell
    written twice keeps its last row). The reader to use while a map is being written into
    the store: ``pandas.read_parquet(folder)`` returns each cell once only when no writer is
    running. An unreadable part file is skipped with a warning (a writer moves it to
    ``_quarantine/`` and computes its cells again)."""
    path = Path(store)
    if not path.is_dir():
        raise ParameterError("store", str(store), "an existing map store folder")
    return load_map_parts(path, quarantine=False)

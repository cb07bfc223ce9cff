"""Overturning maps (the paper's Figs. 4-7) for any backend: grids of Ricker pulses, a resumable
Parquet store, and the agreement of two maps.

A map is one row per cell (:data:`MAP_COLUMNS`): the pulse (``pulse`` shape, ``sign``) at
``amplitude`` A = a_g / (g tan alpha) and ``frequency`` W = omega_g / p (alpha and p of the
taller column), each run from rest for the pulse window (6 T_g) plus 10 s.

* :func:`map_cells` - the grid (inclusive ranges, ``grid=(nA, nW)``, the pulses selected);
* :func:`run_map` - run every cell with one backend: the analytic model through its compiled
  path (:mod:`rockbench.analytic.compiled`, ``method="compiled"``, the default for maps) or the
  ``solve_ivp`` reference (``method="solve_ivp"``); engines through :func:`rockbench.sweep.run_cases`
  (MuJoCo batched in ``mujoco.rollout``), on a local process pool or a Dask cluster. With a
  ``store`` (a Parquet dataset: a folder ``NAME.parquet`` of parts plus ``_inputs.json``) every
  finished chunk is written at once; a rerun skips the stored cells, and a store written for
  other inputs is refused;
* :func:`map_agreement` - two maps cell by cell: fraction of agreeing verdicts, Cohen's kappa,
  and the shift of the minimum-overturning boundary along A, per frequency.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from .errors import ParameterError, RockbenchError

__all__ = ["MAP_COLUMNS", "PULSES", "map_cells", "run_map", "load_map", "reuse_map",
           "map_agreement", "boundary", "mark_near_boundary", "NEAR_BOUNDARY_MARGIN"]

#: The pulses of a map: name -> (shape, sign).
PULSES: dict[str, tuple[str, int]] = {"symmetric+": ("symmetric", 1),
                                      "symmetric-": ("symmetric", -1),
                                      "antisymmetric+": ("antisymmetric", 1),
                                      "antisymmetric-": ("antisymmetric", -1)}

#: Columns of a map, with unit and meaning.
MAP_COLUMNS: dict[str, str] = {
    "amplitude": "-, A = a_g / (g tan alpha), alpha of the taller column",
    "frequency": "-, W = omega_g / p, p of the taller column",
    "pulse": "-, symmetric | antisymmetric Ricker pulse (paper Eqs. 29, 30)",
    "sign": "-, +1 the pulse as printed, -1 mirrored",
    "overturned": "-, |phi| reached the fall angle (engines: or came to rest beyond the critical angle)",
    "exceeded_critical": "-, |phi| exceeded the critical angle of its potential",
    "max_abs_phi_over_alpha": "-, max |phi| / alpha",
    "n_impacts": "-, impacts of the run",
    "fractured": "-, tendons fractured",
    "status": "-, ok | diverged | invalid | error",
    "wall_s": "s, wall time of the integration or stepping (batched: the cell's share)",
}

_KEY = ("pulse", "sign", "amplitude", "frequency")


def _range(text_or_pair: Any, name: str) -> tuple[float, float]:
    if isinstance(text_or_pair, str):
        parts = text_or_pair.split(":")
        if len(parts) != 2:
            raise ParameterError(name, text_or_pair, "LO:HI (inclusive), e.g. 0.5:8")
        try:
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise ParameterError(name, text_or_pair, "LO:HI with two numbers") from None
    else:
        lo, hi = (float(x) for x in text_or_pair)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise ParameterError(name, text_or_pair, "0 < LO <= HI, both finite")
    return lo, hi


def _grid(text_or_pair: Any) -> tuple[int, int]:
    if isinstance(text_or_pair, str):
        try:
            na, nw = (int(x) for x in text_or_pair.lower().split("x"))
        except ValueError:
            raise ParameterError("grid", text_or_pair, "NAxNW, e.g. 100x100") from None
    else:
        na, nw = (int(x) for x in text_or_pair)
    if not (1 <= na <= 1000 and 1 <= nw <= 1000):
        raise ParameterError("grid", text_or_pair, "NAxNW with 1 <= NA, NW <= 1000")
    return na, nw


def _pulses(pulses: str | Sequence[str]) -> list[str]:
    names = list(PULSES) if pulses in ("all", None) else (
        [p.strip() for p in pulses.split(",")] if isinstance(pulses, str) else list(pulses))
    bad = [p for p in names if p not in PULSES]
    if bad or not names:
        raise ParameterError("pulses", pulses, f"all, or a comma-separated subset of "
                                               f"{', '.join(PULSES)}")
    return names


def map_cells(*, grid: Any = (100, 100), amplitude: Any = (0.5, 8.0),
              frequency: Any = (0.5, 10.0), pulses: str | Sequence[str] = "all"
              ) -> list[tuple[str, int, float, float]]:
    """The cells (shape, sign, A, W) of a map: ``grid`` = (nA, nW) points spread evenly over
    the inclusive ranges ``amplitude`` and ``frequency`` ("LO:HI" or a pair), for each selected
    pulse. ``grid=(8, 8), amplitude="1:8"`` gives A = 1, 2, ..., 8. Both ranges must lie
    within the limits of every run (:data:`rockbench.limits.LIMITS` ``A`` and ``W``)."""
    As, Ws = _axes(grid, amplitude, frequency)
    return [(PULSES[p][0], PULSES[p][1], float(A), float(W))
            for p in _pulses(pulses) for W in Ws for A in As]


def _axes(grid: Any, amplitude: Any, frequency: Any) -> tuple[np.ndarray, np.ndarray]:
    """The A and W values of a map's grid (checked against the limits of every run)."""
    from .limits import check_in_limit

    na, nw = _grid(grid)
    a0, a1 = _range(amplitude, "amplitude")
    w0, w1 = _range(frequency, "frequency")
    for key, name, lo, hi in (("A", "amplitude", a0, a1), ("W", "frequency", w0, w1)):
        for v in (lo, hi):  # the limits of `rockbench run`, for every path of a map
            check_in_limit(key, name, v)
    As = np.linspace(a0, a1, na) if na > 1 else np.array([a0])
    Ws = np.linspace(w0, w1, nw) if nw > 1 else np.array([w0])
    return np.round(As, 12), np.round(Ws, 12)


# ------------------------------------------------------------------------------------------
# The store: a Parquet dataset folder with the inputs it was written for
# ------------------------------------------------------------------------------------------
#: A writer merges the store's part files into one when it holds more than this many (and at
#: the end of every run), so that a 100 x 100 x 4 map is not 40 000 files.
COMPACT_EVERY = 64


def _inputs(scene, scene_ref: str, engine: str, settings: dict, method: str,
            tail: float | None, keyed_by_code: bool = True) -> dict[str, Any]:
    """What a store was written for. ``keyed_by_code``: include rockbench's code fingerprint
    (a store written by other code is refused); without it the store is keyed by the inputs
    and the engine's version only, and its reuse must be verified by re-running sample cells
    (:func:`reuse_map`)."""
    from .engines import engine_info
    from .sweep.store import code_fingerprint

    out = {"scene": scene.to_dict(), "scene_ref": scene_ref, "engine": engine,
           "engine_version": next((str(r.get("version", r.get("reason")))
                                   for r in engine_info([engine])), ""),
           "settings": {k: settings[k] for k in sorted(settings)}, "method": method,
           "duration": f"pulse window (6 T_g) + {10.0 if tail is None else tail:g} s"}
    if keyed_by_code:
        out["code"] = code_fingerprint()
    return out


def _oserror(path: Path, e: OSError, doing: str) -> RockbenchError:
    return RockbenchError(f"cannot {doing} the map store {path}: {e.strerror or e}; give a "
                          f"--store in a folder you can write (or make this one writable)")


def _read_inputs(path: Path) -> dict[str, Any] | str:
    """The store's ``_inputs.json`` as a dict, or why it cannot be read (a string)."""
    try:
        old = json.loads((path / "_inputs.json").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as e:
        return f"{type(e).__name__}: {' '.join(str(e).split())[:120]}"
    if not isinstance(old, dict):
        return f"holds a {type(old).__name__}, not a table of inputs"
    return old


def _parts(path: Path) -> list[Path]:
    """The store's part files, oldest first (a later row of a cell wins)."""
    def mtime(p: Path) -> float:
        try:
            return p.stat().st_mtime
        except OSError:
            return math.inf
    return sorted(path.glob("part-*.parquet"), key=lambda p: (mtime(p), p.name))


def _open_store(path: Path, inputs: dict[str, Any]) -> pd.DataFrame:
    """Rows already in the store at ``path`` (``_inputs.json`` written if missing); refuse a
    store written for other inputs (scene, engine, settings, method or code) or one whose
    ``_inputs.json`` is unreadable while it holds cells. The caller holds the writer lock."""
    meta = path / "_inputs.json"
    if meta.exists():
        old = _read_inputs(path)
        if isinstance(old, str):
            if _parts(path):
                raise RockbenchError(
                    f"map store {path}: {meta.name} is unreadable ({old}), so the cells it "
                    f"holds cannot be matched to these inputs; delete the folder {path} to "
                    f"compute the map again, or give another --store")
        else:
            diff = [k for k in inputs if old.get(k) != inputs[k]]
            if diff:
                raise RockbenchError(
                    f"map store {path} was written for other inputs ({', '.join(diff)} "
                    f"differ: {', '.join(f'{k}={old.get(k)!r}' for k in diff if k != 'scene')}"
                    f"); use another --store, or delete it to start again")
            return _load_parts(path, quarantine=True)
    elif _parts(path):
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
        raise _oserror(path, e, "write") from None
    return pd.DataFrame(columns=list(MAP_COLUMNS))


def _write_chunk(path: Path, rows: pd.DataFrame) -> None:
    """Write ``rows`` as a new part file (temporary name, then an atomic rename)."""
    import uuid

    name = f"part-{uuid.uuid4().hex[:16]}.parquet"
    tmp = path / f".tmp-{name}"
    try:
        rows.to_parquet(tmp, index=False)
        os.replace(tmp, path / name)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise _oserror(path, e, "write") from None


def _compact(path: Path) -> None:
    """Merge the part files of the store into one (written before the merged parts are
    removed: an interruption between the two leaves duplicate rows, which :func:`load_map`
    drops and the next writer's compaction removes). Only the writer (lock holder) calls it."""
    parts = _parts(path)
    if len(parts) < 2:
        return
    df = _load_parts(path, quarantine=True)
    parts = [p for p in parts if p.exists()]
    _write_chunk(path, _tidy(df))
    for p in parts:
        try:
            p.unlink()
        except FileNotFoundError:
            pass
        except OSError as e:
            raise _oserror(path, e, "write") from None


def _warn(message: str) -> None:
    import warnings

    warnings.warn(message, RuntimeWarning, stacklevel=3)


def _read_part(p: Path) -> pd.DataFrame | str:
    """A part file's rows, or why it is not a part of a map (a string)."""
    try:
        df = pd.read_parquet(p)
    except ImportError:
        raise
    except Exception as e:  # ArrowInvalid, OSError, ...: truncated, corrupted, empty, foreign
        return f"{type(e).__name__}: {' '.join(str(e).split())[:120]}"
    missing = [c for c in MAP_COLUMNS if c not in df.columns]
    if missing:
        return f"not a map part: no column {', '.join(missing[:3])}"
    try:
        return _tidy(df)
    except (TypeError, ValueError) as e:
        return f"not a map part: {type(e).__name__}: {' '.join(str(e).split())[:120]}"


def _load_parts(path: Path, *, quarantine: bool) -> pd.DataFrame:
    """Every cell of the store at ``path`` (a cell written twice keeps its last row). A part
    file that cannot be read as map rows is skipped with a warning; with ``quarantine`` (the
    writer) it is moved to ``path/_quarantine/`` so that its cells are computed again."""
    from .sweep.store import need_pyarrow

    need_pyarrow()
    frames = []
    for p in _parts(path):
        df = _read_part(p)
        if isinstance(df, str):
            if quarantine:
                q = path / "_quarantine"
                try:
                    q.mkdir(exist_ok=True)
                    os.replace(p, q / p.name)
                except OSError as e:
                    raise _oserror(path, e, "write") from None
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
    return df.drop_duplicates(list(_KEY), keep="last").reset_index(drop=True)


def load_map(store: str | os.PathLike) -> pd.DataFrame:
    """Every cell of a map store (columns :data:`MAP_COLUMNS`, one row per cell; a cell
    written twice keeps its last row). The reader to use while a map is being written into
    the store: ``pandas.read_parquet(folder)`` returns each cell once only when no writer is
    running. An unreadable part file is skipped with a warning (a writer moves it to
    ``_quarantine/`` and computes its cells again)."""
    path = Path(store)
    if not path.is_dir():
        raise ParameterError("store", str(store), "an existing map store folder")
    return _load_parts(path, quarantine=False)


# ------------------------------------------------------------------------------------------
# Running a map
# ------------------------------------------------------------------------------------------
def _duration(scene, W: float, tail: float | None) -> float | None:
    """Run length [s] of a cell: the pulse window 6 T_g plus ``tail`` (None: the default, + 10 s)."""
    if tail is None:
        return None
    return 6.0 * 2.0 * math.pi / (W * scene.p) + tail


#: Free rocking [s] added to an analytic cell that exceeded its critical angle and had not
#: fallen when its run ended, so that a fall under way is finished (the verdict rule of
#: :data:`MAP_COLUMNS` ``overturned``). A frame just past its critical angle leaves it at the
#: rate p (about 1-2 1/s for the paper's frames): 20 s covers a start 1e-9 rad beyond it.
FALL_EXTENSION = 20.0


def _load_scene_ref(ref: Any, overrides: dict | None = None):
    """A Scene from what travels to a worker: a built-in name or a path (with ``overrides``),
    or a scene's table (:meth:`Scene.to_dict`, overrides already applied)."""
    from .scene.scene import Scene, load_scene

    if isinstance(ref, dict):
        return Scene.from_dict(ref, source=f"scene {ref.get('name', '')!r}")
    return load_scene(ref, overrides or None)


def _analytic_rows(scene, cells: Sequence, method: str, tail: float | None,
                   extra: float = 0.0) -> pd.DataFrame:
    """Map rows of analytic ``cells`` in their order, each run for its map length plus
    ``extra`` seconds."""
    if method == "compiled":
        from .analytic.compiled import run_pulse_grid
        if tail is None and not extra:
            df = run_pulse_grid(scene, cells)
        else:
            t = 10.0 if tail is None else tail
            byw: dict[float, list] = {}
            for i, c in enumerate(cells):
                byw.setdefault(c[3], []).append(i)
            df = pd.concat([run_pulse_grid(scene, [cells[i] for i in ix],
                                           duration=_duration(scene, w, t + extra))
                            for w, ix in byw.items()], ignore_index=True)
            order = np.concatenate([np.asarray(ix) for ix in byw.values()])
            df = df.iloc[np.argsort(order, kind="stable")].reset_index(drop=True)  # cells' order
        df["wall_s"] = df["cpu_s"]
        return df[list(MAP_COLUMNS)]
    from .runner import run
    from .scene.motion import RickerPulse
    rows = []
    for shape, sign, A, W in cells:
        pulse = RickerPulse.dimensionless(A, W, scene.structure, shape, sign)
        dur = None if tail is None and not extra else _duration(
            scene, W, (10.0 if tail is None else tail) + extra)
        r = run(scene, pulse, history="minimal", duration=dur)
        s = r.summary
        rows.append({"amplitude": A, "frequency": W, "pulse": shape, "sign": sign,
                     "overturned": s.overturned, "exceeded_critical": s.exceeded_critical,
                     "max_abs_phi_over_alpha": s.max_abs_phi_over_alpha,
                     "n_impacts": s.n_impacts, "fractured": s.fractured, "status": s.status,
                     "wall_s": r.cost.wall_s})
    return pd.DataFrame(rows, columns=list(MAP_COLUMNS))


def _analytic_chunk(args: tuple) -> pd.DataFrame:
    """One chunk of analytic cells (in a worker): compiled path or the solve_ivp reference.

    The verdict rule is the engines' (``engines/loop.py`` ``_collapse``): a structure that is
    past its critical angle when the ground motion is over falls. The reference model does not
    stop short of the fall angle, so a cell that exceeded its critical angle and had not
    fallen by the end of its run is run again :data:`FALL_EXTENSION` seconds longer: a fall
    under way is finished (its row is the longer run's); a frame that came back keeps its
    verdict."""
    scene_ref, overrides, cells, method, tail = args
    scene = _load_scene_ref(scene_ref, overrides)
    df = _analytic_rows(scene, cells, method, tail)
    pending = ((df["status"] == "ok") & df["exceeded_critical"].astype(bool)
               & ~df["overturned"].astype(bool)).to_numpy()
    if pending.any():
        again = [c for c, p in zip(cells, pending) if p]
        longer = _analytic_rows(scene, again, method, tail, extra=FALL_EXTENSION)
        df = df.copy()
        idx = np.flatnonzero(pending)
        for col in MAP_COLUMNS:
            if col != "wall_s":
                df[col] = df[col].astype(object)
                df.loc[idx, col] = longer[col].to_numpy(dtype=object)
        df.loc[idx, "wall_s"] = (df.loc[idx, "wall_s"].to_numpy(float)
                                 + longer["wall_s"].to_numpy(float))
    return df
def _tidy(df: pd.DataFrame) -> pd.DataFrame:
    df = df.copy()
    for c in ("amplitude", "frequency", "max_abs_phi_over_alpha", "wall_s"):
        df[c] = df[c].astype("float64")
    df["sign"] = df["sign"].astype("int64")
    df["n_impacts"] = pd.array([None if pd.isna(v) else int(v) for v in df["n_impacts"]],
                               dtype="Int64")
    for c in ("overturned", "exceeded_critical", "fractured"):
        df[c] = pd.array([None if v is None or v is pd.NA or (isinstance(v, float)
                                                              and math.isnan(v)) else bool(v)
                          for v in df[c]], dtype="boolean")
    df["pulse"] = df["pulse"].astype(str)
    df["status"] = df["status"].astype(str)
    if "inferred" in df.columns:            # an adaptive map's cells that were not simulated
        df["inferred"] = df["inferred"].astype("boolean").fillna(False).astype(bool)
        return df[list(MAP_COLUMNS) + ["inferred"]]
    return df[list(MAP_COLUMNS)]


def _simulated(df: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``df`` that were simulated (an adaptive map's inferred rows left out)."""
    if "inferred" not in df.columns:
        return df
    return df[~df["inferred"].astype("boolean").fillna(False).astype(bool)]


def _cell_key(p: str, s: Any, a: Any, w: Any) -> tuple[str, int, float, float]:
    return (p, int(s), round(float(a), 9), round(float(w), 9))


def _check_backend(engine: str) -> None:
    """BackendUnavailable (one line: which backend, why) before any cell runs."""
    from .engines import get_backend
    from .errors import BackendUnavailable

    ok, info = get_backend(engine).available()
    if not ok:
        raise BackendUnavailable(f"backend {engine!r} cannot run here: {info}")


def run_map(scene: Any, engine: str = "analytic", *, grid: Any = (100, 100),
            amplitude: Any = (0.5, 8.0), frequency: Any = (0.5, 10.0),
            pulses: str | Sequence[str] = "all", overrides: dict | None = None,
            settings: dict | None = None, method: str | None = None,
            store: str | os.PathLike | None = None, workers: int | None = None,
            scheduler: str | None = None, progress: bool = True,
            chunk: int | None = None, tail: float | None = None,
            keyed_by_code: bool = True, adaptive: bool = False) -> pd.DataFrame:
    """Run an overturning map of ``scene`` (a built-in name, a .toml path or a
    :class:`~rockbench.Scene`, with scene ``overrides``) with backend ``engine`` (and its
    ``settings`` overrides) and return it (:data:`MAP_COLUMNS`, sorted by pulse, sign,
    frequency, amplitude).

    ``method`` (analytic only): "compiled" (default when numba imports) or "solve_ivp".
    ``store``: a Parquet dataset folder (created; resumed when it exists for the same inputs;
    refused for other inputs, or while another process writes it). Every finished chunk of
    analytic cells (``chunk`` cells, at most 200) and every finished engine cell (MuJoCo: each
    batch of 16) is on disk before the next result is taken. ``workers``: local processes
    (default and maximum: the cores); ``scheduler``: the address of a running Dask scheduler
    (``tcp://host:port``). ``progress``: a tqdm bar with cells done, rate, time left and how
    many were reused. ``tail``: free rocking after the pulse window [s] (default None: 10 s,
    the package default); shorter tails are for quick looks and tests.
    ``keyed_by_code``: False keys the store by its inputs and the engine version only (not by
    rockbench's code), for measured maps kept across code changes that are checked with
    :func:`reuse_map` before they are reused.
    ``adaptive``: simulate only where the verdict can change (:func:`_adaptive`) and infer the
    other cells; the map (and the store) then has a column ``inferred``. ``attrs``:
    ``reused`` (cells taken from the store), ``cells_run`` (simulated now) and, adaptive,
    ``inferred``.
    """
    from .runner import resolve_engines
    from .scene.scene import Scene, apply_overrides
    from .sweep.executors import check_options
    from .sweep.store import need_pyarrow, writer_lock

    if isinstance(scene, Scene):
        sc = (Scene.from_dict(apply_overrides(scene.to_dict(), overrides), source=scene.name)
              if overrides else scene)
        scene_ref: Any = sc.to_dict()
        ref_name = sc.name
        overrides = None
    else:
        sc = _load_scene_ref(scene, overrides)
        scene_ref = str(scene)
        ref_name = str(scene)
    (engine,) = resolve_engines([engine], name="engine")
    settings = dict(settings or {})
    if engine == "analytic":
        method = method or _default_method()
        if method not in ("compiled", "solve_ivp"):
            raise ParameterError("method", method, "'compiled' or 'solve_ivp'")
        if method == "compiled" and settings:
            raise ParameterError("settings", settings, "none with method='compiled'")
    elif method is not None:
        raise ParameterError("method", method, "given only for the analytic backend")
    if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, int)
                              or chunk < 1):
        raise ParameterError("chunk", chunk, "an integer >= 1 or None")
    executor = "dask" if scheduler else "process"
    check_options(executor, workers, scheduler)
    _check_backend(engine)
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    path = Path(store) if store is not None else None
    common = (executor, workers, scheduler, progress, chunk, tail)

    def go(stored: tuple[Path, pd.DataFrame] | None) -> pd.DataFrame:
        if not adaptive:
            return _run_cells(sc, scene_ref, ref_name, engine, settings, method, overrides,
                              cells, stored, *common)
        return _adaptive(sc, lambda cs, st: _run_cells(
            sc, scene_ref, ref_name, engine, settings, method, overrides, cs, st, *common),
            _axes(grid, amplitude, frequency), _pulses(pulses), stored)

    if path is None:
        return go(None)
    need_pyarrow()
    if path.exists() and not path.is_dir():
        raise ParameterError("store", str(path), "a map store folder (NAME.parquet), not a file")
    created = not path.exists()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _oserror(path, e, "create") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise RockbenchError(f"cannot write the map store {path}: the folder is not writable; "
                             f"give a --store in a folder you can write")
    try:
        with writer_lock(path, "map store"):
            inputs = _inputs(sc, ref_name, engine, settings, method or "", tail, keyed_by_code)
            done = _open_store(path, inputs)
            return go((path, done))
    except BaseException:
        if created and not _parts(path):  # nothing computed: leave no empty store behind
            import shutil
            shutil.rmtree(path, ignore_errors=True)
        raise


def _run_cells(sc, scene_ref: Any, ref_name: str, engine: str, settings: dict,
               method: str | None, overrides: dict | None, cells: list,
               stored: tuple[Path, pd.DataFrame] | None, executor: str,
               workers: int | None, scheduler: str | None, progress: bool,
               chunk: int | None, tail: float | None) -> pd.DataFrame:
    """Run the cells not yet in the store (``stored`` = (folder, its rows), or None), writing
    each finished result to it at once; return the map of ``cells``."""
    from .sweep.executors import cpu_count, execute, local_workers

    path, done = stored if stored is not None else (None, pd.DataFrame(
        columns=list(MAP_COLUMNS)))
    done = _simulated(done)
    have = {_cell_key(p, s, a, w) for p, s, a, w in zip(done["pulse"], done["sign"],
                                                         done["amplitude"], done["frequency"])}
    todo = [c for c in cells if _cell_key(*c) not in have]
    reused = len(cells) - len(todo)
    frames = [done]
    written = [len(_parts(path)) if path is not None else 0]

    def on_result(_key: str, df: pd.DataFrame) -> None:
        frames.append(df)
        if path is not None and len(df):
            _write_chunk(path, _tidy(df))
            written[0] += 1
            if written[0] > COMPACT_EVERY:
                _compact(path)
                written[0] = 1

    if path is not None and written[0] > 1:
        _compact(path)                    # duplicates a killed compaction may have left
    if engine == "analytic":
        n_workers = (local_workers(workers) if executor == "process"
                     else workers or cpu_count())
        size = chunk or (max(1, min(200, math.ceil(len(todo) / (4 * n_workers)))))
        items = [(f"chunk-{i}", (scene_ref, overrides or {}, todo[i:i + size], method, tail))
                 for i in range(0, len(todo), size)]
        execute(_analytic_chunk, items, on_result=on_result,
                crashed=lambda item, why: _crashed(item[2], why),
                label=lambda item: f"{len(item[2])} cells",
                executor=executor,
                workers=n_workers if executor == "process" else workers, dask_address=scheduler, progress=progress and bool(items),
                desc=f"map {sc.name} analytic ({reused} reused)", unit="chunk")
    elif todo:
        _engine_rows(scene_ref, overrides, engine, settings, todo, tail,
                     on_rows=lambda rows: on_result("", rows), executor=executor,
                     workers=workers, dask_address=scheduler, progress=progress)
    if path is not None and written[0] > 1:
        _compact(path)
    out = pd.concat([f for f in frames if len(f)], ignore_index=True) if any(
        len(f) for f in frames) else pd.DataFrame(columns=list(MAP_COLUMNS))
    out = _tidy(out).drop_duplicates(list(_KEY), keep="last")
    out = out[list(MAP_COLUMNS)]
    keep = {_cell_key(*c) for c in cells}
    mask = [_cell_key(p, s, a, w) in keep for p, s, a, w in
            zip(out["pulse"], out["sign"], out["amplitude"], out["frequency"])]
    out = out[mask].sort_values(["pulse", "sign", "frequency", "amplitude"],
                                ascending=[True, False, True, True]).reset_index(drop=True)
    out.attrs.update(scene=sc.name, engine=engine, method=method or "", reused=reused,
                     cells_run=len(todo))
    return out


#: Adaptive maps: the coarse pass simulates every COARSE_STRIDE-th point along A and W (and
#: the last); a block of cells between simulated corners is halved until its corners agree.
COARSE_STRIDE = 4
#: Adaptive maps: a surviving corner whose max |phi| reaches this fraction of the critical
#: angle makes its block "near" (refined), so that survival close to overturning is looked at.
NEAR_CRITICAL = 0.7


def _adaptive(sc, compute, axes: tuple[np.ndarray, np.ndarray], pulses: list[str],
              stored: tuple[Path, pd.DataFrame] | None) -> pd.DataFrame:
    """An adaptive map (issue 27): simulate the corners of the coarse blocks (every
    :data:`COARSE_STRIDE`-th A and W, and the last), then, level by level, halve every block
    whose corners do not all give one verdict with status ok, or where a surviving corner
    rocked beyond :data:`NEAR_CRITICAL` of the critical angle, until blocks are one cell wide;
    the cells of a block whose corners agree take their verdict (``inferred`` True, peak and
    impacts unknown). ``compute(cells, stored)`` simulates cells (reusing stored ones) and
    returns their rows. Measured on the analytic maps of the paper's frames: at 24 x 24 x 4
    it simulates 16-31 % of the cells and reproduces 99.91-100 % of the full grid's verdicts;
    at 100 x 100 x 4 (paper-asymmetric) 15 % and 99.95 % (``docs/maps.md``)."""
    from .runner import info

    As, Ws = axes
    na, nw = len(As), len(Ws)
    consts = info(sc)
    # the smallest critical angle of any direction and device state [alpha] (a frame with
    # intact tendons has none until they fracture)
    crits = [abs(float(v)) for k, v in consts.items() if k.startswith("phi_cr_")
             and v is not None and math.isfinite(float(v))]
    crit = min(crits) / consts["alpha"] if crits else math.inf
    path = stored[0] if stored is not None else None
    known: dict[tuple, Any] = {}                 # (pulse, sign, i, j) -> row (namedtuple)
    frames: list[pd.DataFrame] = []
    reused = run = 0

    def simulate(need: list[tuple[str, int, int, int]]) -> None:
        nonlocal reused, run
        need = [k for k in dict.fromkeys(need) if k not in known]
        if not need:
            return
        cells = [(p, s, float(As[i]), float(Ws[j])) for p, s, i, j in need]
        st = None if path is None else (path, pd.concat(
            [stored[1]] + frames, ignore_index=True) if frames else stored[1])
        df = compute(cells, st)
        reused += int(df.attrs.get("reused", 0))
        run += int(df.attrs.get("cells_run", 0))
        frames.append(df)
        by = {_cell_key(r.pulse, r.sign, r.amplitude, r.frequency): r for r in df.itertuples()}
        for k, c in zip(need, cells):
            known[k] = by[_cell_key(*c)]

    if na < 2 or nw < 2:
        simulate([(PULSES[p][0], PULSES[p][1], i, j) for p in pulses for i in range(na)
                  for j in range(nw)])
        blocks: list[tuple] = []
    else:
        ia = sorted(set(range(0, na, COARSE_STRIDE)) | {na - 1})
        iw = sorted(set(range(0, nw, COARSE_STRIDE)) | {nw - 1})
        blocks = [(PULSES[p][0], PULSES[p][1], a0, a1, w0, w1) for p in pulses
                  for a0, a1 in zip(ia, ia[1:]) for w0, w1 in zip(iw, iw[1:])]
    verdict: dict[tuple, bool] = {}
    while blocks:
        simulate([(p, s, a, w) for p, s, a0, a1, w0, w1 in blocks
                  for a in (a0, a1) for w in (w0, w1)])
        finer = []
        for p, s, a0, a1, w0, w1 in blocks:
            cs = [known[(p, s, a, w)] for a in (a0, a1) for w in (w0, w1)]
            ok = all(c.status == "ok" for c in cs)
            over = {bool(c.overturned) for c in cs if ok}
            near = any(not bool(c.overturned) and c.max_abs_phi_over_alpha >= NEAR_CRITICAL
                       * crit for c in cs if ok)
            if ok and len(over) == 1 and not near:
                v = over.pop()
                for a in range(a0, a1 + 1):
                    for w in range(w0, w1 + 1):
                        verdict.setdefault((p, s, a, w), v)
                continue
            am = [a0, (a0 + a1) // 2, a1] if a1 - a0 > 1 else [a0, a1]
            wm = [w0, (w0 + w1) // 2, w1] if w1 - w0 > 1 else [w0, w1]
            if len(am) == 2 and len(wm) == 2:
                continue                          # one cell wide: every cell is simulated
            finer += [(p, s, x0, x1, y0, y1) for x0, x1 in zip(am, am[1:])
                      for y0, y1 in zip(wm, wm[1:])]
        blocks = finer
    # a cell the store holds simulated (e.g. by a full run) is taken as it is, not inferred
    old = _simulated(stored[1]) if stored is not None else pd.DataFrame()
    if len(old):
        index = {(p, s, round(float(As[a]), 9), round(float(Ws[w]), 9)): (p, s, a, w)
                 for p in {PULSES[q][0] for q in pulses} for s in (1, -1)
                 for a in range(na) for w in range(nw)}
        have = {_cell_key(r.pulse, r.sign, r.amplitude, r.frequency) for r in
                old.itertuples()}
        take = [index[k] for k in have if k in index and index[k] in verdict
                and index[k] not in known]
        if take:
            frames.append(_tidy(old[[_cell_key(r.pulse, r.sign, r.amplitude, r.frequency)
                                     in {(p, s, round(float(As[a]), 9),
                                          round(float(Ws[w]), 9)) for p, s, a, w in take}
                                     for r in old.itertuples()]]))
            reused += len(take)
            known.update({k: None for k in take})
    sim = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(
        columns=list(MAP_COLUMNS))
    sim = _tidy(sim).drop_duplicates(list(_KEY), keep="last")[list(MAP_COLUMNS)]
    sim = sim.assign(inferred=False)
    guessed = [{"amplitude": float(As[a]), "frequency": float(Ws[w]), "pulse": p, "sign": s,
                "overturned": v, "exceeded_critical": True if v else None,
                "max_abs_phi_over_alpha": math.nan, "n_impacts": None, "fractured": None,
                "status": "ok", "wall_s": 0.0, "inferred": True}
               for (p, s, a, w), v in verdict.items() if (p, s, a, w) not in known]
    out = sim
    if guessed:
        inf = _tidy(pd.DataFrame(guessed))
        if path is not None:
            _write_chunk(path, inf)
            _compact(path)
        out = pd.concat([sim, inf], ignore_index=True)
    out = out.sort_values(["pulse", "sign", "frequency", "amplitude"],
                          ascending=[True, False, True, True]).reset_index(drop=True)
    out.attrs.update(scene=sc.name, engine=frames[0].attrs.get("engine", "") if frames else "",
                     method=frames[0].attrs.get("method", "") if frames else "",
                     reused=reused, cells_run=run, inferred=len(guessed))
    return out


def _map_rows(rows: Sequence[dict]) -> pd.DataFrame:
    """Map rows (:data:`MAP_COLUMNS`) of sweep rows (:func:`rockbench.sweep.run_case`); a row
    of a case that failed before it ran (status error) has no result fields: they are empty."""
    return pd.DataFrame([{
        "amplitude": r["motion.A"], "frequency": r["motion.W"], "pulse": r["motion.shape"],
        "sign": r["motion.sign"], "overturned": r.get("overturned"),
        "exceeded_critical": r.get("exceeded_critical"),
        "max_abs_phi_over_alpha": r.get("max_abs_phi_over_alpha", math.nan),
        "n_impacts": r.get("n_impacts"), "fractured": r.get("fractured"),
        "status": r.get("status", "error"), "wall_s": r.get("wall_s", math.nan)}
        for r in rows], columns=list(MAP_COLUMNS))


def _engine_rows(scene_ref: Any, overrides: dict | None, engine: str, settings: dict,
                 cells: Sequence, tail: float | None, on_rows=None,
                 **execution) -> pd.DataFrame:
    """Map rows of engine ``cells`` (shape, sign, A, W), run through
    :func:`rockbench.sweep.run_cases` (MuJoCo batched) with ``execution`` options;
    ``on_rows(frame)`` is called with the map rows of each finished executor item (a cell, or
    a MuJoCo batch) as it finishes."""
    from .sweep import run_cases

    sc = _load_scene_ref(scene_ref, overrides)
    cases = [{"scene": scene_ref, "overrides": overrides or {}, "engine": engine,
              "settings": settings, "duration": _duration(sc, W, tail),
              "motion": {"kind": "ricker", "shape": sh, "sign": sg, "A": A, "W": W}}
             for sh, sg, A, W in cells]
    rows = run_cases(cases, on_rows=(None if on_rows is None else
                                     (lambda rs: on_rows(_map_rows(rs)))), keep="summary",
                     **execution)
    return _map_rows(rows.to_dict("records"))


# ------------------------------------------------------------------------------------------
# Reusing a measured map: verified by re-running sample cells
# ------------------------------------------------------------------------------------------
#: Relative tolerance on max |phi| / alpha when a stored cell is re-run (the engines are
#: deterministic: the same wheel on the same kind of CPU reproduces a run bit for bit).
VERIFY_RTOL = 1e-6


def _check_cells(df: pd.DataFrame, n: int) -> pd.DataFrame:
    """Up to ``n`` stored cells to re-run: short runs (the highest frequencies), one per pulse
    and sign, alternately a survivor that rocked (the median rocking amplitude of the
    survivors) and an overturning cell far from the boundary (the largest A)."""
    top = df[df["frequency"] >= df["frequency"].quantile(0.66)]
    picks = []
    for i, ((_p, _s), g) in enumerate(top.groupby(["pulse", "sign"], sort=True)):
        g = g[g["status"] == "ok"]
        ot = g[g["overturned"].astype(bool)]
        sv = g[~g["overturned"].astype(bool) & (g["max_abs_phi_over_alpha"] > 0.05)]
        if i % 2 == 0 and len(sv):
            sv = sv.sort_values("max_abs_phi_over_alpha")
            picks.append(sv.iloc[len(sv) // 2])
        elif len(ot):
            picks.append(ot.sort_values(["amplitude", "frequency"]).iloc[-1])
        elif len(g):
            picks.append(g.iloc[len(g) // 2])
        if len(picks) >= n:
            break
    return pd.DataFrame(picks).reset_index(drop=True)


def reuse_map(store: str | os.PathLike, scene: str, engine: str, *, grid: Any,
              amplitude: Any, frequency: Any, pulses: str | Sequence[str] = "all",
              tail: float | None = None, check: int = 4,
              rtol: float = VERIFY_RTOL) -> tuple[pd.DataFrame | None, str]:
    """A measured map (a store written with ``keyed_by_code=False``) if it can be trusted on
    this code and machine: written for the same scene, engine version, default settings and
    run length, complete for the grid, and reproduced at ``check`` cells re-run now (verdicts,
    status and impacts equal, max |phi| / alpha within ``rtol``). Returns (map, how it was
    verified) or (None, why it is not reused)."""
    path = Path(store)
    meta = path / "_inputs.json"
    if not meta.is_file():
        return None, f"no measured map at {path}"
    from .scene.scene import load_scene

    sc = load_scene(scene)
    want = _inputs(sc, str(scene), engine, {}, "", tail, keyed_by_code=False)
    old = _read_inputs(path)
    if isinstance(old, str):
        return None, f"the measured map {path.name} has an unreadable {meta.name} ({old})"
    diff = [k for k in want if old.get(k) != want[k]]
    if diff:
        return None, (f"the measured map {path.name} was written for other inputs "
                      f"({', '.join(diff)} differ)")
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    df = load_map(path)
    keys = {(p, int(s), round(float(a), 9), round(float(w), 9))
            for p, s, a, w in zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])}
    missing = [c for c in cells if (c[0], c[1], round(c[2], 9), round(c[3], 9)) not in keys]
    if missing:
        return None, f"the measured map {path.name} lacks {len(missing)} of {len(cells)} cells"
    df = _tidy(df)
    keep = {(c[0], c[1], round(c[2], 9), round(c[3], 9)) for c in cells}
    df = df[[(p, int(s), round(a, 9), round(w, 9)) in keep for p, s, a, w in
             zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])]]
    df = df.sort_values(["pulse", "sign", "frequency", "amplitude"],
                        ascending=[True, False, True, True]).reset_index(drop=True)
    picks = _check_cells(df, check)
    now = _tidy(_engine_rows(str(scene), None, engine, {}, [
        (r.pulse, int(r.sign), float(r.amplitude), float(r.frequency))
        for r in picks.itertuples()], tail, executor="serial", progress=False))
    m = picks.merge(now, on=list(_KEY), suffixes=("", "_now"))
    worst = 0.0
    for r in m.itertuples():
        cell = (f"{r.pulse} {'+' if r.sign > 0 else '-'} A={r.amplitude:.4g} "
                f"W={r.frequency:.4g}")
        for c in ("status", "overturned", "exceeded_critical", "fractured", "n_impacts"):
            if getattr(r, c) != getattr(r, c + "_now"):
                return None, (f"the measured map {path.name} does not reproduce: at {cell} "
                              f"{c} was {getattr(r, c)}, is {getattr(r, c + '_now')} now")
        a, b = r.max_abs_phi_over_alpha, r.max_abs_phi_over_alpha_now
        d = abs(a - b) / max(abs(a), 1e-12)
        worst = max(worst, d)
        if not d <= rtol:
            return None, (f"the measured map {path.name} does not reproduce: at {cell} max "
                          f"|phi|/alpha was {a:.9g}, is {b:.9g} now")
    df.attrs.update(scene=sc.name, engine=engine, method="", reused=len(df))
    return df, (f"measured earlier ({len(df)} cells, {want['engine_version']}), "
                f"reproduced now at {len(m)} re-run cells (largest relative difference in "
                f"max |phi|/alpha {worst:.1e})")


def _crashed(cells, why: str) -> pd.DataFrame:
    return pd.DataFrame([{"amplitude": A, "frequency": W, "pulse": sh, "sign": sg,
                          "overturned": None, "exceeded_critical": None,
                          "max_abs_phi_over_alpha": math.nan, "n_impacts": None,
                          "fractured": None, "status": "error", "wall_s": math.nan}
                         for sh, sg, A, W in cells], columns=list(MAP_COLUMNS))


def _default_method() -> str:
    try:
        from .analytic import compiled  # noqa: F401
        compiled._require_numba()
    except Exception:
        return "solve_ivp"
    return "compiled"


# ------------------------------------------------------------------------------------------
# Agreement of two maps
# ------------------------------------------------------------------------------------------
def boundary(df: pd.DataFrame) -> pd.DataFrame:
    """The minimum-overturning boundary of a map: for each (pulse, sign, frequency), the
    smallest amplitude A that overturns (NaN if none does)."""
    ok = df[df["status"] == "ok"]
    rows = []
    for (p, s, w), g in ok.groupby(["pulse", "sign", "frequency"], sort=True):
        ot = g[g["overturned"].astype(bool)]
        rows.append({"pulse": p, "sign": int(s), "frequency": float(w),
                     "a_min": float(ot["amplitude"].min()) if len(ot) else math.nan})
    return pd.DataFrame(rows, columns=["pulse", "sign", "frequency", "a_min"])


#: Relative margin in A within which a cell is "near the boundary": the engines' own
#: boundary is blurred and not monotone within about 2 % of the reference's (measured in
#: issue 24: MuJoCo overturns at A = 14.90 and survives at A = 15.00, W = 6), so a verdict
#: there says little about an engine.
NEAR_BOUNDARY_MARGIN = 0.02


def mark_near_boundary(ref: pd.DataFrame, scene: Any, *, margin: float = NEAR_BOUNDARY_MARGIN,
                       tail: float | None = None, overrides: dict | None = None,
                       method: str | None = None) -> pd.DataFrame:
    """``ref`` (an analytic map of ``scene``) with a column ``near_boundary``: True where the
    reference verdict changes within ``margin`` (relative) of the cell's A, i.e. where the
    analytic model run at A (1 - margin) or A (1 + margin), same pulse and W, gives the other
    verdict than at A (cells not ok: False). ``tail`` as the map's run length."""
    from .errors import check_positive

    if not 0 < check_positive("margin", margin) < 1:
        raise ParameterError("margin", margin, "in (0, 1)")
    out = ref.copy()
    out["near_boundary"] = False
    ok = out[out["status"] == "ok"]
    if not len(ok):
        return out
    from .scene.scene import Scene

    sc = scene if isinstance(scene, Scene) else _load_scene_ref(str(scene), overrides)
    method = method or _default_method()
    base = [(r.pulse, int(r.sign), float(r.amplitude), float(r.frequency))
            for r in ok.itertuples()]
    verdicts = []
    for f in (1.0 - margin, 1.0 + margin):
        cells = [(p, s, a * f, w) for p, s, a, w in base]
        df = _analytic_chunk((sc.to_dict(), None, cells, method, tail))
        verdicts.append(df["overturned"].astype(bool).to_numpy())
    here = ok["overturned"].astype(bool).to_numpy()
    near = (verdicts[0] != here) | (verdicts[1] != here)
    out.loc[ok.index, "near_boundary"] = near
    out["near_boundary"] = out["near_boundary"].astype(bool)
    return out


def map_agreement(a: pd.DataFrame, b: pd.DataFrame) -> dict[str, Any]:
    """Agreement of map ``b`` with map ``a`` (normally the analytic one) on the cells both ran
    with status ok: ``n`` cells, ``fraction`` of equal verdicts, Cohen's ``kappa`` (agreement
    beyond chance; 1 perfect, 0 chance; NaN if both maps are uniform), ``b_overturns_a_survives``
    and ``a_overturns_b_survives`` counts, and ``shift``: a frame per (pulse, sign, frequency)
    of the boundary A_min of each *on those common cells* and ``shift`` = A_min(b) - A_min(a)
    [-] (negative: b overturns at smaller pulses, earlier).

    When ``a`` has a ``near_boundary`` column (:func:`mark_near_boundary`): ``near_boundary``
    (cells within the margin of the reference boundary), ``disagree_near_boundary`` and
    ``disagree_away`` (differing verdicts near and away from it). ``cells``: the common ok
    cells (key, both verdicts, ``agree``, ``near_boundary``).

    RockbenchError when the maps have no cell in common (nothing to compare); ``n`` = 0 when
    they share cells but none ran ok in both (``fraction`` and ``kappa`` then NaN)."""
    key = list(_KEY)
    ka = [_cell_key(*k) for k in zip(a["pulse"], a["sign"], a["amplitude"], a["frequency"])]
    kb = [_cell_key(*k) for k in zip(b["pulse"], b["sign"], b["amplitude"], b["frequency"])]
    a = a.assign(_k=ka)
    b = b.assign(_k=kb)
    m = a.merge(b.drop(columns=key + [c for c in ("near_boundary",) if c in b.columns]),
                on="_k", suffixes=("_a", "_b"))
    if not len(m):
        raise RockbenchError(
            f"the two maps have no cell in common (first: {len(a)} cells, A "
            f"{_span(a['amplitude'])}, W {_span(a['frequency'])}; second: {len(b)} cells, A "
            f"{_span(b['amplitude'])}, W {_span(b['frequency'])}): compare maps run on the "
            f"same grid (--grid, --amplitude, --frequency, --pulses)")
    m = m[(m["status_a"] == "ok") & (m["status_b"] == "ok")].reset_index(drop=True)
    va = m["overturned_a"].astype(bool).to_numpy()
    vb = m["overturned_b"].astype(bool).to_numpy()
    n = len(m)
    agree = float((va == vb).mean()) if n else math.nan
    kappa = math.nan
    if n:
        pa, pb = va.mean(), vb.mean()
        pe = pa * pb + (1 - pa) * (1 - pb)
        kappa = (agree - pe) / (1 - pe) if pe < 1 else math.nan
    common_a = m[key + ["overturned_a", "status_a"]].rename(
        columns={"overturned_a": "overturned", "status_a": "status"})
    common_b = m[key + ["overturned_b", "status_b"]].rename(
        columns={"overturned_b": "overturned", "status_b": "status"})
    ba = boundary(common_a).merge(boundary(common_b), on=["pulse", "sign", "frequency"],
                                  suffixes=("_a", "_b"))
    ba["shift"] = ba["a_min_b"] - ba["a_min_a"]
    has_near = "near_boundary" in m.columns
    near = (m["near_boundary"].fillna(False).astype(bool).to_numpy() if has_near
            else np.zeros(n, dtype=bool))
    cells = m[key].assign(overturned_a=va, overturned_b=vb, agree=va == vb, near_boundary=near)
    out = {"n": n, "fraction": agree, "kappa": float(kappa),
           "b_overturns_a_survives": int((vb & ~va).sum()),
           "a_overturns_b_survives": int((va & ~vb).sum()), "shift": ba, "cells": cells}
    if has_near:
        out.update(near_boundary=int(near.sum()),
                   disagree_near_boundary=int(((va != vb) & near).sum()),
                   disagree_away=int(((va != vb) & ~near).sum()))
    return out


def _span(x: pd.Series) -> str:
    return f"{float(x.min()):.4g}-{float(x.max()):.4g}" if len(x) else "none"


def describe_shift(shift: pd.DataFrame, name: str = "the engine") -> str:
    """Where a boundary sits relative to the reference, in words (per pulse)."""
    parts = []
    for (p, s), g in shift.groupby(["pulse", "sign"], sort=True):
        g = g.dropna(subset=["shift"])
        if not len(g):
            continue
        early = g[g["shift"] < 0]
        late = g[g["shift"] > 0]
        tag = f"{p} {'+' if s > 0 else '-'}"
        if not len(early) and not len(late):
            parts.append(f"{tag}: same boundary at every frequency")
            continue
        bits = []
        if len(early):
            bits.append(f"earlier (at smaller A, by up to {-early['shift'].min():.3g}) at W = "
                        + ", ".join(f"{w:.3g}" for w in early["frequency"]))
        if len(late):
            bits.append(f"later (by up to {late['shift'].max():.3g}) at W = "
                        + ", ".join(f"{w:.3g}" for w in late["frequency"]))
        parts.append(f"{tag}: {name} overturns " + "; ".join(bits))
    return "; ".join(parts) if parts else "no overturning boundary in both maps"

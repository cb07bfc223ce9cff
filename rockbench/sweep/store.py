"""The one result store: finished work kept on disk, resumable, keyed by the code that made it.

Two kinds of entries, one key scheme (:func:`key`: SHA-256 of the canonical JSON of a plain-data
item, 16 hex digits) and one writing rule (a temporary name, then an atomic ``os.replace``: a
file in the store is always complete; a killed process leaves only a ``.tmp-*`` file, ignored):

* **rows** (sweeps): ``DIR/part-<case_id>.parquet``, one row each (:func:`write_row`), merged
  at the end of a sweep into one ``compact-<uuid>.parquet`` (:func:`compact`);
  :func:`load_store` returns every row (the latest per case id). Why Parquet parts and not one
  appended CSV: cases of one sweep may have different keys (overrides, record vs pulse), which
  a fixed CSV header cannot hold; a killed process can leave a half-written CSV line; and types
  (bool, int, None) survive. Needs ``pyarrow`` (a core dependency).
* **payloads** (the campaign's comparisons: tables and thinned histories): one pickle per item,
  ``DIR/<key>.pkl`` (:func:`write_payload`, :func:`load_payload`).

:func:`code_fingerprint` hashes what decides a run's physics; the campaign keeps its store
under ``<store>/<fingerprint>/`` (``cases/`` for rows, ``comparisons/`` for payloads) so that
results of other code are never mixed in.

:func:`writer_lock` holds a store for one writing process (an ``flock`` on ``DIR/_lock``,
released by the kernel when the process dies, even by ``kill -9``): a second writer is refused
with a message naming the first one's process id.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import pickle
import uuid
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import ParameterError, RockbenchError, RockbenchWarning

__all__ = ["key", "canonical", "code_fingerprint", "store_dir", "default_store", "store_path",
           "need_pyarrow", "have_pyarrow",
           "write_row", "load_store", "compact", "write_payload", "load_payload", "writer_lock",
           "store_error", "quarantine"]


# =========================================================================================
# Keys
# =========================================================================================
def canonical(x: Any) -> Any:
    """Numbers as floats (so that 3, 3.0 and numpy.float64(3) hash alike), recursively."""
    if isinstance(x, dict):
        return {k: canonical(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [canonical(v) for v in x]
    if isinstance(x, bool) or x is None or isinstance(x, str):
        return x
    return float(x)


def key(item: Any) -> str:
    """The store key of a plain-data item: the first 16 hex digits of the SHA-256 of its
    canonical JSON (keys sorted): the same item gets the same key in any process, on any
    machine, in any key order."""
    text = json.dumps(canonical(item), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


#: What decides a run's physics, relative to the package: the analytic model, the engine
#: adapters, the scene model and its data files, and the measurements and metrics computed from
#: a run. Nothing else (command line, report, campaign, studies, testing; the plans and case
#: lists, which are inputs that the stores key on) enters the fingerprint, so editing a help
#: text or a figure keeps every stored result.
PHYSICS_CODE = ("analytic", "engines", "scene", "scenarios", "measure.py", "constants.py",
                "result.py", "comparison.py", "runner.py", "studies/sensitivity.py",
                "verdict.py", "run_length.py", "validity.py")


def fingerprint_files() -> list[str]:
    """The files :func:`code_fingerprint` hashes (paths relative to the package), sorted."""
    import rockbench

    root = Path(rockbench.__file__).resolve().parent
    out = []
    for f in sorted(root.rglob("*")):
        rel = f.relative_to(root).as_posix()
        if (f.is_file() and f.suffix in (".py", ".toml") and "__pycache__" not in rel
                and any(rel == p or rel.startswith(p + "/") for p in PHYSICS_CODE)
                and not (rel.startswith("scenarios/")          # plans and case lists are
                         and (f.name == "cases.toml" or f.name.endswith("-plan.toml")))):
            out.append(rel)
    return out


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """A short hash of what decides a run's physics (:data:`PHYSICS_CODE`: the files of
    :func:`fingerprint_files`) and of the versions of the installed engines."""
    import rockbench

    from ..engines import engine_versions

    root = Path(rockbench.__file__).resolve().parent
    h = hashlib.sha256()
    for rel in fingerprint_files():
        h.update(rel.encode())
        h.update((root / rel).read_bytes())
    h.update(json.dumps(engine_versions(), sort_keys=True).encode())  # imports no engine
    return h.hexdigest()[:12]


# =========================================================================================
# Files
# =========================================================================================
def store_dir(store: str | os.PathLike) -> Path:
    """``store`` as a Path; ParameterError when it exists and is not a directory."""
    p = Path(store)
    if p.exists() and not p.is_dir():
        raise ParameterError("store", str(store), "a directory (created if missing)")
    return p


def default_store(folder: str | os.PathLike) -> Path:
    """The store of a command whose outputs go to ``folder`` when it is given none:
    ``<folder>/store`` (the kinds inside it: :func:`store_path`)."""
    return store_dir(Path(folder) / "store")


def store_path(store: str | os.PathLike, kind: str, *, keyed: bool = True) -> Path:
    """Where the results of one ``kind`` (``"cases"``, ``"maps"``, ``"tradeoff"``...) live.

    ``<store>/<code fingerprint>/<kind>`` when ``keyed`` (results that a change of the
    physics code invalidates), ``<store>/<kind>`` otherwise (stores whose rows carry
    their own key).  ParameterError when ``store`` exists and is not a directory.
    """
    root = store_dir(store)
    return root / code_fingerprint() / kind if keyed else root / kind


def have_pyarrow() -> bool:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True


def need_pyarrow() -> None:
    """RockbenchError (one line, with the remedy) when pyarrow does not import."""
    if not have_pyarrow():
        raise RockbenchError("stores are written in Parquet and need pyarrow, a dependency of "
                             "rockbench that is not installed here: pip install pyarrow")


class writer_lock:
    """Context manager: hold ``directory`` (created if missing) for this process's writes, by
    an exclusive ``flock`` on ``directory/_lock`` (the leading underscore keeps Parquet readers
    from taking it for data). Another process holding it -> RockbenchError naming that process
    and the remedy. The kernel releases the lock when the holder exits or is killed."""

    def __init__(self, directory: Path, what: str = "store"):
        self.directory = Path(directory)
        self.what = what
        self._fd: int | None = None

    def __enter__(self) -> "writer_lock":
        path = self.directory / "_lock"
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            return self
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise store_error(self.directory, e, what=self.what) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            try:
                holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "?"
            except OSError:
                holder = "?"
            os.close(fd)
            raise RockbenchError(
                f"the {self.what} {self.directory} is being written by another process "
                f"(pid {holder}); wait until it finishes (it keeps every cell it computes, "
                f"and a rerun then reuses them), or give another --store") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        self._fd = fd
        return self

    def __exit__(self, *exc) -> None:
        if self._fd is not None:
            try:
                os.ftruncate(self._fd, 0)
            except OSError:
                pass
            # unlock explicitly before closing: a pool worker forked while the lock was held
            # shares its open file description, and closing this copy alone would leave the
            # store locked as long as that worker lives (a kept pool's workers outlive the
            # write)
            import fcntl

            try:
                fcntl.flock(self._fd, fcntl.LOCK_UN)
            except OSError:
                pass
            os.close(self._fd)
            self._fd = None


def store_error(path: Path, e: OSError, doing: str = "write", what: str = "store"
                ) -> RockbenchError:
    """One line for a store that cannot be written (or read): the folder, the system's reason
    and the remedy (a full disk: free space and run again, the finished work is kept; otherwise
    a folder you can write)."""
    import errno

    why = e.strerror or str(e)
    if e.errno in (errno.ENOSPC, errno.EDQUOT):
        remedy = ("free some disk space and run the same command again: every finished case "
                  "is kept in the store and the rerun resumes from it")
    else:
        remedy = "give a --store in a folder you can write (or make this one writable)"
    return RockbenchError(f"cannot {doing} the {what} {path}: {why}; {remedy}")


def _atomic(path: Path, write) -> Path:
    """Call ``write(tmp)`` on a temporary name beside ``path``, then rename it to ``path``; an
    operating-system failure (full disk, read-only folder) is a one-line
    :func:`store_error` and leaves no temporary file."""
    tmp = path.with_name(f".tmp-{path.stem}-{os.getpid()}-{uuid.uuid4().hex[:8]}{path.suffix}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write(tmp)
        os.replace(tmp, path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise store_error(path.parent, e) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


# =========================================================================================
# Rows: a directory of small Parquet files
# =========================================================================================
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


def write_row(directory: Path, row: dict[str, Any]) -> Path:
    """Write one row to ``directory/part-<case_id>.parquet`` atomically."""
    return _atomic(directory / f"part-{row['case_id']}.parquet",
                   lambda tmp: _parquet_safe(pd.DataFrame([row])).to_parquet(tmp, index=False))


def write_table(path: str | os.PathLike, df: pd.DataFrame) -> Path:
    """Write a table of store rows to one Parquet file ``path`` atomically (mixed-type columns
    made storable as the store's rows are)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return _atomic(path, lambda tmp: _parquet_safe(df).to_parquet(tmp, index=False))


def _store_files(directory: Path) -> list[Path]:
    if not directory.is_dir():
        return []
    compacted = sorted(directory.glob("compact-*.parquet"), key=lambda p: p.stat().st_mtime)
    parts = sorted(directory.glob("part-*.parquet"), key=lambda p: p.stat().st_mtime)
    return compacted + parts


def quarantine(directory: Path, f: Path, why: str, *, move: bool, what: str = "store") -> None:
    """Say (a warning, one line) that file ``f`` of a store cannot be read and that its cases
    run again; with ``move`` (the writer, who holds the lock) move it to
    ``directory/_quarantine/``, out of the way of the next readers."""
    import warnings

    if move:
        q = directory / "_quarantine"
        try:
            q.mkdir(exist_ok=True)
            os.replace(f, q / f.name)
        except OSError as e:
            raise store_error(directory, e, what=what) from None
        warnings.warn(f"{what} {directory}: {f.name} is unreadable ({why}); moved it to {q} "
                      f"and its cases run again", RockbenchWarning, stacklevel=3)
    else:
        warnings.warn(f"{what} {directory}: skipped {f.name}, which is unreadable ({why}); "
                      f"its cases run again", RockbenchWarning, stacklevel=3)


def load_store(store: str | os.PathLike, *, damaged: str = "warn") -> pd.DataFrame:
    """Every row of a sweep store (one per case id; the latest wins), or an empty frame. A file
    that cannot be read is skipped (its cases run again): ``damaged="warn"`` says so in a
    warning, ``"move"`` (the writer, holding :class:`writer_lock`) also moves it to
    ``_quarantine/``, ``"quiet"`` says nothing (a caller that reads again as the writer)."""
    need_pyarrow()
    d = store_dir(store)
    frames = []
    for f in _store_files(d):
        try:
            frames.append(pd.read_parquet(f))
        except ImportError:
            raise
        except Exception as e:  # truncated, corrupted, foreign: its cases run again, said
            if damaged != "quiet":
                quarantine(d, f, f"{type(e).__name__}: {' '.join(str(e).split())[:100]}",
                           move=damaged == "move")
            continue
    frames = [f for f in frames if len(f)]
    if not frames:
        return pd.DataFrame(columns=["case_id"])
    df = pd.concat(frames, ignore_index=True)
    return df.drop_duplicates("case_id", keep="last").reset_index(drop=True)


def compact(directory: Path) -> None:
    """Merge the store's files into one ``compact-<uuid>.parquet`` (written atomically before
    the merged files are removed; an interruption leaves duplicates, which loading drops)."""
    files = _store_files(directory)
    if len(files) < 2:
        return
    df = _parquet_safe(load_store(directory))
    try:
        _atomic(directory / f"compact-{uuid.uuid4().hex[:12]}.parquet",
                lambda tmp: df.to_parquet(tmp, index=False))
    except Exception:  # keep the parts: correct, only slower to load
        return
    for f in files:
        f.unlink(missing_ok=True)


# =========================================================================================
# Payloads: one pickle per item
# =========================================================================================
def write_payload(directory: Path, item_key: str, payload: Any) -> Path:
    """Write ``payload`` to ``directory/<item_key>.pkl`` atomically."""
    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            pickle.dump(payload, f, protocol=pickle.HIGHEST_PROTOCOL)

    return _atomic(directory / f"{item_key}.pkl", write)


def load_payload(directory: Path, item_key: str) -> Any:
    """The payload stored under ``item_key``, or None (missing or unreadable: run it again)."""
    try:
        with open(directory / f"{item_key}.pkl", "rb") as f:
            return pickle.load(f)
    except Exception:
        return None

"""Loaders for ground-motion record files, returning :class:`rockbench.scene.motion.Record`.

Two formats (see ``shared/records/PROVENANCE.md``):

* PEER AT2 (:func:`load_at2`): a text header whose line with ``NPTS`` and ``DT`` gives the
  number of samples and the time step [s], followed by the samples in units of g, any number per
  line. Both the old PEER layout (``NPTS=  4000, DT= .01000 SEC``, text may follow) and the
  NGA-West2 layout (``  4000   0.0100   NPTS, DT``) are recognised. g is converted with
  :data:`rockbench.constants.G_STANDARD` so published PGAs are reproduced.
* Headerless columns (:func:`load_columns`): whitespace-separated samples, any number per line,
  read row-major (e.g. the SAC ``LA*.dat`` files, 6 per line, cm/s^2); the time step and units
  are given by the caller. A file of two numbers per line whose first column is a time column
  (``t a``) is recognised and read as times and accelerations; its times must increase
  uniformly with the given time step (see :func:`load_columns`).

Shape checks (``docs/errors.md``): a file must be a regular file of at most
``ROCKBENCH_RECORD_BYTES`` (:mod:`rockbench.limits`, 100 MB); the AT2 header count NPTS must
equal the number of values; :func:`load_record` refuses a time step outside (1e-4, 0.1) s
(limit ``record_dt``).

:func:`load_record` picks the loader from the file suffix. Every failure raises
:class:`~rockbench.errors.RecordError` naming the file (and the line, for a bad value) or
:class:`~rockbench.errors.ParameterError` naming the bad argument.
"""

from __future__ import annotations

import csv
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError, RecordError, check_finite, check_positive
from ..limits import check_in_limit, limit, override_hint
from .motion import Record, unit_factor

__all__ = ["load_at2", "load_columns", "load_record", "find_records", "listed_metadata"]

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][+-]?\d+)?"
#: Old PEER: "NPTS=   7818, DT=   .0050 SEC, ..."; NPTS and DT may come in either order.
_NPTS_KEY = re.compile(r"\bNPTS\s*=\s*(\d+)", re.IGNORECASE)
_DT_KEY = re.compile(rf"\bDT\s*=\s*({_NUMBER})", re.IGNORECASE)
#: NGA-West2: "  4000    0.0100    NPTS, DT ..."
_NGA_LINE = re.compile(rf"^\s*(\d+)\s*,?\s+({_NUMBER})\s+NPTS\s*,\s*DT\b", re.IGNORECASE)
_UNITS = re.compile(r"\bUNITS\s+OF\s+([A-Za-z][A-Za-z/^0-9*]*)", re.IGNORECASE)


def load_at2(path: str | os.PathLike, *, name: str | None = None) -> Record:
    """Read a PEER AT2 file (accelerations in g) into a :class:`Record` in m/s^2.

    The sample times are ``k * DT``, k = 0..NPTS-1 [s]. ``name`` defaults to the file stem;
    ``source`` holds the header lines joined with " | ".
    """
    path, lines = _read_lines(path)
    for k, line in enumerate(lines):
        header = _match_npts_dt(line)
        if header is not None:
            break
    else:
        raise RecordError(f"record file {path}: no header line with NPTS and DT "
                          "(is it a PEER AT2 file?)")
    npts, dt_text = header
    dt = _to_float(dt_text)
    if not (math.isfinite(dt) and dt > 0.0):
        raise RecordError(f"record file {path}, line {k + 1}: DT={dt_text} must be > 0 [s]")
    head = [h.strip() for h in lines[: k + 1]]
    units = _UNITS.search(" ".join(head))
    if units is not None and units.group(1).upper() != "G":
        raise RecordError(f"record file {path}: units {units.group(1)!r} in the header; "
                          "AT2 files must be in units of G")
    values = _parse_values(path, lines, k + 1)
    if values.size != npts:
        raise RecordError(f"record file {path}: header line {k + 1} says NPTS={npts} "
                          f"but {values.size} values follow")
    _check_enough(path, values)
    return Record.from_samples(values, dt, units="g", name=path.stem if name is None else name,
                               source=" | ".join(h for h in head if h))


def load_columns(path: str | os.PathLike, *, dt: float, units: str, t0: float = 0.0,
                 name: str | None = None) -> Record:
    """Read a headerless file of whitespace-separated samples (any number per line, read
    row-major) with time step ``dt`` > 0 [s], first sample at ``t0`` [s], in ``units``
    ("g", "m/s2" or "cm/s2"). Blank lines and lines starting with ``#`` are skipped.
    ``name`` defaults to the file stem.

    A file of exactly two numbers on every line (at least 3 lines) whose first column looks
    like time is a ``t a`` file: first column times [s], second accelerations. Its times must
    be strictly increasing and uniformly spaced (each within 1 % of ``dt`` of the grid
    ``t[0] + k dt``) with a spacing equal to ``dt`` (to 0.1 %); the record then starts at
    ``t[0]`` (``t0`` is not used). Otherwise :class:`RecordError` names the line. A first
    column "looks like time" if it is strictly increasing with nearly constant steps, or, once
    sorted, has equal non-zero steps (shuffled times), or is non-negative and mostly (80 %)
    increasing.
    """
    dt = check_positive("dt", dt)
    t0 = check_finite("t0", t0)
    unit_factor(units)
    path, lines = _read_lines(path)
    rows = _parse_rows(path, lines, 0)
    timed = _time_column(path, rows, dt)
    if timed is not None:
        times, acc = timed
        return Record.from_samples(acc, dt, t0=float(times[0]), units=units,
                                   name=path.stem if name is None else name,
                                   source=f"{path.name} (t a columns, dt={dt:g} s, "
                                          f"units={units})")
    values = np.array([v for _, row in rows for v in row], dtype=float)
    _check_enough(path, values)
    return Record.from_samples(values, dt, t0=t0, units=units,
                               name=path.stem if name is None else name,
                               source=f"{path.name} (dt={dt:g} s, units={units})")


def load_record(path: str | os.PathLike, *, dt: float | None = None, units: str | None = None,
                scale: float = 1.0) -> Record:
    """Load a record by file type: ``.AT2`` (any case) with :func:`load_at2`, anything else with
    :func:`load_columns`, which needs ``dt`` [s] and ``units``. The result is multiplied by
    ``scale`` (finite, non-zero) when it is not 1.

    A headerless file listed in a ``records.csv`` beside it (see :func:`find_records`) takes
    its dt and units from there unless they are given.

    Errors name the command-line options: ``record-dt``, ``record-units``, ``record-scale``.
    For an AT2 file, ``dt`` and ``units`` may be omitted; if given they must agree with the file
    (DT of the header, units of g). The time step (given or from the header) must be in
    (1e-4, 0.1) s (limit ``record_dt`` of :mod:`rockbench.limits`, env
    ``ROCKBENCH_RECORD_DT``).
    """
    scale = check_finite("record-scale", scale)
    if scale == 0.0:
        raise ParameterError("record-scale", scale, "a finite, non-zero real number")
    path = Path(path)
    if path.suffix.lower() == ".at2":
        record = load_at2(path)
        if dt is not None and not math.isclose(check_positive("record-dt", dt), record.dt,
                                                rel_tol=1e-9):
            raise ParameterError("record-dt", dt,
                                 f"omitted or equal to the file's DT = {record.dt:g} s",
                                 f"{path.name} gives its own time step")
        if units is not None and units != "g":
            raise ParameterError("record-units", units, "omitted or 'g'",
                                 f"AT2 file {path.name} is in units of g")
        check_in_limit("record_dt", f"DT of {path.name}", record.dt)
    else:
        listed = listed_metadata(path) if (dt is None or units is None) else None
        if listed is not None:        # dt and units from the records.csv beside the file
            dt = listed["dt"] if dt is None else dt
            units = listed["units"] if units is None else units
        if dt is None:
            raise ParameterError("record-dt", None, "> 0 [s]",
                                 f"required for the headerless record file {path.name}")
        if units is None:
            raise ParameterError("record-units", None, "one of 'g', 'm/s2', 'cm/s2'",
                                 f"required for the headerless record file {path.name}")
        dt = check_in_limit("record_dt", "record-dt", dt)
        unit_factor(units, "record-units")
        record = load_columns(path, dt=dt, units=units)
    return record if scale == 1.0 else record.scaled(scale)


_UNIT_WORDS = (("cm/s", "cm/s2"), ("m/s", "m/s2"), ("g", "g"))


def _units_of(text: Any) -> str:
    t = str(text or "").strip().lower()
    for key, units in _UNIT_WORDS:
        if t.startswith(key):
            return units
    return "cm/s2"


def _read_listing(csv_path: Path) -> dict[str, dict[str, Any]]:
    """``records.csv`` as {file stem: {"dt": s, "units": ...}}; RecordError if unreadable or
    without a dt column (``dt_s`` or ``dt``)."""
    try:
        with open(csv_path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise RecordError(f"{csv_path}: unreadable ({e})") from None
    if not rows:
        return {}
    cols = {c.lower().strip(): c for c in rows[0] if c}
    name_col = cols.get("record") or cols.get("name") or next(iter(rows[0]))
    dt_col = cols.get("dt_s") or cols.get("dt")
    unit_col = cols.get("units") or cols.get("unit")
    if dt_col is None:
        raise RecordError(f"{csv_path}: no dt column (dt_s or dt)")
    out = {}
    for r in rows:
        try:
            dt = float(r[dt_col])
        except (TypeError, ValueError):
            raise RecordError(f"{csv_path}: record {r.get(name_col)!r} has dt "
                              f"{r.get(dt_col)!r}, not a number") from None
        out[str(r[name_col]).strip()] = {
            "dt": dt, "units": _units_of(r[unit_col]) if unit_col else "cm/s2"}
    return out


def listed_metadata(path: str | os.PathLike) -> dict[str, Any] | None:
    """dt [s] and units of a headerless record file from the ``records.csv`` beside it
    (columns ``record`` = file stem, ``dt_s`` or ``dt``, ``units``), or None if it is not
    listed there."""
    p = Path(path)
    listing = p.parent / "records.csv"
    if not listing.is_file():
        return None
    return _read_listing(listing).get(p.stem)


def find_records(records_dir: str | os.PathLike) -> tuple[list[dict[str, Any]], list[str]]:
    """Record files under ``records_dir`` (searched recursively), sorted by name: PEER
    ``.AT2`` files (dt and units from their header) and headerless files listed in a
    ``records.csv`` next to them (columns: ``record`` = file stem, ``dt_s`` or ``dt`` [s], and
    ``units``: "cm/s^2..." / "m/s^2..." / "g"; cm/s^2 when absent).

    Returns (records, notes): each record a dict name, path, dt [s] or None, units or None;
    notes say which files were skipped and why.
    """
    root = Path(records_dir)
    if not root.is_dir():
        raise ParameterError("records_dir", str(records_dir), "an existing folder of record "
                                                              "files (.AT2, or files listed "
                                                              "in a records.csv)")
    records, notes = [], []
    tables: dict[Path, dict[str, dict[str, Any]]] = {}
    for listing in sorted(root.rglob("records.csv")):
        try:
            tables[listing.parent] = _read_listing(listing)
        except RecordError as e:
            notes.append(f"{e}; its files are skipped")
    for p in sorted(root.rglob("*"), key=lambda q: (q.stem.lower(), str(q))):
        if not p.is_file() or p.name == "records.csv" or p.suffix.lower() in (".md", ".csv"):
            continue
        if p.suffix.lower() == ".at2":
            records.append({"name": p.stem, "path": str(p.resolve()), "dt": None,
                            "units": None})
            continue
        entry = tables.get(p.parent, {}).get(p.stem)
        if entry is None:
            notes.append(f"{p.name}: skipped (not an .AT2 file and not listed in a "
                         f"records.csv with its dt)")
            continue
        records.append({"name": p.stem, "path": str(p.resolve()), "dt": entry["dt"],
                        "units": entry["units"]})
    return records, notes


# ------------------------------------------------------------------------------------------------
def _read_lines(path: str | os.PathLike) -> tuple[Path, list[str]]:
    """The file's lines; RecordError naming the file if it cannot be read or is empty."""
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            raise RecordError(f"record file {path} is not a regular file")
        size = path.stat().st_size
    except OSError as exc:
        raise RecordError(f"cannot read record file {path}: {exc.strerror or exc}") from None
    _, max_bytes = limit("record_bytes")
    if size > max_bytes:
        raise RecordError(f"record file {path} has {size} bytes, more than {max_bytes:g} "
                          f"({override_hint('record_bytes')})")
    try:
        text = path.read_text(encoding="ascii", errors="strict")
    except UnicodeDecodeError as exc:
        raise RecordError(f"record file {path}: not plain ASCII text (byte {exc.start})") from None
    except OSError as exc:
        raise RecordError(f"cannot read record file {path}: {exc.strerror or exc}") from None
    if not text.strip():
        raise RecordError(f"record file {path} is empty")
    return path, text.splitlines()


def _match_npts_dt(line: str) -> tuple[int, str] | None:
    """(NPTS, DT text) if ``line`` is an AT2 header line giving both, else None."""
    nga = _NGA_LINE.match(line)
    if nga is not None:
        return int(nga.group(1)), nga.group(2)
    npts, dt = _NPTS_KEY.search(line), _DT_KEY.search(line)
    if npts is not None and dt is not None:
        return int(npts.group(1)), dt.group(1)
    return None


def _to_float(token: str) -> float:
    """Parse a number, accepting Fortran's D exponent (1.0D-03)."""
    return float(token.replace("D", "E").replace("d", "e"))


def _parse_values(path: Path, lines: list[str], start: int) -> np.ndarray:
    """All numbers on ``lines[start:]``, row-major; RecordError naming the file and 1-based line
    of the first token that is not a finite number."""
    return np.array([v for _, row in _parse_rows(path, lines, start) for v in row], dtype=float)


def _parse_rows(path: Path, lines: list[str], start: int) -> list[tuple[int, list[float]]]:
    """(1-based line number, numbers) of every data line of ``lines[start:]`` (blank lines and
    ``#`` comments skipped); RecordError naming the file and line of the first token that is
    not a finite number."""
    rows: list[tuple[int, list[float]]] = []
    for k in range(start, len(lines)):
        line = lines[k].strip()
        if not line or line.startswith("#"):
            continue
        row = []
        for token in line.split():
            try:
                x = _to_float(token)
            except ValueError:
                raise RecordError(f"record file {path}, line {k + 1}: {token!r} is not a number"
                                  ) from None
            if not math.isfinite(x):
                raise RecordError(f"record file {path}, line {k + 1}: value {token!r} is not "
                                  "finite")
            row.append(x)
        rows.append((k + 1, row))
    return rows


def _time_column(path: Path, rows: list[tuple[int, list[float]]], dt: float
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """(times, accelerations) of a ``t a`` file, None for a file of samples; RecordError if
    the first column looks like time but is not strictly increasing, uniform, or spaced by
    ``dt`` [s] (rules: :func:`load_columns`)."""
    if len(rows) < 3 or any(len(r) != 2 for _, r in rows):
        return None
    t = np.array([r[0] for _, r in rows])
    a = np.array([r[1] for _, r in rows])
    steps = np.diff(t)
    span = float(t[-1] - t[0])
    increasing = bool(np.all(steps > 0))
    med = float(np.median(steps))
    sorted_steps = np.diff(np.sort(t))
    smed = float(np.median(sorted_steps))
    uniform_when_sorted = smed > 0 and bool(
        np.all(np.abs(sorted_steps - smed) <= 0.01 * smed))
    mostly_up = bool(np.mean(steps > 0) >= 0.8) and float(t.min()) >= 0.0
    nearly_regular = increasing and med > 0 and bool(
        np.all(np.abs(steps - med) <= 0.5 * med))
    if not (nearly_regular or uniform_when_sorted or mostly_up):
        return None
    what = f"record file {path}: two columns read as time [s] and acceleration"
    if not increasing:
        i = int(np.argmin(steps > 0))
        raise RecordError(f"{what}, but the time on line {rows[i + 1][0]} ({t[i + 1]:g}) is not "
                          f"after the time on line {rows[i][0]} ({t[i]:g}): times must "
                          "increase (for samples only, write another number of values per "
                          "line)")
    step = span / (len(t) - 1)
    off = np.abs(t - (t[0] + step * np.arange(len(t))))
    i = int(np.argmax(off))
    if off[i] > 0.01 * step:
        raise RecordError(f"{what}, but the times are not uniformly spaced: line {rows[i][0]} "
                          f"has t = {t[i]:g}, {off[i]:.3g} s off the grid of step {step:g} s")
    if not math.isclose(step, dt, rel_tol=1e-3):
        raise RecordError(f"{what}, but the time step of the file ({step:g} s) differs from "
                          f"record-dt = {dt:g} s")
    return t, a


def _check_enough(path: Path, values: np.ndarray) -> None:
    if values.size < 2:
        raise RecordError(f"record file {path}: {values.size} acceleration value(s); "
                          "a record needs at least 2")


# ------------------------------------------------------------------------------------------------
# Records shipped inside the package (issue 14): rockbench/records/, provenance in its PROVENANCE.md
def _bundled_dir() -> Path:
    """The package-data folder of the bundled records (``rockbench/records``)."""
    from importlib.resources import files

    return Path(str(files("rockbench") / "records"))


def bundled_records() -> list[dict[str, Any]]:
    """The public-domain records shipped inside the package (``rockbench/records/``; why each
    may be shipped: ``rockbench/records/PROVENANCE.md``, ``docs/records.md``), sorted by name.

    Each is a dict ``name`` (file stem, the key of :func:`load_bundled`), ``path`` (absolute),
    ``dt`` and ``units`` (None for AT2 files: their header gives them), as
    :func:`find_records` returns them. Needs nothing outside the installed package.
    """
    records, _ = find_records(_bundled_dir())
    return records


def load_bundled(name: str) -> Record:
    """The bundled record ``name`` (a file stem of :func:`bundled_records`, case-insensitive,
    e.g. ``"IV1940_ElCentro_180"``) as a :class:`Record` in m/s^2. ParameterError listing the
    bundled names for any other value."""
    records = bundled_records()
    key = str(name).strip().lower() if isinstance(name, str) else None
    for r in records:
        if key is not None and r["name"].lower() in (key, key.removesuffix(".at2")):
            return load_record(r["path"], dt=r["dt"], units=r["units"])
    raise ParameterError("name", name, "one of the bundled records: "
                         + ", ".join(r["name"] for r in records))


__all__ += ["bundled_records", "load_bundled"]

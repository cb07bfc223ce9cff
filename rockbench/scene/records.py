"""Loaders for ground-motion record files, returning :class:`rockbench.scene.motion.Record`.

Two formats (see ``shared/records/PROVENANCE.md``):

* PEER AT2 (:func:`load_at2`): a text header whose line with ``NPTS`` and ``DT`` gives the
  number of samples and the time step [s], followed by the samples, any number per line, in
  the units the header states (``UNITS OF G``, ``UNITS: CM/S^2``, ...: every spelling of
  :mod:`rockbench.scene.units`; an unknown unit is refused, none needs ``units``). Both the old
  PEER layout (``NPTS=  4000, DT= .01000 SEC``, text may follow) and the NGA-West2 layout
  (``  4000   0.0100   NPTS, DT``) are recognised. g is converted with
  :data:`rockbench.constants.G_STANDARD` so published PGAs are reproduced.
* Headerless columns (:func:`load_columns`): whitespace-separated samples, any number per line,
  read row-major (e.g. the SAC ``LA*.dat`` files, 6 per line, cm/s^2); the time step and units
  are given by the caller. A file of two numbers per line whose first column is a time column
  (``t a``) is recognised and read as times and accelerations; its times must increase
  uniformly with the given time step (see :func:`load_columns`).

Shape checks (``docs/errors.md``): a file must be a regular file of at most
``ROCKBENCH_RECORD_BYTES`` (:mod:`rockbench.limits`, 100 MB) holding at most
``record_samples`` (2e6) values, parsed in blocks so that memory stays bounded whatever the
file holds; the AT2 header count NPTS must equal the number of values; :func:`load_record` refuses a time step outside (1e-4, 0.1) s
(limit ``record_dt``).

:func:`load_record` picks the loader from the file suffix. Every failure raises
:class:`~rockbench.errors.RecordError` naming the file (and the line, for a bad value) or
:class:`~rockbench.errors.ParameterError` naming the bad argument.
"""

from __future__ import annotations

import csv
import math
import os
from pathlib import Path
from typing import Any


from ..errors import ParameterError, RecordError, check_finite, check_positive
from ..limits import check_in_limit, limit, override_hint
from .motion import UNIT_SPELLINGS, Record, parse_units
from .record_parse import (_check_enough, _check_path, _header_units, _leading_units,
                           _open_record, _read_header, _scan, _time_column, _to_float)

__all__ = ["load_at2", "load_columns", "load_record", "find_records", "listed_metadata"]

def load_at2(path: str | os.PathLike, *, name: str | None = None,
             units: str | None = None) -> Record:
    """Read a PEER AT2 file into a :class:`Record` in m/s^2.

    The header (the lines up to the one with NPTS and DT, at most :data:`HEADER_LINES`) must
    state the units of the accelerations (``ACCELERATION TIME HISTORY IN UNITS OF G``,
    ``UNITS: CM/S^2``, ``UNITS = gal``, ``ACCELERATION IN CM/S/S``, ...: every spelling of
    :func:`~rockbench.scene.motion.parse_units`); a unit it does not know is refused with a
    :class:`RecordError` naming it and listing the accepted spellings. A header that states no
    units takes ``units`` (required then); a header that states them must agree with
    ``units`` if it is given. The sample times are ``k * DT``, k = 0..NPTS-1 [s]; NPTS is
    checked against the limit ``record_samples`` before any value is read, and the values are
    parsed in blocks (memory bounded by NPTS). ``name`` defaults to the file stem;
    ``source`` holds the header lines joined with " | ".
    """
    path = _check_path(path)
    with _open_record(path) as f:
        head, npts, dt_text = _read_header(path, f)
        k = len(head)
        dt = _to_float(dt_text)
        if not (math.isfinite(dt) and dt > 0.0):
            raise RecordError(f"record file {path}, line {k}: DT={dt_text} must be > 0 [s]")
        stated = _header_units(path, head)
        if units is not None:
            given = parse_units(units, "record-units")
            if stated is not None and given != stated[0]:
                raise ParameterError("record-units", units,
                                     f"omitted or the header's units ({stated[1]!r})",
                                     f"{path.name} states its units")
            stated = stated or (given, units)
        if stated is None:
            raise RecordError(f"record file {path}: the header (lines 1-{k}) states no units of "
                              "acceleration (such as 'UNITS OF G' or 'UNITS: CM/S^2'); give "
                              "them with --record-units (units=)")
        _, most = limit("record_samples")
        if npts > most:
            raise RecordError(f"record file {path}: header line {k} says NPTS={npts}, more than "
                              f"{most:g} samples ({override_hint('record_samples')})")
        scan = _scan(path, f, k + 1, keep=npts)
    if scan.total != npts:
        raise RecordError(f"record file {path}: header line {k} says NPTS={npts} "
                          f"but {scan.total} values follow")
    _check_enough(path, scan.values)
    lines = [h.strip() for h in head]
    return Record.from_samples(scan.values, dt, units=stated[0],
                               name=path.stem if name is None else str(name),
                               source=" | ".join(h for h in lines if h))


def load_columns(path: str | os.PathLike, *, dt: float, units: str, t0: float = 0.0,
                 name: str | None = None) -> Record:
    """Read a headerless file of whitespace-separated samples (any number per line, read
    row-major) with time step ``dt`` > 0 [s], first sample at ``t0`` [s], in ``units`` (any
    spelling of :func:`~rockbench.scene.motion.parse_units`: "g", "gal", "m/s^2", "cm/s2",
    "CM/S/S", ...). Blank lines and lines starting with ``#`` are skipped. ``name`` defaults
    to the file stem. The file is parsed in blocks and refused as soon as it holds more values
    than the limit ``record_samples`` (:mod:`rockbench.limits`).

    A file of exactly two numbers on every line (at least 3 lines) whose first column looks
    like time is a ``t a`` file: first column times [s], second accelerations. Its times must
    be strictly increasing and uniformly spaced (each within 1 % of ``dt`` of the grid
    ``t[0] + k dt``) with a spacing equal to ``dt`` (to 0.1 %); the record then starts at
    ``t[0]`` (``t0`` is not used). Otherwise :class:`RecordError` names the line. A first
    column "looks like time" if it is strictly increasing with nearly constant steps, or, once
    sorted, has equal non-zero steps (shuffled times), or is non-negative and mostly (80 %)
    increasing.
    """
    path = _check_path(path)
    dt = check_positive("dt", dt)
    t0 = check_finite("t0", t0)
    units = parse_units(units)
    name = path.stem if name is None else str(name)
    with _open_record(path) as f:
        scan = _scan(path, f, 1, keep=None, rows=True)
    if scan.blank:
        raise RecordError(f"record file {path} is empty")
    _, most = limit("record_samples")
    timed = _time_column(path, scan, dt)
    if timed is not None:
        times, acc = timed
        return Record.from_samples(acc, dt, t0=float(times[0]), units=units, name=name,
                                   source=f"{path.name} (t a columns, dt={dt:g} s, "
                                          f"units={units})")
    if scan.total > most:
        raise RecordError(f"record file {path} holds {scan.total} values, more than {most:g} "
                          f"samples ({override_hint('record_samples')})")
    _check_enough(path, scan.values)
    return Record.from_samples(scan.values, dt, t0=t0, units=units, name=name,
                               source=f"{path.name} (dt={dt:g} s, units={units})")


def load_record(path: str | os.PathLike, *, dt: float | None = None, units: str | None = None,
                scale: float = 1.0, vertical: str | os.PathLike | None = None,
                vertical_dt: float | None = None,
                vertical_units: str | None = None) -> Record:
    """Load a record by file type: ``.AT2`` (any case) with :func:`load_at2`, anything else with
    :func:`load_columns`, which needs ``dt`` [s] and ``units``. The result is multiplied by
    ``scale`` (finite, non-zero) when it is not 1.

    ``vertical``: the file of the vertical channel (positive up), read the same way (its own
    ``vertical_dt`` [s] and ``vertical_units`` for a headerless file; errors name
    ``record-vertical``), attached with :meth:`Record.with_vertical` (sampled at the horizontal
    channel's times) and multiplied by the same ``scale``.

    A headerless file listed in a ``records.csv`` beside it (see :func:`find_records`) takes
    its dt and units from there unless they are given.

    Errors name the command-line options: ``record-dt``, ``record-units``, ``record-scale``.
    For an AT2 file, ``dt`` and ``units`` may be omitted; if given they must agree with the file
    (DT of the header; the units its header states, in any spelling of
    :func:`~rockbench.scene.motion.parse_units`). The time step (given or from the header) must
    be in (1e-4, 0.1) s (limit ``record_dt`` of :mod:`rockbench.limits`, env
    ``ROCKBENCH_RECORD_DT``).
    """
    path = _check_path(path)
    scale = check_finite("record-scale", scale)
    if scale == 0.0:
        raise ParameterError("record-scale", scale, "a finite, non-zero real number")
    if dt is not None:
        check_positive("record-dt", dt)
    if units is not None:
        parse_units(units, "record-units")
    if path.suffix.lower() == ".at2":
        record = load_at2(path, units=units)
        if dt is not None and not math.isclose(float(dt), record.dt, rel_tol=1e-9):
            raise ParameterError("record-dt", dt,
                                 f"omitted or equal to the file's DT = {record.dt:g} s",
                                 f"{path.name} gives its own time step")
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
            raise ParameterError("record-units", None, "an acceleration unit: "
                                 + ", ".join(UNIT_SPELLINGS),
                                 f"required for the headerless record file {path.name}")
        dt = check_in_limit("record_dt", "record-dt", dt)
        record = load_columns(path, dt=dt, units=parse_units(units, "record-units"))
    if vertical is not None:
        vpath = _check_path(vertical, "record-vertical")
        try:
            vrec = load_record(vpath, dt=vertical_dt, units=vertical_units)
        except ParameterError as exc:
            # the vertical file's own options: name them as such
            name = {"record-dt": "record-vertical-dt", "record-units": "record-vertical-units"
                    }.get(exc.name, "record-vertical")
            raise ParameterError(name, exc.value, exc.valid, f"vertical channel {vpath.name}"
                                 ) from None
        record = record.with_vertical(vrec)
    return record if scale == 1.0 else record.scaled(scale)


def _units_of(text: Any, where: str) -> str:
    """Canonical units of a ``records.csv`` cell (its first words, e.g. "cm/s^2 (already
    scaled)"); cm/s^2 for an empty cell; RecordError naming ``where`` for an unknown unit."""
    t = str(text or "").strip()
    if not t:
        return "cm/s2"
    found = _leading_units(t)
    if found is None:
        raise RecordError(f"{where}: units {t.split()[0]!r} are not an acceleration unit "
                          f"(accepted: {', '.join(UNIT_SPELLINGS)})")
    return found[0]


def _read_listing(csv_path: Path) -> dict[str, dict[str, Any]]:
    """``records.csv`` as {file stem: {"dt": s or None, "units": ..., "vertical": stem or
    None}}; RecordError if unreadable, or with a dt that is not a number. A row's dt may be
    empty (an AT2 file's header gives its own; a headerless file needs one:
    :func:`find_records` says so); ``vertical`` (optional column) names the file stem of the
    record's vertical channel in the same folder (its file name or stem)."""
    try:
        size = csv_path.stat().st_size
        _, max_bytes = limit("record_bytes")
        if size > max_bytes:
            raise RecordError(f"{csv_path} has {size} bytes, more than {max_bytes:g} "
                              f"({override_hint('record_bytes')})")
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
    vert_col = cols.get("vertical")
    if dt_col is None and vert_col is None:
        raise RecordError(f"{csv_path}: no dt column (dt_s or dt)")
    out = {}
    for r in rows:
        text = str(r.get(dt_col) or "").strip() if dt_col is not None else ""
        try:
            dt = float(text) if text else None
        except ValueError:
            raise RecordError(f"{csv_path}: record {r.get(name_col)!r} has dt "
                              f"{r.get(dt_col)!r}, not a number") from None
        entry = {"dt": dt, "units": _units_of(r[unit_col], f"{csv_path}: record "
                                              f"{r.get(name_col)!r}") if unit_col else "cm/s2"}
        vert = str(r.get(vert_col) or "").strip() if vert_col is not None else ""
        if vert:
            entry["vertical"] = vert
        out[str(r[name_col]).strip()] = entry
    return out


def listed_metadata(path: str | os.PathLike) -> dict[str, Any] | None:
    """dt [s] and units of a headerless record file from the ``records.csv`` beside it
    (columns ``record`` = file stem, ``dt_s`` or ``dt``, ``units``), or None if it is not
    listed there; a listed vertical channel (column ``vertical``) adds ``vertical`` (its path),
    ``vertical_dt`` and ``vertical_units`` (:func:`find_records`)."""
    p = _check_path(path)
    listing = p.parent / "records.csv"
    if not listing.is_file():
        return None
    table = _read_listing(listing)
    entry = table.get(p.stem)
    if entry is None:
        return None
    out = {"dt": entry["dt"], "units": entry["units"]}
    if entry.get("vertical"):
        out.update(_vertical_of(listing, table, p.stem, entry))
    return out


def _vertical_of(listing: Path, table: dict[str, dict[str, Any]], name: str,
                 entry: dict[str, Any]) -> dict[str, Any]:
    """``vertical`` (the resolved path), ``vertical_dt`` [s] and ``vertical_units`` of the
    vertical channel that ``listing`` names for record ``name`` (a file stem beside it): an AT2
    file's header gives its own; a headerless one takes its own line of the listing, else the
    record's (two components of one station share the time base). RecordError when the file
    is not there, is ambiguous, or is the record itself."""
    stem = entry["vertical"]
    found = [q for q in listing.parent.iterdir() if q.is_file() and stem in (q.name, q.stem)
             and q.suffix.lower() not in (".md", ".csv")]
    if stem == name or any(q.stem == name for q in found):
        raise RecordError(f"{listing}: record {name!r} names itself as its vertical channel")
    if len(found) != 1:
        raise RecordError(f"{listing}: record {name!r} names the vertical channel {stem!r}, "
                          f"but there is {'no file' if not found else 'more than one file'} "
                          f"{stem}.* beside it")
    v = found[0]
    if v.suffix.lower() == ".at2":
        return {"vertical": str(v.resolve()), "vertical_dt": None, "vertical_units": None}
    own = table.get(v.stem, {})
    dt = own.get("dt") if own.get("dt") is not None else entry["dt"]
    if dt is None:
        raise RecordError(f"{listing}: the vertical channel {v.name!r} of record {name!r} is a "
                          f"headerless file without a dt (give it, or the record, a dt)")
    return {"vertical": str(v.resolve()), "vertical_dt": dt,
            "vertical_units": own.get("units", entry["units"]) if own else entry["units"]}


def find_records(records_dir: str | os.PathLike) -> tuple[list[dict[str, Any]], list[str]]:
    """Record files under ``records_dir`` (searched recursively), sorted by name: PEER
    ``.AT2`` files (dt and units from their header) and headerless files listed in a
    ``records.csv`` next to them (columns: ``record`` = file stem, ``dt_s`` or ``dt`` [s], and
    ``units``: "cm/s^2..." / "m/s^2..." / "g"; cm/s^2 when absent; an AT2 file may be listed
    with an empty dt). A column ``vertical`` names, per record, the file (name or stem) of its
    vertical channel beside it (acceleration positive up, in its own file's units): the record then
    carries ``vertical`` (the path), ``vertical_dt`` and ``vertical_units``
    (:func:`listed_metadata`), and that file is a channel, not a record of its own.

    Returns (records, notes): each record a dict name, path (resolved), dt [s] or None, units
    or None; notes say which other files were skipped and why. A record is identified by its
    path: its ``name`` is its file stem, or, where two files under ``records_dir`` share a stem
    (``a/LA21.dat``, ``b/LA21.dat``), its path relative to ``records_dir`` without the suffix
    (``a/LA21``). A ``records.csv`` that cannot be read, has an unknown unit or a bad dt, or
    lists a file that is not there is an error (:class:`~rockbench.errors.RecordError` naming
    the listing and the entry), not a folder quietly smaller.
    """
    root = _check_path(records_dir, "records_dir")
    if not root.is_dir():
        raise ParameterError("records_dir", str(records_dir), "an existing folder of record "
                                                              "files (.AT2, or files listed "
                                                              "in a records.csv)")
    records, notes = [], []
    tables: dict[Path, dict[str, dict[str, Any]]] = {}
    verticals: dict[Path, dict[str, dict[str, Any]]] = {}      # folder -> record -> channel
    for listing in sorted(root.rglob("records.csv")):
        tables[listing.parent] = table = _read_listing(listing)      # RecordError: stop here
        stems = {q.stem for q in listing.parent.iterdir() if q.is_file()}
        for name in table:
            if name not in stems:
                raise RecordError(f"{listing}: lists record {name!r}, but there is no file "
                                  f"{name}.* beside it (remove the line or add the file)")
        verticals[listing.parent] = {name: _vertical_of(listing, table, name, e)
                                     for name, e in table.items() if e.get("vertical")}
    channels = {(folder, Path(v["vertical"]).stem) for folder, vs in verticals.items()
                for v in vs.values()}
    for p in sorted(root.rglob("*"), key=lambda q: (q.stem.lower(), str(q))):
        if not p.is_file() or p.name == "records.csv" or p.suffix.lower() in (".md", ".csv"):
            continue
        if (p.parent, p.stem) in channels:        # a record's vertical channel, not a record
            continue
        vert = verticals.get(p.parent, {}).get(p.stem, {})
        if p.suffix.lower() == ".at2":
            records.append({"name": p.stem, "path": str(p.resolve()), "dt": None,
                            "units": None, **vert, "_rel": p.relative_to(root)})
            continue
        entry = tables.get(p.parent, {}).get(p.stem)
        if entry is None:
            notes.append(f"{p.name}: skipped (not an .AT2 file and not listed in a "
                         f"records.csv with its dt)")
            continue
        if entry["dt"] is None:
            raise RecordError(f"{p.parent / 'records.csv'}: lists the headerless file "
                              f"{p.name} without a dt")
        records.append({"name": p.stem, "path": str(p.resolve()), "dt": entry["dt"],
                        "units": entry["units"], **vert, "_rel": p.relative_to(root)})
    stems: dict[str, int] = {}
    for r in records:
        stems[r["name"]] = stems.get(r["name"], 0) + 1
    for r in records:
        rel = r.pop("_rel")
        if stems[r["name"]] > 1:                  # the stem alone would merge two records
            r["name"] = rel.with_suffix("").as_posix()
    return records, notes


# ------------------------------------------------------------------------------------------------
# Records shipped inside the package: rockbench/records/, provenance in its PROVENANCE.md
def bundled_dir() -> Path:
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
    records, _ = find_records(bundled_dir())
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

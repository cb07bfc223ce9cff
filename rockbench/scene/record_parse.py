"""Parsing of record files for :mod:`rockbench.scene.records` (private): the AT2 header
(NPTS, DT, units), a bounded block scan of the samples, a time column. Every failure raises
:class:`~rockbench.errors.RecordError` naming the file (and the line, for a bad value).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError, RecordError
from ..limits import limit, override_hint
from .motion import UNIT_SPELLINGS, parse_units

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][+-]?\d+)?"
#: Old PEER: "NPTS=   7818, DT=   .0050 SEC, ..."; NPTS and DT may come in either order.
_NPTS_KEY = re.compile(r"\bNPTS\s*=\s*(\d+)", re.IGNORECASE)
_DT_KEY = re.compile(rf"\bDT\s*=\s*({_NUMBER})", re.IGNORECASE)
#: NGA-West2: "  4000    0.0100    NPTS, DT ..."
_NGA_LINE = re.compile(rf"^\s*(\d+)\s*,?\s+({_NUMBER})\s+NPTS\s*,\s*DT\b", re.IGNORECASE)


#: At most this many lines (each at most :data:`_HEADER_LINE_BYTES`) are searched for an AT2
#: header line with NPTS and DT (PEER's headers have 4).
HEADER_LINES = 100
_HEADER_LINE_BYTES = 1 << 16
#: Bytes read and parsed at a time (the memory of parsing is this plus the samples kept).
_BLOCK = 1 << 18
_FORTRAN = str.maketrans("Dd", "Ee")
#: A units statement in a header: "UNITS OF G", "UNITS: CM/S^2", "UNIT = gal", "units are g".
_UNITS_KEY = re.compile(r"\bUNITS?\b\s*(?:(?:OF|IN|ARE|IS)\b|[:=])?\s*[:=]?\s*", re.IGNORECASE)
#: Without the word UNITS: "ACCELERATION IN CM/S/S", "ACCELERATION (G)".
_ACCEL_IN = re.compile(r"\bACCEL\w*\b(?:[^,;(]*?\bIN\s+|\s*(?=[(\[]))", re.IGNORECASE)


def _check_path(path: Any, name: str = "path") -> Path:
    """``path`` as a Path; ParameterError naming ``name`` unless it is a str or os.PathLike."""
    if isinstance(path, (str, os.PathLike)) and str(path).strip():
        return Path(path)
    shown = repr(path) if len(repr(path)) <= 60 else repr(path)[:57] + "..."
    raise ParameterError(name, shown, "the path of a record file (a str or os.PathLike)")


def _open_record(path: Path):
    """The file opened for binary reading, after the checks that need no reading: it exists, is
    a regular file, and has at most ``record_bytes`` bytes (:mod:`rockbench.limits`)."""
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
        return open(path, "rb")
    except OSError as exc:
        raise RecordError(f"cannot read record file {path}: {exc.strerror or exc}") from None


def _ascii(path: Path, data: bytes, offset: int) -> str:
    try:
        return data.decode("ascii")
    except UnicodeDecodeError as exc:
        raise RecordError(f"record file {path}: not plain ASCII text (byte {offset + exc.start})"
                          ) from None


def _read_header(path: Path, f) -> tuple[list[str], int, str]:
    """(header lines up to and including the NPTS/DT line, NPTS, DT text), reading at most
    :data:`HEADER_LINES` lines; RecordError naming the file otherwise."""
    head: list[str] = []
    offset = 0
    while len(head) < HEADER_LINES:
        raw = f.readline(_HEADER_LINE_BYTES)
        if not raw:
            break
        line = _ascii(path, raw, offset)
        offset += len(raw)
        head.append(line.rstrip("\r\n"))
        found = _match_npts_dt(line)
        if found is not None:
            return head, found[0], found[1]
    if not any(h.strip() for h in head):
        raise RecordError(f"record file {path} is empty")
    raise RecordError(f"record file {path}: no header line with NPTS and DT in its first "
                      f"{len(head)} lines (is it a PEER AT2 file?)")


def _leading_units(text: str) -> tuple[str, str] | None:
    """(canonical units, as written) of the unit at the start of ``text`` (up to 5 words, the
    longest that is a unit; trailing punctuation ignored), or None."""
    words = text.split()[:5]
    for n in range(len(words), 0, -1):
        cand = " ".join(words[:n]).rstrip(".,;:")
        try:
            return parse_units(cand), cand
        except ParameterError:
            continue
    return None


def _header_units(path: Path, head: list[str]) -> tuple[str, str] | None:
    """(canonical units, as written) that the header lines state, None if they state none;
    RecordError for a statement whose unit is unknown or two statements that disagree."""
    found: list[tuple[str, str]] = []
    for line in head:
        for key in (_UNITS_KEY, _ACCEL_IN):
            for m in key.finditer(line):
                rest = line[m.end():]
                if not rest.strip():
                    continue
                u = _leading_units(rest)
                if u is None:
                    word = rest.split()[0].rstrip(".,;:")
                    if key is _ACCEL_IN and not any(c in word for c in "/^()[]"):
                        continue          # "ACCELERATION IN THE N-S DIRECTION": no unit
                    raise RecordError(
                        f"record file {path}: the header's units {word!r} ({line.strip()!r}) "
                        f"are not an acceleration unit rockbench knows; accepted (any case): "
                        f"{', '.join(UNIT_SPELLINGS)}")
                found.append(u)
            if found and key is _UNITS_KEY:
                break
    if not found:
        return None
    if len({c for c, _ in found}) > 1:
        raise RecordError(f"record file {path}: the header states two units, "
                          f"{found[0][1]!r} and "
                          f"{next(w for c, w in found if c != found[0][0])!r}")
    return found[0]


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
    return float(token.translate(_FORTRAN))


@dataclass
class _Scan:
    """What :func:`_scan` read: ``values`` (the first ``keep`` numbers, row-major), ``total``
    (every number in the file, counted), and, when rows were asked for and every data line
    held exactly two numbers, ``lines``: the 1-based line number of each data line."""

    values: np.ndarray
    total: int
    lines: np.ndarray | None = None
    blank: bool = False


def _scan(path: Path, f, line0: int, *, keep: int | None, rows: bool = False) -> _Scan:
    """The numbers of the rest of the open file ``f`` (whose next line is line ``line0``),
    parsed in blocks of :data:`_BLOCK` bytes. ``values`` holds them all while there are at most
    ``keep`` (None: the limit ``record_samples``; twice it while a ``t a`` file of ``keep``
    samples is possible); past that they are dropped and only counted (``total``), so memory is
    bounded whatever the file holds (the caller refuses such a file). Blank lines and lines starting with ``#`` are skipped;
    RecordError naming the file and the line of the first token that is not a finite number.
    ``rows``: also track whether every data line holds exactly two numbers (a ``t a`` file)."""
    most = int(limit("record_samples")[1])
    if keep is None:
        keep = most
    pieces: list[np.ndarray] = []
    kept = total = 0
    line = line0               # number of the line the next part starts on
    offset = f.tell()          # byte offset of the next part
    carry = b""
    mid_line = in_comment = False
    two = rows                 # every data line so far has two numbers
    line_nos: list[np.ndarray] = []     # per block: the line number of each data line
    blank = True
    while True:
        raw = f.read(_BLOCK)
        data = carry + raw
        if raw:
            cut = data.rfind(b"\n") + 1
            if cut == 0:      # a line longer than a block: cut it at a blank
                cut = max(data.rfind(b" "), data.rfind(b"\t"), data.rfind(b"\r")) + 1
                if cut == 0:
                    if len(data) > 4 * _BLOCK:
                        raise RecordError(f"record file {path}, line {line}: a token of more "
                                          f"than {len(data)} characters is not a number")
                    carry = data
                    continue
            part, carry = data[:cut], data[cut:]
        else:
            part, carry = data, b""
        text = _ascii(path, part, offset)
        offset += len(part)
        if "\r" in text:
            text = text.replace("\r\n", "\n").replace("\r", "\n")
        ends_mid = bool(raw) and not text.endswith("\n")
        blank = blank and not text.strip()
        if "#" in text or mid_line or two:
            kept_lines, numbers = [], []
            lines = text.split("\n")
            for i, ln in enumerate(lines):
                if i == 0 and mid_line:
                    comment = in_comment
                    two = False
                else:
                    comment = ln.lstrip().startswith("#")
                if not comment:
                    kept_lines.append(ln)
                    if two and ln.strip():
                        if len(ln.split()) == 2:
                            numbers.append(line + i)
                        else:
                            two = False
            line_nos = line_nos + [np.array(numbers, dtype=np.int64)] if two else []
            in_comment = ends_mid and comment
            body = "\n".join(kept_lines)
        else:
            body = text
        mid_line = ends_mid
        # values beyond ``keep`` (twice it while the file may be a t a file) are only counted:
        # the caller refuses the file, and what was kept is dropped
        if total <= (2 * keep if two else keep):
            tokens = body.translate(_FORTRAN).split()
            try:
                arr = np.array(tokens, dtype=float)
            except ValueError:
                arr = None
            if arr is None or not np.isfinite(arr).all():
                _bad_token(path, text, line)
            n = arr.size
            pieces.append(arr)
            kept += n
        else:
            n = len(body.split())
        total += n
        if total > (2 * keep if two else keep):
            pieces, kept, line_nos = [], 0, []
        line += text.count("\n")
        if not raw:
            break
    values = np.concatenate(pieces) if pieces else np.zeros(0)
    lines = np.concatenate(line_nos) if two and rows and line_nos else None
    return _Scan(values, total, lines, blank)


def _bad_token(path: Path, text: str, line0: int) -> None:
    """Raise the RecordError for the first token of ``text`` (starting on line ``line0``) that
    is not a finite number, naming the file, the line and the token."""
    for i, ln in enumerate(text.split("\n")):
        if ln.lstrip().startswith("#"):
            continue
        for token in ln.split():
            try:
                x = _to_float(token)
            except ValueError:
                raise RecordError(f"record file {path}, line {line0 + i}: {token!r} is not a "
                                  "number") from None
            if not math.isfinite(x):
                raise RecordError(f"record file {path}, line {line0 + i}: value {token!r} is "
                                  "not finite")
    raise RecordError(f"record file {path}: a value near line {line0} is not a finite number")


def _time_column(path: Path, scan: _Scan, dt: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(times, accelerations) of a ``t a`` file, None for a file of samples; RecordError if
    the first column looks like time but is not strictly increasing, uniform, or spaced by
    ``dt`` [s] (rules: :func:`load_columns`)."""
    if scan.lines is None or scan.lines.size < 3 or scan.total != scan.values.size:
        return None
    lines = scan.lines
    t = scan.values[0::2]
    a = scan.values[1::2]
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
    _, most = limit("record_samples")
    if t.size > most:
        raise RecordError(f"record file {path} holds {t.size} samples (t a lines), more than "
                          f"{most:g} ({override_hint('record_samples')})")
    what = f"record file {path}: two columns read as time [s] and acceleration"
    if not increasing:
        i = int(np.argmin(steps > 0))
        raise RecordError(f"{what}, but the time on line {lines[i + 1]} ({t[i + 1]:g}) is not "
                          f"after the time on line {lines[i]} ({t[i]:g}): times must "
                          "increase (for samples only, write another number of values per "
                          "line)")
    step = span / (len(t) - 1)
    off = np.abs(t - (t[0] + step * np.arange(len(t))))
    i = int(np.argmax(off))
    if off[i] > 0.01 * step:
        raise RecordError(f"{what}, but the times are not uniformly spaced: line {lines[i]} "
                          f"has t = {t[i]:g}, {off[i]:.3g} s off the grid of step {step:g} s")
    if not math.isclose(step, dt, rel_tol=1e-3):
        raise RecordError(f"{what}, but the time step of the file ({step:g} s) differs from "
                          f"record-dt = {dt:g} s")
    return t, a


def _check_enough(path: Path, values: np.ndarray) -> None:
    if values.size < 2:
        raise RecordError(f"record file {path}: {values.size} acceleration value(s); "
                          "a record needs at least 2")



"""Acceleration units of ground-motion records: every spelling record headers and agencies use
(``g``, ``gal``, ``cm/s^2``, ``CM/S/S``, ``cm/sec2``, ``m/s^2``, ``mm/s^2``, ``in/s^2``, ...) to one
canonical name and its factor to m/s^2; an unknown spelling is refused, never read as g."""

from __future__ import annotations

import re
from typing import Any

from ..constants import G_STANDARD
from ..errors import ParameterError

__all__ = ["UNIT_FACTORS", "UNIT_SPELLINGS", "parse_units", "unit_factor"]

#: Factor [m/s^2 per unit] converting accelerations in the given units to m/s^2, by canonical
#: name (:func:`parse_units` maps every accepted spelling to one of these). Units of g use
#: :data:`rockbench.constants.G_STANDARD` so that published PGAs are reproduced; 1 gal = 1 cm/s^2;
#: 1 in = 0.0254 m and 1 ft = 0.3048 m exactly.
UNIT_FACTORS: dict[str, float] = {"g": G_STANDARD, "m/s2": 1.0, "cm/s2": 0.01, "mm/s2": 0.001,
                                  "in/s2": 0.0254, "ft/s2": 0.3048}

#: Spellings of a length in an acceleration unit, by canonical length.
_LENGTHS = {"m": ("m", "meter", "meters", "metre", "metres"),
            "cm": ("cm", "centimeter", "centimeters", "centimetre", "centimetres"),
            "mm": ("mm", "millimeter", "millimeters", "millimetre", "millimetres"),
            "in": ("in", "inch", "inches"),
            "ft": ("ft", "foot", "feet")}
_LENGTH_OF = {w: k for k, ws in _LENGTHS.items() for w in ws}
_SECOND = r"(?:s|sec|secs|second|seconds)"
#: "<length>" + per second squared: /s^2, /s**2, /s2, /s/s, /sec2, /sec/sec, s^-2, s-2 (with
#: an optional separator ' ', '.', '*' before s^-2); the unit already lower-cased and stripped.
_PER_S2 = re.compile(rf"^([a-z]+)\s*(?:/\s*{_SECOND}\s*(?:\^|\*\*)?\s*2|/\s*{_SECOND}\s*/\s*"
                     rf"{_SECOND}|/\s*\(\s*{_SECOND}\s*(?:\^|\*\*)?\s*2\s*\)|"
                     rf"\s*[.*]?\s*{_SECOND}\s*(?:\^|\*\*)?\s*-\s*2)$")
_G_WORDS = ("g", "gs", "g's", "g-units", "g units")
_GAL_WORDS = ("gal", "gals", "galileo", "galileos")

#: The accepted spellings, as the errors list them (case-insensitive; sec/second for s, the
#: length spelled out, ^2, **2, 2, /s/s and s^-2 are all accepted).
UNIT_SPELLINGS = ("g", "gal", "m/s^2", "cm/s^2", "mm/s^2", "in/s^2", "ft/s^2", "CM/S/S",
                  "cm/sec2", "cm/sec/sec", "cm s^-2", "m/s2", "cm/s2")


def parse_units(text: Any, name: str = "units") -> str:
    """The canonical name (a key of :data:`UNIT_FACTORS`) of an acceleration unit written
    ``text``, as record headers and agencies write it: ``g``/``G``, ``gal``, ``cm/s^2``,
    ``CM/S/S``, ``cm/sec2``, ``cm/sec**2``, ``cm s^-2``, ``m/s^2``, ``mm/s^2``, ``in/s^2``
    (inch), ``ft/s^2``, ... (case-insensitive, surrounding brackets and blanks ignored).

    Raises :class:`ParameterError` naming ``name``, the text and the accepted spellings for
    anything else (a unit that is not an acceleration, a typo, a non-string).
    """
    if isinstance(text, str):
        t = text.strip().lower().replace("\u00b2", "2")
        while len(t) > 1 and t[0] + t[-1] in ("()", "[]", "{}"):
            t = t[1:-1].strip()
        if t in UNIT_FACTORS:
            return t
        if t in _G_WORDS:
            return "g"
        if t in _GAL_WORDS:
            return "cm/s2"
        m = _PER_S2.match(t)
        if m is not None and m.group(1) in _LENGTH_OF:
            return f"{_LENGTH_OF[m.group(1)]}/s2"
    raise ParameterError(name, text, "an acceleration unit: " + ", ".join(UNIT_SPELLINGS),
                         "case-insensitive; sec or second for s, 2, ^2, **2, /s/s or s^-2 for "
                         "the square")


def unit_factor(units: str, name: str = "units") -> float:
    """Factor converting accelerations in ``units`` (any spelling :func:`parse_units`
    accepts) to m/s^2.

    Raises :class:`ParameterError` naming ``name`` for any other value.
    """
    return UNIT_FACTORS[parse_units(units, name)]

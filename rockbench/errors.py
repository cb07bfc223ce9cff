"""Exceptions raised by rockbench.

Every validation error names the parameter, the value received and the valid range, so that a
user (or the command line, which prints it on one line) can fix the input without a traceback.
"""

from __future__ import annotations

import math
from typing import Any


class RockbenchError(Exception):
    """Base class of every error rockbench raises on purpose."""


class ParameterError(RockbenchError, ValueError):
    """A parameter is outside its valid range.

    Attributes
    ----------
    name : str
        Parameter name as the user spells it (scene key, CLI option or argument name).
    value : object
        The offending value.
    valid : str
        Human-readable description of the valid range, e.g. ``"> 0"`` or ``"<= column_height_left"``.
    """

    def __init__(self, name: str, value: Any, valid: str, detail: str | None = None):
        self.name = name
        self.value = value
        self.valid = valid
        msg = f"invalid {name}={value!r}: must be {valid}"
        if detail:
            msg += f" ({detail})"
        super().__init__(msg)


class SceneError(RockbenchError, ValueError):
    """A scene file cannot be read or names an unknown key/scene."""


class RecordError(RockbenchError, ValueError):
    """A ground-motion record file cannot be parsed or is physically invalid."""


class RockbenchWarning(UserWarning):
    """Something a user should know that does not stop the work (a damaged store file
    skipped, workers capped at the cores); the command line prints each one as one line."""


class BackendUnavailable(RockbenchError, ImportError):
    """A registered backend cannot be used because its engine package does not import."""


def check_finite(name: str, value: Any) -> float:
    """Return ``value`` as float; raise :class:`ParameterError` if it is not a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a finite real number") from None
    if isinstance(value, bool) or not math.isfinite(x):
        raise ParameterError(name, value, "a finite real number")
    return x


def check_positive(name: str, value: Any) -> float:
    """Return ``value`` as float; raise unless it is finite and > 0."""
    x = check_finite(name, value)
    if x <= 0.0:
        raise ParameterError(name, value, "> 0")
    return x


def check_nonnegative(name: str, value: Any) -> float:
    """Return ``value`` as float; raise unless it is finite and >= 0."""
    x = check_finite(name, value)
    if x < 0.0:
        raise ParameterError(name, value, ">= 0")
    return x


def check_range(name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False) -> float:
    """Return ``value`` as float; raise unless ``lo <(=) value <(=) hi``."""
    x = check_finite(name, value)
    bad_lo = x <= lo if lo_open else x < lo
    bad_hi = x >= hi if hi_open else x > hi
    if bad_lo or bad_hi:
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ParameterError(name, value, f"in {lb}{lo:g}, {hi:g}{rb}")
    return x


def check_int(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    """Return ``value`` as int; raise unless it is an integral number in [lo, hi] (hi None:
    no upper bound). Booleans are refused."""
    ok = (not isinstance(value, bool) and isinstance(value, (int, float))
          or type(value).__module__ == "numpy" and hasattr(value, "is_integer"))
    try:
        ok = ok and float(value).is_integer() and value >= lo and (hi is None or value <= hi)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ParameterError(name, value, f"an integer in [{lo}, {hi}]" if hi is not None
                             else f"an integer >= {lo}")
    return int(value)


def check_choice(name: str, value: Any, choices) -> Any:
    """Return ``value`` if it is one of ``choices``; raise naming the choices otherwise."""
    if value not in tuple(choices):
        raise ParameterError(name, value, f"one of {', '.join(map(str, choices))}")
    return value

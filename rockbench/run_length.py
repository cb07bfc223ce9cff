"""THE run-length rule: how long a run lasts when no one gives its duration, said once for
every backend, path, study, store and page.

A run starts at its ground motion's start (``t_start``: -3 T_g for a Ricker pulse, 0 for a
record; 0 for free rocking, which has no motion) and lasts until ``tail`` seconds of free
rocking after the end of the motion's *window*::

    run length = (window's end - t_start) + tail,    tail = FREE_TAIL (10 s) by default

The windows (:func:`run_length`'s ``window``):

* ``"whole"`` (the default): the whole motion, [t_start, t_end] (a Ricker pulse's
  [-3 T_g, 3 T_g]: 6 T_g; a record's samples; none for free rocking, whose run is the tail);
* ``"strong"``: a Ricker pulse's strong part, to :data:`STRONG_END` T_g after its centre
  (4.5 T_g from the start), rounded to 0.1 ms: after 1.5 T_g the pulse is below 4e-5 of its
  peak (antisymmetric; 1e-8 symmetric), so the validation set
  (:mod:`rockbench.studies.validation`), whose many runs are repeated at every time step of
  every engine, counts its tail from there rather than from 3 T_g;
* a number: the window's length [s] from the run's start. A map's cell has no pulse built
  when its run length is decided: :func:`pulse_window` computes 6 T_g from W and p, and
  :func:`pulse_run_length` is a cell's length (the values every stored map was run for).

Units: seconds.
"""

from __future__ import annotations

import math
from typing import Any

from .constants import FREE_TAIL

__all__ = ["run_length", "pulse_window", "pulse_run_length", "STRONG_END", "describe"]

#: End of a Ricker pulse's strong part [T_g after its centre]: the window ``"strong"``.
STRONG_END = 1.5

#: Half the window of a Ricker pulse [T_g]: it spans [-3 T_g, 3 T_g]
#: (:class:`rockbench.scene.motion.RickerPulse`).
_PULSE_HALF_WINDOW = 3.0


def _tail(tail: float | None) -> float:
    return FREE_TAIL if tail is None else tail


def run_length(motion: Any = None, tail: float | None = None, *, window: str = "whole") -> float:
    """The run length [s] of a run of ``motion`` from its start (module docstring): the
    window's length plus ``tail`` [s] of free rocking (None: :data:`rockbench.constants.FREE_TAIL`).

    ``motion``: a ground motion (``t_start``, ``t_end`` [s]; a Ricker pulse also ``period``
    for ``window="strong"``), None (free rocking: the tail alone) or a number, the window's
    length [s]."""
    t = _tail(tail)
    if motion is None:
        return t
    if isinstance(motion, (int, float)):
        return float(motion) + t
    if window == "whole":
        return max(float(motion.t_end) - float(motion.t_start), 0.0) + t
    if window == "strong":
        return round(STRONG_END * motion.period + t - motion.t_start, 4)
    raise ValueError(f"window {window!r}: 'whole' or 'strong'")


def pulse_window(W: float, p: float) -> float:
    """A Ricker pulse's window [s], 6 T_g with T_g = 2 pi / (W p), from its dimensionless
    frequency W = omega_g / p and the structure's p [rad/s] (no pulse built)."""
    return 2.0 * _PULSE_HALF_WINDOW * 2.0 * math.pi / (W * p)


def pulse_run_length(W: float, p: float, tail: float | None,
                     extra: float = 0.0) -> float | None:
    """The run length [s] of a Ricker-pulse cell (a map's, a campaign's pulse case): its
    :func:`pulse_window` plus ``tail`` [s] plus ``extra`` [s] (a fall finished:
    :func:`rockbench.verdict.finish_fall`). None when ``tail`` is None and there is no
    ``extra``: the backend then takes :func:`run_length` of the pulse itself (the same 6 T_g
    + FREE_TAIL, up to the last bit)."""
    if tail is None and not extra:
        return None
    return run_length(pulse_window(W, p), _tail(tail) + extra)


def describe(kind: str = "motion", tail: float | None = None, motion: Any = None) -> str:
    """The rule in words, for messages, stores and pages: ``kind`` "pulse" ("pulse window
    (6 T_g) + 10 s"; a map store's identity keeps this text) or "motion" ("the motion's length
    + 10 s, or 10 s of free rocking"; with a ``motion``, its numbers: "the motion's 6.28 s +
    10 s")."""
    t = _tail(tail)
    if kind == "pulse":
        return f"pulse window ({2 * _PULSE_HALF_WINDOW:g} T_g) + {t:g} s"
    if motion is not None:
        return f"the motion's {run_length(motion, 0.0):g} s + {t:g} s"
    return f"the motion's length + {t:g} s, or {t:g} s of free rocking"

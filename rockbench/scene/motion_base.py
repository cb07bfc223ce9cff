"""The interface every ground motion offers (:class:`GroundMotion`; the conventions are in
:mod:`rockbench.scene.motion`, which also holds the Ricker pulses) and the checks shared by
the pulses and the records. Import :class:`GroundMotion` from :mod:`rockbench.scene.motion`.
"""

from __future__ import annotations

import abc
from typing import Any

import numpy as np

from ..errors import ParameterError, check_finite
from ..result import motion_label

def _check_factor(factor: Any) -> float:
    x = check_finite("factor", factor)
    if x == 0.0:
        raise ParameterError("factor", factor, "a finite, non-zero real number")
    return x


def _check_interval(t0: Any, t1: Any) -> tuple[float, float]:
    a, b = check_finite("t0", t0), check_finite("t1", t1)
    if b < a:
        raise ParameterError("t1", t1, f">= t0 = {a:g}")
    return a, b


# ------------------------------------------------------------------------------------------------
class GroundMotion(abc.ABC):
    """A horizontal ground acceleration history u_g''(t) [m/s^2], positive to the right (+x).

    Contract for a subclass:

    * attributes (or properties) ``t_start`` [s], the time at which a run starts from rest, and
      ``t_end`` [s], after which ``|u_g''|`` is identically zero or below 1e-12 of :attr:`peak`;
    * :meth:`acceleration`, :meth:`knots`, :meth:`max_abs_after`, :attr:`peak`,
      :meth:`describe` and :meth:`scaled` as documented here;
    * :attr:`vertical`: None (the default: no vertical motion) or a :class:`GroundMotion`
      (whose own ``vertical`` is None) giving the vertical ground acceleration a_v(t) [m/s^2],
      positive up, on the same clock (same ``t_start``, ``t_end``); ``knots`` then bracket
      thresholds of both (module docstring) and ``scaled`` scales both.

    Instances are immutable and picklable (they travel to sweep workers).
    """

    t_start: float
    t_end: float
    #: The vertical component (positive up) or None; see the class docstring.
    vertical: "GroundMotion | None" = None

    @abc.abstractmethod
    def acceleration(self, t):
        """Ground acceleration [m/s^2] at time ``t`` [s]: float -> float, ndarray -> ndarray."""

    @abc.abstractmethod
    def knots(self, t0: float, t1: float) -> np.ndarray:
        """Sorted times [s] covering ``[t0, t1]``, both included, such that the acceleration is
        monotonic between consecutive knots."""

    @abc.abstractmethod
    def max_abs_after(self, t: float) -> float:
        """Supremum of ``|acceleration|`` over ``[t, inf)`` [m/s^2]."""

    @property
    @abc.abstractmethod
    def peak(self) -> float:
        """Maximum of ``|acceleration|`` over all times [m/s^2]."""

    @abc.abstractmethod
    def describe(self) -> dict[str, Any]:
        """JSON-safe description: ``kind`` plus parameters, units in the key names."""

    @abc.abstractmethod
    def scaled(self, factor: float) -> GroundMotion:
        """A new motion whose acceleration is ``factor`` times this one (factor finite, != 0;
        negative reverses the direction)."""

    @property
    def duration(self) -> float:
        """``t_end - t_start`` [s]."""
        return self.t_end - self.t_start

    def label(self, long: bool = False) -> str:
        """The one human label of this motion (:func:`rockbench.result.motion_label`)."""
        return motion_label(self.describe(), long=long)


def _short(values: Any) -> str:
    text = repr(values)
    return text if len(text) <= 60 else text[:57] + "..."


def _times(t: Any) -> np.ndarray:
    """``t`` [s] (a number or an array of numbers) as a float array; ParameterError naming
    ``t`` for anything else (a string, None, a bool)."""
    try:
        if t is None or isinstance(t, (bool, np.bool_, str, bytes)):
            raise TypeError
        return np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError("t", _short(t), "a time [s] or an array of times") from None


"""Any horizontal ground motion with any vertical one (:class:`WithVertical`). Import it from
:mod:`rockbench.scene.motion` or :mod:`rockbench`.

A Ricker pulse carries its own vertical part (``RickerPulse(..., vertical_ratio=r)``: the same
wavelet in phase) and a record its own channel (:meth:`Record.with_vertical`: sampled at the
horizontal channel's times). :class:`WithVertical` pairs two motions that are neither: a
vertical pulse of its own period under a still or a recorded horizontal ground, a vertical
record under a pulse, two analytic motions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from .motion_base import GroundMotion, _check_interval

__all__ = ["WithVertical"]


class WithVertical(GroundMotion):
    """The ground motion whose horizontal acceleration is ``horizontal``'s and whose vertical
    acceleration is ``vertical``'s, on one clock.

    Parameters
    ----------
    horizontal : GroundMotion
        u_g''(t) [m/s^2], positive to the right; without a vertical part of its own.
    vertical : GroundMotion
        a_v(t) [m/s^2], positive up (the normal force of a body at rest is m (g + a_v));
        without a vertical part of its own.

    The run starts at the earlier ``t_start`` of the two and the motion ends at the later
    ``t_end`` [s] (each component is zero, or below 1e-12 of its peak, outside its own window).
    :meth:`acceleration`, :meth:`max_abs_after` and :attr:`peak` are the horizontal's;
    :attr:`vertical` is ``vertical`` as given. :meth:`knots` are the union of both components'
    knots: between two of them each component is monotonic, so a threshold on one of them
    (lift-off at a_v = -g) is bracketed exactly, and one on a combination
    ``u_g'' + c a_v`` too when both are linear between the knots (records, a still ground) or
    move in the same direction; a pulse's knots are T_g / 400 apart, which bounds what a
    combination of two pulses of different periods can hide between them.
    :meth:`scaled` scales both components (a negative factor reverses both).
    """

    def __init__(self, horizontal: GroundMotion, vertical: GroundMotion):
        for name, m in (("horizontal", horizontal), ("vertical", vertical)):
            if not isinstance(m, GroundMotion):
                raise ParameterError(name, type(m).__name__, "a GroundMotion (acceleration "
                                     "[m/s^2] of time [s])")
            if getattr(m, "vertical", None) is not None:
                raise ParameterError(name, m.label(), "a motion without a vertical part of "
                                     "its own (WithVertical gives the one vertical part)")
        self._h = horizontal
        self._v = vertical
        self.t_start = float(min(horizontal.t_start, vertical.t_start))
        self.t_end = float(max(horizontal.t_end, vertical.t_end))

    @property
    def horizontal(self) -> GroundMotion:
        """The horizontal component (as given)."""
        return self._h

    @property
    def vertical(self) -> GroundMotion:          # type: ignore[override]
        """The vertical component a_v(t) [m/s^2], positive up (as given)."""
        return self._v

    def acceleration(self, t):
        """The horizontal acceleration u_g''(t) [m/s^2] at ``t`` [s]."""
        return self._h.acceleration(t)

    def knots(self, t0: float, t1: float) -> np.ndarray:
        """The union of both components' knots in [``t0``, ``t1``] [s], both ends included."""
        t0, t1 = _check_interval(t0, t1)
        return np.unique(np.concatenate([np.asarray(self._h.knots(t0, t1), dtype=float),
                                         np.asarray(self._v.knots(t0, t1), dtype=float)]))

    def max_abs_after(self, t: float) -> float:
        """sup |u_g''| over [t, inf) [m/s^2] (the horizontal's)."""
        return self._h.max_abs_after(t)

    @property
    def peak(self) -> float:
        """max |u_g''| [m/s^2] (the horizontal's)."""
        return self._h.peak

    def describe(self) -> dict[str, Any]:
        """The horizontal's description with ``vertical``: the vertical's."""
        return dict(self._h.describe(), vertical=self._v.describe())

    def scaled(self, factor: float) -> WithVertical:
        """Both components times ``factor`` (finite, != 0)."""
        return WithVertical(self._h.scaled(factor), self._v.scaled(factor))

    def __repr__(self) -> str:
        return f"WithVertical({self._h!r}, vertical={self._v!r})"

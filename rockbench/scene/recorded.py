"""A recorded accelerogram as a :class:`~rockbench.scene.motion.GroundMotion`: samples at
strictly increasing times, linear between samples, with an optional vertical channel on the
same time base. Conventions as in :mod:`rockbench.scene.motion` (SI units, up positive for the
vertical channel). Import it from :mod:`rockbench.scene.motion` or :mod:`rockbench`.
"""

from __future__ import annotations

import bisect
from typing import Any

import numpy as np

from ..errors import ParameterError, check_finite, check_positive
from .motion_base import GroundMotion, _check_factor, _check_interval, _short, _times
from .units import UNIT_FACTORS, parse_units

__all__ = ["Record"]


class Record(GroundMotion):
    """A recorded accelerogram: samples at strictly increasing times, linear between samples.

    ``acceleration(t)`` interpolates linearly between samples and is exactly 0 outside
    ``[time[0], time[-1]]``; ``t_start = time[0]``, ``t_end = time[-1]``.

    Parameters
    ----------
    time : array_like
        Sample times [s]: 1-D, finite, strictly increasing, at least 2 samples.
    acceleration : array_like
        Samples [m/s^2] (already converted), finite, same length as ``time``.
    name : str
        Short label (e.g. "LA21").
    source : str
        Where the data came from (e.g. the file header).
    units_in : str
        Units of the original data, any spelling of :func:`parse_units` (metadata only; kept
        as its canonical name, a key of :data:`UNIT_FACTORS`).

    vertical : Record, optional
        The vertical channel [m/s^2], positive up (see :meth:`with_vertical`: it is sampled
        at this record's times). Default None: no vertical motion.

    At most ``record_samples`` samples (limit of :mod:`rockbench.limits`, 2e6 unless
    ``ROCKBENCH_RECORD_SAMPLES`` raises it), checked before any array is built.
    """

    def __init__(self, time: Any, acceleration: Any, name: str = "", source: str = "",
                 units_in: str = "m/s2", vertical: Record | None = None):
        _check_samples("time", time)
        _check_samples("acceleration", acceleration)
        t = _finite_vector("time", time)
        a = _finite_vector("acceleration", acceleration)
        if t.size < 2:
            raise ParameterError("time", f"{t.size} sample(s)", "at least 2 samples")
        if a.size != t.size:
            raise ParameterError("acceleration", f"{a.size} samples",
                                 f"as many samples as time ({t.size})")
        steps = np.diff(t)
        if not np.all(steps > 0):
            i = int(np.argmin(steps > 0))
            where = f"time[{i + 1}]={float(t[i + 1])!r} after time[{i}]={float(t[i])!r}"
            raise ParameterError("time", where, "strictly increasing")
        units_in = parse_units(units_in, "units_in")
        t.setflags(write=False)
        a.setflags(write=False)
        self._time, self._acc = t, a
        self._time_list = t.tolist()  # fast scalar lookup with bisect
        self.name, self.source, self.units_in = str(name), str(source), units_in
        absacc = np.abs(a)
        self._sufmax = np.maximum.accumulate(absacc[::-1])[::-1]
        self._scale = 1.0
        self._nominal_dt: float | None = None  # the exact dt of equally spaced samples, if known
        self.vertical: Record | None = None
        self._vertical_resampled = False
        if vertical is not None:
            self._attach_vertical(vertical)

    # --- the vertical channel ------------------------------------------------------------------
    def _attach_vertical(self, vertical: Any) -> None:
        if not isinstance(vertical, Record):
            raise ParameterError("vertical", type(vertical).__name__,
                                 "a Record (the vertical channel, m/s^2, positive up)")
        if vertical.vertical is not None:
            raise ParameterError("vertical", vertical, "a Record without a vertical channel "
                                 "of its own")
        same = (vertical.npts == self.npts
                and np.allclose(vertical.time, self._time, rtol=0.0,
                                atol=1e-9 * max(1.0, float(np.max(np.abs(self._time))))))
        samples = vertical.samples if same else vertical.acceleration(self._time)
        v = Record(self._time, samples, name=vertical.name, source=vertical.source,
                   units_in=vertical.units_in)
        v._nominal_dt = self._nominal_dt
        v._scale = vertical._scale
        self.vertical = v
        self._vertical_resampled = not same

    def with_vertical(self, vertical: Record | None) -> Record:
        """This record with ``vertical`` [m/s^2, positive up] as its vertical channel (None:
        without one).

        The two channels share one time base: the vertical channel is *sampled at this
        record's times* (its own linear interpolation there, 0 outside its span). Two
        components of one station share the time base already (same start, dt and number of
        samples): their samples are then kept exactly. Otherwise the resampling is exact only
        where the vertical's samples are a subset of these times; a vertical sampled more
        finely loses what lies between them (``describe()["vertical_resampled"]`` says so).
        Why one time base: between two shared samples both accelerations are linear, so every
        threshold of the model (uplift at |u_g''| = lambda (g + a_v), sliding at
        |u_g''| = mu (g + a_v), loss of contact at a_v = -g) is crossed at most once and found
        exactly, by both analytic paths.
        """
        new = Record(self._time, self._acc, name=self.name, source=self.source,
                     units_in=self.units_in)
        new._scale = self._scale
        new._nominal_dt = self._nominal_dt
        if vertical is not None:
            new._attach_vertical(vertical)
        return new

    def with_vertical_ratio(self, ratio: float) -> Record:
        """This record with the vertical channel ``ratio`` times its own samples: a_v = r u_g''
        at every sample, in phase (as a Ricker pulse's ``vertical_ratio``; r in [0, 3], limit
        ``vertical_ratio``; 0: without a vertical channel). For a record without a recorded
        vertical channel (it replaces one this record has)."""
        from ..limits import check_in_limit

        if isinstance(ratio, (bool, np.bool_)):
            raise ParameterError("vertical_ratio", ratio, "a finite number in [0, 3]")
        r = check_in_limit("vertical_ratio", "vertical_ratio", ratio)
        if r == 0.0:
            return self.with_vertical(None)
        v = Record(self._time, r * self._acc, name=f"{r:g} x {self.name}", source=self.source,
                   units_in=self.units_in)
        v._scale = self._scale * r
        v._nominal_dt = self._nominal_dt
        return self.with_vertical(v)

    @classmethod
    def from_samples(cls, acc: Any, dt: float, t0: float = 0.0, units: str = "m/s2",
                     name: str = "", source: str = "") -> Record:
        """Record from equally spaced samples ``acc`` in ``units`` (any spelling of
        :func:`parse_units`: "g", "gal", "m/s^2", "cm/s/s", ...; g is
        :data:`rockbench.constants.G_STANDARD`), time step ``dt`` > 0 [s], first sample at ``t0``
        [s]. At most ``record_samples`` samples (:mod:`rockbench.limits`)."""
        dt = check_positive("dt", dt)
        t0 = check_finite("t0", t0)
        units = parse_units(units)
        factor = UNIT_FACTORS[units]
        _check_samples("acc", acc)
        a = _finite_vector("acceleration", acc) * factor
        record = cls(t0 + dt * np.arange(a.size), a, name=name, source=source, units_in=units)
        record._nominal_dt = dt
        return record

    # --- data --------------------------------------------------------------------------------
    @property
    def time(self) -> np.ndarray:
        """Sample times [s] (read-only)."""
        return self._time

    @property
    def samples(self) -> np.ndarray:
        """Acceleration samples [m/s^2] (read-only)."""
        return self._acc

    @property
    def npts(self) -> int:
        """Number of samples."""
        return int(self._time.size)

    @property
    def dt(self) -> float:
        """Sample spacing [s]: the ``dt`` given to :meth:`from_samples`, otherwise the median
        spacing of :attr:`time`."""
        if self._nominal_dt is not None:
            return self._nominal_dt
        return float(np.median(np.diff(self._time)))

    @property
    def t_start(self) -> float:
        """Time of the first sample [s]."""
        return float(self._time[0])

    @property
    def t_end(self) -> float:
        """Time of the last sample [s]."""
        return float(self._time[-1])

    @property
    def peak(self) -> float:
        """Peak ground acceleration max |sample| [m/s^2]."""
        return float(self._sufmax[0])

    # --- GroundMotion interface ------------------------------------------------------------
    def acceleration(self, t):
        """Linear interpolation of the samples [m/s^2] at ``t`` [s]; exactly 0 outside
        [t_start, t_end]."""
        if isinstance(t, (float, int)) and not isinstance(t, bool):
            ts = self._time_list
            if not ts[0] <= t <= ts[-1]:
                return 0.0
            i = bisect.bisect_right(ts, t) - 1
            if i >= len(ts) - 1:
                return float(self._acc[-1])
            w = (t - ts[i]) / (ts[i + 1] - ts[i])
            return float((1.0 - w) * self._acc[i] + w * self._acc[i + 1])
        t = _times(t)
        out = np.interp(t, self._time, self._acc, left=0.0, right=0.0)
        return float(out) if out.ndim == 0 else out

    def knots(self, t0: float, t1: float) -> np.ndarray:
        """``t0``, the sample times strictly inside (t0, t1), and ``t1`` [s]."""
        t0, t1 = _check_interval(t0, t1)
        i0 = np.searchsorted(self._time, t0, side="right")
        i1 = np.searchsorted(self._time, t1, side="left")
        ends = [t0] if t1 == t0 else [t0, t1]
        return np.unique(np.concatenate([ends, self._time[i0:i1]]))

    def max_abs_after(self, t: float) -> float:
        """sup |u_g''| over [t, inf) [m/s^2], exact for linear interpolation: the larger of
        |u_g''(t)| and the largest |sample| later than t (O(log n))."""
        t = check_finite("t", t)
        i = int(np.searchsorted(self._time, t, side="right"))
        later = float(self._sufmax[i]) if i < self._sufmax.size else 0.0
        return max(later, abs(self.acceleration(t)))

    def describe(self) -> dict[str, Any]:
        d = {
            "kind": "record",
            "name": self.name,
            "source": self.source,
            "units_in": self.units_in,
            "npts": self.npts,
            "dt_s": self.dt,
            "t_start_s": self.t_start,
            "t_end_s": self.t_end,
            "pga_m_s2": self.peak,
            "scale": self._scale,
        }
        if self.vertical is not None:       # absent without a vertical channel (keys unchanged)
            d["vertical_name"] = self.vertical.name
            d["vertical_pga_m_s2"] = self.vertical.peak
            d["vertical_resampled"] = self._vertical_resampled
        return d

    def scaled(self, factor: float) -> Record:
        """The record with every sample times ``factor``; the name gets " x{factor:g}". A
        vertical channel is scaled by the same factor (the whole ground motion, both
        components: a negative factor reverses both)."""
        factor = _check_factor(factor)
        new = Record(self._time, factor * self._acc, name=f"{self.name} x{factor:g}",
                     source=self.source, units_in=self.units_in)
        new._scale = self._scale * factor
        new._nominal_dt = self._nominal_dt
        if self.vertical is not None:
            v = self.vertical.scaled(factor)
            v._nominal_dt = self._nominal_dt
            new.vertical = v
            new._vertical_resampled = self._vertical_resampled
        return new

    def __repr__(self) -> str:
        vert = (f", vertical={self.vertical.name!r} (pga {self.vertical.peak:g} m/s2)"
                if self.vertical is not None else "")
        return (f"Record(name={self.name!r}, npts={self.npts}, dt={self.dt:g}, "
                f"t_start={self.t_start:g}, pga={self.peak:g} m/s2{vert})")


def _finite_vector(name: str, values: Any) -> np.ndarray:
    """``values`` as a new 1-D float array; ParameterError naming ``name`` unless all finite."""
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, _short(values), "a 1-D array of finite real numbers") from None
    if arr.ndim != 1:
        raise ParameterError(name, f"array of shape {arr.shape}", "a 1-D array")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise ParameterError(name, f"{name}[{i}]={float(arr[i])!r}", "finite")
    return arr


def _check_samples(name: str, values: Any) -> None:
    """ParameterError naming ``name`` if ``values`` holds more samples than the limit
    ``record_samples`` (:mod:`rockbench.limits`), checked from its length before any copy."""
    from ..limits import check_count

    try:
        n = len(values)
    except TypeError:
        return                 # a scalar or an iterator: _finite_vector names it
    check_count("record_samples", name, n, "samples")

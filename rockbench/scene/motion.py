"""Ground motions: Ricker pulses (Eqs. 29-30 of the paper) and recorded accelerograms, each
horizontal with an optional vertical component.

Conventions (``docs/conventions.md``): SI units, seconds, m/s^2. The ground acceleration
``u_g''(t)`` is horizontal, positive to the right (+x). A motion's ``vertical`` is None (no
vertical motion) or another :class:`GroundMotion` on the same clock whose acceleration
``a_v(t)`` [m/s^2] is vertical, positive up (+y): a pulse's vertical part is the same wavelet
times ``vertical_ratio`` (in phase), a record's is a second channel sampled at the horizontal
channel's times (:meth:`Record.with_vertical`). A run starts from rest at
:attr:`GroundMotion.t_start`; after :attr:`GroundMotion.t_end` the excitation is zero (records) or
below 1e-12 of its peak (pulses), so a solver may treat the motion as free rocking from there on.

Every motion offers the same small interface (:class:`GroundMotion`):

* ``acceleration(t)`` [m/s^2] for a float or an array of times [s];
* ``knots(t0, t1)``: times between which the acceleration is monotonic, so that a threshold
  crossing (e.g. the uplift condition ``|u_g''| > g tan alpha``) is bracketed by a sign change
  between consecutive knots and can be refined with ``scipy.optimize.brentq``;
* ``max_abs_after(t)`` [m/s^2]: the exact supremum of ``|u_g''|`` over ``[t, inf)`` (lets a solver
  decide that a structure at rest will never uplift again);
* ``peak`` [m/s^2], ``describe()`` (JSON-safe metadata) and ``scaled(factor)``;
* ``vertical``: None or the vertical component (a :class:`GroundMotion`, positive up). With
  one, ``knots`` serve both: between consecutive knots every combination
  ``u_g'' + c a_v`` (c a constant) is monotonic (pulse: a_v = ratio u_g''; record: both linear
  between the shared samples), so a threshold such as ``|u_g''| > lambda (g + a_v)`` is still
  bracketed by the knots.
"""

from __future__ import annotations

import abc
import bisect
import math
import os
from typing import Any

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_finite, check_positive
from ..limits import check_in_limit
from .units import UNIT_FACTORS, UNIT_SPELLINGS, parse_units, unit_factor
from ..result import motion_label

__all__ = [
    "GroundMotion",
    "RickerPulse",
    "Record",
    "UNIT_FACTORS",
    "UNIT_SPELLINGS",
    "parse_units",
    "unit_factor",
    "antisymmetric_beta",
    "make_pulse",
    "motion_from_spec",
]

#: Ricker pulse shapes of Eq. (29) ("symmetric") and Eq. (30) ("antisymmetric").
PULSE_SHAPES = ("symmetric", "antisymmetric")

#: Pulse knots are at most this fraction of the period T_g apart.
_KNOTS_PER_PERIOD = 400

#: A pulse run starts at t = -_HALF_WINDOW T_g and its excitation ends at +_HALF_WINDOW T_g.
_HALF_WINDOW = 3.0

def _check_factor(factor: Any) -> float:
    x = check_finite("factor", factor)
    if x == 0.0:
        raise ParameterError("factor", factor, "a finite, non-zero real number")
    return x


def _check_shape(shape: Any) -> str:
    if not isinstance(shape, str) or shape not in PULSE_SHAPES:
        raise ParameterError("shape", shape, f"one of {', '.join(map(repr, PULSE_SHAPES))}")
    return shape


def _check_sign(sign: Any) -> int:
    if isinstance(sign, (bool, np.bool_)) or not isinstance(sign, (int, float, np.number)) \
            or sign not in (1, -1):
        raise ParameterError("sign", sign, "+1 or -1")
    return int(sign)


def _check_vertical_ratio(ratio: Any) -> float:
    """The vertical ratio as a float in the limit ``vertical_ratio`` of
    :mod:`rockbench.limits` ([0, 3]); ParameterError naming ``vertical_ratio`` otherwise."""
    if isinstance(ratio, (bool, np.bool_)):
        raise ParameterError("vertical_ratio", ratio, "a finite number in [0, 3]")
    return check_in_limit("vertical_ratio", "vertical_ratio", ratio)


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


# ------------------------------------------------------------------------------------------------
# Ricker wavelets in dimensionless time tau = t / T_g. Written with ``exp`` as an argument so the
# same expression serves scalars (math.exp, fast in an ODE right-hand side) and arrays (np.exp).

def _symmetric_wavelet(tau, exp=np.exp):
    """Eq. (29) divided by a_g: (1 - 2 pi^2 tau^2) exp(-pi^2 tau^2)."""
    u = math.pi**2 * tau * tau
    return (1.0 - 2.0 * u) * exp(-u)


def _x_of_tau(tau):
    """x = 2 pi tau / sqrt(3), the natural variable of Eq. (30)."""
    return (2.0 * math.pi / math.sqrt(3.0)) * tau


def _antisymmetric_raw(tau, exp=np.exp):
    """Eq. (30) times beta / a_g: f(x) = (x^2 - 3) x exp(-x^2 / 2), x = 2 pi tau / sqrt(3)."""
    x = _x_of_tau(tau)
    return (x * x - 3.0) * x * exp(-0.5 * x * x)


def antisymmetric_beta() -> float:
    """The factor beta of Eq. (30) that makes the antisymmetric Ricker pulse peak at exactly a_g.

    With x = 2 pi t / (sqrt(3) T_g), Eq. (30) is (a_g / beta) f(x) with
    f(x) = (x^3 - 3x) exp(-x^2/2). Then f'(x) = -(x^4 - 6x^2 + 3) exp(-x^2/2), a quadratic in x^2
    with roots x^2 = 3 -+ sqrt(6). The larger |f| is at x^2 = 3 - sqrt(6), where
    x^2 - 3 = -sqrt(6), so

        beta = max |f| = sqrt(6) sqrt(3 - sqrt(6)) exp(-(3 - sqrt(6)) / 2) = 1.38007...

    (the paper rounds it to 1.38). The secondary extrema at x^2 = 3 + sqrt(6) have
    |f| = sqrt(6) sqrt(3 + sqrt(6)) exp(-(3 + sqrt(6)) / 2) = 0.3749..., i.e. 0.272 beta.
    """
    x2 = 3.0 - math.sqrt(6.0)
    return math.sqrt(6.0) * math.sqrt(x2) * math.exp(-0.5 * x2)


def _extrema_tau(shape: str) -> np.ndarray:
    """Dimensionless times tau = t / T_g of all local extrema of the wavelet, sorted.

    Symmetric (Eq. 29): d/du[(1 - 2u) e^-u] = (2u - 3) e^-u with u = pi^2 tau^2, so tau = 0 and
    tau = +-sqrt(3/2) / pi. Antisymmetric (Eq. 30): x^2 = 3 -+ sqrt(6) (see
    :func:`antisymmetric_beta`), tau = sqrt(3) x / (2 pi).
    """
    if shape == "symmetric":
        t = math.sqrt(1.5) / math.pi
        return np.array([-t, 0.0, t])
    xs = np.sqrt([3.0 - math.sqrt(6.0), 3.0 + math.sqrt(6.0)])
    taus = math.sqrt(3.0) * xs / (2.0 * math.pi)
    return np.concatenate([-taus[::-1], taus])


class RickerPulse(GroundMotion):
    """A Ricker wavelet ground acceleration pulse centred at t = 0 [paper Eqs. (29), (30)].

    Symmetric (Mexican hat, Eq. 29)::

        u_g''(t) = s a_g (1 - 2 pi^2 t^2 / T_g^2) exp(-pi^2 t^2 / T_g^2)

    Antisymmetric (Vassiliou & Makris 2011, Eq. 30)::

        u_g''(t) = s (a_g / beta) (4 pi^2 t^2 / (3 T_g^2) - 3) (2 pi t / (sqrt(3) T_g))
                   exp(-2 pi^2 t^2 / (3 T_g^2))

    with beta = :func:`antisymmetric_beta` = 1.38007... computed so that max |u_g''| = a_g exactly.
    ``s`` = ``sign``: +1 is the pulse as printed (symmetric: positive peak a_g at t = 0;
    antisymmetric: positive lobe at t < 0, negative main lobe at t > 0), -1 its mirror image.
    T_g = 2 pi / omega_g is the period at which the wavelet's Fourier spectrum peaks.

    With ``vertical_ratio`` r > 0 the ground also moves vertically, in phase:
    a_v(t) = r u_g''(t) [m/s^2], positive up (the same wavelet, sign and period; peak r a_g).
    :attr:`vertical` is then that pulse (a :class:`RickerPulse` of amplitude r a_g), None when
    r = 0.

    The pulse is defined for all t; a run starts from rest at ``t_start = -3 T_g`` and
    ``t_end = +3 T_g``. Beyond +-3 T_g, |u_g''| / a_g < 1e-36 (symmetric) and < 1e-22
    (antisymmetric): the truncation is far below the 1e-12 of the :class:`GroundMotion` contract.
    The velocity t-integral of either pulse returns to exactly zero (closed forms:
    v_g = s a_g t exp(-pi^2 t^2 / T_g^2) for Eq. 29; v_g = s (a_g / beta) (sqrt(3) T_g / (2 pi))
    (1 - x^2) exp(-x^2 / 2) for Eq. 30, x = 2 pi t / (sqrt(3) T_g)).

    Parameters
    ----------
    amplitude : float
        a_g > 0 [m/s^2], the maximum of |u_g''|; at most 1e4 m/s^2 (limit ``amplitude`` of
        :mod:`rockbench.limits`).
    period : float
        T_g > 0 [s], in [1e-4, 1e4] s (limit ``period``).
    shape : {"symmetric", "antisymmetric"}
    sign : {+1, -1}
    vertical_ratio : float
        r [-], peak vertical over peak horizontal acceleration, in [0, 3] (limit
        ``vertical_ratio``; default 0: no vertical motion).
    """

    def __init__(self, amplitude: float, period: float, shape: str = "symmetric", sign: int = 1,
                 vertical_ratio: float = 0.0):
        self._amplitude = check_in_limit("amplitude", "amplitude", amplitude)
        self._period = check_in_limit("period", "period", period)
        self._shape = _check_shape(shape)
        self._sign = _check_sign(sign)
        self._vertical_ratio = _check_vertical_ratio(vertical_ratio)
        self._dimensionless: dict[str, float] | None = None
        self.vertical = None
        if self._vertical_ratio > 0.0:
            self.vertical = RickerPulse(self._vertical_ratio * self._amplitude, self._period,
                                        self._shape, self._sign)
        if shape == "symmetric":
            self._wavelet, self._scale = _symmetric_wavelet, self._sign * self._amplitude
        else:
            self._wavelet = _antisymmetric_raw
            self._scale = self._sign * self._amplitude / antisymmetric_beta()
        self._extrema = self._period * _extrema_tau(shape)
        # suffix maxima of |acc| at the extrema, for max_abs_after
        ext_abs = np.abs(self.acceleration(self._extrema))
        self._extrema_sufmax = np.maximum.accumulate(ext_abs[::-1])[::-1]

    # --- construction helpers ---------------------------------------------------------------
    @classmethod
    def dimensionless(cls, A: float, W: float, structure: Any, shape: str = "symmetric",
                      sign: int = 1, vertical_ratio: float = 0.0) -> RickerPulse:
        """The pulse at the paper's dimensionless coordinates (Fig. 4 axes).

        ``A = a_g / (g tan alpha)`` > 0 and ``W = omega_g / p`` > 0 with ``alpha`` [rad] and ``p``
        [rad/s] of ``structure`` (the taller column of a frame), g = :data:`rockbench.constants.G`:
        a_g = A g tan(alpha) [m/s^2] and T_g = 2 pi / (W p) [s]. A is at most 100 and W in
        [0.01, 1000] (limits ``A`` and ``W`` of :mod:`rockbench.limits`; the paper's maps use
        A up to ~20 and W 0.3-50). ``vertical_ratio`` as in the class docstring.
        """
        A = check_in_limit("A", "A", A)
        W = check_in_limit("W", "W", W)
        try:
            alpha, p = float(structure.alpha), float(structure.p)
        except (AttributeError, TypeError, ValueError):
            raise ParameterError("structure", structure,
                                 "a Block or Frame (an object with .alpha [rad] and .p [rad/s])"
                                 ) from None
        pulse = cls(A * G * math.tan(alpha), 2.0 * math.pi / (W * p), shape, sign,
                    vertical_ratio)
        pulse._dimensionless = {"A": A, "W": W, "alpha_rad": alpha, "p_rad_s": p}
        return pulse

    # --- parameters --------------------------------------------------------------------------
    @property
    def amplitude(self) -> float:
        """a_g [m/s^2]."""
        return self._amplitude

    @property
    def period(self) -> float:
        """T_g [s]."""
        return self._period

    @property
    def omega(self) -> float:
        """omega_g = 2 pi / T_g [rad/s]."""
        return 2.0 * math.pi / self._period

    @property
    def shape(self) -> str:
        """"symmetric" (Eq. 29) or "antisymmetric" (Eq. 30)."""
        return self._shape

    @property
    def sign(self) -> int:
        """+1 (as printed in the paper) or -1 (mirrored)."""
        return self._sign

    @property
    def vertical_ratio(self) -> float:
        """r [-]: a_v = r u_g'' (0: no vertical motion)."""
        return self._vertical_ratio

    @property
    def t_start(self) -> float:
        """-3 T_g [s]."""
        return -_HALF_WINDOW * self._period

    @property
    def t_end(self) -> float:
        """+3 T_g [s]."""
        return _HALF_WINDOW * self._period

    @property
    def peak(self) -> float:
        """a_g [m/s^2] (exact for both shapes, by the choice of beta)."""
        return self._amplitude

    # --- GroundMotion interface ------------------------------------------------------------
    def acceleration(self, t):
        """u_g''(t) [m/s^2] by Eq. (29) or (30); ``t`` [s] float or array."""
        if isinstance(t, (float, int)) and not isinstance(t, bool):
            return self._scale * self._wavelet(t / self._period, math.exp)
        t = _times(t)
        out = self._scale * self._wavelet(t / self._period)
        return float(out) if out.ndim == 0 else out

    def knots(self, t0: float, t1: float) -> np.ndarray:
        """``t0``, ``t1`` [s], a uniform grid of spacing <= T_g / 400 over the part of
        [t0, t1] inside the pulse window [-3 T_g, 3 T_g], and the pulse's extrema inside
        (t0, t1), so that u_g'' is strictly monotonic between knots. Outside the window the
        wavelet has no extremum (all lie within 0.7 T_g of t = 0), so at most 2400 grid knots
        are returned whatever the interval's length (a long run of a short pulse stays cheap).
        """
        t0, t1 = _check_interval(t0, t1)
        parts = [np.array([t0, t1])]
        a, b = max(t0, self.t_start), min(t1, self.t_end)
        if a < b:
            n = max(1, math.ceil((b - a) * _KNOTS_PER_PERIOD / self._period))
            parts.append(np.linspace(a, b, n + 1))
        parts.append(self._extrema[(self._extrema > t0) & (self._extrema < t1)])
        return np.unique(np.concatenate(parts))

    def max_abs_after(self, t: float) -> float:
        """sup |u_g''| over [t, inf) [m/s^2], exact: the larger of |u_g''(t)| and |u_g''| at the
        analytic extrema later than t."""
        t = check_finite("t", t)
        i = int(np.searchsorted(self._extrema, t, side="left"))
        later = float(self._extrema_sufmax[i]) if i < self._extrema.size else 0.0
        return max(later, abs(self.acceleration(t)))

    def describe(self) -> dict[str, Any]:
        d: dict[str, Any] = {
            "kind": "ricker",
            "shape": self._shape,
            "sign": self._sign,
            "amplitude_m_s2": self._amplitude,
            "period_s": self._period,
            "omega_rad_s": self.omega,
            "t_start_s": self.t_start,
            "t_end_s": self.t_end,
        }
        if self._shape == "antisymmetric":
            d["beta"] = antisymmetric_beta()
        if self._vertical_ratio > 0.0:      # absent without vertical motion (keys unchanged)
            d["vertical_ratio"] = self._vertical_ratio
        if self._dimensionless is not None:
            d.update(self._dimensionless)
        return d

    def scaled(self, factor: float) -> RickerPulse:
        """The same pulse with a_g -> |factor| a_g and sign -> sign * sign(factor); the
        dimensionless amplitude A (if any) scales with it, W is unchanged. The vertical part
        (a_v = r u_g'') scales with it: the ratio r is kept."""
        factor = _check_factor(factor)
        new = RickerPulse(abs(factor) * self._amplitude, self._period, self._shape,
                          self._sign * (1 if factor > 0 else -1), self._vertical_ratio)
        if self._dimensionless is not None:
            new._dimensionless = dict(self._dimensionless, A=abs(factor) * self._dimensionless["A"])
        return new

    def __repr__(self) -> str:
        vr = (f", vertical_ratio={self._vertical_ratio!r}" if self._vertical_ratio > 0.0
              else "")
        return (f"RickerPulse(amplitude={self._amplitude!r}, period={self._period!r}, "
                f"shape={self._shape!r}, sign={self._sign!r}{vr})")


def make_pulse(shape: str, sign: int, *, structure: Any = None, A: float | None = None,
               W: float | None = None, amplitude: float | None = None,
               period: float | None = None, vertical_ratio: float = 0.0) -> RickerPulse:
    """Build a :class:`RickerPulse` either from dimensionless ``A``, ``W`` and ``structure``
    (see :meth:`RickerPulse.dimensionless`) or from ``amplitude`` [m/s^2] and ``period`` [s],
    with the vertical part ``vertical_ratio`` [-] times the horizontal one (default 0: none).

    Exactly one of the two sets must be given, completely; anything else raises
    :class:`ParameterError` naming the missing or conflicting parameter.
    """
    dimless = A is not None or W is not None
    dimensional = amplitude is not None or period is not None
    if dimless and dimensional:
        raise ParameterError("amplitude" if amplitude is not None else "period",
                             amplitude if amplitude is not None else period,
                             "omitted when A and W are given",
                             "give either (A, W, structure) or (amplitude, period)")
    if dimless:
        for key, value in (("A", A), ("W", W), ("structure", structure)):
            if value is None:
                raise ParameterError(key, None, "given: A, W and structure go together")
        return RickerPulse.dimensionless(A, W, structure, shape, sign, vertical_ratio)
    if dimensional:
        for key, value in (("amplitude", amplitude), ("period", period)):
            if value is None:
                raise ParameterError(key, None, "given: amplitude and period go together")
        return RickerPulse(amplitude, period, shape, sign, vertical_ratio)
    raise ParameterError("A", None, "given with W and structure, unless amplitude and period are",
                         "no pulse intensity was specified")


def motion_from_spec(spec: dict[str, Any] | None, structure: Any = None) -> GroundMotion | None:
    """The one translator from a motion *spec* (plain data: what cases, sweeps, maps and the
    campaign store) to a :class:`GroundMotion`.

    ``None`` or ``{"kind": "none"}``: free rocking (returns None).
    ``{"kind": "ricker", "shape", "sign", "A", "W"}`` (dimensionless, needs ``structure``) or
    ``{"kind": "ricker", "shape", "sign", "amplitude" [m/s^2], "period" [s]}``: see
    :func:`make_pulse`; either may add ``"vertical_ratio"`` [-] (a vertical part, default 0;
    ``describe()`` writes it when it is not 0, so a description reads back as the same pulse).
    ``{"kind": "record", "path", "dt" [s], "units", "scale"}``: see
    :func:`rockbench.scene.records.load_record` (``dt`` and ``units`` may be omitted for an
    AT2 file); ``"vertical_path"`` (with ``"vertical_dt"`` [s] and ``"vertical_units"`` for a
    headerless file) adds the vertical channel (:func:`rockbench.scene.records.load_record`'s
    ``vertical``), scaled by the same ``scale``.
    """
    if spec is None:
        return None
    if not isinstance(spec, dict):
        raise ParameterError("motion", spec, "a dict with 'kind' in ricker, record, none "
                                             "(or None)")
    kind = spec.get("kind")
    if kind == "none":
        return None
    if kind == "ricker":
        vr = spec.get("vertical_ratio", 0.0)
        if "A" in spec or "W" in spec:
            return make_pulse(spec.get("shape", "symmetric"), spec.get("sign", 1),
                              structure=structure, A=spec.get("A"), W=spec.get("W"),
                              vertical_ratio=vr)
        return make_pulse(spec.get("shape", "symmetric"), spec.get("sign", 1),
                          amplitude=spec.get("amplitude", spec.get("amplitude_m_s2")),
                          period=spec.get("period", spec.get("period_s")), vertical_ratio=vr)
    if kind == "record":
        from .records import load_record
        if not isinstance(spec.get("path"), (str, os.PathLike)):
            raise ParameterError("motion.path", spec.get("path"), "the path of a record file")
        vpath = spec.get("vertical_path")
        if vpath is not None and not isinstance(vpath, (str, os.PathLike)):
            raise ParameterError("motion.vertical_path", vpath, "the path of a record file")
        return load_record(spec["path"], dt=spec.get("dt"), units=spec.get("units"),
                           scale=spec.get("scale", 1.0), vertical=vpath,
                           vertical_dt=spec.get("vertical_dt"),
                           vertical_units=spec.get("vertical_units"))
    raise ParameterError("motion.kind", kind, "one of ricker, record, none")


# ------------------------------------------------------------------------------------------------
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


def _check_samples(name: str, values: Any) -> None:
    """ParameterError naming ``name`` if ``values`` holds more samples than the limit
    ``record_samples`` (:mod:`rockbench.limits`), checked from its length before any copy."""
    from ..limits import check_count

    try:
        n = len(values)
    except TypeError:
        return                 # a scalar or an iterator: _finite_vector names it
    check_count("record_samples", name, n, "samples")

"""Ground motions: Ricker pulses (Eqs. 29-30 of the paper) and recorded accelerograms, each
horizontal with an optional vertical component.

Conventions (``docs/conventions.md``): SI units, seconds, m/s^2. The ground acceleration
``u_g''(t)`` is horizontal, positive to the right (+x). A motion's ``vertical`` is None (no
vertical motion) or another :class:`GroundMotion` on the same clock whose acceleration
``a_v(t)`` [m/s^2] is vertical, positive up (+y): a pulse's vertical part is the same wavelet
times ``vertical_ratio`` (in phase), a record's is a second channel sampled at the horizontal
channel's times (:meth:`Record.with_vertical`), and any two motions pair as
:class:`WithVertical` (horizontal, vertical). A run starts from rest at
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

import math
import os
from typing import Any

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_finite
from ..limits import check_in_limit
from .motion_base import GroundMotion, _check_factor, _check_interval, _times
from .recorded import Record
from .units import UNIT_FACTORS, UNIT_SPELLINGS, parse_units, unit_factor
from .with_vertical import WithVertical

__all__ = [
    "GroundMotion",
    "RickerPulse",
    "Record",
    "WithVertical",
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
    ``vertical``), scaled by the same ``scale``; or ``"vertical_ratio"`` r [-] the channel r
    times the (scaled) horizontal one (:meth:`Record.with_vertical_ratio`; not both).
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
        vr = spec.get("vertical_ratio", 0.0)
        if vpath is not None and vr:
            raise ParameterError("motion.vertical_ratio", vr, "left out with vertical_path (a "
                                 "record has one vertical channel)")
        rec = load_record(spec["path"], dt=spec.get("dt"), units=spec.get("units"),
                          scale=spec.get("scale", 1.0), vertical=vpath,
                          vertical_dt=spec.get("vertical_dt"),
                          vertical_units=spec.get("vertical_units"))
        return rec.with_vertical_ratio(vr) if vr else rec
    raise ParameterError("motion.kind", kind, "one of ricker, record, none")

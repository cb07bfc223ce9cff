"""Intensity measures of a ground-motion record: what a fragility curve is drawn against
(``docs/fragility.md``). Pure functions of a :class:`rockbench.scene.motion.Record` as loaded
(scale 1); a scaled record's measure is the scale times this one (every measure here is
linear in the record).

Two measures are the record's alone (PGA, PGV); three need the structure's own scales, the
slenderness alpha [rad] and the frequency parameter p [rad/s] of the taller column
(:class:`Structure`): the dimensionless PGA / (g tan alpha) and PGV / (p g tan alpha) of the
rocking literature, and the pseudo-spectral acceleration at the period the structure defines,
T_p = 2 pi / p. Why that period: the rocking equation has one time scale, 1 / p; a ground
motion of circular frequency omega_g drives it by omega_g / p (the paper's W axis), and T_p is
the period of W = 1. A rocking frame is not an oscillator (its period grows with its amplitude,
Housner 1963; Makris & Konstantinidis 2003 warn against reading it from a linear oscillator's
spectrum): Sa(T_p) is a candidate measure, judged by its dispersion like the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_positive

__all__ = ["MEASURES", "BASE_MEASURE", "SA_DAMPING", "SA_TAIL_PERIODS", "Structure",
           "intensity", "intensities", "pseudo_spectral_acceleration", "strong_motion_end"]

#: Intensity measures: key -> (name, unit, definition).
MEASURES: dict[str, tuple[str, str, str]] = {
    "pga": ("PGA", "m/s^2", "peak ground acceleration max |a_g| of the scaled record"),
    "pgv": ("PGV", "m/s", "peak ground velocity max |v_g| of the scaled record, v_g the "
                          "trapezoidal integral of a_g from v_g = 0 at the first sample, "
                          "no baseline correction"),
    "pga_norm": ("PGA/(g tan alpha)", "-",
                 "PGA over the uplift acceleration g tan alpha of the taller column (g = 9.81 "
                 "m/s^2): the A of the paper's axes"),
    "pgv_norm": ("PGV/(p g tan alpha)", "-",
                 "PGV over p g tan alpha, alpha and p [rad/s] of the taller column"),
    "sa": ("Sa(T_p)", "m/s^2",
           "5 %-damped pseudo-spectral acceleration omega^2 max |u| at the period T_p = 2 pi / p "
           "of the taller column's frequency parameter p (W = omega_g / p = 1), the oscillator "
           "from rest, exact for a linear a_g between samples, run 3 periods past the record"),
}

#: A dimensionless measure -> the measure it is a constant multiple of for one structure: its
#: fragility dispersion is that measure's (its median is the other's over the constant).
BASE_MEASURE: dict[str, str] = {"pga_norm": "pga", "pgv_norm": "pgv"}

#: Damping ratio of the oscillator of Sa [-]; free vibration after the record [periods].
SA_DAMPING = 0.05
SA_TAIL_PERIODS = 3.0

_STRUCTURAL = ("pga_norm", "pgv_norm", "sa")


@dataclass(frozen=True)
class Structure:
    """The scales of a structure that the dimensionless measures and Sa need: ``alpha`` the
    slenderness [rad] and ``p`` the frequency parameter [rad/s] of the taller column."""

    alpha: float
    p: float

    def __post_init__(self) -> None:
        a = check_positive("alpha", self.alpha)
        if not a < math.pi / 2:
            raise ParameterError("alpha", self.alpha, "in (0, pi/2) rad")
        object.__setattr__(self, "alpha", a)
        object.__setattr__(self, "p", check_positive("p", self.p))

    @classmethod
    def of(cls, scene: Any) -> "Structure":
        """The scales of a Scene (its taller column: ``scene.alpha``, ``scene.p``)."""
        return cls(float(scene.alpha), float(scene.p))

    @property
    def period(self) -> float:
        """T_p = 2 pi / p [s]: the period of Sa."""
        return 2.0 * math.pi / self.p

    @property
    def uplift_acceleration(self) -> float:
        """g tan alpha [m/s^2]."""
        return G * math.tan(self.alpha)

    def factor(self, measure: str) -> float:
        """The constant a dimensionless measure divides its base measure by (1 otherwise):
        g tan alpha [m/s^2] for pga_norm, p g tan alpha [m/s] for pgv_norm."""
        if measure == "pga_norm":
            return self.uplift_acceleration
        if measure == "pgv_norm":
            return self.p * self.uplift_acceleration
        return 1.0


def _check(measure: str) -> None:
    if measure not in MEASURES:
        raise ParameterError("intensity", measure, f"one of {', '.join(MEASURES)}")


def _velocity(record) -> np.ndarray:
    a = np.asarray(record.samples, dtype=float)
    t = np.asarray(record.time, dtype=float)
    return np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(t))])


def pseudo_spectral_acceleration(record, period: float, damping: float = SA_DAMPING) -> float:
    """omega^2 max |u| [m/s^2] of the oscillator u'' + 2 zeta omega u' + omega^2 u = -a_g(t)
    from rest (omega = 2 pi / ``period`` [s], zeta = ``damping`` in [0, 1)), exact for a_g
    linear between the record's samples (the first-order-hold discretization), run
    :data:`SA_TAIL_PERIODS` periods past the record's last sample (its free vibration).
    Samples at unequal spacing are resampled linearly at the smallest spacing first."""
    from scipy.signal import cont2discrete, lfilter, ss2tf

    period = check_positive("period", period)
    if not 0.0 <= damping < 1.0:
        raise ParameterError("damping", damping, "in [0, 1)")
    t = np.asarray(record.time, dtype=float)
    a = np.asarray(record.samples, dtype=float)
    steps = np.diff(t)
    dt = float(steps.min())
    if float(steps.max()) - dt > 1e-9 * dt:
        tt = np.arange(t[0], t[-1] + dt / 2, dt)
        a, t = np.interp(tt, t, a), tt
    w = 2.0 * math.pi / period
    sys = (np.array([[0.0, 1.0], [-w * w, -2.0 * damping * w]]), np.array([[0.0], [-1.0]]),
           np.array([[1.0, 0.0]]), np.array([[0.0]]))
    ad, bd, cd, dd, _ = cont2discrete(sys, dt, method="foh")
    num, den = ss2tf(ad, bd, cd, dd)
    a = np.concatenate([a, np.zeros(int(math.ceil(SA_TAIL_PERIODS * period / dt)))])
    return w * w * float(np.max(np.abs(lfilter(num[0], den, a))))


def intensities(record, structure: Structure | None = None,
                measures: Iterable[str] | None = None) -> dict[str, float]:
    """The measures ``measures`` (default: every one of :data:`MEASURES` that ``structure``
    allows: PGA and PGV without it) of a Record as loaded (scale 1), in the units of
    :data:`MEASURES`. ``structure``: a :class:`Structure`, needed by pga_norm, pgv_norm and
    sa (ParameterError without it)."""
    keys = list(measures) if measures is not None else [
        k for k in MEASURES if structure is not None or k not in _STRUCTURAL]
    for k in keys:
        _check(k)
        if k in _STRUCTURAL and structure is None:
            raise ParameterError("structure", None, f"a Structure (alpha, p) for the measure {k}")
    out: dict[str, float] = {}
    pga = float(np.max(np.abs(np.asarray(record.samples, dtype=float))))
    pgv = float(np.max(np.abs(_velocity(record)))) if {"pgv", "pgv_norm"} & set(keys) else 0.0
    for k in keys:
        if k == "sa":
            out[k] = pseudo_spectral_acceleration(record, structure.period)
        else:
            base = BASE_MEASURE.get(k, k)
            v = pga if base == "pga" else pgv
            out[k] = v / (structure.factor(k) if k in BASE_MEASURE else 1.0)
    return out


def intensity(record, measure: str = "pga", structure: Structure | None = None) -> float:
    """The intensity measure ``measure`` (:data:`MEASURES`) of a
    :class:`rockbench.scene.motion.Record` as loaded (scale 1), in its unit: PGA [m/s^2], PGV
    [m/s], PGA / (g tan alpha) [-], PGV / (p g tan alpha) [-], Sa(T_p) [m/s^2]; the last three
    need ``structure`` (:class:`Structure`)."""
    _check(measure)
    return intensities(record, structure, [measure])[measure]


def strong_motion_end(record, fraction: float = 0.95) -> float:
    """The time [s] from the record's first sample at which int a_g^2 dt (trapezoidal) reaches
    ``fraction`` (in (0, 1]) of its total: the end of the strong motion (95 %: the t_95 of the
    significant duration D5-95). 0 for a record of zeros."""
    if not 0.0 < fraction <= 1.0:
        raise ParameterError("fraction", fraction, "in (0, 1]")
    t = np.asarray(record.time, dtype=float)
    a2 = np.asarray(record.samples, dtype=float) ** 2
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (a2[1:] + a2[:-1]) * np.diff(t))])
    if cum[-1] <= 0.0:
        return 0.0
    i = int(np.searchsorted(cum, fraction * cum[-1]))
    if i == 0:
        return 0.0
    lo, hi = cum[i - 1], cum[i]
    w = (fraction * cum[-1] - lo) / (hi - lo) if hi > lo else 1.0
    return float(t[i - 1] + w * (t[i] - t[i - 1]) - t[0])

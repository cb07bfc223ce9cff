"""Synthetic ground motions: the site-based stochastic model of Rezaeian & Der Kiureghian.

A record set the package may ship and regenerate bit for bit from a seed, for
studies (fragility, the report's Fig. 9 section) that need >= 20 records without external files.
``docs/synthetic.md`` is the user's page: the model, its sources, the default scenario, and what
the motions are not (no near-fault velocity pulses).

The model
---------
* Rezaeian S., Der Kiureghian A. (2008), "A stochastic ground motion model with separable
  temporal and spectral nonstationarities", Earthquake Eng. Struct. Dyn. 37:1565-1584
  (RDK08): a time-modulated, filtered, discretized white noise. With white-noise pulses u_i
  (iid standard normal) at t_i = i dt and t_k the current sample,

      x(t_k) = q(t_k) * sum_{i<k} h(t_k - t_i; t_i) u_i / sqrt(sum_{i<k} h(t_k - t_i; t_i)^2)

  (unit variance before modulation, so E[x(t)^2] = q(t)^2 whatever dt), with the gamma-shaped
  modulating function q(t) = alpha1 t^(alpha2 - 1) exp(-alpha3 t) [m/s^2] and the impulse
  response of a linear oscillator whose frequency is that of the pulse's time tau:

      h(s; tau) = omega_f(tau) / sqrt(1 - zeta_f^2) exp(-zeta_f omega_f(tau) s)
                  sin(omega_f(tau) sqrt(1 - zeta_f^2) s),   s >= 0,
      omega_f(tau) = omega_mid + omega' (tau - t_mid),   zeta_f constant.

* Rezaeian S., Der Kiureghian A. (2010), "Simulation of synthetic ground motions for specified
  earthquake and site characteristics", Earthquake Eng. Struct. Dyn. 39:1155-1180 (RDK10):
  (a) the physical parameters theta = (Ia, D5-95, t_mid, omega_mid/2pi, omega'/2pi, zeta_f)
  are predicted from the fault type F (0 strike-slip, 1 reverse), the moment magnitude M, the
  rupture distance R_rup [km] and V_s30 [m/s] in the standard-normal space:
  nu_i = Phi^-1(F_i(theta_i)) = mu_i(F, M, R, V) + eta_i + eps_i, F_i the fitted marginal
  distribution of theta_i, eta/eps the inter/intra-event errors (correlated between the six
  parameters); (b) a high-pass filter, the critically damped oscillator
  z'' + 2 omega_c z' + omega_c^2 z = x(t) from rest, whose z'' is the simulated acceleration:
  its velocity z' and displacement z return to zero after the motion (omega_c = 2 pi 0.2 rad/s,
  :data:`CORNER_FREQUENCY`).

Sources of the numbers (:data:`MARGINALS`, :data:`REGRESSION`, :data:`SIGMA_TAU`,
:data:`CORRELATION`): the fitted marginal distributions, the regression coefficients, the
inter-/intra-event standard deviations and the correlation of the total errors of RDK10, as the
authors' regression outputs (``combo_*_NlinearRegressionWRndEffect_u1.mat``) are written in the
SCEC Broadband Platform (``bbp/comps/rzz2015_gmpe.py``, Apache-2.0; used there by Rezaeian,
Zhong, Hartzell & Zareian 2015, BSSA 105(6), to validate simulations with these equations).
The paper's own text could not be read where this was written, so tables are not numbered here;
``docs/synthetic.md`` says how the numbers were checked (the ensemble's median PGA, PGV and
spectral shape against the NGA-West2 model of Boore et al. 2014, ``tests/scene/test_synthetic.py``).

Choices of this implementation (documented, not the papers'): a drawn parameter set whose
modulating function would not start from zero (alpha2 <= 1, i.e. D5-95 / t_mid >= 4.93) is
drawn again (2.1 % of the default scenario's draws); omega_f(tau) is floored at
2 pi :data:`FREQUENCY_FLOOR` (the linear law turns negative early in a record with a steep
positive slope or late with a steep negative one: 27 % of the default scenario's sets touch the
floor somewhere, in the quiet start or end of the motion); zeta_f is capped at 0.99; the
excitation ends when 99.99 % of the expected Arias intensity is reached and the record lasts
:data:`TAIL` seconds more, in which the high-pass filter comes to rest.

Units of Ia. The regression's Ia is taken as int a^2 dt with a in g (g^2 s, the unit the
authors' code labels its Arias intensities with); the Arias intensity (pi / 2g) int a^2 dt
[m/s] is pi g / 2 times it. Read as (pi / 2g) int a^2 dt in s.g instead, every motion would
have 2 / pi of the energy and 0.80 of the amplitudes: the median PGA of the default scenario
would fall from 1.06 to 0.85 of the NGA-West2 median (``docs/synthetic.md``, measured over 100
records).
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..constants import G_STANDARD
from ..errors import ParameterError, RockbenchError, check_finite, check_positive
from .motion import Record

__all__ = ["FAULTS", "RANGES", "MARGINALS", "REGRESSION", "SIGMA_TAU", "CORRELATION",
           "CORNER_FREQUENCY", "FREQUENCY_FLOOR", "TAIL", "ScenarioEarthquake",
           "ModelParameters", "DEFAULT_SCENARIO", "predicted_median", "draw_parameters",
           "modulating_parameters", "excitation_end", "record_duration", "simulate", "ensemble",
           "write_ensemble", "arias_intensity", "energy_times", "upcrossings"]

#: Fault types of RDK10: F = 0 strike-slip (and normal), F = 1 reverse (and reverse-oblique).
FAULTS: dict[str, int] = {"strike-slip": 0, "reverse": 1}

#: Range of the regression's data set (RDK10, NGA records without near-fault pulses):
#: name -> (low, high, unit). A scenario outside it is refused.
RANGES: dict[str, tuple[float, float, str]] = {
    "magnitude": (6.1, 7.6, "-"),
    "distance": (6.3, 111.5, "km"),
    "vs30": (206.0, 2016.0, "m/s"),
}

#: Fitted marginal distributions F_i of the six parameters (RDK10), in the paper's units:
#: Ia [g^2 s] lognormal (mean and standard deviation of ln Ia); D5-95 [s] and t_mid [s] beta on
#: [low, high]; omega_mid/2pi [Hz] gamma (shape, scale [Hz]); omega'/2pi [Hz/s] two-sided
#: exponential on [-2, 0.5] with density c exp(b x) for x < 0 and c exp(-a x) for x >= 0;
#: zeta_f [-] beta on [0.02, 1].
MARGINALS: dict[str, tuple[Any, ...]] = {
    "arias": ("lognormal", -4.8255, 1.4318),
    "d595": ("beta", 1.1314, 2.4474, 5.0, 45.0),
    "tmid": ("beta", 1.5792, 3.6405, 0.5, 40.0),
    "f_mid": ("gamma", 4.0982, 1.4330),
    "f_slope": ("two-sided exponential", 17.095, 6.7729, 4.8512, -2.0, 0.5),
    "zeta": ("beta", 1.4250, 5.7208, 0.02, 1.0),
}

#: Regression of the mean mu_i in the standard-normal space (RDK10, random-effects regression):
#: Ia: b0 + b1 (M / 7) + b2 F + b3 ln(R_rup / 25 km) + b4 ln(V_s30 / 750 m/s);
#: the five others: b0 + b1 M + b2 F + b3 R_rup [km] + b4 V_s30 [m/s].
REGRESSION: dict[str, tuple[float, float, float, float, float]] = {
    "arias": (-2.2962, 2.9440, -0.0707, -1.3564, -0.2654),
    "d595": (-6.1946, 0.9703, -0.7034, 0.0087, -0.0007),
    "tmid": (-5.0105, 0.6625, -0.3450, 0.0139, -0.0002),
    "f_mid": (2.2525, -0.2586, -0.0808, -0.0084, 0.0000),
    "f_slope": (-2.4886, 0.3440, 0.0441, 0.0026, -0.0001),
    "zeta": (-0.2583, 0.1293, -0.4772, -0.0115, 0.0004),
}

#: Intra-event sigma_i and inter-event tau_i standard deviations in the normal space (RDK10).
SIGMA_TAU: dict[str, tuple[float, float]] = {
    "arias": (0.5937, 0.2738), "d595": (0.5688, 0.4574), "tmid": (0.4145, 0.5114),
    "f_mid": (0.7228, 0.6918), "f_slope": (0.9529, 0.1286), "zeta": (0.7601, 0.6815),
}

#: Correlation of the total errors eta_i + eps_i (RDK10), in the order of :data:`REGRESSION`.
CORRELATION: tuple[tuple[float, ...], ...] = (
    (1.0000, -0.3555, 0.0066, -0.1545, 0.1341, -0.0078),
    (-0.3555, 1.0000, 0.6729, -0.1303, -0.1576, -0.1958),
    (0.0066, 0.6729, 1.0000, -0.2761, -0.1977, -0.2188),
    (-0.1545, -0.1303, -0.2761, 1.0000, -0.2034, 0.2814),
    (0.1341, -0.1576, -0.1977, -0.2034, 1.0000, -0.0137),
    (-0.0078, -0.1958, -0.2188, 0.2814, -0.0137, 1.0000),
)

#: Corner frequency omega_c / 2 pi [Hz] of the high-pass filter (RDK10).
CORNER_FREQUENCY = 0.2
#: Lowest filter frequency omega_f / 2 pi [Hz] (this implementation's floor, see the module doc).
FREQUENCY_FLOOR = 0.3
#: Seconds [s] after the excitation's end (99.99 % of the expected Arias intensity, when q(t)
#: is about 1 % of its peak): the high-pass filter's state decays
#: as (1 + omega_c t) exp(-omega_c t), 6e-5 after 10 s at 0.2 Hz.
TAIL = 10.0
_ZETA_MAX = 0.99
#: Arias intensity [m/s] of a record whose int a^2 dt is 1 g^2 s: (pi / 2 g) g^2.
_ARIAS_PER_G2S = math.pi * G_STANDARD / 2.0
#: Fraction of the expected energy int q^2 dt after which the excitation is ended.
_EXCITATION = 0.9999
_NAMES = tuple(REGRESSION)
_MAX_DRAWS = 1000


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ScenarioEarthquake:
    """An earthquake and a site: ``magnitude`` M (moment magnitude, -), ``distance`` R_rup
    (closest distance to the rupture, km), ``vs30`` V_s30 (m/s), ``fault`` "strike-slip" or
    "reverse" (:data:`FAULTS`). Each must lie in the range of RDK10's data set
    (:data:`RANGES`); ParameterError names the parameter, the value and the range."""

    magnitude: float
    distance: float
    vs30: float
    fault: str = "strike-slip"

    def __post_init__(self) -> None:
        for name, (lo, hi, unit) in RANGES.items():
            x = check_finite(name, getattr(self, name))
            if not lo <= x <= hi:
                where = f" {unit}" if unit != "-" else ""
                raise ParameterError(name, getattr(self, name),
                                     f"in [{lo:g}, {hi:g}]{where}, the range of the data set "
                                     "of Rezaeian & Der Kiureghian (2010)")
            object.__setattr__(self, name, x)
        if not isinstance(self.fault, str) or self.fault not in FAULTS:
            raise ParameterError("fault", self.fault, " or ".join(map(repr, FAULTS)))

    def label(self) -> str:
        """``M7.0-R15`` (magnitude, R_rup [km]), the stem of the ensemble's record names."""
        return f"M{self.magnitude:.1f}-R{self.distance:g}"

    def describe(self) -> str:
        """One line with units: ``M 7.0 strike-slip, R_rup 15 km, V_s30 400 m/s``."""
        return (f"M {self.magnitude:g} {self.fault}, R_rup {self.distance:g} km, "
                f"V_s30 {self.vs30:g} m/s")


#: The default scenario: a shallow crustal strike-slip earthquake of M 7.0 at R_rup = 15 km,
#: recorded on firm ground (V_s30 = 760 m/s, the NEHRP B/C boundary). Why: M 7 gives the long
#: strong-motion phase (median D5-95 about 18 s) and the long-period content of the large events
#: rocking studies care about; 15 km keeps it in the data set's far field (near-fault pulses are
#: not modelled); on firm ground the model's median spectrum agrees best with the NGA-West2
#: model of Boore et al. (2014) (at V_s30 = 400 m/s the model's weak site scaling puts its
#: medians 0.54-0.71 of NGA-West2's in PGV and between 0.3 and 1 s; ``docs/synthetic.md``,
#: measured). Its records span PGA about 0.06-0.8 g (median about 0.2 g, BSSA14's 0.19 g):
#: about half exceed the paper's frames' uplift threshold g tan(alpha) = 0.14 g unscaled (11 of
#: the 20 of seed 0), and the fragility ladder scales them to overturning.
DEFAULT_SCENARIO = ScenarioEarthquake(7.0, 15.0, 760.0, "strike-slip")


@dataclass(frozen=True)
class ModelParameters:
    """One set of the model's physical parameters (RDK10): ``arias`` Ia [m/s] (expected Arias
    intensity (pi / 2 g) int E[a^2] dt, g = 9.80665 m/s^2; the regression's g^2 s times
    pi g / 2),
    ``d595`` D5-95 [s] (time between 5 % and 95 % of Ia), ``tmid`` [s] (time at 45 % of Ia),
    ``f_mid`` = omega_mid / 2 pi [Hz] (filter frequency at t_mid), ``f_slope`` = omega' / 2 pi
    [Hz/s] (its rate of change), ``zeta`` zeta_f [-] (filter damping ratio)."""

    arias: float
    d595: float
    tmid: float
    f_mid: float
    f_slope: float
    zeta: float

    def __post_init__(self) -> None:
        for name in ("arias", "d595", "tmid", "f_mid"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        object.__setattr__(self, "f_slope", check_finite("f_slope", self.f_slope))
        z = check_finite("zeta", self.zeta)
        if not 0.0 < z <= _ZETA_MAX:
            raise ParameterError("zeta", self.zeta, f"in (0, {_ZETA_MAX}]")
        object.__setattr__(self, "zeta", z)

    def describe(self) -> str:
        """The six numbers with units, for a record's ``source``."""
        return (f"Ia {self.arias:.4g} m/s, D5-95 {self.d595:.4g} s, t_mid {self.tmid:.4g} s, "
                f"f_mid {self.f_mid:.4g} Hz, f' {self.f_slope:.4g} Hz/s, "
                f"zeta_f {self.zeta:.4g}")


# ------------------------------------------------------------------------------------------------
# The predictive model: scenario -> normal space -> physical parameters (RDK10)
def _mean_nu(s: ScenarioEarthquake) -> list[float]:
    """mu_i(F, M, R, V) of the six parameters in the standard-normal space (:data:`REGRESSION`)."""
    f = FAULTS[s.fault]
    out = []
    for name in _NAMES:
        b0, bm, bf, br, bv = REGRESSION[name]
        if name == "arias":
            out.append(b0 + bm * s.magnitude / 7.0 + bf * f + br * math.log(s.distance / 25.0)
                       + bv * math.log(s.vs30 / 750.0))
        else:
            out.append(b0 + bm * s.magnitude + bf * f + br * s.distance + bv * s.vs30)
    return out


def _slope_ppf(p: float) -> float:
    """Inverse of the two-sided exponential CDF of omega'/2pi [Hz/s] (:data:`MARGINALS`)."""
    _, a, b, c, lo, hi = MARGINALS["f_slope"]
    p0 = c / b * (1.0 - math.exp(b * lo))            # CDF at 0
    if p < p0:
        return math.log(p * b / c + math.exp(b * lo)) / b
    arg = 1.0 - (p - p0) * a / c
    return hi if arg <= math.exp(-a * hi) else -math.log(arg) / a


def _to_physical(nu: Sequence[float]) -> ModelParameters:
    """theta_i = F_i^-1(Phi(nu_i)) (:data:`MARGINALS`), Ia converted from g^2 s to m/s."""
    from scipy.special import betaincinv, gammaincinv, ndtr

    vals = {}
    for name, v in zip(_NAMES, nu):
        kind, *par = MARGINALS[name]
        p = float(ndtr(v))
        if kind == "lognormal":
            vals[name] = math.exp(par[0] + par[1] * v) * _ARIAS_PER_G2S
        elif kind == "beta":
            a, b, lo, hi = par
            vals[name] = lo + (hi - lo) * float(betaincinv(a, b, p))
        elif kind == "gamma":
            vals[name] = float(gammaincinv(par[0], p)) * par[1]
        else:
            vals[name] = _slope_ppf(p)
    vals["zeta"] = min(vals["zeta"], _ZETA_MAX)
    return ModelParameters(**vals)


def predicted_median(scenario: ScenarioEarthquake) -> ModelParameters:
    """The parameters at nu = mu (zero errors): the medians RDK10 predicts for ``scenario``
    (the marginal transforms are monotonic, so the median maps to the median)."""
    return _to_physical(_mean_nu(scenario))


def _cholesky(c: Sequence[Sequence[float]]) -> list[list[float]]:
    """Lower Cholesky factor in plain floats (identical on every machine, no LAPACK call)."""
    n = len(c)
    lo = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = c[i][j] - sum(lo[i][k] * lo[j][k] for k in range(j))
            lo[i][j] = math.sqrt(s) if i == j else s / lo[j][j]
    return lo


def _covariance_factor() -> list[list[float]]:
    sd = [math.hypot(*SIGMA_TAU[n]) for n in _NAMES]
    cov = [[CORRELATION[i][j] * sd[i] * sd[j] for j in range(6)] for i in range(6)]
    return _cholesky(cov)


def _stream(seed: int, index: int) -> np.random.Generator:
    """The random stream of record ``index`` (0-based) of the ensemble of ``seed``: the same
    whatever the ensemble's size (``numpy.random.SeedSequence(seed).spawn``)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index,)))


def _draw_one(scenario: ScenarioEarthquake, rng: np.random.Generator) -> ModelParameters:
    """nu ~ N(mu, Sigma_total) mapped to the physical space, drawn again while the modulating
    function cannot be built (:func:`modulating_parameters`)."""
    mu, lo = _mean_nu(scenario), _covariance_factor()
    for _ in range(_MAX_DRAWS):
        z = [float(x) for x in rng.standard_normal(6)]
        nu = [mu[i] + sum(lo[i][k] * z[k] for k in range(i + 1)) for i in range(6)]
        p = _to_physical(nu)
        if modulating_parameters(p, strict=False) is not None:
            return p
    raise RockbenchError(f"no valid parameter set in {_MAX_DRAWS} draws for {scenario}")


def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError("seed", seed, "an integer >= 0")
    return int(seed)


def _check_n(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= 10000:
        raise ParameterError("n", n, "an integer in [1, 10000]")
    return int(n)


def draw_parameters(scenario: ScenarioEarthquake = DEFAULT_SCENARIO, n: int = 20,
                    seed: int = 0) -> list[ModelParameters]:
    """The ``n`` parameter sets :func:`ensemble` uses for ``scenario`` and ``seed``: each drawn
    with its own total error (one earthquake per record: the ensemble is a set of records of
    many earthquakes sharing M, R_rup, V_s30 and the fault type), in the normal space with the
    total standard deviations sqrt(sigma^2 + tau^2) and :data:`CORRELATION`."""
    if not isinstance(scenario, ScenarioEarthquake):
        raise ParameterError("scenario", scenario, "a ScenarioEarthquake")
    seed, n = _check_seed(seed), _check_n(n)
    return [_draw_one(scenario, _stream(seed, i)) for i in range(n)]


# ------------------------------------------------------------------------------------------------
# The time-modulating function (RDK08): gamma-shaped q(t) from (Ia, D5-95, t_mid)
def _gamma_quantile(k: float, p: float) -> float:
    from scipy.special import gammaincinv
    return float(gammaincinv(k, p))


def _ratio(k: float) -> float:
    """D5-95 / t_mid of a cumulative q^2 that is a gamma CDF of shape k (scale-free)."""
    return (_gamma_quantile(k, 0.95) - _gamma_quantile(k, 0.05)) / _gamma_quantile(k, 0.45)


def modulating_parameters(params: ModelParameters, *, strict: bool = True
                          ) -> tuple[float, float, float] | None:
    """(alpha1 [m/s^(1 + alpha2)], alpha2 [-], alpha3 [1/s]) of q(t) = alpha1 t^(alpha2 - 1)
    exp(-alpha3 t) [m/s^2] (RDK08) with the expected Arias intensity, D5-95 and t_mid of
    ``params``.

    q^2 is proportional to a gamma density of shape k = 2 alpha2 - 1 and rate lam = 2 alpha3,
    so the times at 5, 45 and 95 % of Ia are the gamma quantiles Q(k, p) / lam: k solves
    (Q(k, .95) - Q(k, .05)) / Q(k, .45) = D5-95 / t_mid (a decreasing function of k), lam =
    Q(k, .45) / t_mid, and alpha1^2 = (2 g Ia / pi) lam^k / Gamma(k), since
    (pi / 2g) int q^2 dt = Ia. Needs alpha2 > 1 (q(0) = 0; D5-95 / t_mid < 4.93): otherwise
    ParameterError, or None with ``strict=False``."""
    from scipy.optimize import brentq
    from scipy.special import gammaln

    r = params.d595 / params.tmid
    lo_k, hi_k = 1.0, 1e5
    if not _ratio(hi_k) < r < _ratio(lo_k):
        if strict:
            raise ParameterError("d595", params.d595, f"with t_mid = {params.tmid:g} s, a "
                                 f"ratio D5-95 / t_mid in ({_ratio(hi_k):.3g}, "
                                 f"{_ratio(lo_k):.3g}) (alpha2 > 1)")
        return None
    lk = brentq(lambda x: _ratio(math.exp(x)) - r, 0.0, math.log(hi_k), xtol=1e-13)
    k = math.exp(lk)
    lam = _gamma_quantile(k, 0.45) / params.tmid
    ln_a1 = 0.5 * (math.log(2.0 * G_STANDARD * params.arias / math.pi) + k * math.log(lam)
                   - float(gammaln(k)))
    return math.exp(ln_a1), 0.5 * (k + 1.0), 0.5 * lam


def record_duration(params: ModelParameters) -> float:
    """Length [s] of a simulated record: :func:`excitation_end` plus :data:`TAIL`."""
    return excitation_end(params) + TAIL


def excitation_end(params: ModelParameters) -> float:
    """Time [s] at which 99.99 % of the expected Arias intensity is reached: the modulated
    noise is zero after it (q(t) is then about 1 % of its peak)."""
    a1, a2, a3 = modulating_parameters(params)
    return _gamma_quantile(2.0 * a2 - 1.0, _EXCITATION) / (2.0 * a3)


# ------------------------------------------------------------------------------------------------
# One realization (RDK08 filtered white noise, RDK10 high-pass filter)
def _filtered_noise(t: np.ndarray, params: ModelParameters, u: np.ndarray) -> np.ndarray:
    """Unit-variance filtered white noise at the sample times ``t`` [s] (RDK08): for each lag
    j dt, every pulse u_i adds h(j dt; t_i) u_i to sample i + j; normalized by the root of the
    sum of h^2. Lags beyond which exp(-zeta omega s) < 1e-8 are not summed (relative effect
    below 1e-8)."""
    n, dt = t.size, float(t[1] - t[0])
    omega = 2.0 * math.pi * np.maximum(params.f_mid + params.f_slope * (t - params.tmid),
                                       FREQUENCY_FLOOR)
    z = params.zeta
    amp = omega / math.sqrt(1.0 - z * z)
    # h(j dt; t_i) = amp_i Im(step_i^j): one complex product per lag instead of exp and sin
    step = np.exp(complex(-z, math.sqrt(1.0 - z * z)) * omega * dt)
    lags = min(n - 1, int(math.ceil(math.log(1e8) / (z * float(omega.min())) / dt)))
    num, den = np.zeros(n), np.zeros(n)
    power = np.ones(n, dtype=complex)
    for j in range(1, lags + 1):
        m = n - j
        power[:m] *= step[:m]
        h = amp[:m] * power[:m].imag
        num[j:] += h * u[:m]
        den[j:] += h * h
    out = np.zeros(n)
    ok = den > 0.0
    out[ok] = num[ok] / np.sqrt(den[ok])
    return out


def _high_pass(x: np.ndarray, dt: float, corner: float) -> np.ndarray:
    """z'' of z'' + 2 w z' + w^2 z = x(t) from rest, w = 2 pi ``corner`` (RDK10), the input
    linear between samples (exact first-order-hold discretization)."""
    from scipy.signal import cont2discrete, lfilter, ss2tf

    w = 2.0 * math.pi * corner
    a = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
    b = np.array([[0.0], [1.0]])
    c = np.array([[-w * w, -2.0 * w]])
    d = np.array([[1.0]])
    ad, bd, cd, dd, _ = cont2discrete((a, b, c, d), dt, method="foh")
    num, den = ss2tf(ad, bd, cd, dd)
    return lfilter(num[0], den, x)


def simulate(params: ModelParameters, dt: float, duration: float, rng: np.random.Generator, *,
             corner: float = CORNER_FREQUENCY, name: str = "", source: str = "") -> Record:
    """One realization of the model with parameters ``params``: samples every ``dt`` [s] (in
    [1e-3, 0.05] s) from t = 0 to ``duration`` [s] (> 0; :func:`record_duration` covers the
    motion), white noise from ``rng`` (a ``numpy.random.Generator``), high-pass corner
    ``corner`` [Hz] (> 0; RDK10's 0.2 Hz). A :class:`~rockbench.scene.motion.Record` in m/s^2."""
    if not isinstance(params, ModelParameters):
        raise ParameterError("params", params, "a ModelParameters")
    dt = check_positive("dt", dt)
    if not 1e-3 <= dt <= 0.05:
        raise ParameterError("dt", dt, "in [0.001, 0.05] s")
    duration = check_positive("duration", duration)
    if not 10 * dt <= duration <= 3600.0:
        raise ParameterError("duration", duration, f"in [{10 * dt:g}, 3600] s")
    corner = check_positive("corner", corner)
    if not isinstance(rng, np.random.Generator):
        raise ParameterError("rng", rng, "a numpy.random.Generator")
    a1, a2, a3 = modulating_parameters(params)
    t = dt * np.arange(int(math.floor(duration / dt + 1e-9)) + 1)
    u = rng.standard_normal(t.size)
    q = np.zeros(t.size)
    q[1:] = np.exp(math.log(a1) + (a2 - 1.0) * np.log(t[1:]) - a3 * t[1:])
    q[t > excitation_end(params)] = 0.0
    x = q * _filtered_noise(t, params, u)
    acc = _high_pass(x, dt, corner)
    return Record.from_samples(acc, dt, units="m/s2", name=name, source=source)


def ensemble(scenario: ScenarioEarthquake = DEFAULT_SCENARIO, n: int = 20, seed: int = 0,
             dt: float = 0.01) -> list[Record]:
    """``n`` synthetic records of ``scenario``: parameter sets of :func:`draw_parameters` and one
    realization each (:func:`simulate`, length :func:`record_duration`), record i from its own
    random stream of ``seed`` (so the first records do not change with ``n``). Bit-for-bit
    reproducible for a seed on one platform and NumPy/SciPy version. Named
    ``RDK10-M7.0-R15-01``...; ``source`` names the model, the scenario, the seed and the
    parameters."""
    if not isinstance(scenario, ScenarioEarthquake):
        raise ParameterError("scenario", scenario, "a ScenarioEarthquake")
    seed, n = _check_seed(seed), _check_n(n)
    width = max(2, len(str(n)))
    out = []
    for i in range(n):
        rng = _stream(seed, i)
        p = _draw_one(scenario, rng)
        name = f"RDK10-{scenario.label()}-{i + 1:0{width}d}"
        source = (f"Rezaeian & Der Kiureghian (2010) stochastic model; scenario "
                  f"{scenario.describe()}; seed {seed}, realization {i + 1}; "
                  f"{p.describe()}; high-pass {CORNER_FREQUENCY:g} Hz")
        out.append(simulate(p, dt, record_duration(p), rng, name=name, source=source))
    return out


def write_ensemble(records: Sequence[Record], folder: str | os.PathLike) -> Path:
    """Write ``records`` as headerless files ``NAME.txt`` (one sample per line, m/s^2, 17
    significant digits) with a ``records.csv`` (record, dt_s, units, source) in ``folder``
    (created): a folder ``--records`` and :func:`rockbench.scene.records.find_records` read.
    Returns the folder."""
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    rows = []
    for r in records:
        if not isinstance(r, Record) or not r.name or "/" in r.name:
            raise ParameterError("records", r, "Records with a name usable as a file stem")
        np.savetxt(root / f"{r.name}.txt", np.asarray(r.samples), fmt="%.17g")
        rows.append({"record": r.name, "dt_s": repr(r.dt), "units": "m/s^2",
                     "source": r.source})
    with open(root / "records.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=["record", "dt_s", "units", "source"])
        w.writeheader()
        w.writerows(rows)
    return root


# ------------------------------------------------------------------------------------------------
# The parameters measured on a record (RDK08's definitions), to check a simulation against them
def arias_intensity(acc: Any, dt: float) -> float:
    """Arias intensity (pi / 2 g) int a^2 dt [m/s] of samples ``acc`` [m/s^2] every ``dt`` [s]
    (rectangle rule; g = 9.80665 m/s^2)."""
    a = np.asarray(acc, dtype=float)
    return float(math.pi / (2.0 * G_STANDARD) * dt * np.sum(a * a))


def energy_times(acc: Any, dt: float, fractions: Sequence[float] = (0.05, 0.45, 0.95)
                 ) -> tuple[float, ...]:
    """Times [s] (from the first sample) at which the cumulative int a^2 dt reaches each of
    ``fractions`` of its total: (t5, t_mid, t95) by default, D5-95 = t95 - t5."""
    a = np.asarray(acc, dtype=float)
    cum = np.concatenate([[0.0], np.cumsum(a * a)])
    cum /= cum[-1]
    t = dt * np.arange(cum.size) - dt / 2.0
    t[0] = 0.0
    return tuple(float(np.interp(f, cum, t)) for f in fractions)


def upcrossings(acc: Any, dt: float, t0: float, t1: float) -> int:
    """Number of zero up-crossings (a sample <= 0 followed by one > 0) of ``acc`` between the
    times ``t0`` and ``t1`` [s] from the first sample: over a window, about the integral of the
    filter frequency omega_f(t) / 2 pi [Hz]."""
    a = np.asarray(acc, dtype=float)
    i0, i1 = max(0, int(round(t0 / dt))), min(a.size - 1, int(round(t1 / dt)))
    seg = a[i0:i1 + 1]
    return int(np.count_nonzero((seg[:-1] <= 0.0) & (seg[1:] > 0.0)))

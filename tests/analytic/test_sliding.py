"""Newmark's sliding block (:mod:`rockbench.analytic.sliding`) against closed forms, a
semi-analytic solution, its own other path, symmetry and the energy balance.

SI units: accelerations m/s^2, displacements m, velocities m/s, times s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rockbench.analytic.sliding import rectangular_pulse_displacement, sliding_response
from rockbench.constants import G
from rockbench.errors import ParameterError
from rockbench.scene.motion import GroundMotion, Record, RickerPulse


class HalfSine(GroundMotion):
    """a_g = A sin(pi t / T) on [0, T], zero elsewhere (a test motion, smooth inside)."""

    def __init__(self, amplitude: float, duration: float):
        self.A, self.T = amplitude, duration
        self.t_start, self.t_end = 0.0, duration

    def acceleration(self, t):
        if isinstance(t, float):
            return self.A * math.sin(math.pi * t / self.T) if 0.0 <= t <= self.T else 0.0
        t = np.asarray(t, dtype=float)
        out = np.where((t >= 0) & (t <= self.T), self.A * np.sin(np.pi * t / self.T), 0.0)
        return float(out) if out.ndim == 0 else out

    def knots(self, t0, t1):
        return np.unique(np.concatenate([[t0, t1], [0.5 * self.T] if t0 < 0.5 * self.T < t1
                                         else [], np.linspace(t0, t1, 401)]))

    def max_abs_after(self, t):
        return abs(self.A) if t <= 0.5 * self.T else abs(self.acceleration(t))

    @property
    def peak(self):
        return abs(self.A)

    def describe(self):
        return {"kind": "half-sine", "amplitude_m_s2": self.A, "duration_s": self.T}

    def scaled(self, factor):
        return HalfSine(factor * self.A, self.T)


def noise_record(seed: int, n: int = 600, dt: float = 0.01, peak: float = 0.6 * G) -> Record:
    """A band-limited random accelerogram [m/s^2] (moving average of white noise)."""
    rng = np.random.default_rng(seed)
    x = np.convolve(rng.standard_normal(n + 8), np.ones(9) / 9.0, mode="valid")
    x *= peak / np.max(np.abs(x))
    return Record.from_samples(x, dt, units="m/s2")


def gauss_integral(f, breaks: np.ndarray, nodes: int = 4, sub: int = 1) -> float:
    """Sum over the intervals between ``breaks`` (each cut into ``sub`` parts) of Gauss-Legendre
    quadrature with ``nodes`` points (exact for polynomials of degree 2 nodes - 1)."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.unique(np.concatenate([np.linspace(a, b, sub + 1)
                                      for a, b in zip(breaks[:-1], breaks[1:])]))
    a, b = edges[:-1, None], edges[1:, None]
    t = 0.5 * (a + b) + 0.5 * (b - a) * x[None, :]
    return float(np.sum(0.5 * (b - a) * w[None, :] * f(t.ravel()).reshape(t.shape)))


# --- closed forms -------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["exact", "ivp"])
def test_constant_step_parabola_stop_time_and_newmark_displacement(method):
    """a_g = a > mu g on [0, T], then 0: u = -(a - mu g) t^2 / 2 while the ground accelerates,
    the block stops at a T / (mu g) with Newmark's displacement -a T^2 (a - mu g) / (2 mu g)."""
    mu, a, T = 0.3, 0.7 * G, 0.4
    r = sliding_response(Record([0.0, T], [a, a]), mu, method=method)
    tol = 1e-13 if method == "exact" else 1e-10
    t = np.linspace(0.0, T, 9)
    u, v = r.state(t)
    np.testing.assert_allclose(u, -(a - mu * G) * t**2 / 2.0, rtol=tol, atol=1e-15)
    np.testing.assert_allclose(v, -(a - mu * G) * t, rtol=tol, atol=1e-15)
    assert r.summary.end_time == pytest.approx(a * T / (mu * G), rel=tol)
    u_newmark = rectangular_pulse_displacement(a, T, mu)
    assert u_newmark == pytest.approx(-a * T**2 * (a - mu * G) / (2 * mu * G), rel=1e-15)
    assert r.summary.final_displacement == pytest.approx(u_newmark, rel=tol)
    assert r.summary.onset_time == 0.0 and r.summary.slip_episodes == 1
    assert r.summary.slip_path == pytest.approx(abs(u_newmark), rel=tol)
    assert r.summary.final_velocity == 0.0 and r.summary.status == "ok"


@pytest.mark.parametrize("ratio, T", [(1.05, 0.2), (2.0, 0.5), (5.0, 0.05), (20.0, 1.0)])
@pytest.mark.parametrize("sign", [1, -1])
def test_rectangular_pulse_newmark(ratio, T, sign):
    """Newmark (1965): a pulse A = ratio mu g for T s slides A T^2 (A - mu g) / (2 mu g),
    against the ground's acceleration; a pulse that starts late (the run starts at its start)."""
    mu = 0.25
    A = sign * ratio * mu * G
    r = sliding_response(Record([1.0, 1.0 + T], [A, A]), mu)
    expected = -sign * abs(A) * T**2 * (abs(A) - mu * G) / (2 * mu * G)
    assert r.summary.final_displacement == pytest.approx(expected, rel=1e-12)
    assert r.summary.max_abs_displacement == pytest.approx(abs(expected), rel=1e-12)
    assert r.summary.end_time == pytest.approx(1.0 + abs(A) * T / (mu * G), rel=1e-12)


def half_sine_reference(A: float, T: float, mu: float) -> tuple[float, float]:
    """(stop time [s], permanent u [m]) for a_g = A sin(pi t/T), A > mu g, from the closed-form
    v(t) and u(t) of the one slip (u'' = -a_g + mu g) and Brent's method for the stop."""
    w, ay = math.pi / T, mu * G
    t1 = math.asin(ay / A) / w

    def v(t):   # valid on [t1, T]; after T the ground is still: u'' = ay
        tt = min(t, T)
        vv = (A / w) * (math.cos(w * tt) - math.cos(w * t1)) + ay * (tt - t1)
        return vv + ay * max(t - T, 0.0)

    def u(t):
        tt = min(t, T)
        uu = (A / w) * ((math.sin(w * tt) - math.sin(w * t1)) / w - math.cos(w * t1) * (tt - t1)) \
            + 0.5 * ay * (tt - t1) ** 2
        return uu + v(T) * max(t - T, 0.0) + 0.5 * ay * max(t - T, 0.0) ** 2 if t > T else uu

    # v < 0 just after t1; it returns to 0 before T if v(T) >= 0, else after
    ts = brentq(v, t1 + 1e-9 * T, T, xtol=1e-15, rtol=1e-15) if v(T) >= 0 else T - v(T) / ay
    return ts, u(ts)


@pytest.mark.parametrize("ratio", [1.3, 3.0, 8.0])   # 1.3 stops during the pulse, the others after
def test_half_sine_against_the_semi_analytic_solution(ratio):
    """The integrator's path (DOP853 with events) against closed-form v(t), u(t) and a root of
    v by Brent's method: a different method; 1e-10 relative."""
    mu, T = 0.2, 0.6
    A = ratio * mu * G
    ts, u_ref = half_sine_reference(A, T, mu)
    r = sliding_response(HalfSine(A, T), mu)
    assert (ts < T) == (ratio < math.pi / 2)
    assert r.summary.final_displacement == pytest.approx(u_ref, rel=1e-10)
    stop = r.breaks[-1] if ts > T else [p.t1 for p in r.pieces if p.sigma][-1]
    assert stop == pytest.approx(ts, rel=1e-10)
    assert r.summary.onset_time == pytest.approx(math.asin(1 / ratio) * T / math.pi, rel=1e-10)


def test_ricker_pulse_integrator_matches_the_closed_form_on_finer_samplings():
    """Both paths on one motion: the pulse by DOP853, and the pulse sampled every T/n by the
    closed form, whose only error is the linear interpolation of the pulse: it falls as 1/n^2
    (ratio 4 from n = 2000 to 4000) and Richardson's extrapolation meets the integrator's
    result to 2e-9."""
    pulse = RickerPulse(0.5 * G, 0.5, "antisymmetric")
    mu = 0.15
    smooth = sliding_response(pulse, mu).summary
    sampled = {}
    for n in (2000, 4000):
        t = np.arange(pulse.t_start, pulse.t_end + 1e-12, pulse.period / n)
        sampled[n] = sliding_response(Record(t, pulse.acceleration(t)), mu).summary
    for key in ("final_displacement", "slip_path"):
        ref, coarse, fine = (getattr(s, key) for s in (smooth, sampled[2000], sampled[4000]))
        assert (coarse - ref) / (fine - ref) == pytest.approx(4.0, rel=0.02)
        assert (4.0 * fine - coarse) / 3.0 == pytest.approx(ref, rel=2e-9)
    assert smooth.slip_episodes == sampled[4000].slip_episodes >= 2


def test_record_by_both_paths():
    rec = noise_record(3, n=300)
    exact = sliding_response(rec, 0.2, method="exact")
    ivp = sliding_response(rec, 0.2, method="ivp")
    assert exact.summary.slip_episodes == ivp.summary.slip_episodes > 3
    np.testing.assert_allclose(ivp.history.u, exact.history.u, rtol=0,
                               atol=1e-10 * exact.summary.max_abs_displacement)


# --- thresholds and symmetry ----------------------------------------------------------------------
@pytest.mark.parametrize("factor", [0.5, 0.999999, 1.0])
def test_no_slip_at_or_below_the_threshold(factor):
    """max |a_g| <= mu g: no slip (a pulse whose peak only touches mu g does not slide)."""
    mu = 0.3
    for motion in (RickerPulse(factor * mu * G, 0.4), Record([0.0, 1.0, 2.0],
                                                              [0.0, factor * mu * G, 0.0])):
        s = sliding_response(motion, mu).summary
        assert s.onset_time is None and s.slip_episodes == 0
        assert s.max_abs_displacement == 0.0 and s.slip_path == 0.0


def test_antisymmetry():
    """a_g -> -a_g gives u -> -u (both paths)."""
    rec = noise_record(7)
    pulse = RickerPulse(0.8 * G, 0.3)
    for motion, tol in ((rec, 1e-15), (pulse, 1e-12)):
        a = sliding_response(motion, 0.25)
        b = sliding_response(motion.scaled(-1.0), 0.25)
        scale = a.summary.max_abs_displacement
        assert scale > 0
        np.testing.assert_allclose(b.history.u, -a.history.u, rtol=0, atol=tol * scale)
        assert b.summary.slip_episodes == a.summary.slip_episodes


def test_reversal_without_sticking():
    """Square wave +A on [0, T1), -A on [T1, 2 T1): the slip stops at
    T1 + (A - mu g) T1 / (A + mu g), where |a_g| > mu g: the block slides back at once."""
    mu, A, T1 = 0.2, 0.6 * G, 0.5
    eps = 1e-9
    rec = Record([0.0, T1 - eps, T1, 2 * T1], [A, A, -A, -A])
    r = sliding_response(rec, mu, t_end=2 * T1)
    t_stop = T1 + (A - mu * G) * T1 / (A + mu * G)
    stops = [p.t1 for p in r.pieces if p.sigma == -1]
    assert stops[-1] == pytest.approx(t_stop, abs=1e-8)
    assert r.summary.slip_episodes == 2
    h = r.history
    assert h.sliding[(h.t > 0) & (h.t < 2 * T1)].all()
    assert h.v.min() < 0 < h.v.iloc[-1]


# --- energy ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["exact", "ivp"])
def test_energy_balance(path):
    """Work of the ground's inertial force -int a_g v = friction dissipation
    int mu (g + a_v) |v| + v^2/2 (per unit mass), to 1e-9 relative, stopped mid-slip."""
    mu = 0.2
    if path == "exact":
        h, v, t_end = noise_record(11, n=400), noise_record(12, n=400, peak=0.4 * G), 3.1
    else:
        h, v, t_end = RickerPulse(0.7 * G, 0.4), RickerPulse(0.3 * G, 0.25, "antisymmetric"), 0.0
    r = sliding_response(h, mu, v, t_end=t_end, method=path)
    assert r.summary.slip_episodes >= 1 and r.summary.final_velocity != 0.0
    breaks = np.unique(np.concatenate([r.breaks, h.knots(r.breaks[0], r.breaks[-1]),
                                       v.knots(r.breaks[0], r.breaks[-1])]))
    vel = lambda t: r.state(t)[1]
    sub, nodes = (1, 4) if path == "exact" else (4, 10)
    work = gauss_integral(lambda t: -h.acceleration(t) * vel(t), breaks, nodes, sub)
    diss = gauss_integral(lambda t: mu * (G + v.acceleration(t)) * np.abs(vel(t)), breaks,
                          nodes, sub)
    kinetic = 0.5 * r.summary.final_velocity ** 2
    assert work == pytest.approx(diss + kinetic, rel=1e-9)


# --- vertical motion ------------------------------------------------------------------------------
@pytest.mark.parametrize("c", [-0.35 * G, 0.5 * G])
def test_constant_vertical_acceleration_scales_mu(c):
    """a_v = c (constant) is exactly mu -> mu (g + c) / g."""
    mu = 0.2
    h = noise_record(5)
    v = Record(h.time, np.full(h.npts, c))
    a = sliding_response(h, mu, v, t_end=h.t_end)
    b = sliding_response(h, mu * (G + c) / G, t_end=h.t_end)
    assert a.summary.slip_episodes == b.summary.slip_episodes >= 1
    np.testing.assert_allclose(a.history.u, b.history.u, rtol=0,
                               atol=1e-12 * b.summary.max_abs_displacement)


def test_smooth_horizontal_with_a_record_vertical():
    """A pulse with a (constant) vertical record: the integrator between the record's samples,
    equal to the pulse alone with mu (g + c) / g."""
    mu, c = 0.2, -0.3 * G
    h = RickerPulse(0.6 * G, 0.4, "antisymmetric")
    v = Record(np.linspace(h.t_start, h.t_end, 61), np.full(61, c))
    a = sliding_response(h, mu, v, t_end=h.t_end)
    b = sliding_response(h, mu * (G + c) / G, t_end=h.t_end)
    assert a.summary.slip_episodes == b.summary.slip_episodes >= 2
    np.testing.assert_allclose(a.history.u, b.history.u, rtol=0,
                               atol=1e-9 * b.summary.max_abs_displacement)


def test_loss_of_contact_linear():
    """a_v falling linearly to -1.5 g over 1 s: g + a_v = 0 at t = 2/3 s; the run stops."""
    h = Record([0.0, 1.0], [0.1 * G, 0.1 * G])
    v = Record([0.0, 1.0], [0.0, -1.5 * G])
    r = sliding_response(h, 0.3, v)
    s = r.summary
    assert s.status == "lost contact" and s.lost_contact_time == pytest.approx(2 / 3, rel=1e-14)
    assert s.end_time == s.lost_contact_time == r.history.t.iloc[-1]
    # the horizontal 0.1 g exceeds mu (g + a_v) once g + a_v < g / 3, i.e. from t = 4/9 s
    assert s.onset_time == pytest.approx(4 / 9, rel=1e-11)


def test_loss_of_contact_smooth():
    """A downward vertical Ricker pulse of 1.2 g: contact is lost where
    1.2 (1 - 2 pi^2 tau^2) exp(-pi^2 tau^2) = 1, tau = t / T (tau < 0: the first crossing)."""
    T = 0.4
    h = RickerPulse(0.05 * G, 0.3)
    v = RickerPulse(1.2 * G, T, sign=-1)
    r = sliding_response(h, 0.3, v)
    f = lambda tau: 1.2 * (1 - 2 * math.pi**2 * tau**2) * math.exp(-math.pi**2 * tau**2) - 1.0
    tau = brentq(f, -0.3, 0.0, xtol=1e-15)
    assert r.summary.status == "lost contact"
    assert r.summary.lost_contact_time == pytest.approx(tau * T, rel=1e-10)


# --- the motion's own vertical part: the default -------------------------------------------------
def test_a_pulse_slides_under_the_normal_force_of_its_own_vertical_part():
    """RickerPulse(0.6 g, 0.5 s, vertical_ratio=0.5) on mu = 0.3: by default its vertical part
    (a_v = 0.5 a_g, in phase) sets the normal force. On the first (negative) lobe a_v < 0, so
    the block slips once |a_g| = mu g / (1 + mu r) = 0.261 g, which that lobe (0.268 g) reaches;
    without the vertical part the slip starts on the main lobe, at a_g = mu g. An explicit
    ``vertical`` overrides: the same pulse given as ``vertical=`` is the same run, None none."""
    mu, r, A, T = 0.3, 0.5, 0.6 * G, 0.5
    pulse = RickerPulse(A, T, vertical_ratio=r)
    w = lambda tau: (1 - 2 * math.pi**2 * tau**2) * math.exp(-math.pi**2 * tau**2)
    own = sliding_response(pulse, mu)
    lobe = brentq(lambda tau: -A * w(tau) - mu * G / (1 + mu * r), -1.0, -math.sqrt(1.5) / math.pi,
                  xtol=1e-15)
    assert own.summary.onset_time == pytest.approx(lobe * T, rel=1e-9)
    given = sliding_response(RickerPulse(A, T), mu, vertical=pulse.vertical)
    np.testing.assert_allclose(own.history.u, given.history.u, rtol=0, atol=1e-15)
    assert own.summary.onset_time == given.summary.onset_time
    flat = sliding_response(pulse, mu, vertical=None)
    main = brentq(lambda tau: A * w(tau) - mu * G, -math.sqrt(1.5) / math.pi + 1e-3, 0.0,
                  xtol=1e-15)
    assert flat.summary.onset_time == pytest.approx(main * T, rel=1e-9)
    assert flat.summary.final_displacement == sliding_response(RickerPulse(A, T), mu
                                                               ).summary.final_displacement
    assert abs(own.summary.max_abs_displacement / flat.summary.max_abs_displacement - 1) > 0.05


def test_a_record_slides_under_the_normal_force_of_its_vertical_channel():
    """A rectangular pulse a on [0, T] with a vertical channel c on the same samples: the block
    slips at a - mu (g + c) during the pulse and stops at mu g after it (both channels are 0
    then), u = -(a - a1) T^2 / 2 - ((a - a1) T)^2 / (2 a2), a1 = mu (g + c), a2 = mu g."""
    mu, a, c, T = 0.25, 0.6 * G, -0.3 * G, 0.4
    rec = Record([0.0, T], [a, a]).with_vertical(Record([0.0, T], [c, c]))
    a1, a2 = mu * (G + c), mu * G
    expected = -(a - a1) * T**2 / 2 - ((a - a1) * T) ** 2 / (2 * a2)
    r = sliding_response(rec, mu)
    assert r.summary.final_displacement == pytest.approx(expected, rel=1e-12)
    flat = sliding_response(rec, mu, vertical=None)
    assert flat.summary.final_displacement == pytest.approx(
        rectangular_pulse_displacement(a, T, mu), rel=1e-12)


# --- arguments ------------------------------------------------------------------------------------
def test_bad_arguments():
    rec = Record([0.0, 1.0], [1.0, 1.0])
    with pytest.raises(ParameterError, match="mu"):
        sliding_response(rec, 0.0)
    with pytest.raises(ParameterError, match="method"):
        sliding_response(RickerPulse(1.0, 1.0), 0.2, method="exact")
    with pytest.raises(ParameterError, match="t_end"):
        sliding_response(rec, 0.2, t_end=-1.0)
    with pytest.raises(ParameterError, match="horizontal"):
        sliding_response(lambda t: 0.0, 0.2)
    with pytest.raises(ParameterError, match="vertical.*the motion's own"):
        sliding_response(rec, 0.2, vertical="own")

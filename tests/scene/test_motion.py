"""Ground motions: Ricker pulses (paper Eqs. 29-30) and piecewise-linear records."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import cumulative_trapezoid, quad
from scipy.optimize import minimize_scalar

from rockbench.constants import G, G_STANDARD
from rockbench.errors import ParameterError
from rockbench.scene.motion import Record, RickerPulse, antisymmetric_beta, make_pulse
from rockbench.scene.scene import load_scene

PAPER = load_scene("paper-asymmetric").structure      # a Frame: the paper's, written out
HOUSNER = load_scene("housner-block").structure       # a Block

SHAPES = ("symmetric", "antisymmetric")
FAST = settings(max_examples=60, deadline=None)

#: x^2 = 3 - sqrt(6): the main extremum of the antisymmetric wavelet (Eq. 30).
X_MAIN = math.sqrt(3.0 - math.sqrt(6.0))


def t_main(period: float) -> float:
    """Time [s] > 0 of the antisymmetric pulse's main extremum: x = 2 pi t / (sqrt(3) T)."""
    return math.sqrt(3.0) * period * X_MAIN / (2.0 * math.pi)


def fine_grid(pulse: RickerPulse, n: int = 200_001) -> np.ndarray:
    return np.linspace(pulse.t_start, pulse.t_end, n)


# --- amplitude and beta --------------------------------------------------------------------------
def test_beta_is_the_published_value_but_computed():
    beta = antisymmetric_beta()
    assert round(beta, 2) == 1.38
    assert beta != 1.38
    # it is the maximum of |(x^2 - 3) x exp(-x^2/2)| (found numerically here)
    res = minimize_scalar(lambda x: -abs((x * x - 3) * x * math.exp(-x * x / 2)),
                          bounds=(0.2, 1.5), method="bounded", options={"xatol": 1e-12})
    assert -res.fun == pytest.approx(beta, rel=1e-12)
    assert res.x == pytest.approx(X_MAIN, abs=1e-5)


def test_symmetric_peak_is_amplitude_at_zero():
    p = RickerPulse(2.3, 0.8)
    assert p.acceleration(0.0) == 2.3
    assert np.max(np.abs(p.acceleration(fine_grid(p)))) == pytest.approx(2.3, rel=1e-15)
    assert p.peak == 2.3


@pytest.mark.parametrize("sign", [1, -1])
def test_antisymmetric_peak_equals_amplitude(sign):
    a_g, T = 2.5, 0.7
    p = RickerPulse(a_g, T, "antisymmetric", sign)
    ts = t_main(T)
    # Eq. (30) as printed: negative main lobe at t > 0, positive mirror at t < 0 (odd function)
    assert p.acceleration(ts) == pytest.approx(-sign * a_g, rel=1e-12)
    assert p.acceleration(-ts) == pytest.approx(sign * a_g, rel=1e-12)
    around = np.linspace(ts - 1e-3 * T, ts + 1e-3 * T, 20_001)
    assert np.max(np.abs(p.acceleration(around))) == pytest.approx(a_g, rel=1e-12)
    assert np.max(np.abs(p.acceleration(fine_grid(p)))) <= a_g * (1 + 1e-12)
    res = minimize_scalar(lambda t: -abs(p.acceleration(t)), bounds=(0.0, 0.5 * T),
                          method="bounded", options={"xatol": 1e-12})
    assert -res.fun == pytest.approx(a_g, rel=1e-12)
    assert p.peak == a_g


@pytest.mark.parametrize("shape", SHAPES)
def test_sign_minus_one_negates(shape):
    t = np.linspace(-2.0, 2.0, 1001)
    plus, minus = RickerPulse(1.7, 0.6, shape, 1), RickerPulse(1.7, 0.6, shape, -1)
    np.testing.assert_array_equal(minus.acceleration(t), -plus.acceleration(t))


def test_symmetric_pulse_is_even_and_antisymmetric_is_odd():
    t = np.linspace(0.0, 3.0, 1001)
    s, a = RickerPulse(1.0, 1.0), RickerPulse(1.0, 1.0, "antisymmetric")
    np.testing.assert_array_equal(s.acceleration(-t), s.acceleration(t))
    np.testing.assert_array_equal(a.acceleration(-t), -a.acceleration(t))


def test_closed_form_equations():
    a_g, T = 1.3, 0.9
    t = np.linspace(-2.5, 2.5, 777)
    eq29 = a_g * (1 - 2 * np.pi**2 * t**2 / T**2) * np.exp(-np.pi**2 * t**2 / T**2)
    eq30 = (a_g / antisymmetric_beta()) * (4 * np.pi**2 * t**2 / (3 * T**2) - 3) \
        * (2 * np.pi * t / (np.sqrt(3) * T)) * np.exp(-0.5 * 4 * np.pi**2 * t**2 / (3 * T**2))
    np.testing.assert_allclose(RickerPulse(a_g, T).acceleration(t), eq29, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(RickerPulse(a_g, T, "antisymmetric").acceleration(t), eq30,
                               rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("shape", SHAPES)
def test_scalar_and_array_evaluation_agree(shape):
    p = RickerPulse(3.0, 0.4, shape, -1)
    t = np.linspace(-1.3, 1.3, 101)
    scalars = np.array([p.acceleration(float(x)) for x in t])
    np.testing.assert_allclose(scalars, p.acceleration(t), rtol=1e-14, atol=1e-16)
    assert isinstance(p.acceleration(0.1), float)
    assert isinstance(p.acceleration(np.float64(0.1)), float)
    assert isinstance(p.acceleration(1), float)
    assert p.acceleration(np.array(0.1)) == p.acceleration(0.1)


# --- ground velocity and displacement ------------------------------------------------------------
@pytest.mark.parametrize("shape", SHAPES)
def test_pulse_has_zero_mean_and_returns_to_rest(shape):
    a_g, T = 2.0, 0.5
    p = RickerPulse(a_g, T, shape)
    integral, _ = quad(p.acceleration, p.t_start, p.t_end, points=[0.0], limit=200)
    assert abs(integral) < 1e-12 * a_g * T
    t = fine_grid(p, 60_001)
    v = cumulative_trapezoid(p.acceleration(t), t, initial=0.0)
    d = cumulative_trapezoid(v, t, initial=0.0)
    vmax = np.max(np.abs(v))
    assert abs(v[-1]) < 1e-9 * vmax  # velocity returns to zero ...
    assert abs(d[-1]) < 1e-6 * np.max(np.abs(d))  # ... and so does the displacement
    # velocity matches the closed forms of the RickerPulse docstring
    if shape == "symmetric":
        exact = a_g * t * np.exp(-np.pi**2 * t**2 / T**2)
    else:
        x = 2 * np.pi * t / (np.sqrt(3) * T)
        exact = a_g / antisymmetric_beta() * np.sqrt(3) * T / (2 * np.pi) \
            * (1 - x**2) * np.exp(-x**2 / 2)
    np.testing.assert_allclose(v, exact, atol=1e-7 * vmax)


# --- truncation window --------------------------------------------------------------------------
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("sign", [1, -1])
def test_tails_beyond_the_window_are_negligible(shape, sign):
    a_g, T = 4.0, 1.3
    p = RickerPulse(a_g, T, shape, sign)
    assert p.t_start == -3 * T
    assert p.t_end >= p.t_start
    after = np.linspace(p.t_end, p.t_end + 20 * T, 5001)
    before = np.linspace(p.t_start - 20 * T, p.t_start, 5001)
    assert np.max(np.abs(p.acceleration(after))) < 1e-12 * a_g
    assert np.max(np.abs(p.acceleration(before))) < 1e-12 * a_g
    assert p.max_abs_after(p.t_end) < 1e-12 * a_g


# --- knots ----------------------------------------------------------------------------------------
def assert_monotonic_between(motion, knots, per_interval=25):
    """On a fine sample inside every knot interval, the acceleration never changes direction."""
    w = np.linspace(0.0, 1.0, per_interval)
    sub = knots[:-1, None] + (knots[1:] - knots[:-1])[:, None] * w[None, :]
    a = motion.acceleration(sub)
    d = np.diff(a, axis=1)
    tol = 1e-13 * max(motion.peak, 1e-300)
    rising = np.all(d >= -tol, axis=1)
    falling = np.all(d <= tol, axis=1)
    assert np.all(rising | falling)


@pytest.mark.parametrize("shape", SHAPES)
def test_pulse_knots_are_fine_sorted_and_bracket_monotonic_pieces(shape):
    p = RickerPulse(1.0, 0.37, shape, -1)
    for t0, t1 in [(p.t_start, p.t_end), (-0.123, 0.0917), (0.05, 0.05 + 1e-4)]:
        k = p.knots(t0, t1)
        assert k[0] == t0 and k[-1] == t1
        assert np.all(np.diff(k) > 0)
        assert np.max(np.diff(k)) <= p.period / 400 * (1 + 1e-12)
        assert_monotonic_between(p, k)
    # the analytic extrema are knots, so every extremum is bracketed exactly
    k = p.knots(p.t_start, p.t_end)
    ext = np.array([-t_main(p.period), t_main(p.period)]) if shape == "antisymmetric" else [0.0]
    assert np.all(np.isin(ext, k))
    assert p.knots(0.2, 0.2).tolist() == [0.2]


def test_knots_reject_reversed_interval():
    with pytest.raises(ParameterError, match="t1"):
        RickerPulse(1.0, 1.0).knots(1.0, 0.0)


# --- max_abs_after --------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", SHAPES)
def test_pulse_max_abs_after_matches_brute_force(shape):
    p = RickerPulse(2.0, 0.5, shape, -1)
    grid = np.linspace(p.t_start, p.t_end, 300_001)
    absacc = np.abs(p.acceleration(grid))
    brute = np.maximum.accumulate(absacc[::-1])[::-1]
    for i in range(0, grid.size, 3001):
        exact = p.max_abs_after(grid[i])
        assert exact >= brute[i] * (1 - 1e-14)
        assert exact == pytest.approx(brute[i], rel=1e-6, abs=1e-14)
    assert p.max_abs_after(-100.0) == pytest.approx(p.peak, rel=1e-12)


# --- dimensionless construction ----------------------------------------------------------------
@pytest.mark.parametrize("structure", [PAPER, HOUSNER])
def test_dimensionless_pulse(structure):
    A, W = 3.5, 2.0
    p = RickerPulse.dimensionless(A, W, structure, "antisymmetric", -1)
    assert p.amplitude == pytest.approx(A * 9.81 * math.tan(structure.alpha), rel=1e-15)
    assert p.period == pytest.approx(2 * math.pi / (W * structure.p), rel=1e-15)
    assert p.omega / structure.p == pytest.approx(W, rel=1e-15)
    assert p.amplitude / (G * math.tan(structure.alpha)) == pytest.approx(A, rel=1e-15)
    d = p.describe()
    assert d["A"] == A and d["W"] == W
    assert (p.shape, p.sign) == ("antisymmetric", -1)
    assert make_pulse("antisymmetric", -1, structure=structure, A=A, W=W).describe() == d
    assert p.scaled(2.0).describe()["A"] == pytest.approx(2 * A)


def test_dimensionless_rejects_non_structure():
    with pytest.raises(ParameterError, match="structure"):
        RickerPulse.dimensionless(1.0, 1.0, object())


def test_make_pulse_from_amplitude_and_period():
    p = make_pulse("symmetric", 1, amplitude=2.0, period=0.3)
    assert (p.amplitude, p.period, p.shape, p.sign) == (2.0, 0.3, "symmetric", 1)


@pytest.mark.parametrize("kwargs, missing", [
    ({"A": 1.0, "structure": PAPER}, "W"),
    ({"W": 1.0, "structure": PAPER}, "A"),
    ({"A": 1.0, "W": 1.0}, "structure"),
    ({"amplitude": 1.0}, "period"),
    ({"period": 1.0}, "amplitude"),
    ({"A": 1.0, "W": 1.0, "structure": PAPER, "amplitude": 1.0}, "amplitude"),
    ({}, "A"),
])
def test_make_pulse_names_what_is_wrong(kwargs, missing):
    with pytest.raises(ParameterError, match=missing):
        make_pulse("symmetric", 1, **kwargs)


# --- describe / scaled ----------------------------------------------------------------------------
def test_describe_is_json_safe_and_complete():
    d = RickerPulse(1.5, 0.25, "antisymmetric", -1).describe()
    assert json.loads(json.dumps(d)) == d
    assert d["kind"] == "ricker" and d["shape"] == "antisymmetric" and d["sign"] == -1
    assert d["amplitude_m_s2"] == 1.5 and d["period_s"] == 0.25
    assert d["omega_rad_s"] == pytest.approx(2 * math.pi / 0.25)
    assert d["beta"] == antisymmetric_beta()


@pytest.mark.parametrize("shape", SHAPES)
def test_scaled_pulse(shape):
    p = RickerPulse(1.5, 0.25, shape, 1)
    q = p.scaled(-2.0)
    t = np.linspace(-1, 1, 301)
    np.testing.assert_allclose(q.acceleration(t), -2.0 * p.acceleration(t), rtol=1e-14, atol=1e-16)
    assert (q.amplitude, q.sign, q.period, q.shape) == (3.0, -1, 0.25, shape)


@pytest.mark.parametrize("bad", [0.0, math.nan, math.inf, "x"])
def test_scaled_rejects_bad_factor(bad):
    with pytest.raises(ParameterError, match="factor"):
        RickerPulse(1.0, 1.0).scaled(bad)
    with pytest.raises(ParameterError, match="factor"):
        Record([0.0, 1.0], [1.0, 2.0]).scaled(bad)


# --- bad pulse parameters ------------------------------------------------------------------------
bad_positive = st.one_of(st.floats(max_value=0.0), st.just(math.nan), st.just(math.inf),
                         st.just(-math.inf), st.text("abinfxyz", max_size=4), st.none())


@FAST
@given(bad_positive)
def test_bad_amplitude_or_period_is_named(bad):
    with pytest.raises(ParameterError, match="amplitude"):
        RickerPulse(bad, 1.0)
    with pytest.raises(ParameterError, match="period"):
        RickerPulse(1.0, bad)
    with pytest.raises(ParameterError, match="A"):
        RickerPulse.dimensionless(bad, 1.0, PAPER)
    with pytest.raises(ParameterError, match="W"):
        RickerPulse.dimensionless(1.0, bad, PAPER)


@FAST
@given(st.one_of(st.text(), st.integers(), st.none()).filter(
    lambda s: s not in ("symmetric", "antisymmetric")))
def test_bad_shape_is_named(bad):
    with pytest.raises(ParameterError, match="shape"):
        RickerPulse(1.0, 1.0, bad)


@FAST
@given(st.one_of(st.integers().filter(lambda i: i not in (1, -1)), st.floats(allow_nan=True)
                 .filter(lambda x: x not in (1.0, -1.0)), st.booleans(), st.text()))
def test_bad_sign_is_named(bad):
    with pytest.raises(ParameterError, match="sign"):
        RickerPulse(1.0, 1.0, "symmetric", bad)


# --- records -------------------------------------------------------------------------------------
def small_record() -> Record:
    return Record([0.5, 1.0, 1.5, 2.5], [1.0, -3.0, 2.0, 0.5], name="toy")


def test_record_interpolation_at_samples_midpoints_and_outside():
    r = small_record()
    for ti, ai in zip(r.time, r.samples):
        assert r.acceleration(float(ti)) == ai
    np.testing.assert_array_equal(r.acceleration(r.time), r.samples)
    mids = 0.5 * (r.time[1:] + r.time[:-1])
    means = 0.5 * (r.samples[1:] + r.samples[:-1])
    np.testing.assert_allclose(r.acceleration(mids), means, rtol=1e-15)
    np.testing.assert_allclose([r.acceleration(float(m)) for m in mids], means, rtol=1e-15)
    outside = np.array([-10.0, 0.0, 0.4999999, 2.5000001, 1e9])
    assert np.all(r.acceleration(outside) == 0.0)
    assert all(r.acceleration(float(t)) == 0.0 for t in outside)
    assert (r.t_start, r.t_end, r.npts, r.peak) == (0.5, 2.5, 4, 3.0)


def test_record_from_samples_converts_units():
    acc = [0.1, -0.2, 0.05]
    g = Record.from_samples(acc, 0.01, t0=1.0, units="g", name="a")
    np.testing.assert_allclose(g.samples, np.array(acc) * G_STANDARD, rtol=1e-15)
    np.testing.assert_allclose(g.time, [1.0, 1.01, 1.02], rtol=1e-15)
    assert g.dt == 0.01 and g.units_in == "g"
    cm = Record.from_samples(acc, 0.01, units="cm/s2")
    np.testing.assert_allclose(cm.samples, np.array(acc) / 100, rtol=1e-15)
    si = Record.from_samples(acc, 0.01)
    np.testing.assert_array_equal(si.samples, acc)


def test_record_knots_and_monotonic_pieces():
    rng = np.random.default_rng(1)
    r = Record.from_samples(rng.normal(size=200), 0.02)
    k = r.knots(0.013, 1.5)
    assert k[0] == 0.013 and k[-1] == 1.5 and np.all(np.diff(k) > 0)
    inside = r.time[(r.time > 0.013) & (r.time < 1.5)]
    assert np.all(np.isin(inside, k)) and k.size == inside.size + 2
    assert_monotonic_between(r, k)
    assert_monotonic_between(r, r.knots(-1.0, r.t_end))


def test_record_scaled_and_described():
    r = small_record().scaled(-2.0)
    np.testing.assert_array_equal(r.samples, [-2.0, 6.0, -4.0, -1.0])
    assert r.name == "toy x-2"
    d = r.scaled(0.5).describe()
    assert json.loads(json.dumps(d)) == d
    assert d["kind"] == "record" and d["scale"] == -1.0 and d["pga_m_s2"] == 3.0
    assert d["npts"] == 4


@st.composite
def records_and_times(draw):
    n = draw(st.integers(2, 40))
    steps = draw(st.lists(st.floats(1e-3, 10.0), min_size=n - 1, max_size=n - 1))
    t0 = draw(st.floats(-100.0, 100.0))
    time = t0 + np.concatenate([[0.0], np.cumsum(steps)])
    acc = draw(st.lists(st.floats(-1e3, 1e3), min_size=n, max_size=n))
    t = draw(st.floats(time[0] - 5.0, time[-1] + 5.0))
    return Record(time, acc), t


@FAST
@given(records_and_times())
def test_record_max_abs_after_is_exact(case):
    r, t = case
    brute = max([abs(r.acceleration(t))]
                + [abs(a) for ti, a in zip(r.time, r.samples) if ti >= t])
    assert r.max_abs_after(t) == brute
    # it bounds every value later on (dense check)
    later = np.linspace(t, r.t_end + 1.0, 2001)
    assert np.all(np.abs(r.acceleration(later)) <= r.max_abs_after(t) * (1 + 1e-12) + 1e-300)


@pytest.mark.parametrize("time, acc, name", [
    ([0.0, 1.0, 1.0], [0.0, 1.0, 2.0], "time"),
    ([0.0, 2.0, 1.0], [0.0, 1.0, 2.0], "time"),
    ([0.0], [1.0], "time"),
    ([0.0, math.nan], [1.0, 2.0], "time"),
    ([0.0, 1.0], [1.0, math.inf], "acceleration"),
    ([0.0, 1.0], [1.0, 2.0, 3.0], "acceleration"),
    ([[0.0, 1.0]], [1.0, 2.0], "time"),
    ("abc", [1.0, 2.0], "time"),
])
def test_record_rejects_bad_arrays(time, acc, name):
    with pytest.raises(ParameterError, match=name):
        Record(time, acc)


@pytest.mark.parametrize("kwargs, name", [
    ({"dt": 0.0}, "dt"), ({"dt": -0.01}, "dt"), ({"dt": math.nan}, "dt"),
    ({"dt": 0.01, "units": "furlong"}, "units"), ({"dt": 0.01, "t0": math.inf}, "t0"),
])
def test_from_samples_rejects_bad_arguments(kwargs, name):
    with pytest.raises(ParameterError, match=name):
        Record.from_samples([1.0, 2.0], **kwargs)

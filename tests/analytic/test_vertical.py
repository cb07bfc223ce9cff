"""Vertical ground motion in the analytic SDOF model, against independent formulations.

* the block: an event-driven Newton-Euler integration about its corner written here from the
  block's mass, inertia and half-sizes (moment about the pivot of -m (a_g, g + a_v), Housner's
  eta = 1 - 1.5 sin^2 alpha at impacts, uplift when |a_g| > (b/h)(g + a_v)): no Dynamics, no
  mechanism;
* the frame (free-standing and hybrid): the three bodies as a constrained system (KKT over the
  poses, :mod:`threebodies`), the devices' forces from the engines' point forces, uplift when
  the KKT system's phi'' turns towards the rocking direction, integrated over its first
  rocking segment.

Both analytic paths (solve_ivp and the compiled kernel) are held to them and to each other.
SI units, radians.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rockbench.analytic.compiled import NUMBA_AVAILABLE, simulate_compiled
from rockbench.analytic.solver import AnalyticSettings, simulate
from rockbench.constants import G
from rockbench.scene.motion import Record, RickerPulse
from rockbench.scene.scene import load_scene
from threebodies import ThreeBodies, device_wrench

BLOCK = load_scene("housner-block")
needs_numba = pytest.mark.skipif(not NUMBA_AVAILABLE, reason="numba not installed")
PATHS = [simulate, pytest.param(simulate_compiled, marks=needs_numba)]


# --- an independent block ---------------------------------------------------------------------
def block_run(block, a_g, a_v, t0, t1, ts, rest_ratio=1e-4):
    """phi(ts) [rad] of a rigid block (half-width b, half-height h) under a_g(t), a_v(t),
    integrated event by event: about the corner (-s b, 0) it rocks by
    I_P phi'' = m (r_y a_g - r_x (g + a_v)), r = Rot(phi) (s b, h); phi'+ = eta phi'- at
    phi = 0 (eta = 1 - 1.5 sin^2 alpha); rest when |phi'+| <= rest_ratio p alpha; uplift from
    rest when a_g > (b/h)(g + a_v) (s = +1) or a_g < -(b/h)(g + a_v) (s = -1)."""
    b, h, m = block.b, block.H, block.mass
    ip = block.inertia_cm + m * (b * b + h * h)
    beta = b / h
    al = math.atan(beta)
    eta = 1.0 - 1.5 * math.sin(al) ** 2
    p = math.sqrt(m * G * math.hypot(b, h) / ip)
    v_rest = rest_ratio * p * al
    out = np.zeros_like(ts)
    t, phi, w, s = t0, 0.0, 0.0, 0
    grid = np.linspace(t0, t1, 200001)

    def up(tt):
        return a_g(tt) - beta * (G + a_v(tt)), -a_g(tt) - beta * (G + a_v(tt))

    while t < t1:
        if s == 0:
            later = grid[grid > t]
            e = np.array([up(x) for x in later]) if later.size else np.zeros((0, 2))
            hit = np.flatnonzero((e[:, 0] > 0) | (e[:, 1] > 0)) if e.size else []
            if not len(hit):
                break
            i = int(hit[0])
            k = 0 if e[i, 0] > 0 else 1
            lo = later[i - 1] if i else t
            t = brentq(lambda x: up(x)[k], lo, later[i], xtol=1e-14)
            s, phi, w = (1 if k == 0 else -1), 0.0, 0.0
            continue

        def rhs(tt, y, s=s):
            c, sn = math.cos(y[0]), math.sin(y[0])
            rx, ry = c * s * b - sn * h, sn * s * b + c * h
            return [y[1], m * (ry * a_g(tt) - rx * (G + a_v(tt))) / ip]

        def impact(tt, y, ts_=t, s=s):
            return s * y[0] if tt != ts_ else 1.0
        impact.terminal, impact.direction = True, -1
        sol = solve_ivp(rhs, (t, t1), [phi, w], method="DOP853", rtol=1e-12, atol=1e-14,
                        events=impact, dense_output=True)
        seg = (ts >= t) & (ts <= sol.t[-1])
        out[seg] = sol.sol(ts[seg])[0]
        t, phi, w = sol.t[-1], 0.0, eta * sol.y[1, -1]
        if sol.status != 1:
            break
        s = -s if abs(w) > v_rest else 0
        if s == 0:
            w = 0.0
    return out


def synthetic_record(t_end=3.0, dt=0.005, ah=0.35, av=-0.45):
    """A horizontal record (two sines) with a vertical channel (a faster sine) [m/s^2]."""
    t = np.arange(0.0, t_end + dt / 2, dt)
    env = np.sin(np.pi * t / t_end) ** 2
    h = ah * G * env * (np.sin(2 * np.pi * t / 0.7) + 0.4 * np.sin(2 * np.pi * t / 0.23))
    v = av * G * env * np.sin(2 * np.pi * t / 0.31)
    return Record(t, h, name="H", vertical=Record(t, v, name="V"))


@pytest.mark.parametrize("fn", PATHS)
@pytest.mark.parametrize("motion", ["pulse", "record"])
def test_block_matches_an_independent_newton_euler_run(fn, motion):
    """The block under a pulse with an in-phase vertical part (0.6) and under a record with a
    vertical channel: phi(t) of the analytic path within 5e-8 rad (2.5e-7 of alpha) of the
    block integrated here from its own equations, through uplifts and impacts (measured:
    3.4e-11 rad through 4 impacts under the pulse, 8.7e-9 through 7 under the record)."""
    st = BLOCK.structure
    if motion == "pulse":
        m = RickerPulse.dimensionless(1.5, 3.0, st, "antisymmetric", 1, vertical_ratio=0.6)
    else:
        m = synthetic_record()
    r = fn(BLOCK, m, duration=m.t_end - m.t_start + 1.0)
    h = r.history
    ts = h["t"].to_numpy()
    want = block_run(st, m.acceleration, m.vertical.acceleration, m.t_start, ts[-1], ts)
    assert r.summary.n_impacts >= 2                    # impacts are part of what is checked
    err = np.max(np.abs(h["phi"].to_numpy() - want))
    assert err < 5e-8, err
    assert r.summary.max_abs_phi > 0.15 * st.alpha


# --- an independent frame: the three bodies ----------------------------------------------------
def frame_segment(scene, a_g, a_v, t0, t1):
    """(uplift time, direction, solution) of the frame's first rocking segment as three bodies:
    uplift where the KKT system at rest (pins at the s-pivots) first gives s phi'' > 0, then
    the Baumgarte-stabilised DAE (with the devices' forces) until phi returns to 0."""
    st = scene.structure
    kkt = {s: ThreeBodies(st, s) for s in (1, -1)}
    rest = {s: kkt[s].state(0.0, 0.0) for s in (1, -1)}

    def pdd(s, tt):
        return s * kkt[s].solve(*rest[s], a_g(tt), a_v(tt))[0][2]

    grid = np.linspace(t0, t1, 4001)
    for i, x in enumerate(grid):
        hit = [s for s in (1, -1) if pdd(s, x) > 0]
        if hit:
            s = hit[0]
            tu = brentq(lambda y: pdd(s, y), grid[i - 1], x, xtol=1e-14)
            break
    else:
        raise AssertionError("the frame never uplifts")
    dev = scene.has_devices

    def dae(tt, y):
        extra = device_wrench(scene, y[:9], y[9:]) if dev else None
        qdd, _ = kkt[s].solve(y[:9], y[9:], a_g(tt), a_v(tt), baumgarte=20.0, extra=extra)
        return np.concatenate([y[9:], qdd])

    def back(tt, y):
        return s * y[2] if tt > tu + 1e-3 else 1.0
    back.terminal, back.direction = True, -1
    q0, qd0 = rest[s]
    sol = solve_ivp(dae, (tu, t1), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-11,
                    atol=1e-13, events=back, dense_output=True)
    return tu, s, sol


@pytest.mark.parametrize("fn", PATHS)
@pytest.mark.parametrize("name, sign, ratio", [("paper-asymmetric", 1, 0.6),
                                               ("paper-asymmetric", -1, 0.4),
                                               ("paper-asymmetric-hybrid", 1, 0.6),
                                               ("paper-symmetric-hybrid", -1, 0.5)])
def test_frame_matches_the_three_bodies(fn, name, sign, ratio):
    """The frame's first rocking segment under a pulse with a vertical part: uplift time within
    1e-10 s and phi(t) within 1e-9 rad of the three bodies as a constrained system (devices
    from the engines' point forces), until the first impact, itself within 1e-9 s (measured:
    1e-12 s, 1.2e-11 rad, 4.6e-11 s)."""
    scene = load_scene(name)
    m = RickerPulse.dimensionless(2.5, 3.0, scene.structure, "symmetric", sign,
                                  vertical_ratio=ratio)
    r = fn(scene, m)
    tu, s, sol = frame_segment(scene, m.acceleration, m.vertical.acceleration, m.t_start,
                               m.t_end)
    ups = r.events[r.events["kind"] == "uplift"]
    assert int(ups["direction"].iloc[0]) == s
    assert abs(float(ups["t"].iloc[0]) - tu) < 1e-10
    t_imp = float(sol.t[-1])
    assert sol.status == 1                          # the segment ended with an impact
    h = r.history
    seg = (h["t"] > tu) & (h["t"] < t_imp)
    assert seg.sum() > 100
    want = sol.sol(h["t"][seg].to_numpy())[2]
    err = np.max(np.abs(h["phi"][seg].to_numpy() - want))
    assert err < 1e-9, err
    first = r.events[r.events["kind"] == "impact"]["t"].iloc[0]
    assert abs(first - t_imp) < 1e-9


# --- the two paths, and today's results ---------------------------------------------------------
@needs_numba
@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric",
                                  "paper-asymmetric-hybrid-eps1", "paper-symmetric"])
def test_both_paths_agree_with_vertical_motion(name):
    """solve_ivp and the compiled kernel, pulses and a record with vertical channels: the same
    events and peaks, histories and peaks within 1e-6 alpha (the project's tolerance across
    paths, docs/reproducibility.md; measured <= 1.6e-7 alpha), the same sliding onset within
    1e-6 s."""
    scene = load_scene(name)
    st = scene.structure
    motions = [RickerPulse.dimensionless(3.0, 4.0, st, "symmetric", -1, vertical_ratio=0.7),
               RickerPulse.dimensionless(4.5, 6.0, st, "antisymmetric", 1, vertical_ratio=0.3),
               synthetic_record(ah=0.25)]
    for m in motions:
        a, b = simulate(scene, m), simulate_compiled(scene, m)
        assert a.summary.n_impacts == b.summary.n_impacts
        assert a.summary.fractured == b.summary.fractured
        n = min(len(a.history), len(b.history))
        tol = 1e-6 * st.alpha
        assert np.max(np.abs(a.history["phi"][:n] - b.history["phi"][:n])) < tol
        assert abs(b.summary.max_abs_phi - a.summary.max_abs_phi) < tol
        assert (a.summary.sliding_onset is None) == (b.summary.sliding_onset is None)
        if a.summary.sliding_onset is not None:
            assert b.summary.sliding_onset == pytest.approx(a.summary.sliding_onset, abs=1e-6)


@pytest.mark.parametrize("fn", PATHS)
def test_a_zero_vertical_channel_is_todays_model(fn):
    """A record with a vertical channel of zeros runs the vertical code (g + 0.0) and gives
    today's history to round-off (the uplift crossing is computed from the excess
    a_g - lambda (g + a_v) instead of a_g: a different rounding, <= 1e-12 rad)."""
    rec = synthetic_record()
    flat = Record(rec.time, rec.samples)
    zero = flat.with_vertical(Record(rec.time, np.zeros(rec.npts)))
    for name in ("housner-block", "paper-asymmetric-hybrid"):
        scene = load_scene(name)
        a, b = fn(scene, flat), fn(scene, zero)
        assert len(a.history) == len(b.history)
        assert a.summary.n_impacts == b.summary.n_impacts
        np.testing.assert_allclose(b.history["phi"], a.history["phi"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("fn", PATHS)
def test_uplift_threshold_with_an_in_phase_vertical_part(fn):
    """With a_v = r a_g, clockwise uplift from rest needs |a_g| > |lambda| g / (1 + r |lambda|)
    on the negative lobe: a symmetric pulse of sign -1 whose peak is that value times
    1 + 1e-6 uplifts, times 1 - 1e-6 does not."""
    scene = load_scene("paper-asymmetric")
    lam = abs(reference_lambda(scene, -1))
    r = 0.8
    crit = lam * G / (1.0 + r * lam)
    for f, uplifts in ((1.0 + 1e-6, True), (1.0 - 1e-6, False)):
        m = RickerPulse(crit * f, 0.5, "symmetric", -1, vertical_ratio=r)
        assert fn(scene, m).summary.uplifted is uplifts
        # and without the vertical part that amplitude is below the threshold lambda g
        assert fn(scene, RickerPulse(crit * f, 0.5, "symmetric", -1)).summary.uplifted is False


def reference_lambda(scene, s):
    from rockbench.analytic.reference import reference_of
    return reference_of(scene).lam[s]


# --- loss of contact ----------------------------------------------------------------------------
@pytest.mark.parametrize("fn", PATHS)
def test_lift_off_ends_the_run_where_the_ground_falls_faster_than_g(fn):
    """A symmetric pulse with a vertical part of peak 1.5 g, sign -1: g + a_v first vanishes
    on the main lobe, where (1 - 2u) e^-u = -g / (r a_g) (u = pi^2 t^2 / T_g^2, t < 0,
    solved here from Eq. 29): the run stops there, marked outside the model. The base slides
    before: as g + a_v falls to 0 with a_g = a_v / r != 0 the demand |a_g| / (g + a_v) grows
    without bound; with a friction of 1 it passes 1 where |a_g| = g + a_v, i.e.
    a_g (1 + r) = -g on the falling lobe (a squat block, b/h = 1.3 > mu, that does not rock first)."""
    scene = load_scene("housner-block", {"width": 2.6, "height": 2.0})
    a, T, r = 6.0, 0.6, 1.5 * G / 6.0
    m = RickerPulse(a, T, "symmetric", -1, vertical_ratio=r)

    def n(t):
        u = math.pi ** 2 * t * t / T ** 2
        return G - r * a * (1 - 2 * u) * math.exp(-u)
    t_lift = brentq(n, -0.3 * T, 0.0, xtol=1e-15)
    res = fn(scene, m)
    assert res.summary.t_lift_off == pytest.approx(t_lift, abs=1e-12)
    assert res.history["t"].iloc[-1] == pytest.approx(t_lift, abs=1e-12)
    t_slide = brentq(lambda t: n(t) + (n(t) - G) / r, -0.3 * T, 0.0, xtol=1e-15)
    assert t_slide < t_lift
    assert res.summary.sliding_onset == pytest.approx(t_slide, abs=res.settings["output_dt"])
    assert res.summary.sliding_contact == "base"
    assert res.summary.t_outside == res.summary.sliding_onset
    assert res.summary.validity.startswith(
        f"outside the model from t = {res.summary.sliding_onset:.6g} s: the base needs")
    assert "outside the model" in str(res.summary)


def test_settings_path_is_reported():
    """Sanity: the vertical runs go through the path the settings name."""
    m = RickerPulse.dimensionless(3.0, 3.0, BLOCK.structure, vertical_ratio=0.3)
    r = simulate(BLOCK, m, settings=AnalyticSettings(method="DOP853"))
    assert r.settings["path"] == "solve_ivp"
    assert r.motion["vertical_ratio"] == 0.3

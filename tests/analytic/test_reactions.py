"""Contact forces of the rocking models (:mod:`rockbench.analytic.reactions`) and the equation
of motion with vertical ground acceleration (g -> g + a_v).

Independent checks: the block against its closed form (Newton for the centre of mass about a
fixed corner); the frame against the Lagrange multipliers of the constrained three-body system
(9 coordinates, 8 pin constraints: a KKT system that uses only the bodies' poses, not the
mechanism's derivatives), at random instants and along a trajectory integrated numerically;
and against the SDOF equation of motion (Eq. 17 with g + a_v). SI units.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rockbench.analytic.dynamics import Dynamics
from rockbench.analytic.initiation import rocking_friction_demand
from rockbench.analytic.reactions import (block_reactions, frame_reactions, reaction_history,
                                          rocking_acceleration, uplift_direction)
from rockbench.constants import G
from rockbench.errors import ParameterError
from rockbench.scene.mechanism import mechanism
from rockbench.scene.scene import load_scene
from threebodies import ThreeBodies

BLOCK = load_scene("housner-block").structure
ASYM = load_scene("paper-asymmetric").structure
SYM = load_scene("paper-symmetric").structure
FRAMES = {"asymmetric": ASYM, "symmetric": SYM}


def weight(frame) -> float:
    return (frame.mass_left + frame.mass_beam + frame.mass_right) * G


# --- the block: closed form -----------------------------------------------------------------------
def block_closed_form(block, s, phi, phidot, a_g, a_v, phiddot=None):
    """(H, V, phi'') [N, N, rad/s^2]: r = pivot -> G = (s R sin(alpha - s phi),
    R cos(alpha - s phi)); phi'' = 3 (a_g r_y - (g + a_v) r_x) / (4 R^2) (moment about the
    pivot, I_O = 4 m R^2 / 3); H = m (a_g - phi'' r_y - phi'^2 r_x),
    V = m (g + a_v + phi'' r_x - phi'^2 r_y)."""
    m, R, al = block.mass, block.R, block.alpha
    rx, ry = s * R * math.sin(al - s * phi), R * math.cos(al - s * phi)
    ge = G + a_v
    if phiddot is None:
        phiddot = 3.0 * (a_g * ry - ge * rx) / (4.0 * R * R)
    return (m * (a_g - phiddot * ry - phidot**2 * rx),
            m * (ge + phiddot * rx - phidot**2 * ry), phiddot)


def test_block_against_the_closed_form():
    rng = np.random.default_rng(3)
    for _ in range(200):
        s = int(rng.choice([1, -1]))
        phi = s * rng.uniform(0.0, 1.2 * BLOCK.alpha)
        phidot, a_g, a_v = rng.normal(0, 1.0), rng.normal(0, 3.0), rng.uniform(-5.0, 5.0)
        H, V, pdd = block_closed_form(BLOCK, s, phi, phidot, a_g, a_v)
        r = block_reactions(BLOCK, s, phi, phidot, None, a_g, a_v)
        assert r.phiddot == pytest.approx(pdd, rel=1e-12, abs=1e-14)
        assert r.phiddot == pytest.approx(rocking_acceleration(BLOCK, s, phi, phidot, a_g, a_v),
                                          rel=1e-12, abs=1e-14)
        scale = BLOCK.mass * G
        assert r.pivot.tangential == pytest.approx(H, abs=1e-12 * scale)
        assert r.pivot.normal == pytest.approx(V, abs=1e-12 * scale)
        assert abs(r.moment_residual) < 1e-9 * scale * BLOCK.R
        # a given phi'' (here 0.3 rad/s^2 off the model's) gives the closed form's forces and
        # the residual moment I_O (phi'' - phi''_model)
        g = block_reactions(BLOCK, s, phi, phidot, pdd + 0.3, a_g, a_v)
        H2, V2, _ = block_closed_form(BLOCK, s, phi, phidot, a_g, a_v, pdd + 0.3)
        assert (g.pivot.tangential, g.pivot.normal) == pytest.approx((H2, V2), abs=1e-9 * scale)
        assert g.moment_residual == pytest.approx(4 / 3 * BLOCK.mass * BLOCK.R**2 * 0.3,
                                                  rel=1e-9)


def test_block_at_rest_and_at_uplift():
    """At rest: V = m g, H = 0. At the uplift threshold (phi'' = 0, a_g = lambda g): H = m a_g,
    V = m g, so the demand is exactly lambda = tan alpha; the same with a vertical acceleration
    at a_g = tan alpha (g + a_v)."""
    m, ta = BLOCK.mass, math.tan(BLOCK.alpha)
    r = block_reactions(BLOCK, 1, 0.0, 0.0, 0.0, 0.0)
    assert (r.pivot.tangential, r.pivot.normal) == (0.0, pytest.approx(m * G, rel=1e-15))
    for s in (1, -1):
        for a_v in (0.0, -3.0, 4.0):
            a_g = s * ta * (G + a_v)
            r = block_reactions(BLOCK, s, 0.0, 0.0, 0.0, a_g, a_v)
            assert abs(r.moment_residual) < 1e-9 * m * G * BLOCK.R  # phi'' = 0 is the model's
            assert r.pivot.demand == pytest.approx(ta, rel=1e-13)
            assert r.pivot.normal == pytest.approx(m * (G + a_v), rel=1e-14)


def test_block_first_instant_demand_is_shentons_boundary():
    """The pivot's demand at the first instant of rocking (phi = phi' = 0, the model's phi'')
    is the rock / slide-rock boundary of the initiation criteria."""
    beta = math.tan(BLOCK.alpha)
    for A in (beta, 0.3, 0.7, 2.0, 8.0):
        for a_v in (0.0, 2.5):
            r = block_reactions(BLOCK, 1, 0.0, 0.0, None, A * (G + a_v), a_v)
            assert r.pivot.demand == pytest.approx(
                rocking_friction_demand(beta, A * (1 + a_v / G), a_v / G), rel=1e-12)


def test_block_centripetal_term():
    """At fixed phi and phi'', phi' only adds the centripetal -m phi'^2 r to the pivot's force
    (r from the pivot to G): it pulls towards the pivot and unloads it. Where the horizontal
    force already points to the pivot's side, the demand grows with phi'^2 until the pivot
    lifts, at phi'^2 = V(0) / (m r_y)."""
    s, phi = 1, 0.4 * BLOCK.alpha
    a_g = -0.5 * G                       # the ground pulls the block back: H points left
    pdd = rocking_acceleration(BLOCK, s, phi, 0.0, a_g)
    base = block_reactions(BLOCK, s, phi, 0.0, pdd, a_g)
    rx = BLOCK.R * math.sin(BLOCK.alpha - phi)
    ry = BLOCK.R * math.cos(BLOCK.alpha - phi)
    assert base.pivot.tangential < 0
    lift = base.pivot.normal / (BLOCK.mass * ry)
    w2 = np.linspace(0.0, 0.999 * lift, 50)
    demands = []
    for w in np.sqrt(w2):
        r = block_reactions(BLOCK, s, phi, w, pdd, a_g)
        assert r.pivot.tangential - base.pivot.tangential == pytest.approx(
            -BLOCK.mass * w * w * rx, abs=1e-9 * BLOCK.mass * G)
        assert r.pivot.normal - base.pivot.normal == pytest.approx(
            -BLOCK.mass * w * w * ry, abs=1e-9 * BLOCK.mass * G)
        demands.append(r.pivot.demand)
    assert np.all(np.diff(demands) > 0)
    r = block_reactions(BLOCK, s, phi, math.sqrt(1.001 * lift), pdd, a_g)
    assert r.pivot.opens and r.pivot.demand == math.inf


# --- the frame: the KKT system of the three bodies (threebodies.py) -------------------------------
def random_states(frame, s, n, rng):
    lim = 0.8 * mechanism(frame, s).limit() if frame is ASYM else 0.8
    for _ in range(n):
        yield (s * rng.uniform(0.0, min(lim, 3 * frame.alpha)), rng.normal(0, 0.5),
               rng.normal(0, 3.0), rng.uniform(-4.0, 4.0))


@pytest.mark.parametrize("name", ["asymmetric", "symmetric"])
@pytest.mark.parametrize("s", [1, -1])
def test_frame_against_the_lagrange_multipliers(name, s):
    """Random instants: the equilibrium solve's phi'' and contact forces equal the KKT
    system's (independent of the mechanism's derivatives), and phi'' equals Eq. 17 with
    g -> g + a_v (and Dynamics.acceleration when a_v = 0)."""
    frame = FRAMES[name]
    kkt = ThreeBodies(frame, s)
    W = weight(frame)
    rng = np.random.default_rng(15 if s > 0 else 16)
    for phi, phidot, a_g, a_v in random_states(frame, s, 40, rng):
        r = frame_reactions(frame, s, phi, phidot, None, a_g, a_v)
        qdd, lam = kkt.solve(*kkt.state(phi, phidot), a_g, a_v)
        assert r.phiddot == pytest.approx(qdd[2], rel=1e-9, abs=1e-12)
        assert r.phiddot == pytest.approx(rocking_acceleration(frame, s, phi, phidot, a_g, a_v),
                                          rel=1e-11, abs=1e-13)
        if a_v == 0.0:
            assert r.phiddot == pytest.approx(Dynamics(frame, s).acceleration(phi, phidot, a_g))
        np.testing.assert_allclose([r.A.fx, r.A.fy], lam["A"], atol=1e-9 * W)
        np.testing.assert_allclose([r.D.fx, r.D.fy], lam["D"], atol=1e-9 * W)
        np.testing.assert_allclose([r.B.fx, r.B.fy], -lam["B"], atol=1e-9 * W)
        np.testing.assert_allclose([r.C.fx, r.C.fy], lam["C"], atol=1e-9 * W)
        assert r.moment_residual == 0.0


def test_frame_along_an_integrated_trajectory():
    """The three-body system integrated as a DAE (Baumgarte-stabilised KKT, 9 coordinates)
    under horizontal and vertical ground motion, against the SDOF equation with g + a_v: the
    same phi(t) (1e-8 rad), and its multipliers equal the contact forces computed from the
    SDOF state (1e-7 of the weight)."""
    frame, s = ASYM, 1
    kkt = ThreeBodies(frame, s)
    a_g = lambda t: 0.25 * G * math.sin(2 * math.pi * t / 0.9)
    a_v = lambda t: -0.4 * G * math.sin(2 * math.pi * t / 0.35)
    phi0, phidot0, T = 0.3 * frame.alpha, 0.15, 0.6

    def sdof(t, y):
        return [y[1], rocking_acceleration(frame, s, y[0], y[1], a_g(t), a_v(t))]

    def dae(t, y):
        qdd, _ = kkt.solve(y[:9], y[9:], a_g(t), a_v(t), baumgarte=20.0)
        return np.concatenate([y[9:], qdd])

    q0, qd0 = kkt.state(phi0, phidot0)
    ts = np.linspace(0.0, T, 13)
    one = solve_ivp(sdof, (0, T), [phi0, phidot0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=ts)
    many = solve_ivp(dae, (0, T), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-11,
                     atol=1e-13, t_eval=ts)
    assert np.all(one.y[0] > 0)            # no impact: the mechanism holds throughout
    np.testing.assert_allclose(many.y[2], one.y[0], atol=1e-8)
    W = weight(frame)
    for k, t in enumerate(ts):
        r = frame_reactions(frame, s, one.y[0, k], one.y[1, k], None, a_g(t), a_v(t))
        _, lam = kkt.solve(many.y[:9, k], many.y[9:, k], a_g(t), a_v(t))
        np.testing.assert_allclose([r.A.fx, r.A.fy, r.D.fx, r.D.fy],
                                   np.concatenate([lam["A"], lam["D"]]), atol=1e-7 * W)


@pytest.mark.parametrize("name", ["asymmetric", "symmetric"])
def test_frame_totals_momentum_and_moment_balance(name):
    """Sum of the pivots' forces = sum m_i (a_i + (a_g, g + a_v)) (linear momentum), and
    the moment of the pivots' forces about A = the rate of angular momentum about A of the
    three bodies plus the moment of their loads (checks the split between A and D)."""
    frame = FRAMES[name]
    rng = np.random.default_rng(5)
    for s in (1, -1):
        mech = mechanism(frame, s)
        bodies = list(zip((frame.mass_left, frame.mass_beam, frame.mass_right),
                          (frame.inertia_left, frame.inertia_beam, frame.inertia_right)))
        A, D = frame.pivots(s)["A"], frame.pivots(s)["D"]
        for phi, phidot, a_g, a_v in random_states(frame, s, 20, rng):
            r = frame_reactions(frame, s, phi, phidot, None, a_g, a_v)
            fx = fy = mom = 0.0
            for (m, I), k in zip(bodies, mech.configuration(phi).bodies):
                ax = k.dx * r.phiddot + k.ddx * phidot**2 + a_g
                ay = k.dy * r.phiddot + k.ddy * phidot**2 + G + a_v
                al = k.dtheta * r.phiddot + k.ddtheta * phidot**2
                fx, fy = fx + m * ax, fy + m * ay
                mom += I * al + (k.x - A[0]) * m * ay - (k.y - A[1]) * m * ax
            W = weight(frame)
            assert r.A.fx + r.D.fx == pytest.approx(fx, abs=1e-10 * W)
            assert r.A.fy + r.D.fy == pytest.approx(fy, abs=1e-10 * W)
            arm = (D[0] - A[0]) * r.D.fy - (D[1] - A[1]) * r.D.fx
            assert arm == pytest.approx(mom, abs=1e-10 * W * frame.L)


@pytest.mark.parametrize("name", ["asymmetric", "symmetric"])
def test_frame_at_rest_and_at_uplift(name):
    """At rest the pivots carry the weight: sum V = total weight, sum H = 0 (the moment the
    mechanism cannot carry, G(0) g, is the residual). At uplift (a_g = lambda (g + a_v),
    phi'' = 0 consistent: no residual) sum H / sum V = lambda."""
    frame = FRAMES[name]
    W = weight(frame)
    r = frame_reactions(frame, 1, 0.0, 0.0, 0.0, 0.0)
    assert r.A.normal + r.D.normal == pytest.approx(W, rel=1e-13)
    assert abs(r.A.tangential + r.D.tangential) < 1e-12 * W
    assert r.moment_residual == pytest.approx(Dynamics(frame, 1).terms(0.0).gravity * G,
                                              rel=1e-12)
    for s in (1, -1):
        lam = Dynamics(frame, s).uplift_threshold()
        for a_v in (0.0, -2.0, 3.0):
            r = frame_reactions(frame, s, 0.0, 0.0, 0.0, lam * (G + a_v), a_v)
            assert abs(r.moment_residual) < 1e-10 * W * frame.L
            H, V = r.A.tangential + r.D.tangential, r.A.normal + r.D.normal
            assert H / V == pytest.approx(lam, rel=1e-12)
            assert V == pytest.approx(W * (1 + a_v / G), rel=1e-12)
            assert not (r.A.opens or r.B.opens or r.C.opens or r.D.opens)
            if frame.symmetric:   # the parallelogram: every contact as a block's, tan alpha
                for c in "ABCD":
                    assert getattr(r, c).demand == pytest.approx(math.tan(frame.alpha),
                                                                 rel=1e-12)


def test_vertical_acceleration_scales_every_force():
    """Scaling (a_g, g + a_v) by k and phi'^2 by k scales phi'' and every contact force by k:
    the vertical acceleration acts as a change of gravity."""
    frame, s = ASYM, -1
    rng = np.random.default_rng(9)
    for phi, phidot, a_g, _ in random_states(frame, s, 10, rng):
        base = frame_reactions(frame, s, phi, phidot, None, a_g)
        for k in (0.4, 1.7):
            r = frame_reactions(frame, s, phi, phidot * math.sqrt(k), None, k * a_g,
                                k * G - G)
            assert r.phiddot == pytest.approx(k * base.phiddot, rel=1e-11, abs=1e-13)
            for c in "ABCD":
                got, ref = getattr(r, c), getattr(base, c)
                assert (got.normal, got.tangential) == pytest.approx(
                    (k * ref.normal, k * ref.tangential), abs=1e-10 * weight(frame))


def test_frame_centripetal_term_unloads_the_pivots():
    """At fixed phi'', phi'^2 changes the total pivot force by -sum m_i d2G_i/dphi2 phi'^2
    (the centripetal accelerations), and the pivots lift once it exceeds the load."""
    frame, s, phi = ASYM, 1, 0.5 * ASYM.alpha
    pdd = rocking_acceleration(frame, s, phi, 0.0, 0.0)
    base = frame_reactions(frame, s, phi, 0.0, pdd, 0.0)
    bodies = mechanism(frame, s).configuration(phi).bodies
    ms = (frame.mass_left, frame.mass_beam, frame.mass_right)
    cy = sum(m * k.ddy for m, k in zip(ms, bodies))
    assert cy < 0
    for w in (0.5, 1.0, 2.0):
        r = frame_reactions(frame, s, phi, w, pdd, 0.0)
        assert (r.A.normal + r.D.normal) - (base.A.normal + base.D.normal) == pytest.approx(
            cy * w * w, rel=1e-9)
    fast = frame_reactions(frame, s, phi, 20.0, pdd, 0.0)
    assert fast.A.opens or fast.D.opens
    assert fast.max_demand == math.inf


def test_uplift_direction_with_vertical_acceleration():
    """|a_g| > |lambda| (g + a_v) uplifts, in the direction of a_g (Eq. 20 with g + a_v)."""
    for structure in (BLOCK, ASYM):
        lp = Dynamics(structure, 1).uplift_threshold()
        ln = Dynamics(structure, -1).uplift_threshold()
        for a_v in (0.0, -4.0, 5.0):
            ge = G + a_v
            assert uplift_direction(structure, 1.001 * lp * ge, a_v) == 1
            assert uplift_direction(structure, 0.999 * lp * ge, a_v) == 0
            assert uplift_direction(structure, lp * ge, a_v) == 0        # a grazing touch
            assert uplift_direction(structure, 1.001 * ln * ge, a_v) == -1
            assert uplift_direction(structure, 0.999 * ln * ge, a_v) == 0
    with pytest.raises(ParameterError, match="a_v"):
        uplift_direction(BLOCK, 1.0, -G)


def test_reaction_history_and_arguments():
    phi = np.linspace(0.0, 0.5 * ASYM.alpha, 5)
    h = reaction_history(ASYM, 1, phi, 0.1, None, 2.0, -1.0)
    assert list(h.columns[:4]) == ["phiddot", "normal_A", "tangential_A", "demand_A"]
    r = frame_reactions(ASYM, 1, phi[3], 0.1, None, 2.0, -1.0)
    assert h.demand_D.iloc[3] == r.D.demand and h.phiddot.iloc[3] == r.phiddot
    hb = reaction_history(BLOCK, -1, -phi, np.zeros(5), 0.0, 0.0)   # held still: the weight
    np.testing.assert_allclose(hb.normal_pivot, BLOCK.mass * G, rtol=1e-14)
    np.testing.assert_allclose(hb.tangential_pivot, 0.0, atol=1e-9)
    with pytest.raises(ParameterError, match="structure"):
        frame_reactions(BLOCK, 1, 0.0, 0.0, None, 0.0)
    with pytest.raises(ParameterError, match="direction"):
        block_reactions(BLOCK, 0, 0.0, 0.0, None, 0.0)

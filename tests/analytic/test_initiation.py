"""Shenton's (1996) initiation criteria (:mod:`rockbench.analytic.initiation`): the paper's
statements (its abstract, J. Eng. Mech. 122(7), p. 690: the only part of the paper we could
read; docs/sliding.md) and an independent solution of the rigid-body contact problem at the
first instant, by enumeration of the contact states of the block's two corners.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rockbench.analytic.initiation import (MODES, initiation_mode, mode_map,
                                           rock_friction_limit, rocking_friction_demand,
                                           rocking_threshold, sliding_threshold)
from rockbench.errors import ParameterError


# --- the independent check: the contact problem at the first instant ---------------------------
def consistent_modes(beta: float, mu: float, A: float, ge: float = 1.0, h: float = 1.0
                     ) -> list[str]:
    """Every mode whose contact states are consistent, for a block (half-width beta h,
    half-height h, unit mass) at rest under the effective gravity ge [m/s^2] and the inertial
    force -A ge (horizontal), Coulomb friction mu.

    Unknowns x = (ax, ay, al, NL, FL, NR, FR): the accelerations of the centre of mass and the
    angular acceleration, and the normal and friction forces at the left (-b, -h) and right
    (b, -h) corners. A corner is open (N = F = 0, its normal acceleration must be > 0),
    sticking (normal and tangential accelerations 0; N >= 0, |F| <= mu N) or slipping in
    direction d (normal acceleration 0, F = -d mu N; N >= 0, tangential acceleration of
    sign d). Each of the 16 combinations is a linear system; the consistent ones are kept.
    """
    b = beta * h
    I = (b * b + h * h) / 3.0
    corners = {"L": -b, "R": b}
    tol = 1e-9
    found = []
    for states in itertools.product(("open", "stick", "slip+", "slip-"), repeat=2):
        rows = [np.array([1, 0, 0, 0, -1, 0, -1.0]),           # ax = FL + FR - A ge
                np.array([0, 1, 0, -1, 0, -1, 0.0]),           # ay = NL + NR - ge
                np.array([0, 0, I, b, -h, -b, -h])]            # I al = sum r x F
        rhs = [-A * ge, -ge, 0.0]
        for k, (name, state) in enumerate(zip("LR", states)):
            x = corners[name]
            iN, iF = 3 + 2 * k, 4 + 2 * k
            normal = np.zeros(7)
            normal[[1, 2]] = (1.0, x)          # ay + al x: the corner's vertical acceleration
            tangent = np.zeros(7)
            tangent[[0, 2]] = (1.0, h)         # ax + al h: its horizontal acceleration
            if state == "open":
                e1, e2 = np.zeros(7), np.zeros(7)
                e1[iN], e2[iF] = 1.0, 1.0
                rows += [e1, e2]
            elif state == "stick":
                rows += [normal, tangent]
            else:
                d = 1.0 if state == "slip+" else -1.0
                e = np.zeros(7)
                e[iF], e[iN] = 1.0, d * mu
                rows += [normal, e]
            rhs += [0.0, 0.0]
        M, r = np.array(rows), np.array(rhs)
        sol, *_ = np.linalg.lstsq(M, r, rcond=None)
        if np.max(np.abs(M @ sol - r)) > tol:
            continue                            # no solution of this combination
        ax, ay, al, NL, FL, NR, FR = sol
        ok = True
        for name, state, N, F in (("L", states[0], NL, FL), ("R", states[1], NR, FR)):
            x = corners[name]
            if state == "open":
                ok &= ay + al * x > tol
            elif state == "stick":
                ok &= N > -tol and (states == ("stick", "stick") or abs(F) <= mu * N + tol)
            else:
                d = 1.0 if state == "slip+" else -1.0
                ok &= N > -tol and d * (ax + al * h) > tol
        if states == ("stick", "stick"):        # the split of F is indeterminate: its sum
            ok &= abs(FL + FR) <= mu * (NL + NR) + tol
        if ok:
            found.append({("stick", "stick"): "rest", ("open", "open"): "free-flight"}.get(
                states, "rock" if "stick" in states and "open" in states else
                "slide-rock" if "open" in states else "slide"))
    return sorted(set(found))


def near_a_boundary(beta, mu, A, gap=2e-3) -> bool:
    return min(abs(A - mu), abs(A - beta), abs(mu - beta),
               abs(mu - rocking_friction_demand(beta, A)) if A > beta else 1.0) < gap


def test_enumeration_agrees_with_the_criteria_on_random_cases():
    """1000 random (b/h, mu, a_g/g, a_v/g) away from the boundaries: the contact problem has
    exactly one consistent mode, and it is the one of the criteria."""
    rng = np.random.default_rng(1996)
    seen = set()
    n = 0
    while n < 1000:
        beta, mu = rng.uniform(0.1, 1.5), rng.uniform(0.05, 2.0)
        a, av = rng.uniform(-3.0, 3.0), rng.uniform(-0.7, 0.7)
        ge = 1.0 + av
        if near_a_boundary(beta, mu, abs(a) / ge):
            continue
        n += 1
        modes = consistent_modes(beta, mu, abs(a) / ge, ge=ge)
        expected = initiation_mode(beta, mu, a, av)
        assert modes == [expected], (beta, mu, a, av, modes)
        seen.add(expected)
    assert seen == {"rest", "slide", "rock", "slide-rock"}


def test_enumeration_finds_slide_rock_above_the_rock_limit_nowhere():
    """Friction above mu_inf = (4 beta^2 + 1) / (3 beta): the block rocks (the slide-rock
    solution would need theta'' < 0) at every acceleration above b/h."""
    for beta in (0.2, 0.5, 1.0):
        mu = 1.05 * rock_friction_limit(beta)
        for A in (1.01 * beta, 2.0, 10.0, 100.0):
            assert consistent_modes(beta, mu, A) == ["rock"] == [initiation_mode(beta, mu, A)]


# --- the paper's statements (abstract, p. 690) ---------------------------------------------------
def test_a_slide_rock_mode_can_start_from_rest_with_friction_above_b_over_h():
    """"a slide-rock mode is initiated when friction is greater than the width-to-height
    ratio, but less than a critical value that is a function of the ground acceleration";
    "it is incorrect to assume that a rock mode ensues if static friction is simply greater
    than the width-to-height ratio"."""
    beta, A = 0.25, 0.8
    mu_r = rocking_friction_demand(beta, A)
    assert beta < mu_r
    assert initiation_mode(beta, 0.5 * (beta + mu_r), A) == "slide-rock"
    grid = mode_map(beta, np.linspace(0.01, 2.0, 400), np.linspace(0.0, 3.0, 300))
    slide_rock = grid.codes == MODES.index("slide-rock")
    assert slide_rock.any()
    mus = np.broadcast_to(grid.mu[:, None], grid.codes.shape)
    acc = np.broadcast_to(grid.a_g_over_g[None, :], grid.codes.shape)
    assert np.all(mus[slide_rock] > beta)
    assert np.all(mus[slide_rock] < _demand_grid(beta, acc[slide_rock]))


def _demand_grid(beta, acc):
    return np.array([rocking_friction_demand(beta, a) for a in acc])


def test_friction_to_rock_increases_with_the_acceleration():
    """"The friction required to initiate a rock mode increases with ground acceleration":
    mu_r(A) rises from b/h at A = b/h towards mu_inf."""
    for beta in (0.1, 0.3, 0.7, 1.2):
        A = np.linspace(beta, 50.0, 500)
        mu_r = _demand_grid(beta, A)
        assert mu_r[0] == pytest.approx(beta, rel=1e-14)
        assert np.all(np.diff(mu_r) > 0)
        assert mu_r[-1] < rock_friction_limit(beta)
        assert rocking_friction_demand(beta, 1e12) == pytest.approx(rock_friction_limit(beta),
                                                                   rel=1e-8)


def test_transition_slide_then_slide_rock_then_rock_as_friction_rises():
    """"A more natural transition of the governing mode of response, from sliding to
    slide-rock and finally to pure rocking, as friction is increased for a given foundation
    acceleration": along mu at fixed a_g > b/h g, the modes come in that order, once each."""
    for beta, A in ((0.2, 0.5), (0.5, 1.5), (1.0, 3.0)):
        codes = mode_map(beta, np.linspace(0.01, 3.0, 3000), [A]).codes[:, 0]
        runs = [MODES[c] for c, _ in itertools.groupby(codes)]
        assert runs == ["slide", "slide-rock", "rock"]


def test_classical_limits():
    """Below both thresholds: rest; mu < b/h: slide as soon as |a_g| > mu g (whatever a_g);
    a grazing touch of a threshold is not an initiation."""
    assert initiation_mode(0.3, 0.5, 0.29) == "rest"
    assert initiation_mode(0.3, 0.2, 0.21) == "slide"
    assert initiation_mode(0.3, 0.2, 25.0) == "slide"
    assert initiation_mode(0.3, 0.2, -0.21) == "slide"
    assert initiation_mode(0.3, 0.2, 0.2) == "rest"
    assert initiation_mode(0.3, 0.5, 0.3) == "rest"
    assert initiation_mode(0.3, 0.5, 0.31) == "rock"


# --- vertical acceleration -----------------------------------------------------------------------
def test_vertical_acceleration_scales_the_thresholds():
    assert sliding_threshold(0.4, 0.25) == pytest.approx(0.5, rel=1e-15)
    assert rocking_threshold(0.2, -0.5) == pytest.approx(0.1, rel=1e-15)
    rng = np.random.default_rng(7)
    for _ in range(300):
        beta, mu, a, av = (rng.uniform(0.1, 1.5), rng.uniform(0.05, 2.0),
                           rng.uniform(-3, 3), rng.uniform(-0.9, 2.0))
        assert initiation_mode(beta, mu, a, av) == initiation_mode(beta, mu, a / (1 + av))
    assert initiation_mode(0.3, 0.5, 0.0, -1.0) == "free-flight"
    assert initiation_mode(0.3, 0.5, 0.4, -1.5) == "free-flight"
    assert mode_map(0.3, [0.5], [0.1], -1.2).fraction("free-flight") == 1.0


def test_mode_map_matches_the_scalar_function_and_refuses_bad_input():
    mus, acc = np.linspace(0.05, 1.5, 23), np.linspace(-2.0, 2.0, 31)
    grid = mode_map(0.4, mus, acc, 0.3)
    for i, m in enumerate(mus):
        for j, a in enumerate(acc):
            assert grid.modes[i, j] == initiation_mode(0.4, m, a, 0.3)
    assert sum(grid.fraction(m) for m in MODES) == pytest.approx(1.0)
    with pytest.raises(ParameterError, match="mu"):
        mode_map(0.4, [0.0, 0.5], acc)
    with pytest.raises(ParameterError, match="b_over_h"):
        initiation_mode(-1.0, 0.5, 0.3)
    with pytest.raises(ParameterError, match="mode"):
        grid.fraction("tumble")

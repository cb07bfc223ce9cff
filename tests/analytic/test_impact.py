"""Coefficient of restitution eta (paper, Eqs. 22-28): closed forms for the block (Housner) and the
symmetric frame (Eq. 28), and for any frame an independent solution of the impulse-momentum
equations of the three bodies with sticking new pivots (the system of Eqs. 23-27).
"""

from __future__ import annotations

import math
from dataclasses import replace
from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockbench.analytic.dynamics import Dynamics
from rockbench.analytic.impact import eta, restitution
from rockbench.analytic.reference import Reference
from rockbench.scene.scene import Scene, load_scene
from rockbench.scene.structure import Block, Frame

FAST = settings(max_examples=40, deadline=None)

PAPER_ASYM = load_scene("paper-asymmetric").structure
PAPER_SYM = load_scene("paper-symmetric").structure
HOUSNER = load_scene("housner-block").structure


def eq28(frame: Frame) -> float:
    """Eq. 28 (Makris & Vassiliou 2012): eta of the symmetric frame, gamma = m_BC / (2 m_AB)."""
    a, g = frame.alpha, frame.mass_beam / (2.0 * frame.mass_left)
    return (1.0 - 1.5 * math.sin(a) ** 2 + 3.0 * g * math.cos(2.0 * a)) / (1.0 + 3.0 * g)


def housner(alpha: float) -> float:
    return 1.0 - 1.5 * math.sin(alpha) ** 2


def symmetric(frame: Frame) -> Frame:
    d = {k: v for k, v in frame.to_dict().items() if k != "type"}
    d["column_height_right"] = d["column_height_left"]
    return Frame(**d)


def frames(min_slender: float, min_ratio: float):
    """Frames with 2H / 2b >= min_slender and H1 / H >= min_ratio."""
    return st.builds(
        lambda w, slender, ratio, gap, over, bh, rho, mr: Frame(
            column_width=w, column_height_left=slender * w,
            column_height_right=ratio * slender * w, span=w + gap,
            beam_width=w + gap + w + over, beam_height=bh, beam_gyration_radius=rho,
            mass_ratio=mr),
        w=st.floats(0.2, 2.0), slender=st.floats(min_slender, 15.0),
        ratio=st.floats(min_ratio, 1.0), gap=st.floats(0.5, 14.0), over=st.floats(0.0, 4.0),
        bh=st.floats(0.3, 3.0), rho=st.floats(0.3, 6.0), mr=st.floats(0.05, 20.0))


#: slender frames (both columns: alpha < 0.35 rad), for which the frame keeps rocking after an
#: impact (eta > 0); squat ones (alpha up to 1.2 rad) may give eta <= 0 (no rocking).
SLENDER = frames(4.0, 0.7)
ANY = frames(1.0, 0.3)


# --- impulse-momentum equations, solved directly ----------------------------------------------
def impulse_momentum_eta(structure, post: int) -> tuple[float, np.ndarray]:
    """Solve the impact at phi = 0 from the mechanism ``-post`` into ``post`` as a linear system.

    Unknowns: the post-impact velocities (vx, vy, omega) of every body and the impulses at the
    post mechanism's pivots (two components each). Equations: linear and angular momentum of
    each body (angular about its centre of mass), and the post pivots stick (ground pivots at
    rest, column-beam joints with equal velocities on both bodies). Pre-impact velocities are
    finite differences of the pre mechanism's poses at phi'^- = +1. Returns (eta, impulses
    [N s] per unit phi'^-, two components per pivot in the order A, B, C, D; at a joint, the
    impulse on the column).
    """
    pre = -post
    dpre = Dynamics(structure, pre)
    h = 1e-6
    # velocities at phi' = +1 (the solution is linear in phi'^-; physically phi'^- has the
    # sign of ``post``: the structure swings back through phi = 0)
    cp, cm = dpre.configuration(h).bodies, dpre.configuration(-h).bodies
    vpre = [((p.x - m.x) / (2 * h), (p.y - m.y) / (2 * h), (p.theta - m.theta) / (2 * h))
            for p, m in zip(cp, cm)]
    if isinstance(structure, Block):
        bodies = [(structure.mass, structure.inertia_cm, (0.0, structure.H))]
        pins = [((-post * structure.b, 0.0), 0, None)]
    else:
        f = structure
        bodies = [(f.mass_left, f.inertia_left, f.com_left),
                  (f.mass_beam, f.inertia_beam, f.com_beam),
                  (f.mass_right, f.inertia_right, f.com_right)]
        piv = f.pivots(post)
        pins = [(piv["A"], 0, None), (piv["B"], 0, 1), (piv["C"], 2, 1), (piv["D"], 2, None)]
    nb, npin = len(bodies), len(pins)
    n = 3 * nb + 2 * npin
    M = np.zeros((n, n))
    rhs = np.zeros(n)
    # momentum: m (v+ - v-) = sum impulses;  Ic (w+ - w-) = sum moments about the CoM
    for i, (m, Ic, _) in enumerate(bodies):
        M[3 * i, 3 * i] = m
        M[3 * i + 1, 3 * i + 1] = m
        M[3 * i + 2, 3 * i + 2] = Ic
        rhs[3 * i: 3 * i + 3] = (m * vpre[i][0], m * vpre[i][1], Ic * vpre[i][2])
    for j, (P, a, b) in enumerate(pins):
        col = 3 * nb + 2 * j
        for body, sign in ((a, 1.0), (b, -1.0)):
            if body is None:
                continue
            gx, gy = bodies[body][2]
            M[3 * body, col] -= sign
            M[3 * body + 1, col + 1] -= sign
            M[3 * body + 2, col] -= -sign * (P[1] - gy)
            M[3 * body + 2, col + 1] -= sign * (P[0] - gx)
    # sticking: velocity of the material point at P, (vx - w (Py - gy), vy + w (Px - gx))
    row = 3 * nb
    for P, a, b in pins:
        for body, sign in ((a, 1.0), (b, -1.0)):
            if body is None:
                continue
            gx, gy = bodies[body][2]
            M[row, 3 * body] += sign
            M[row, 3 * body + 2] += -sign * (P[1] - gy)
            M[row + 1, 3 * body + 1] += sign
            M[row + 1, 3 * body + 2] += sign * (P[0] - gx)
        row += 2
    sol = np.linalg.solve(M, rhs)
    # phi' is the rotation rate of the left column (of the block)
    return float(sol[2] / vpre[0][2]), sol[3 * nb:]


@pytest.mark.parametrize("structure", [HOUSNER, PAPER_SYM, PAPER_ASYM],
                         ids=["block", "symmetric", "asymmetric"])
@pytest.mark.parametrize("post", [1, -1])
def test_eta_solves_the_impulse_momentum_equations(structure, post):
    e_direct, impulses = impulse_momentum_eta(structure, post)
    assert eta(structure, post) == pytest.approx(e_direct, rel=1e-8)
    assert restitution(structure, -post, post) == eta(structure, post)
    assert 0.0 < eta(structure, post) < 1.0
    # every impulse is compressive: the foundation pushes the new pivots up, the beam bears down
    # on the column tops (impulses scaled to the physical phi'^-, of the sign of ``post``)
    vertical = post * impulses[1::2]
    assert vertical[0] > 0.0
    if len(vertical) == 4:
        assert vertical[1] < 0.0 and vertical[2] < 0.0 and vertical[3] > 0.0


@FAST
@given(frame=ANY, post=st.sampled_from([1, -1]))
def test_eta_solves_the_impulse_momentum_equations_random(frame, post):
    e_direct, _ = impulse_momentum_eta(frame, post)
    assert eta(frame, post) == pytest.approx(e_direct, rel=1e-7, abs=1e-9)


@FAST
@given(frame=ANY, post=st.sampled_from([1, -1]))
def test_impact_loses_energy(frame, post):
    """Energy after / before = eta^2 I_post(0) / I_pre(0) < 1, whatever the geometry (for a
    squat asymmetric frame |eta| itself may exceed 1 when I_post(0) < I_pre(0))."""
    e = eta(frame, post)
    i_pre = Dynamics(frame, -post).terms(0.0).inertia
    i_post = Dynamics(frame, post).terms(0.0).inertia
    assert e * e * i_post / i_pre < 1.0


@FAST
@given(frame=SLENDER, post=st.sampled_from([1, -1]))
def test_slender_frames_keep_rocking_after_an_impact(frame, post):
    """eta > 0 for slender frames; eta < 1 is guaranteed where I_post(0) = I_pre(0) (symmetric
    frame, block): an asymmetric frame can rebound faster (e.g. span 2 m, H1/H = 0.75, heavy
    beam: eta_cw = 1.0002) while losing energy (test_impact_loses_energy)."""
    assert eta(frame, post) > 0.0
    sym = symmetric(frame)
    assert Dynamics(sym, post).terms(0.0).inertia == pytest.approx(
        Dynamics(sym, -post).terms(0.0).inertia, rel=1e-12)
    assert 0.0 < eta(sym, post) < 1.0


# --- closed forms -----------------------------------------------------------------------------
@pytest.mark.parametrize("post", [1, -1])
def test_paper_symmetric_eta_is_eq28(post):
    assert eta(PAPER_SYM, post) == pytest.approx(eq28(PAPER_SYM), rel=1e-13)
    # gamma = 5, sin^2 alpha = 0.02: (1 - 0.03 + 15 x 0.96) / 16
    assert eta(PAPER_SYM, post) == pytest.approx(15.37 / 16.0, rel=1e-13)


@FAST
@given(frame=ANY, post=st.sampled_from([1, -1]))
def test_symmetric_eta_is_eq28_random(frame, post):
    sym = symmetric(frame)
    assert eta(sym, post) == pytest.approx(eq28(sym), rel=1e-11)


@pytest.mark.parametrize("mass_ratio", [1e-9, 1e-6])
def test_symmetric_eta_tends_to_housner_for_a_weightless_beam(mass_ratio):
    f = replace(PAPER_SYM, mass_ratio=mass_ratio)
    e = eta(f, 1)
    assert e == pytest.approx(eq28(f), rel=1e-13)
    assert abs(e - housner(f.alpha)) < 10 * mass_ratio
    assert abs(eta(f, -1) - housner(f.alpha)) < 10 * mass_ratio


def test_symmetric_eta_decreases_with_the_beam_mass():
    """Eq. 28 runs from Housner's 1 - 1.5 sin^2 alpha (weightless beam) down to cos(2 alpha)
    = 1 - 2 sin^2 alpha (infinitely heavy beam): a heavier cap beam loses more per impact."""
    es = [eta(replace(PAPER_SYM, mass_ratio=r), 1) for r in (1e-9, 1.0, 10.0, 1e9)]
    assert all(a > b for a, b in pairwise(es))
    assert es[0] == pytest.approx(housner(PAPER_SYM.alpha), abs=1e-8)
    assert es[-1] == pytest.approx(math.cos(2 * PAPER_SYM.alpha), abs=1e-8)


@FAST
@given(width=st.floats(0.1, 3.0), height=st.floats(0.5, 15.0))
def test_block_eta_is_housner(width, height):
    blk = Block(width=width, height=height)
    for post in (1, -1):
        assert eta(blk, post) == pytest.approx(housner(blk.alpha), rel=1e-12, abs=1e-14)
    assert blk.eta_housner == pytest.approx(housner(blk.alpha), rel=1e-15)


def test_reference_eta_keys_are_the_direction_after_the_impact():
    """eta_ccw is the restitution of the impact after which the frame rocks counterclockwise."""
    ref = Reference(Scene(PAPER_ASYM))
    assert ref.eta[1] == pytest.approx(restitution(PAPER_ASYM, -1, 1), rel=1e-15)
    assert ref.eta[-1] == pytest.approx(restitution(PAPER_ASYM, 1, -1), rel=1e-15)
    assert ref.eta[1] != pytest.approx(ref.eta[-1], rel=1e-3)
    const = ref.constants()
    assert (const["eta_ccw"], const["eta_cw"]) == (ref.eta[1], ref.eta[-1])

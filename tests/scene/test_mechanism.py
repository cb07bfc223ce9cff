"""Kinematics of the rocking mechanisms (four-bar linkage of the frame, rotation of the block).

Every derivative the mechanism returns is checked against Richardson-extrapolated central finite
differences of the positions it returns; loop closure is checked by computing each pivot as a
material point of both bodies it joins (the joints must stay closed, the link lengths fixed).
Units: metres, radians.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockbench.scene.mechanism import FrameMechanism, geometric_limit, mechanism
from rockbench.scene.scene import load_scene
from rockbench.scene.structure import Block, Frame
from strategies import dist, frames, material_point

FAST = settings(max_examples=40, deadline=None)

PAPER_ASYM = load_scene("paper-asymmetric").structure
PAPER_SYM = load_scene("paper-symmetric").structure
HOUSNER = load_scene("housner-block").structure
STRUCTURES = {"block": HOUSNER, "symmetric": PAPER_SYM, "asymmetric": PAPER_ASYM}
FRACTIONS = (0.0, 0.05, 0.3, 0.6, 0.9)


# --- helpers ----------------------------------------------------------------------------------
def d1(f, x: float, h: float) -> float:
    """Richardson-extrapolated central difference of f at x (error O(h^4))."""
    c = lambda hh: (f(x + hh) - f(x - hh)) / (2.0 * hh)
    return (4.0 * c(0.5 * h) - c(h)) / 3.0


def d2(f, x: float, h: float) -> float:
    """Richardson-extrapolated second central difference of f at x."""
    c = lambda hh: (f(x + hh) - 2.0 * f(x) + f(x - hh)) / (hh * hh)
    return (4.0 * c(0.5 * h) - c(h)) / 3.0



blocks = st.builds(Block, width=st.floats(0.1, 3.0), height=st.floats(0.5, 12.0))


def check_derivatives(structure, direction: int, frac: float) -> None:
    mech = mechanism(structure, direction)
    lim = geometric_limit(mech)
    phi = direction * frac * lim
    h = 1e-3 * max(lim - abs(phi), 1e-3) if frac > 0 else 1e-3
    h = min(h, 1e-3)
    cfg = mech.configuration(phi)
    scale = max(structure.R if isinstance(structure, Block) else structure.R0, 1.0)
    for i, body in enumerate(cfg.bodies):
        for name, dname, ddname, sc in (("x", "dx", "ddx", scale), ("y", "dy", "ddy", scale),
                                        ("theta", "dtheta", "ddtheta", 1.0)):
            f = lambda p, i=i, name=name: getattr(mech.configuration(p).bodies[i], name)
            df = lambda p, i=i, dname=dname: getattr(
                mech.configuration(p).bodies[i], dname)
            fd1 = d1(f, phi, h)
            fd2 = d1(df, phi, h)
            fd2b = d2(f, phi, 10 * h)
            got1, got2 = getattr(body, dname), getattr(body, ddname)
            where = f"{mech.body_names[i]}.{name} s={direction:+d} phi={phi:.6g}"
            assert got1 == pytest.approx(fd1, rel=1e-6, abs=1e-7 * sc), where
            assert got2 == pytest.approx(fd2, rel=1e-6, abs=1e-6 * sc), where
            assert got2 == pytest.approx(fd2b, rel=1e-4, abs=1e-4 * sc), where


# --- derivatives against finite differences -----------------------------------------------
@pytest.mark.parametrize("kind", list(STRUCTURES))
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("frac", FRACTIONS)
def test_derivatives_paper_structures(kind, direction, frac):
    check_derivatives(STRUCTURES[kind], direction, frac)


@FAST
@given(frame=frames, direction=st.sampled_from([1, -1]), frac=st.floats(0.0, 0.9))
def test_derivatives_random_frames(frame, direction, frac):
    check_derivatives(frame, direction, frac)


@FAST
@given(block=blocks, direction=st.sampled_from([1, -1]), frac=st.floats(0.0, 0.9))
def test_derivatives_random_blocks(block, direction, frac):
    check_derivatives(block, direction, frac)


# --- loop closure ----------------------------------------------------------------------------
def check_closure(frame: Frame, direction: int, frac: float) -> None:
    mech = mechanism(frame, direction)
    lim = geometric_limit(mech)
    phi = direction * frac * lim
    piv = frame.pivots(direction)
    rest = mech.configuration(0.0).bodies
    left, beam, right = mech.configuration(phi).bodies
    A = material_point(left, rest[0], piv["A"])
    B_col = material_point(left, rest[0], piv["B"])
    B_beam = material_point(beam, rest[1], piv["B"])
    C_beam = material_point(beam, rest[1], piv["C"])
    C_col = material_point(right, rest[2], piv["C"])
    D = material_point(right, rest[2], piv["D"])
    tol = 1e-9 * frame.R0
    # pivots on the ground stay put, joints stay closed
    assert dist(A, piv["A"]) < tol and dist(D, piv["D"]) < tol
    assert dist(B_col, B_beam) < tol and dist(C_beam, C_col) < tol
    # link lengths
    assert dist(A, B_col) == pytest.approx(2.0 * frame.R0, rel=1e-12)
    assert dist(B_beam, C_beam) == pytest.approx(frame.L, rel=1e-12)
    assert dist(D, C_col) == pytest.approx(2.0 * frame.R1, rel=1e-12)
    # the left column turns by phi about A
    assert left.theta == pytest.approx(phi, abs=1e-15)


@pytest.mark.parametrize("frame", [PAPER_ASYM, PAPER_SYM], ids=["asymmetric", "symmetric"])
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("frac", FRACTIONS)
def test_loop_closure_paper_frames(frame, direction, frac):
    check_closure(frame, direction, frac)


@FAST
@given(frame=frames, direction=st.sampled_from([1, -1]), frac=st.floats(0.0, 0.9))
def test_loop_closure_random_frames(frame, direction, frac):
    check_closure(frame, direction, frac)


# --- rest configuration, symmetric frame, block ----------------------------------------------
@pytest.mark.parametrize("kind", list(STRUCTURES))
@pytest.mark.parametrize("direction", [1, -1])
def test_rest_configuration_is_the_structure_at_rest(kind, direction):
    st_ = STRUCTURES[kind]
    bodies = mechanism(st_, direction).configuration(0.0).bodies
    if isinstance(st_, Block):
        rest = [(0.0, st_.H)]
    else:
        rest = [st_.com_left, st_.com_beam, st_.com_right]
    for body, (x, y) in zip(bodies, rest, strict=True):
        assert (body.x, body.y, body.theta) == pytest.approx((x, y, 0.0), abs=1e-12)


@FAST
@given(frame=frames, direction=st.sampled_from([1, -1]), frac=st.floats(0.0, 0.9))
def test_symmetric_frame_is_a_parallelogram(frame, direction, frac):
    """H1 = H: the beam translates (no rotation) and the right column turns with the left one."""
    sym = Frame(**{**{k: v for k, v in frame.to_dict().items() if k != "type"},
                   "column_height_right": frame.column_height_left})
    assert sym.symmetric
    mech = mechanism(sym, direction)
    phi = direction * frac * geometric_limit(mech)
    _, beam, right = mech.configuration(phi).bodies
    assert beam.theta == pytest.approx(0.0, abs=1e-12)
    assert beam.dtheta == pytest.approx(0.0, abs=1e-12)
    assert beam.ddtheta == pytest.approx(0.0, abs=1e-10)
    assert right.theta == pytest.approx(phi, abs=1e-12)
    assert right.dtheta == pytest.approx(1.0, abs=1e-12)
    assert right.ddtheta == pytest.approx(0.0, abs=1e-10)
    # the beam moves like the top pivot B: on a circle of radius 2 R0 about A
    b0 = mech.configuration(0.0).bodies[1]
    assert math.hypot(beam.x - b0.x, beam.y - b0.y) == pytest.approx(
        2.0 * sym.R0 * 2.0 * abs(math.sin(0.5 * phi)), abs=1e-12 * sym.R0)


@pytest.mark.parametrize("direction", [1, -1])
def test_block_turns_about_its_corner(direction):
    blk = HOUSNER
    mech = mechanism(blk, direction)
    rest = mech.configuration(0.0).bodies[0]
    for phi in (0.1 * direction, 0.7 * direction, 1.4 * direction):
        body = mech.configuration(phi).bodies[0]
        pivot = (-direction * blk.b, 0.0)
        assert dist(material_point(body, rest, pivot), pivot) < 1e-12
        assert dist((body.x, body.y), pivot) == pytest.approx(blk.R, rel=1e-13)
        # the centre of mass height is R cos(alpha - |phi|) (Housner 1963)
        assert body.y == pytest.approx(blk.R * math.cos(blk.alpha - abs(phi)), rel=1e-13)


# --- geometric limit -------------------------------------------------------------------------
@pytest.mark.parametrize("direction", [1, -1])
def test_geometric_limit_is_the_toggle_of_the_asymmetric_frame(direction):
    mech = mechanism(PAPER_ASYM, direction)
    lim = geometric_limit(mech)
    assert 0.5 < lim < math.pi
    mech.configuration(direction * lim * (1.0 - 1e-9))
    with pytest.raises(ValueError, match="beyond the reach"):
        mech.configuration(direction * lim * (1.0 + 1e-6))
    # at the toggle B, C and D are collinear: |BD| = 2 R1 + L or |2 R1 - L|
    piv = PAPER_ASYM.pivots(direction)
    rest = mech.configuration(0.0).bodies
    left = mech.configuration(direction * lim).bodies[0]
    bd = dist(material_point(left, rest[0], piv["B"]), piv["D"])
    r1, L = 2.0 * PAPER_ASYM.R1, PAPER_ASYM.L
    assert min(abs(bd - (r1 + L)), abs(bd - abs(r1 - L))) < 1e-6 * L


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("width, height, span", [(1.0, 7.0, 8.0), (0.4, 3.0, 2.5),
                                                 (2.0, 4.0, 9.0)])
def test_a_parallelogram_folds_flat_at_half_pi_plus_alpha(direction, width, height, span):
    """Equal columns: the closed form pi/2 + alpha equals the searched tangency."""
    from rockbench.scene.mechanism import _searched_limit

    f = Frame(column_width=width, column_height_left=height, column_height_right=height,
              span=span, beam_width=span + width + 1.0, beam_height=1.0, mass_ratio=5.0)
    mech = mechanism(f, direction)
    lim = geometric_limit(mech)
    assert lim == pytest.approx(math.pi / 2 + f.alpha, abs=1e-12)
    assert lim == pytest.approx(_searched_limit(mech), abs=1e-6)   # a tangency: the search
    # finds it to the square root of its margin tolerance


def test_frame_mechanism_rejects_a_bad_direction():
    with pytest.raises(ValueError, match="direction"):
        FrameMechanism(PAPER_ASYM, 0)

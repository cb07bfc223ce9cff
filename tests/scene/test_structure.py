"""Structures (rockbench.scene.structure): derived geometry, masses and inertias of the paper's
frame and of Housner's block, and validation of every parameter (hypothesis). SI units."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockbench.constants import G
from rockbench.errors import ParameterError
from rockbench.scene.scene import load_scene
from rockbench.scene.structure import Block, Frame

FAST = settings(max_examples=60, deadline=None)
BAD_POSITIVE = st.one_of(st.just(0.0), st.just(-0.0), st.floats(max_value=0.0),
                         st.sampled_from([math.nan, math.inf, -math.inf]))
FRAME_FIELDS = [f.name for f in fields(Frame)]
BLOCK_FIELDS = [f.name for f in fields(Block)]
#: the paper's asymmetric frame, as its scene file states it (no field has the paper's value
#: as a default any more)
PAPER = {k: v for k, v in load_scene("paper-asymmetric").structure.to_dict().items()
         if k != "type"}


def paper(**changes) -> Frame:
    return Frame(**{**PAPER, **changes})


def block(**changes) -> Block:
    return Block(**{"width": 1.0, "height": 5.0, **changes})


def raises_named(name: str, valid: str | None = None):
    """Context manager: a ParameterError naming ``name`` (and ``valid`` in its message)."""

    class _Check:
        def __enter__(self):
            self._ctx = pytest.raises(ParameterError)
            self.info = self._ctx.__enter__()
            return self.info

        def __exit__(self, *exc):
            handled = self._ctx.__exit__(*exc)
            err = self.info.value
            assert err.name == name
            assert name in str(err)
            assert err.valid and err.valid in str(err)
            if valid is not None:
                assert valid in str(err)
            return handled

    return _Check()


# --- derived values of the paper's frame ---------------------------------------------------------
def test_paper_frame_derived_values():
    f = paper()
    assert (f.b, f.H, f.H1, f.h, f.L) == (0.5, 3.5, 2.8, 1.0, 8.0)
    assert f.mass_left == pytest.approx(17500.0, rel=1e-15)
    assert f.mass_right == pytest.approx(14000.0, rel=1e-15)
    assert f.mass_beam == pytest.approx(175000.0, rel=1e-15)
    assert f.gamma == pytest.approx(5.0, rel=1e-15)
    assert f.alpha == pytest.approx(math.atan(0.5 / 3.5), rel=1e-15)
    assert f.alpha1 == pytest.approx(math.atan(0.5 / 2.8), rel=1e-15)
    assert f.R0 == pytest.approx(math.sqrt(0.5**2 + 3.5**2), rel=1e-15)
    assert f.R1 == pytest.approx(math.sqrt(0.5**2 + 2.8**2), rel=1e-15)
    assert f.p == pytest.approx(math.sqrt(3 * G / (4 * f.R0)), rel=1e-15)
    assert f.p == pytest.approx(1.4425724, rel=1e-7)
    assert f.step == pytest.approx(1.4, rel=1e-15)
    assert not f.symmetric
    # inertias: rectangles about their centroid, the beam from its radius of gyration
    assert f.inertia_left == pytest.approx(17500.0 * (1.0 + 49.0) / 12.0, rel=1e-14)
    assert f.inertia_right == pytest.approx(14000.0 * (1.0 + 5.6**2) / 12.0, rel=1e-14)
    assert f.inertia_beam == pytest.approx(175000.0 * 3.58**2, rel=1e-14)
    # rest positions: origin at the centre of the left column's base, beam soffit level at 7 m
    assert f.com_left == pytest.approx((0.0, 3.5))
    assert f.com_right == pytest.approx((8.0, 1.4 + 2.8))
    assert f.com_beam == pytest.approx((4.0, 8.0))


def test_paper_frame_pivots_and_beam_offsets():
    f = paper()
    ccw, cw = f.pivots(1), f.pivots(-1)
    # counterclockwise: bottom-left corners on the ground, top-right corners at the beam
    expect_ccw = {"A": (-0.5, 0.0), "B": (0.5, 7.0), "C": (8.5, 7.0), "D": (7.5, 1.4)}
    expect_cw = {"A": (0.5, 0.0), "B": (-0.5, 7.0), "C": (7.5, 7.0), "D": (8.5, 1.4)}
    for got, expect in ((ccw, expect_ccw), (cw, expect_cw)):
        assert set(got) == set(expect)
        for k in expect:
            assert got[k] == pytest.approx(expect[k], abs=1e-14)
    # r_BC, psi_BC from the geometry (the paper prints 3.68 m and 4.64 m)
    r_p, psi_p = f.beam_offset(1)
    r_n, psi_n = f.beam_offset(-1)
    assert r_p == pytest.approx(math.hypot(3.5, 1.0), rel=1e-15)
    assert r_n == pytest.approx(math.hypot(4.5, 1.0), rel=1e-15)
    assert psi_p == pytest.approx(math.atan2(1.0, 3.5), rel=1e-15)
    assert psi_n == pytest.approx(math.atan2(1.0, 4.5), rel=1e-15)
    assert r_n > r_p and psi_n < psi_p          # as the paper states below Eq. 19
    assert r_p == pytest.approx(3.68, abs=0.05) and r_n == pytest.approx(4.64, abs=0.05)
    with raises_named("direction"):
        f.pivots(0)


def test_symmetric_frame_and_housner_block():
    f = paper(column_height_right=7.0)
    assert f.symmetric and f.step == 0.0 and f.R1 == f.R0 and f.mass_right == f.mass_left
    blk = block()
    assert (blk.width, blk.height) == (1.0, 5.0)
    assert blk.mass == pytest.approx(2500.0 * 5.0, rel=1e-15)
    assert blk.alpha == pytest.approx(math.atan(0.2), rel=1e-15)
    assert blk.R == pytest.approx(math.hypot(0.5, 2.5), rel=1e-15)
    assert blk.p == pytest.approx(math.sqrt(3 * G / (4 * blk.R)), rel=1e-15)
    assert blk.inertia_cm == pytest.approx(blk.mass * (1.0 + 25.0) / 12.0, rel=1e-14)
    assert blk.eta_housner == pytest.approx(1 - 1.5 * math.sin(blk.alpha) ** 2, rel=1e-15)
    assert blk.to_dict()["type"] == "block" and paper().to_dict()["type"] == "frame"


@FAST
@given(w=st.floats(0.1, 3.0), hl=st.floats(1.0, 20.0), ratio=st.floats(0.1, 1.0),
       mr=st.floats(0.01, 50.0), depth=st.floats(0.1, 3.0), rho=st.floats(500.0, 8000.0))
def test_masses_scale_with_geometry(w, hl, ratio, mr, depth, rho):
    f = paper(column_width=w, column_height_left=hl, column_height_right=ratio * hl,
              span=w + 5.0, beam_width=2 * w + 6.0, mass_ratio=mr, depth=depth, density=rho)
    assert f.mass_left == pytest.approx(rho * w * hl * depth, rel=1e-13)
    assert f.mass_right == pytest.approx(rho * w * ratio * hl * depth, rel=1e-13)
    assert f.mass_beam == pytest.approx(mr * f.mass_left, rel=1e-13)
    assert f.gamma == pytest.approx(mr / 2.0, rel=1e-13)
    assert math.tan(f.alpha) == pytest.approx(w / hl, rel=1e-12)
    assert f.alpha <= f.alpha1


# --- validation -----------------------------------------------------------------------------------
@FAST
@given(name=st.sampled_from(FRAME_FIELDS), bad=BAD_POSITIVE)
def test_frame_rejects_non_positive_or_non_finite(name, bad):
    valid = "> 0" if math.isfinite(bad) else "finite"
    with raises_named(name, valid):
        paper(**{name: bad})


@FAST
@given(name=st.sampled_from(BLOCK_FIELDS), bad=BAD_POSITIVE)
def test_block_rejects_non_positive_or_non_finite(name, bad):
    valid = "> 0" if math.isfinite(bad) else "finite"
    with raises_named(name, valid):
        block(**{name: bad})


@pytest.mark.parametrize("bad", ["tall", None, True, [1.0], "nan"])
def test_non_numbers_are_rejected(bad):
    with raises_named("column_width"):
        paper(column_width=bad)
    with raises_named("height"):
        block(height=bad)


@FAST
@given(hl=st.floats(1.0, 20.0), excess=st.floats(1e-9, 2.0))
def test_right_column_taller_than_left_is_rejected(hl, excess):
    with raises_named("column_height_right", "column_height_left"):
        paper(column_height_left=hl, column_height_right=hl * (1.0 + excess))


@FAST
@given(w=st.floats(0.1, 5.0), frac=st.floats(1e-6, 1.0))
def test_span_not_wider_than_the_columns_is_rejected(w, frac):
    with raises_named("span", "column_width"):
        paper(column_width=w, span=w * frac, beam_width=100.0)


@FAST
@given(w=st.floats(0.1, 3.0), gap=st.floats(0.1, 20.0), short=st.floats(1e-6, 0.99))
def test_beam_narrower_than_span_plus_column_width_is_rejected(w, gap, short):
    need = w + gap + w
    with raises_named("beam_width", "span + column_width"):
        paper(column_width=w, span=w + gap, beam_width=need * (1.0 - short))
    # exactly covering both column tops is allowed
    assert paper(column_width=w, span=w + gap, beam_width=need).beam_width == need


def test_structures_are_immutable():
    f = paper()
    with pytest.raises(AttributeError):
        f.span = 3.0  # type: ignore[misc]


# --- required fields, the beam's mass and radius of gyration ---------------------------------------
@pytest.mark.parametrize("name", ["column_width", "column_height_left", "column_height_right",
                                  "span", "beam_width", "beam_height"])
def test_frame_dimensions_are_required(name):
    """No dimension of the paper's frame is a silent default any more."""
    fields_ = {k: v for k, v in PAPER.items() if k != name}
    with raises_named(name, "given"):
        Frame(**fields_)
    with raises_named(name, "given"):
        paper(**{name: None})


@pytest.mark.parametrize("name", ["width", "height"])
def test_block_dimensions_are_required(name):
    with raises_named(name, "given"):
        Block(**{"width": 1.0, "height": 5.0, name: None})
    b = Block(width=1.0, height=5.0)
    assert (b.depth, b.density) == (1.0, 2500.0)      # physical defaults: 1 m, concrete


def test_beam_defaults_are_a_uniform_solid_beam():
    """Neither beam_mass nor mass_ratio: a solid beam of the columns' density; no
    beam_gyration_radius: a uniform rectangle's."""
    f = paper(mass_ratio=None, beam_gyration_radius=None)
    assert f.mass_beam == pytest.approx(2500.0 * 13.0 * 2.0 * 1.0, rel=1e-15)
    assert f.rho == pytest.approx(math.sqrt((13.0**2 + 2.0**2) / 12.0), rel=1e-15)
    assert f.rho == pytest.approx(3.80, abs=0.005)    # the paper states 3.58 m instead
    assert f.inertia_beam == pytest.approx(f.mass_beam * (13.0**2 + 2.0**2) / 12.0, rel=1e-14)
    assert "beam_mass" not in f.to_dict() and "beam_gyration_radius" not in f.to_dict()


@FAST
@given(m=st.floats(100.0, 1e7), rho=st.floats(0.1, 10.0))
def test_beam_mass_and_gyration_radius_set_directly(m, rho):
    f = paper(mass_ratio=None, beam_mass=m, beam_gyration_radius=rho)
    assert f.mass_beam == m and f.rho == rho
    assert f.inertia_beam == pytest.approx(m * rho**2, rel=1e-15)
    assert f.to_dict()["beam_mass"] == m and "mass_ratio" not in f.to_dict()
    # the ratio that gives the same beam gives the same frame's masses
    g = paper(mass_ratio=m / f.mass_left, beam_gyration_radius=rho)
    assert g.mass_beam == pytest.approx(m, rel=1e-15)


def test_beam_mass_and_mass_ratio_given_together_must_agree():
    f = paper(mass_ratio=10.0, beam_mass=175000.0)     # consistent: the mass is kept
    assert f.beam_mass == 175000.0 and f.mass_ratio is None
    assert f == paper(mass_ratio=None, beam_mass=175000.0)
    with raises_named("mass_ratio", "beam_mass / left column mass = 9.714"):
        paper(mass_ratio=10.0, beam_mass=170000.0)

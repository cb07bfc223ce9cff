"""Scenes (rockbench.scene.scene) and devices (rockbench.scene.devices): built-in TOML scenes,
overrides, and the errors bad scene input gives (each names the parameter and its valid range)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockbench.analytic.reference import Reference
from rockbench.errors import ParameterError, SceneError
from rockbench.scene.devices import Devices
from rockbench.scene.scene import Scene, apply_overrides, builtin_scenes, load_scene
from rockbench.scene.structure import Block, Frame

FAST = settings(max_examples=50, deadline=None)
REQUIRED = ("paper-asymmetric", "paper-symmetric", "paper-asymmetric-hybrid",
            "paper-asymmetric-hybrid-eps2", "paper-asymmetric-hybrid-eps1",
            "paper-symmetric-hybrid", "housner-block")
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])
#: the paper's frame and devices, written out (the classes have no paper defaults)
PAPER_FRAME = Frame(column_width=1.0, column_height_left=7.0, column_height_right=5.6, span=8.0,
                    beam_width=13.0, beam_height=2.0, beam_gyration_radius=3.58, mass_ratio=10.0)
PAPER_DEVICES = {"tendon_stiffness": 23.5e6, "tendon_length": 8.5, "damping": 25.3e6,
                 "fracture_strain": None}


def dev(**changes) -> Devices:
    return Devices(**{**PAPER_DEVICES, **changes})


def check_error(err: ParameterError, name: str, valid: str | None = None) -> None:
    assert err.name == name and name in str(err)
    assert err.valid in str(err)
    if valid is not None:
        assert valid in err.valid


def write(tmp_path, text: str, name: str = "scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


# --- built-in scenes -------------------------------------------------------------------------------
def test_builtin_scenes_are_listed_with_descriptions():
    scenes = builtin_scenes()
    for name in REQUIRED:
        assert name in scenes and scenes[name].strip()


@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_every_builtin_scene_loads(name):
    sc = load_scene(name)
    assert sc.name == name
    assert isinstance(sc.structure, (Block, Frame))
    const = Reference(sc).constants()
    for key in ("alpha", "p", "eta_ccw", "eta_cw", "lambda_ccw", "lambda_cw"):
        assert math.isfinite(const[key])
    assert const["lambda_ccw"] > 0 > const["lambda_cw"]
    assert 0 < const["eta_ccw"] < 1 and 0 < const["eta_cw"] < 1


def test_builtin_scene_contents():
    asym, sym = load_scene("paper-asymmetric"), load_scene("paper-symmetric")
    assert asym.structure == PAPER_FRAME and asym.devices is None and not asym.has_devices
    assert sym.structure == replace(PAPER_FRAME, column_height_right=7.0)
    assert sym.structure.symmetric
    assert load_scene("housner-block").structure == Block(width=1.0, height=5.0)
    paper_devices = {"tendon_stiffness": 23.5e6, "tendon_length": 8.5, "damping": 25.3e6}
    for name, eps in (("paper-asymmetric-hybrid", None), ("paper-asymmetric-hybrid-eps2", 0.02),
                      ("paper-asymmetric-hybrid-eps1", 0.01)):
        sc = load_scene(name)
        assert sc.structure == PAPER_FRAME
        assert sc.devices == Devices(**paper_devices, fracture_strain=eps)
        assert sc.has_devices
    sh = load_scene("paper-symmetric-hybrid")
    assert sh.structure.symmetric and sh.devices == Devices(**paper_devices,
                                                             fracture_strain=None)


def test_scene_from_a_file_and_round_trip(tmp_path):
    sc = load_scene("paper-asymmetric-hybrid-eps1")
    d = sc.to_dict()
    again = Scene.from_dict(d)
    assert again == sc
    p = write(tmp_path, """
name = "my-frame"
description = "a test frame"
fall_angle = 0.5
preset = "paper"
[structure]
type = "frame"
column_height_right = 6.0
[devices]
tendon_stiffness = 1e6
""")
    mine = load_scene(p)
    assert mine.name == "my-frame" and mine.fall_angle == 0.5
    assert mine.structure == replace(PAPER_FRAME, column_height_right=6.0)
    assert mine.devices == dev(tendon_stiffness=1e6)
    assert mine.fall_angles == {1: 0.5, -1: 0.5}
    assert load_scene(str(p)) == mine


# --- overrides -----------------------------------------------------------------------------------
@pytest.mark.parametrize("key", ["span", "structure.span"])
def test_span_override(key):
    sc = load_scene("paper-asymmetric", {key: "9"})
    assert sc.structure.span == 9.0
    assert sc.structure == replace(PAPER_FRAME, span=9.0)
    assert load_scene("paper-asymmetric", {key: 9}).structure.span == 9.0


def test_fracture_strain_overrides():
    assert load_scene("paper-asymmetric-hybrid-eps1",
                      {"devices.fracture_strain": "none"}).devices.fracture_strain is None
    assert load_scene("paper-asymmetric-hybrid-eps1",
                      {"fracture_strain": "0.02"}).devices.fracture_strain == 0.02
    assert load_scene("paper-asymmetric-hybrid", {"devices": "none"}).devices is None


def test_other_overrides():
    sc = load_scene("paper-asymmetric", {"fall_angle": "1.2", "mass_ratio": "5",
                                         "structure.column_height_right": "7"})
    assert sc.fall_angle == 1.2 and sc.structure.mass_ratio == 5.0
    assert sc.structure.symmetric
    # overrides do not change the data they are applied to
    data = {"structure": {"span": 8.0}}
    out = apply_overrides(data, {"span": "10"})
    assert data == {"structure": {"span": 8.0}} and out["structure"]["span"] == 10.0


def test_bad_overrides():
    with pytest.raises(SceneError, match="unknown scene parameter 'spam'.*span"):
        load_scene("paper-asymmetric", {"spam": "1"})
    with pytest.raises(SceneError, match="cannot parse value 'wide'"):
        load_scene("paper-asymmetric", {"span": "wide"})
    with pytest.raises(SceneError, match="unknown scene table 'beam'"):
        load_scene("paper-asymmetric", {"beam.width": "10"})
    with pytest.raises(ParameterError) as e:
        load_scene("paper-asymmetric", {"span": "-1"})
    check_error(e.value, "span", "[0.001, 1000] m")     # the range, before any arithmetic
    with pytest.raises(ParameterError) as e:
        load_scene("paper-asymmetric", {"span": "12.5"})   # the 13 m beam no longer covers both
    check_error(e.value, "beam_width", "span + column_width")


# --- scene errors ----------------------------------------------------------------------------------
def test_unknown_scene_name_lists_the_builtins():
    with pytest.raises(SceneError) as e:
        load_scene("paper-asymetric")
    msg = str(e.value)
    assert "paper-asymetric" in msg
    for name in REQUIRED:
        assert name in msg


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(SceneError, match="does not exist"):
        load_scene(tmp_path / "nothing.toml")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(write(tmp_path, "[structure\nspan = 3"))


@pytest.mark.parametrize("text, where, key", [
    ('colour = "red"\n[structure]\n', "top-level", "colour"),
    ('[structure]\ntype = "frame"\nspan_m = 8.0\n', "[structure]", "span_m"),
    ('[structure]\ntype = "block"\nspan = 8.0\n', "[structure]", "span"),
    ('[structure]\n[devices]\nstiffness = 1e6\n', "[devices]", "stiffness"),
])
def test_unknown_toml_keys(tmp_path, text, where, key):
    with pytest.raises(SceneError) as e:
        load_scene(write(tmp_path, text))
    msg = str(e.value)
    assert where in msg and repr(key) in msg
    assert "known" in msg or "allowed" in msg


def test_unknown_structure_type(tmp_path):
    with pytest.raises(ParameterError) as e:
        load_scene(write(tmp_path, '[structure]\ntype = "arch"\n'))
    check_error(e.value, "structure.type", "block")


def test_devices_on_a_block_are_rejected(tmp_path):
    with pytest.raises(ParameterError) as e:
        Scene(Block(width=1.0, height=5.0), dev())
    check_error(e.value, "devices", "absent for a block")
    with pytest.raises(ParameterError) as e:
        load_scene(write(tmp_path, '[structure]\ntype = "block"\nwidth = 1.0\nheight = 5.0\n'
                                   '[devices]\ntendon_stiffness = 0.0\ntendon_length = 1.0\n'
                                   'fracture_strain = "none"\ndamping = 1e6\n'))
    check_error(e.value, "devices")
    with pytest.raises(ParameterError) as e:   # said first, not "missing tendon_length"
        load_scene(write(tmp_path, '[structure]\ntype = "block"\nwidth = 1.0\n'
                                   '[devices]\ntendon_stiffness = 1e6\n', "p.toml"))
    check_error(e.value, "devices", "absent for a block")
    with pytest.raises(ParameterError) as e:
        Scene(PAPER_FRAME, devices={"damping": 1.0})  # type: ignore[arg-type]
    check_error(e.value, "devices", "Devices")
    with pytest.raises(ParameterError) as e:
        Scene("frame")  # type: ignore[arg-type]
    check_error(e.value, "structure", "Block or a Frame")


@FAST
@given(bad=st.one_of(st.floats(max_value=0.0), st.floats(min_value=math.pi, exclude_min=True,
                                                         allow_infinity=False), NON_FINITE))
def test_bad_fall_angle(bad):
    with pytest.raises(ParameterError) as e:
        Scene(PAPER_FRAME, fall_angle=bad)
    check_error(e.value, "fall_angle")


# --- devices -----------------------------------------------------------------------------------------
@FAST
@given(bad=st.one_of(st.floats(max_value=0.0), NON_FINITE))
def test_bad_fracture_strain(bad):
    with pytest.raises(ParameterError) as e:
        dev(fracture_strain=bad)
    # a strain <= 0 is told the whole range, not only "> 0" (issue 23's acceptance)
    check_error(e.value, "fracture_strain", None if not math.isfinite(bad) or bad > 0
                else "[0.0001, 1)")


@FAST
@given(bad=st.floats(min_value=5e-324, max_value=0.99999e-4))
def test_fracture_strain_below_a_hundredth_of_a_percent_is_rejected(bad):
    """Found by the geometry fuzz: eps_f = 6.7e-135 was accepted and the analytic model's
    fracture angle then failed (brentq: the round-off strain at rest already exceeds it)."""
    with pytest.raises(ParameterError) as e:
        dev(fracture_strain=bad)
    check_error(e.value, "fracture_strain", "[0.0001, 1)")


def test_the_smallest_fracture_strain_gives_a_fracture_angle():
    from rockbench.analytic.reference import Reference

    ref = Reference(Scene(PAPER_FRAME, dev(fracture_strain=1e-4)))
    for s in (1, -1):
        assert 0.0 < ref.fracture_angle[s] < 1e-3


@FAST
@given(bad=st.floats(min_value=1.0, allow_infinity=False))
def test_fracture_strain_of_one_or_more_is_rejected(bad):
    with pytest.raises(ParameterError) as e:
        dev(fracture_strain=bad)
    check_error(e.value, "fracture_strain", "[0.0001, 1)")


@FAST
@given(name=st.sampled_from(["tendon_stiffness", "damping"]),
       bad=st.one_of(st.floats(max_value=-1e-300), NON_FINITE))
def test_negative_or_non_finite_device_constants(name, bad):
    with pytest.raises(ParameterError) as e:
        dev(**{name: bad})
    check_error(e.value, name, ">= 0" if math.isfinite(bad) else None)


@FAST
@given(bad=st.one_of(st.floats(max_value=0.0), NON_FINITE))
def test_bad_tendon_length(bad):
    with pytest.raises(ParameterError) as e:
        dev(tendon_length=bad)
    check_error(e.value, "tendon_length")


@pytest.mark.parametrize("name", list(PAPER_DEVICES))
def test_every_device_parameter_is_required(name):
    """No device parameter silently takes the paper's value (fracture_strain too: None, no
    fracture, is said, not assumed)."""
    with pytest.raises(ParameterError) as e:
        Devices(**{k: v for k, v in PAPER_DEVICES.items() if k != name})
    check_error(e.value, name, "given")


def test_device_flags():
    d = dev()
    assert d.has_tendons and d.has_dampers
    none = dev(tendon_stiffness=0.0, damping=0.0)
    assert not none.has_tendons and not none.has_dampers
    assert not Scene(PAPER_FRAME, none).has_devices


def test_bad_values_in_a_scene_file_name_the_parameter(tmp_path):
    p = write(tmp_path, 'preset = "paper"\n[structure]\ntype = "frame"\n'
                        'column_height_right = 8.0\n')
    with pytest.raises(ParameterError) as e:
        load_scene(p)
    check_error(e.value, "column_height_right", "column_height_left")
    p = write(tmp_path, 'preset = "paper"\n[structure]\ntype = "frame"\n[devices]\n'
                        'fracture_strain = 0.0\n', "b.toml")
    with pytest.raises(ParameterError) as e:
        load_scene(p)
    check_error(e.value, "fracture_strain", "[0.0001, 1) or None")


def test_frame_whose_mechanism_breaks_before_alpha_is_refused():
    """A squat frame with a very short right column: rocking counterclockwise, the beam would
    rotate faster than the left column (it would bear on that column's other top corner), so
    the paper's three-block mechanism does not describe it; the scene says so up front."""
    from rockbench.scene.structure import Frame

    squat = Frame(column_width=2.0, column_height_left=2.9, column_height_right=1.28, span=2.5,
                  beam_width=4.5, beam_height=1.0, beam_gyration_radius=1.0, mass_ratio=1.0)
    with pytest.raises(ParameterError, match="structure.*mechanism holds up to"):
        Scene(structure=squat)
    Scene(structure=PAPER_FRAME)  # the paper's frame is fine

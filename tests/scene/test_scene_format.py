"""The scene format as an explicit, documented input (issue 23 section 1) and its limits
(issue 22 section 3): docs/scenes.md is the schema's output, no field silently takes the
paper's value, the paper's scenes build the same structures as before, Scene <-> TOML round
trips, a Scene is accepted wherever a scene name is, and every scene the validator accepts is
inside the model (finite alpha, p, lambda; eta >= 0), everything else is refused naming the field.
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
import tomllib
from dataclasses import fields, replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import rockbench as rb
from rockbench.analytic.dynamics import Dynamics
from rockbench.analytic.reference import Reference
from rockbench.cli.main import main
from rockbench.errors import ParameterError, RockbenchError, SceneError
from rockbench.scene.devices import Devices
from rockbench.scene.schema import FIELDS, fields_of, markdown, required
from rockbench.scene.scene import (Scene, apply_overrides, builtin_scenes, load_scene,
                                   restitution, save_scene)
from rockbench.scene.structure import Block, Frame

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "scenes"
EXAMPLES = ROOT / "docs" / "examples"
FAST = settings(max_examples=40, deadline=None,
                suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow])
PAPER = {k: v for k, v in load_scene("paper-asymmetric").to_dict()["structure"].items()}
PAPER_DEVICES = load_scene("paper-asymmetric-hybrid").to_dict()["devices"]


def refused(capsys, *argv, names=()) -> str:
    """The CLI exits 2 with one line ``rockbench: error: ...`` naming ``names``."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (code, out, err)
    assert len(lines) == 1 and lines[0].startswith("rockbench: error: "), err
    for n in names:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def toml_file(tmp_path, text: str, name: str = "scene.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def table(d: dict) -> str:
    return "".join(f"{k} = {json.dumps(v) if isinstance(v, str) else repr(v)}\n"
                   for k, v in d.items() if v is not None)


# --- the paper's scenes build what they built before ------------------------------------------
def _snapshot_module():
    spec = importlib.util.spec_from_file_location("make_builtin_before",
                                                  DATA / "make_builtin_before.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _close(a, b, path):
    if isinstance(a, dict):
        assert set(a) == set(b), (path, sorted(set(a) ^ set(b)))
        for k in a:
            _close(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float):
        assert b == pytest.approx(a, rel=1e-12, abs=1e-300), path
    else:
        assert a == b, (path, a, b)


def test_builtin_scenes_build_the_structures_they_built_before():
    """alpha, p, masses, inertias, pivots, device constants, eta, lambda, fall angles and the
    equation-of-motion terms of every built-in scene, to 1e-12, against the numbers the code
    computed before the scene format changed (commit c34a4e7); to_dict too (the maps' stores
    are keyed by it)."""
    before = json.loads((DATA / "builtin_before.json").read_text())
    assert before["commit"].startswith("c34a4e7")
    now = _snapshot_module().snapshot()
    assert set(now) == set(before["scenes"]) == set(builtin_scenes())
    for name in now:
        _close(before["scenes"][name], now[name], name)


def test_paper_scene_files_are_explicit_and_complete():
    """Every paper scene file states every field of its structure and devices: it loads the
    same with nothing to fill in (no field left to a default)."""
    for name in builtin_scenes():
        data = tomllib.loads((ROOT / "rockbench" / "scenarios" / f"{name}.toml").read_text())
        st_ = data["structure"]
        kind = st_["type"]
        stated = set(st_) - {"type"}
        assert set(required(kind)) <= stated, name
        if kind == "frame":
            assert {"beam_gyration_radius", "mass_ratio", "depth", "density"} <= stated, name
        else:
            assert {"depth", "density"} <= stated, name
        if "devices" in data:
            assert set(data["devices"]) == {f.name for f in fields_of("devices")}, name


# --- the documentation is the schema's output ------------------------------------------------------
def test_docs_scenes_md_is_generated_from_the_schema():
    """docs/scenes.md cannot go stale: it is markdown() (regenerate with the command it names)."""
    assert (ROOT / "docs" / "scenes.md").read_text() == markdown()


def test_the_schema_lists_every_field_of_the_classes():
    for table_, cls in (("block", Block), ("frame", Frame), ("devices", Devices)):
        assert sorted(f.name for f in fields_of(table_)) == sorted(f.name for f in fields(cls))
    top = {f.name for f in fields_of("scene")}
    assert top == {"kind", "name", "version", "description", "preset", "fall_angle"}
    for f in FIELDS:
        assert f.meaning and (f.unit or f.table == "scene")
        assert f.range_text()


def test_the_docs_example_loads_and_is_the_bridge_bent_example(tmp_path):
    text = (ROOT / "docs" / "scenes.md").read_text()
    snippet = re.search(r"```toml\n(.*?)```", text, re.S).group(1)
    mine = load_scene(toml_file(tmp_path, snippet))
    bent = load_scene(EXAMPLES / "bridge-bent.toml")
    assert mine.structure == bent.structure and mine.devices == bent.devices


# --- examples written from docs/scenes.md alone -------------------------------------------------
@pytest.mark.parametrize("name", ["bridge-bent", "museum-pedestal"])
def test_examples_load_and_run(name):
    sc = rb.load_scene(EXAMPLES / f"{name}.toml")
    assert sc.name == name
    ref = Reference(sc)
    assert 0.0 < ref.eta[1] <= 1.0 and 0.0 < ref.eta[-1] <= 1.0
    pulse = rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=sc.structure)
    r = rb.run(sc, pulse, duration=4.0)
    s = r.summary
    assert s.status == "ok" and math.isfinite(s.max_abs_phi_over_alpha)
    assert 0.0 < s.max_abs_phi_over_alpha < 1.0 and not s.overturned   # it rocks and survives
    if name == "bridge-bent":
        st_ = sc.structure
        assert sc.has_devices and st_.symmetric and st_.mass_beam == 300000.0
        assert st_.rho == pytest.approx(math.sqrt((10.0**2 + 1.5**2) / 12.0), rel=1e-15)
        assert st_.mass_left == pytest.approx(2500.0 * 1.2 * 6.0 * 1.2, rel=1e-15)
    else:
        assert sc.structure.mass == pytest.approx(2700.0 * 0.5 * 1.2 * 0.5, rel=1e-15)


# --- no silent values from the paper -------------------------------------------------------------
@pytest.mark.parametrize("missing", [f.name for f in fields_of("devices")])
def test_a_devices_table_that_leaves_out_a_parameter_is_refused(tmp_path, capsys, missing):
    """Before: [devices] with only tendon_stiffness and tendon_length got the paper's 25.3 MN s/m
    damper. Now: one line naming what is missing (SceneError; CLI exit 2)."""
    dev = {k: ("none" if v is None else v) for k, v in PAPER_DEVICES.items() if k != missing}
    p = toml_file(tmp_path, '[structure]\n' + table(PAPER) + "[devices]\n" + table(dev))
    with pytest.raises(SceneError, match=f"missing {missing}") as e:
        load_scene(p)
    assert "\n" not in str(e.value)
    refused(capsys, "info", p, names=(missing, "devices"))


@pytest.mark.parametrize("missing", ["beam_width", "beam_height", "span", "column_width",
                                     "column_height_left", "column_height_right"])
def test_a_frame_that_leaves_out_a_dimension_is_refused(tmp_path, capsys, missing):
    """Before: a frame without beam_* got the paper's 13 x 2 m beam."""
    st_ = {k: v for k, v in PAPER.items() if k != missing}
    p = toml_file(tmp_path, "[structure]\n" + table(st_))
    with pytest.raises(SceneError, match=f"missing {missing}"):
        load_scene(p)
    refused(capsys, "info", p, names=(missing,))


def test_a_block_needs_its_width_and_height(tmp_path):
    with pytest.raises(SceneError, match="missing height"):
        load_scene(toml_file(tmp_path, '[structure]\ntype = "block"\nwidth = 1.0\n'))
    sc = load_scene(toml_file(tmp_path, '[structure]\ntype = "block"\nwidth = 1.0\n'
                                        'height = 4.0\n', "b.toml"))
    assert (sc.structure.depth, sc.structure.density) == (1.0, 2500.0)   # physical defaults


def test_the_paper_preset_fills_what_is_left_out_on_purpose(tmp_path):
    paper = load_scene("paper-asymmetric")
    hybrid = load_scene("paper-asymmetric-hybrid")
    sc = load_scene(toml_file(tmp_path, 'preset = "paper"\n[structure]\ntype = "frame"\n'))
    assert sc.structure == paper.structure and sc.devices is None
    sc = load_scene(toml_file(tmp_path, 'preset = "paper"\n[structure]\ntype = "frame"\n'
                                        'span = 9.0\n[devices]\ndamping = 0.0\n', "b.toml"))
    assert sc.structure == replace(paper.structure, span=9.0)
    assert sc.devices == replace(hybrid.devices, damping=0.0)
    # a beam given by its mass keeps it: the preset's mass_ratio is not added
    sc = load_scene(toml_file(tmp_path, 'preset = "paper"\n[structure]\ntype = "frame"\n'
                                        'beam_mass = 50000.0\n', "c.toml"))
    assert sc.structure.mass_beam == 50000.0 and sc.structure.mass_ratio is None
    with pytest.raises(SceneError, match="block takes no preset"):
        load_scene(toml_file(tmp_path, 'preset = "paper"\n[structure]\ntype = "block"\n'
                                       'width = 1.0\nheight = 4.0\n', "d.toml"))
    with pytest.raises(SceneError, match="presets are 'paper'"):
        load_scene(toml_file(tmp_path, 'preset = "mander"\n[structure]\ntype = "frame"\n',
                             "e.toml"))


def test_fracture_strain_none_is_said_not_assumed(tmp_path):
    dev = {**{k: v for k, v in PAPER_DEVICES.items() if v is not None}}
    base = "[structure]\n" + table(PAPER) + "[devices]\n" + table(dev)
    sc = load_scene(toml_file(tmp_path, base + 'fracture_strain = "none"\n'))
    assert sc.devices.fracture_strain is None
    sc = load_scene(toml_file(tmp_path, base + 'fracture_strain = "None"\n', "b.toml"))
    assert sc.devices.fracture_strain is None
    with pytest.raises(SceneError, match="fracture_strain = 'never'"):
        load_scene(toml_file(tmp_path, base + 'fracture_strain = "never"\n', "c.toml"))


def test_beam_mass_and_mass_ratio_overrides_replace_each_other():
    sc = load_scene("paper-asymmetric", {"beam_mass": "50000"})
    assert sc.structure.mass_beam == 50000.0 and sc.structure.mass_ratio is None
    back = load_scene(sc, {"mass_ratio": 10})
    assert back.structure == load_scene("paper-asymmetric").structure
    with pytest.raises(ParameterError, match="mass_ratio"):
        Scene.from_dict(apply_overrides(sc.to_dict(), None) | {
            "structure": {**sc.to_dict()["structure"], "mass_ratio": 3.0}})


# --- a Scene wherever a scene name is; writing scenes back ---------------------------------------
def test_load_scene_accepts_a_scene():
    sc = load_scene("paper-asymmetric-hybrid-eps1")
    assert load_scene(sc) is sc and rb.load_scene(sc) is sc
    wider = load_scene(sc, {"span": 9.0, "devices.fracture_strain": "none"})
    assert wider.structure.span == 9.0 and wider.devices.fracture_strain is None
    assert wider.name == sc.name and sc.structure.span == 8.0
    with pytest.raises(ParameterError, match="rockbench.Scene"):
        load_scene(3.0)


def test_save_scene_round_trip_of_every_builtin_scene(tmp_path):
    for name in builtin_scenes():
        sc = load_scene(name)
        p = rb.save_scene(sc, tmp_path / f"{name}.toml")
        assert load_scene(p) == sc
        assert tomllib.loads(p.read_text())["name"] == name


def test_save_scene_refuses_what_it_cannot_write(tmp_path):
    sc = load_scene("housner-block")
    with pytest.raises(ParameterError, match=r"\.toml"):
        save_scene(sc, tmp_path / "scene.txt")
    with pytest.raises(ParameterError, match="Scene"):
        save_scene({"name": "x"}, tmp_path / "x.toml")
    with pytest.raises(SceneError, match="cannot write scene file"):
        save_scene(sc, tmp_path / "no" / "such" / "folder" / "x.toml")
    assert not list(tmp_path.glob(".*tmp*"))


NAMES = st.text(st.characters(blacklist_categories=("Cs",)), max_size=30)


@st.composite
def scenes(draw):
    """Valid scenes of every kind: blocks, frames (beam by ratio, mass or neither; gyration
    radius given or not), with or without devices, any name, description and fall angle."""
    name, description = draw(NAMES), draw(NAMES)
    fall = draw(st.one_of(st.none(), st.floats(0.01, math.pi)))
    if draw(st.booleans()):
        h = draw(st.floats(0.05, 50.0))
        structure = Block(width=h * draw(st.floats(0.05, 1.4)), height=h,
                          depth=draw(st.floats(0.01, 10.0)), density=draw(st.floats(1.0, 25000.0)))
        devices = None
    else:
        w = draw(st.floats(0.1, 2.0))
        hl = w * draw(st.floats(3.0, 20.0))
        span = w + draw(st.floats(0.5, 10.0))
        beam = draw(st.sampled_from(["ratio", "mass", "neither"]))
        kw = {"mass_ratio": draw(st.floats(0.1, 30.0))} if beam == "ratio" else {}
        if beam == "mass":
            kw["beam_mass"] = draw(st.floats(0.5, 20.0)) * 2500.0 * w * hl
        if draw(st.booleans()):
            kw["beam_gyration_radius"] = draw(st.floats(0.1, 10.0))
        structure = Frame(column_width=w, column_height_left=hl,
                          column_height_right=hl * draw(st.floats(0.7, 1.0)), span=span,
                          beam_width=span + w + draw(st.floats(0.0, 3.0)),
                          beam_height=draw(st.floats(0.2, 3.0)), **kw)
        devices = draw(st.one_of(st.none(), st.builds(
            Devices, tendon_stiffness=st.floats(0.0, 1e9), tendon_length=st.floats(0.5, 50.0),
            fracture_strain=st.one_of(st.none(), st.floats(1e-4, 0.5)),
            damping=st.floats(0.0, 1e9))))
    try:
        return Scene(structure, devices, name=name, description=description, fall_angle=fall)
    except RockbenchError:
        assume(False)


@FAST
@given(sc=scenes())
def test_save_and_load_give_the_same_scene(tmp_path_factory, sc):
    """load(save(scene)) == scene, for any valid scene (names with any character included)."""
    p = tmp_path_factory.mktemp("rt") / "scene.toml"
    assert load_scene(save_scene(sc, p)) == sc
    assert Scene.from_dict(tomllib.loads(sc.to_toml())) == sc


# --- issue 22 section 3: the limits of the model -----------------------------------------------------
def test_a_block_too_wide_to_rock_is_refused(capsys):
    """Before: accepted, and info printed eta = -0.49. eta = 1 - 1.5 sin^2 alpha >= 0 holds up
    to width / height = sqrt(2) (alpha = 54.7 deg)."""
    line = refused(capsys, "info", "housner-block", "--set", "width=10", "--set", "height=5",
                   names=("width", "sqrt(2)", "eta"))
    assert "7.07107" in line
    edge = load_scene("housner-block", {"width": 5.0 * math.sqrt(2.0) * (1 - 1e-9)})
    assert restitution(edge.structure, -1, 1) == pytest.approx(0.0, abs=1e-8)
    assert restitution(edge.structure, -1, 1) >= 0.0
    with pytest.raises(ParameterError) as e:
        load_scene("housner-block", {"width": 5.0 * math.sqrt(2.0) * (1 + 1e-9)})
    assert e.value.name == "width"
    assert math.degrees(math.atan(math.sqrt(2.0) / 1.0 * 1.0)) == pytest.approx(54.7356, abs=1e-4)


def test_a_frame_too_wide_to_rock_is_refused_at_its_own_limit(capsys):
    """The frame's limit depends on its beam: computed from its own eta. Just inside it eta
    is ~0 and accepted; just outside refused."""
    over = {"column_width": 7.5, "span": 8.0, "beam_width": 16.0}
    line = refused(capsys, "info", "paper-asymmetric", *sum((["--set", f"{k}={v}"]
                                                              for k, v in over.items()), []),
                   names=("column_width", "eta"))
    limit = float(re.search(r"<= ([0-9.]+) m", line).group(1))
    assert 5.0 < limit < 7.5
    frame = load_scene("paper-asymmetric", over | {"column_width": limit * (1 - 1e-5)})
    etas = [restitution(frame.structure, -s, s) for s in (1, -1)]
    assert min(etas) >= 0.0 and min(etas) < 1e-3
    with pytest.raises(ParameterError, match="column_width"):
        load_scene("paper-asymmetric", over | {"column_width": limit * (1 + 1e-5)})
    # the limit depends on the beam (not a fixed angle): a lighter beam allows wider columns
    limits = {}
    for ratio in (100.0, 10.0, 0.5):
        with pytest.raises(ParameterError) as e:
            load_scene("paper-asymmetric", over | {"mass_ratio": ratio})
        limits[ratio] = float(re.search(r"<= ([0-9.]+) m", str(e.value)).group(1))
    assert limits[10.0] == limit
    assert limits[100.0] < limits[10.0] < limits[0.5] < 7.5
    assert load_scene("paper-asymmetric", over | {"mass_ratio": 0.01}).structure.alpha > 0.8


@pytest.mark.parametrize("value", ["1e-200", "1e200", "0.0001", "2000"])
def test_lengths_outside_1_mm_to_1_km_are_refused_before_arithmetic(capsys, value):
    """Before: 1e-200 -> ZeroDivisionError, 1e200 -> OverflowError."""
    refused(capsys, "info", "housner-block", "--set", f"width={value}", "--set",
            f"height={value}", names=("width", "[0.001, 1000] m", "ROCKBENCH_LENGTH"))


@pytest.mark.parametrize("value", ["1e-16", "0.5", "30000"])
def test_a_density_outside_the_physical_range_is_refused(capsys, value):
    """Before: 1e-16 kg/m^3 left OpenSees and PyBullet frozen, status ok."""
    refused(capsys, "info", "paper-asymmetric", "--set", f"density={value}",
            names=("density", "[1, 25000] kg/m^3"))


@pytest.mark.parametrize("key, value, limit", [
    ("tendon_stiffness", "2e12", "stiffness"), ("damping", "2e12", "damping"),
    ("tendon_length", "1e-5", "length"), ("mass_ratio", "1e5", "mass_ratio"),
    ("beam_mass", "1e12", "mass_ratio")])
def test_device_and_beam_constants_outside_their_ranges_are_refused(capsys, key, value, limit):
    refused(capsys, "info", "paper-asymmetric-hybrid", "--set", f"{key}={value}",
            names=(key, f"ROCKBENCH_{limit.upper()}"))


def test_a_range_can_be_widened_by_its_environment_variable(monkeypatch):
    with pytest.raises(ParameterError):
        load_scene("housner-block", {"width": 2000.0, "height": 3000.0})
    monkeypatch.setenv("ROCKBENCH_LENGTH", "1e-3,1e4")
    assert load_scene("housner-block", {"width": 2000.0, "height": 3000.0}).structure.width == 2000


# --- fuzz: scene geometry extremes ---------------------------------------------------------------------
EXTREME = st.one_of(
    st.floats(1e-3, 1e3),                                     # inside the length range
    st.floats(1e-3, 1e3).map(lambda x: x * 1e-3),             # around the lower bound
    st.sampled_from([0.0, -1.0, 1e-300, 1e-200, 1e-4, 0.999e-3, 1e-3, 1e3, 1.001e3, 1e200,
                     1e300, math.inf, -math.inf, math.nan, 5e-324]),
    st.floats(allow_nan=False, allow_infinity=False, min_value=-1e308, max_value=1e308))
BLOCK_KEYS = ("width", "height", "depth", "density")
FRAME_KEYS = ("column_width", "column_height_left", "column_height_right", "span", "beam_width",
              "beam_height", "beam_gyration_radius", "mass_ratio", "beam_mass", "depth",
              "density")


@st.composite
def scene_data(draw):
    """A scene as data, its fields drawn from the paper's values, plausible ones and extremes."""
    if draw(st.booleans()):
        base = {"type": "block", "width": 1.0, "height": 5.0}
        keys = BLOCK_KEYS
        plausible = {"width": st.floats(0.05, 20.0), "height": st.floats(0.05, 20.0),
                     "depth": st.floats(0.05, 5.0), "density": st.floats(1.0, 25000.0)}
    else:
        base = dict(PAPER)
        keys = FRAME_KEYS
        plausible = {k: st.floats(0.1, 30.0) for k in keys}
        plausible["density"] = st.floats(1.0, 25000.0)
        plausible["beam_mass"] = st.floats(1e2, 1e7)
        plausible["mass_ratio"] = st.floats(1e-3, 1e3)
    for k in draw(st.lists(st.sampled_from(keys), max_size=4, unique=True)):
        base[k] = draw(st.one_of(plausible[k], EXTREME))
    if base["type"] == "frame" and "beam_mass" in base and draw(st.booleans()):
        base.pop("mass_ratio", None)
    data = {"structure": base}
    if base["type"] == "frame" and draw(st.booleans()):
        data["devices"] = {"tendon_stiffness": draw(st.one_of(st.floats(0, 1e9), EXTREME)),
                           "tendon_length": draw(st.one_of(st.floats(0.5, 20), EXTREME)),
                           "fracture_strain": draw(st.one_of(st.none(), st.floats(0, 1.5))),
                           "damping": draw(st.one_of(st.floats(0, 1e9), EXTREME))}
    return data


@settings(max_examples=150, deadline=None)
@given(data=scene_data())
def test_fuzz_scene_geometry_extremes(data):
    """Every scene the validator accepts is inside the model: finite alpha, p and lambda, eta
    >= 0 (and no impact gains kinetic energy: eta^2 I_after <= I_before); everything else
    raises a SceneError or ParameterError naming a field, never another exception."""
    try:
        sc = Scene.from_dict(data)
    except (ParameterError, SceneError) as e:
        named = set(data["structure"]) | set(data.get("devices") or {}) | {"structure"}
        assert any(n in str(e) for n in named), str(e)
        assert "\n" not in str(e)
        return
    st_ = sc.structure
    assert math.isfinite(st_.alpha) and 0.0 < st_.alpha < math.pi / 2
    assert math.isfinite(sc.p) and sc.p > 0.0
    ref = Reference(sc)
    for s in (1, -1):
        eta = restitution(st_, -s, s)
        assert math.isfinite(eta) and eta >= 0.0 and ref.eta[s] == eta
        i_after = Dynamics(st_, s).terms(0.0).inertia
        i_before = Dynamics(st_, -s).terms(0.0).inertia
        assert eta * eta * i_after <= i_before * (1.0 + 1e-12)
        assert math.isfinite(ref.lam[s]) and s * ref.lam[s] > 0.0
    if isinstance(st_, Block) or st_.symmetric:
        assert max(ref.eta.values()) <= 1.0 + 1e-15


@pytest.mark.parametrize("length", [1e-200, 1e200])
def test_lengths_out_of_range_are_named_even_with_both_beam_masses(length):
    """Frame checks beam_mass against mass_ratio x m_AB; with lengths out of range m_AB is 0 or
    inf and no arithmetic on it may happen first: the error names the length."""
    data = {"structure": {**PAPER, "column_width": length, "column_height_left": length,
                          "column_height_right": length, "beam_mass": 5.0, "mass_ratio": 2.0}}
    with pytest.raises(ParameterError) as e:
        Scene.from_dict(data)
    assert e.value.name == "column_width"


@pytest.mark.parametrize("preset", [["paper"], {"a": 1}, 3, True, "Paper"])
def test_a_preset_that_is_not_a_preset_name_is_refused(preset):
    with pytest.raises(SceneError, match="presets are 'paper'"):
        Scene.from_dict({"preset": preset, "structure": {"type": "frame"}})

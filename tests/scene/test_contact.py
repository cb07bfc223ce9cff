"""The scene's ``[contact]`` table: friction and beam_friction read, validated, written back and
overridden like every scene field."""

from __future__ import annotations

import math
import tomllib

import pytest

import rockbench as rb
from rockbench.errors import ParameterError, SceneError
from rockbench.scene.contact import Contact
from rockbench.scene.scene import Scene, load_scene, save_scene
from rockbench.scene.schema import fields_of, markdown

BLOCK = """
name = "squat"
[structure]
type = "block"
width = 1.0
height = 1.2
"""


def _scene(text: str) -> Scene:
    return Scene.from_dict(tomllib.loads(text), source="test")


def test_no_contact_table_gives_no_friction():
    s = _scene(BLOCK)
    assert s.contact == Contact() and s.friction is None and not s.contact.given
    assert "[contact]" not in s.to_toml() and "contact" not in s.to_dict()


def test_contact_round_trips_through_toml(tmp_path):
    frame = load_scene("paper-asymmetric")
    for scene in (_scene(BLOCK + "[contact]\nfriction = 0.35\n"),
                  frame.replace(contact=Contact(friction=0.4, beam_friction=0.7)),
                  frame.replace(contact=Contact(friction=2.5))):
        back = load_scene(save_scene(scene, tmp_path / "s.toml"))
        assert back == scene
        assert back.friction == scene.contact.friction
        assert back.contact.beam == (scene.contact.beam_friction or scene.contact.friction)


@pytest.mark.parametrize("table, name", [
    ("friction = 0.0", "contact.friction"), ("friction = -0.2", "contact.friction"),
    ("friction = 10.5", "contact.friction"), ("friction = nan", "contact.friction"),
    ("friction = inf", "contact.friction"),
    ("friction = 0.3\nbeam_friction = 0.0", "contact.beam_friction"),
    ("friction = 0.3\nbeam_friction = 11", "contact.beam_friction")])
def test_bad_friction_is_refused_naming_the_field_and_range(table, name):
    with pytest.raises(ParameterError) as e:
        _scene(_frame_text() + "[contact]\n" + table + "\n")
    assert e.value.name == name and "(0, 10]" in str(e.value)


def _frame_text() -> str:
    return load_scene("paper-asymmetric").to_toml()


def test_the_range_ends_are_accepted():
    assert _scene(BLOCK + "[contact]\nfriction = 10\n").friction == 10.0
    assert _scene(BLOCK + "[contact]\nfriction = 1e-6\n").friction == 1e-6


def test_beam_friction_is_for_frames_and_needs_friction():
    with pytest.raises(ParameterError, match="contact.beam_friction.*absent for a block"):
        _scene(BLOCK + "[contact]\nfriction = 0.3\nbeam_friction = 0.5\n")
    with pytest.raises(ParameterError, match="contact.beam_friction.*together with"):
        Contact(beam_friction=0.5)


def test_unknown_keys_and_non_numbers_are_refused():
    with pytest.raises(SceneError, match=r"\[contact\].*unknown parameter.*static_friction"):
        _scene(BLOCK + "[contact]\nstatic_friction = 0.3\n")
    with pytest.raises(SceneError, match="friction = 'high' is a str"):
        _scene(BLOCK + "[contact]\nfriction = \"high\"\n")
    with pytest.raises(SceneError, match=r"\[contact\] must be a table"):
        _scene("contact = 0.3\n" + BLOCK)
    with pytest.raises(ParameterError, match="contact.friction"):
        Contact(friction=True)


def test_overrides_set_and_remove_the_friction():
    s = load_scene("paper-asymmetric", {"contact.friction": "0.3"})
    assert s.friction == 0.3 and s.contact.beam == 0.3
    s = load_scene(s, {"beam_friction": 0.6, "friction": 0.5})
    assert s.contact == Contact(friction=0.5, beam_friction=0.6)
    assert load_scene(s, {"contact": "none"}).contact == Contact()
    assert load_scene(s, {"contact.beam_friction": "none"}).contact == Contact(friction=0.5)
    with pytest.raises(ParameterError, match="contact.friction"):
        load_scene("housner-block", {"contact.friction": "0"})


def test_validity_reads_the_scene_friction():
    from rockbench.validity import DEFAULT_FRICTION, friction_of

    assert friction_of(load_scene("housner-block")) == DEFAULT_FRICTION
    assert friction_of(load_scene("housner-block", {"friction": 0.25})) == 0.25


def test_the_schema_documents_the_table():
    names = [f.name for f in fields_of("contact")]
    assert names == ["friction", "beam_friction"]
    page = markdown()
    assert "## `[contact]`" in page and "No friction given" in page
    for f in fields_of("contact"):
        assert f.unit == "-" and "(0, 10]" in f.range_text() and f.meaning


def test_a_scene_with_friction_is_not_equal_to_one_without():
    base = load_scene("housner-block")
    assert base.replace(contact=Contact(friction=0.5)) != base
    assert math.isclose(base.replace(contact=Contact(friction=0.5)).friction, 0.5)
    assert rb.Scene(rb.Block(width=1.0, height=2.0), contact=Contact(0.4)).friction == 0.4

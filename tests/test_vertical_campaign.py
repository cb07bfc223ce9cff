"""Vertical ground motion through `advise` and `report`: the evidence with a vertical part
(every pulse and record of it, thresholds and labels computed with it, both signs of a mirror-
symmetric structure), the campaign's parts building every motion with it, the plan key and the
command-line option checked with the one limit."""

import math

import pytest

import rockbench as rb
from rockbench.campaign import parts as P
from rockbench.scene.motion import motion_from_spec
from rockbench.studies.validation import overturn_threshold, validation_set


@pytest.fixture(scope="module")
def block_sets():
    block = rb.load_scene("housner-block")
    return block, validation_set(block, size="quick"), validation_set(block, size="quick",
                                                                      vertical=0.4)


def test_the_evidence_carries_the_vertical_part_in_every_motion(block_sets):
    block, flat, vert = block_sets
    assert all("vertical_ratio" not in (c.motion_spec() or {}) for c in flat)
    moving = [c for c in vert if c.motion is not None]
    assert moving and all(c.motion_spec()["vertical_ratio"] == 0.4 for c in moving)
    for c in moving:                      # the spec reads back as a motion with a vertical part
        m = motion_from_spec(c.motion_spec(), block.structure)
        assert m.vertical is not None
        t = m.t_start + 0.5 * (m.t_end - m.t_start)
        a_h = m.acceleration(t)
        assert math.isclose(m.vertical.acceleration(t), 0.4 * a_h, rel_tol=1e-9,
                            abs_tol=1e-12)


def test_a_mirror_symmetric_block_keeps_both_signs_with_a_vertical_part(block_sets):
    """A pulse's vertical part turns with its sign: the reversed pulse is no mirror image."""
    _, flat, vert = block_sets
    signs = lambda cs: {dict(c.motion)["sign"] for c in cs  # noqa: E731
                        if c.motion is not None and dict(c.motion)["kind"] == "ricker"}
    assert signs(flat) == {1}
    assert signs(vert) == {1, -1}


def test_thresholds_are_computed_with_the_vertical_part():
    """In phase, an upward ground acceleration while the pulse pushes adds to gravity: the
    pulse needs more amplitude to overturn the block (and the labels follow the threshold)."""
    block = rb.load_scene("housner-block")
    flat = overturn_threshold(block, 4.0, "symmetric", 1)
    up = overturn_threshold(block, 4.0, "symmetric", 1, vertical=0.5)
    assert math.isfinite(flat) and math.isfinite(up) and up != pytest.approx(flat, rel=0.01)


def test_a_bad_vertical_ratio_is_refused_by_name():
    with pytest.raises(rb.ParameterError, match="vertical"):
        validation_set("housner-block", size="quick", vertical=4.0)


def test_the_campaign_parts_build_every_motion_with_the_plans_vertical(monkeypatch):
    from rockbench.campaign.plan import campaign_plan

    seen = []
    monkeypatch.setattr(P, "_comparisons", lambda jobs, **kw: seen.extend(jobs) or [])
    plan = dict(campaign_plan(), vertical=0.3)
    ctx = {"plan": plan, "names": ["analytic"], "cache": None, "quick": False,
           "run": {"executor": "serial", "workers": 1, "progress": False,
                   "dask_address": None}}
    P._part_comparisons(ctx)
    moving = [j for j in seen if j["motion"] is not None]
    assert moving and all(j["motion"]["vertical_ratio"] == 0.3 for j in moving)
    # the symmetric frame's reversed pulses run: with a vertical part they are no mirror
    sym = {j["motion"]["sign"] for j in moving if j["scene"] == "paper-symmetric"}
    assert sym == {1, -1}
    seen.clear()
    P._part_comparisons(dict(ctx, plan=campaign_plan()))
    assert all("vertical_ratio" not in j["motion"] for j in seen if j["motion"] is not None)
    assert {j["motion"]["sign"] for j in seen
            if j["motion"] is not None and j["scene"] == "paper-symmetric"} == {1}


def test_a_record_keeps_its_own_vertical_channel_else_takes_the_plans_ratio():
    rec = {"path": "h.AT2", "vertical": "v.AT2", "vertical_dt": None}
    assert P._record_vertical(rec, {"vertical": 0.5}) == {"vertical_path": "v.AT2"}
    assert P._record_vertical({"path": "h.AT2"}, {"vertical": 0.5}) == {"vertical_ratio": 0.5}
    assert P._record_vertical({"path": "h.AT2"}, {"vertical": 0.0}) == {}


def test_the_plan_key_is_checked_with_the_one_limit(tmp_path):
    from rockbench.campaign.plan import load_plan

    good = tmp_path / "good.toml"
    good.write_text('kind = "campaign-plan"\nversion = 1\n[campaign]\n'
                    'scenes = ["housner-block"]\nvertical = 0.5\n', encoding="utf-8")
    assert load_plan(good, folder=tmp_path)["vertical"] == 0.5
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace("0.5", "3.5"), encoding="utf-8")
    with pytest.raises(Exception, match="vertical"):
        load_plan(bad, folder=tmp_path)


@pytest.mark.parametrize("command", [["advise", "housner-block"], ["report", "housner-block"]])
def test_the_commands_refuse_a_vertical_ratio_beyond_the_limit(command, capsys, tmp_path):
    from rockbench.cli.main import main

    assert main(command + ["--vertical", "5", "-q"]
                + (["--out", str(tmp_path)] if command[0] == "report" else [])) == 2
    assert "--vertical" in capsys.readouterr().err

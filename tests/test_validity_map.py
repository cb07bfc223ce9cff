"""The validity map (rockbench.studies.validity_map): the agreement rule exactly, the regions of
clear cells, the store's resume, bad inputs, the report's sentences and the command line."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

import rockbench as rb
from rockbench.errors import ParameterError
from rockbench.studies import validity_map as vm
from rockbench.studies.validity_map import (REGIONS, VALIDITY_COLUMNS, classify_cell,
                                            relative_spread, validity_map)

HAVE = set(rb.available_backends())
ENGINES = [e for e in ("pymunk", "mujoco") if e in HAVE]
needs_engine = pytest.mark.skipif(not ENGINES, reason="neither pymunk nor mujoco is installed")


def _run(engine, *, status="ok", overturned=False, phi=0.1, sliding=0.05, cpu=1.0):
    return {"engine": engine, "status": status, "overturned": overturned, "max_abs_phi": phi,
            "max_sliding": sliding, "cpu_s": cpu}


# ------------------------------------------------------------------------------------------
# The rule, on synthetic rows
# ------------------------------------------------------------------------------------------
def test_relative_spread_is_range_over_median_with_a_floor():
    assert relative_spread([1.0, 1.1, 0.9], 1e-3) == pytest.approx(0.2)
    assert relative_spread([2.0, None, float("nan"), 3.0], 1e-3) == pytest.approx(1.0 / 2.5)
    # near zero the floor decides: 0.2 mm apart, floor 1 mm -> 0.2
    assert relative_spread([0.0, 2e-4], 1e-3) == pytest.approx(0.2)
    assert math.isnan(relative_spread([None, float("nan")], 1e-3))


def test_engines_within_tolerance_agree_and_the_cheapest_is_named():
    runs = [_run("a", phi=0.100, sliding=0.050, cpu=2.0),
            _run("b", phi=0.105, sliding=0.052, cpu=0.5),
            _run("c", phi=0.098, sliding=0.049, cpu=1.0)]
    c = classify_cell(runs, tolerance=0.10)
    assert c["region"] == "agree" and c["cheapest"] == "b"
    assert c["spread_phi"] == pytest.approx((0.105 - 0.098) / 0.100)
    assert c["spread_sliding"] == pytest.approx((0.052 - 0.049) / 0.050)


def test_a_spread_just_beyond_the_tolerance_disagrees():
    runs = [_run("a", phi=1.0), _run("b", phi=1.11)]        # spread 0.11 / 1.055 = 0.104
    assert classify_cell(runs, tolerance=0.10)["region"] == "disagree"
    assert classify_cell(runs, tolerance=0.11)["region"] == "agree"
    slide = [_run("a", sliding=0.05), _run("b", sliding=0.07)]
    c = classify_cell(slide, tolerance=0.10)
    assert c["region"] == "disagree" and c["cheapest"] == ""


def test_different_verdicts_disagree_whatever_the_spreads():
    runs = [_run("a", overturned=True, phi=1.5), _run("b", overturned=False, phi=1.5)]
    assert classify_cell(runs, tolerance=10.0)["region"] == "disagree"


def test_when_every_engine_overturns_the_verdict_alone_decides():
    """A toppled structure's sliding is the fall's (the paper's frame at mu = 1 under A = 5,
    W = 1: pymunk 6 cm, MuJoCo 5 mm, both overturned at the same stop angle): the verdict is
    the agreement, the spreads are still reported; a survivor's sliding still counts."""
    fell = [_run("a", overturned=True, phi=1.0, sliding=0.061, cpu=2.0),
            _run("b", overturned=True, phi=1.3, sliding=0.005, cpu=1.0)]
    c = classify_cell(fell, tolerance=0.10)
    assert c["region"] == "agree" and c["cheapest"] == "b"
    assert c["spread_sliding"] > 1.0 and c["spread_phi"] > 0.1
    stood = [dict(r, overturned=False) for r in fell]
    assert classify_cell(stood, tolerance=0.10)["region"] == "disagree"
    one_fell = [fell[0], dict(fell[1], overturned=False)]
    assert classify_cell(one_fell, tolerance=10.0)["region"] == "disagree"


def test_a_run_that_did_not_finish_ok_makes_the_cell_diverged():
    for bad in ("diverged", "invalid", "error"):
        runs = [_run("a"), _run("b", status=bad)]
        assert classify_cell(runs)["region"] == "diverged"
    assert classify_cell([])["region"] == "diverged"
    assert classify_cell([_run("a", phi=float("nan"))])["region"] == "diverged"


def test_an_engine_without_sliding_does_not_count_against_agreement():
    runs = [_run("a", sliding=None), _run("b", sliding=None)]
    c = classify_cell(runs)
    assert c["region"] == "agree" and math.isnan(c["spread_sliding"])


def test_one_engine_agrees_with_itself():
    c = classify_cell([_run("a", cpu=3.0)])
    assert c["region"] == "agree" and c["cheapest"] == "a" and c["spread_phi"] == 0.0


# ------------------------------------------------------------------------------------------
# Cells of a real scene
# ------------------------------------------------------------------------------------------
def _slender():
    # tan alpha = 0.2: A = 0.5 is a PGA of 0.1 g, far below mu g = 0.3 g; A = 8 is 1.6 g
    return rb.load_scene("housner-block", {"contact.friction": 0.3})


def test_cells_below_and_far_above_the_friction():
    df = validity_map(_slender(), A=[0.5, 8.0], W=[2.0, 6.0], engines=ENGINES or ["pymunk"],
                      workers=1, tail=0.5)
    assert list(df.columns) == list(VALIDITY_COLUMNS) and len(df) == 4
    assert set(df["region"]) <= set(REGIONS)
    low, high = df[df["A"] == 0.5], df[df["A"] == 8.0]
    assert (low["region"] == "model").all() and (low["reason"] == "inside").all()
    assert (low["engines_run"] == "").all() and low["spread_phi"].isna().all()
    assert (high["region"] != "model").all()
    assert high["reason"].str.startswith("outside").all()
    assert high["sliding_onset_s"].notna().all()
    if ENGINES:
        assert (high["engines_run"] == ",".join(ENGINES)).all()


@needs_engine
def test_a_squat_block_on_low_friction_slides_and_the_region_follows_the_rule(tmp_path):
    # tan alpha = 0.5, mu = 0.2: a pulse of A = 3 (1.5 g) makes the base slide
    sc = rb.load_scene("housner-block", {"height": 2.0, "contact.friction": 0.2})
    df = validity_map(sc, A=[3.0], W=[3.0], engines=ENGINES, workers=1, tail=1.0,
                      store=tmp_path)
    row = df.iloc[0]
    assert row["region"] in ("agree", "disagree")
    stored = rb.sweep.load_store(rb.sweep.store.store_path(tmp_path, "validity"))
    runs = json.loads(stored["runs"].iloc[0])
    assert [r["engine"] for r in runs] == ENGINES
    assert all(r["status"] == "ok" and r["max_sliding"] > 0.01 for r in runs)  # > 1 cm
    assert classify_cell(runs)["region"] == row["region"]
    if row["region"] == "agree":
        assert row["cheapest"] in ENGINES


def test_the_store_resumes_and_a_second_call_runs_nothing(tmp_path, monkeypatch):
    calls = []
    real = vm._run_cell

    def counted(item):
        calls.append((item["A"], item["W"]))
        return real(item)

    monkeypatch.setattr(vm, "_run_cell", counted)
    kw = dict(A=[0.5, 0.8, 1.0], W=[2.0, 5.0, 8.0], engines=ENGINES or ["pymunk"],
              workers=1, tail=0.5, store=tmp_path)
    first = validity_map(_slender(), **kw)
    assert len(calls) == 9
    second = validity_map(_slender(), **kw)
    assert len(calls) == 9                       # nothing new ran
    pd.testing.assert_frame_equal(first, second)
    validity_map(_slender(), **dict(kw, A=[0.5, 0.8, 1.0, 1.2]))
    assert len(calls) == 12                      # only the new row of cells


@pytest.mark.parametrize("kw, name", [
    (dict(vertical_ratio=-0.1), "vertical_ratio"),
    (dict(vertical_ratio=3.5), "vertical_ratio"),
    (dict(A=[]), "A"),
    (dict(W=[]), "W"),
    (dict(A=[-1.0]), "A"),
    (dict(engines=["nope"]), "engines"),
    (dict(engines=["analytic"]), "engines"),
    (dict(shape="square"), "shape"),
    (dict(sign=0), "sign"),
    (dict(tolerance=0.0), "tolerance"),
    (dict(engines=ENGINES or ["pymunk"], settings={"drake": {"dt": 1e-3}}), "settings"),
])
def test_bad_inputs_name_the_parameter(kw, name):
    if "settings" in kw and not ENGINES:
        pytest.skip("no engine installed to take settings")
    with pytest.raises(ParameterError) as e:
        validity_map(_slender(), **dict(dict(A=[0.5], W=[2.0], workers=1), **kw))
    assert e.value.name == name


@needs_engine
def test_a_setting_the_engine_does_not_have_is_refused_before_any_run():
    with pytest.raises(ParameterError) as e:
        validity_map(_slender(), A=[8.0], W=[2.0], engines=ENGINES[:1], workers=1,
                     settings={ENGINES[0]: {"no_such_field": 1}})
    assert e.value.name == "settings" and "no_such_field" in str(e.value)


# ------------------------------------------------------------------------------------------
# The report's sentences and the command line
# ------------------------------------------------------------------------------------------
def _frame(regions):
    return pd.DataFrame([{"A": float(i), "W": 1.0, "region": r, "reason": "",
                          "cheapest": "pymunk" if r == "agree" else ""}
                         for i, r in enumerate(regions)])


def test_the_sentences_count_the_cells_of_each_region():
    from rockbench.report.validity_figures import validity_sentences

    words = validity_sentences(_frame(["model"] * 5 + ["agree"] * 2 + ["disagree"]),
                               friction=0.4, tolerance=0.1, engines=["pymunk", "mujoco"])
    assert words[0].startswith("In 5 of 8 cells the analytic model holds")
    assert "mu = 0.4" in words[0]
    assert "in 2, disagree in 1" in words[1] and "failed in 0" in words[1]
    # a planted diverged row changes the sentence
    words = validity_sentences(_frame(["model"] * 5 + ["agree"] * 2 + ["diverged"]),
                               friction=0.4, tolerance=0.1, engines=["pymunk", "mujoco"])
    assert "disagree in 0" in words[1] and "failed in 1" in words[1]
    words = validity_sentences(_frame(["model"] * 3), friction=0.4, tolerance=0.1,
                               engines=["pymunk"])
    assert "In 3 of 3 cells" in words[0] and "no engine had to run" in words[1]


def test_the_figure_has_the_maps_axes_and_a_legend_below():
    from rockbench.report.validity_figures import plot_validity_map

    fig = plot_validity_map(pd.DataFrame({"A": [1.0, 2.0, 1.0, 2.0], "W": [1.0, 1.0, 2.0, 2.0],
                                          "region": ["model", "agree", "disagree",
                                                     "diverged"]}))
    ax = fig.axes[0]
    assert "a_g / (g tan α)" in ax.get_ylabel() and "ω_g / p" in ax.get_xlabel()
    assert len(fig.legends) == 1 and len(fig.legends[0].get_texts()) == 4
    fig = plot_validity_map(pd.DataFrame({"A": [1.0, 2.0], "W": [1.0, 1.0],
                                          "region": ["model", "agree"]}), a_mu=1.5)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert texts[0] == "PGA = mu g (structure at rest)" and len(texts) == 3


@pytest.mark.parametrize("argv, option", [
    (["--vertical", "-1"], "--vertical"),
    (["--grid", "101"], "--grid"),
    (["--engine", "nope"], "--engine"),
    (["--engine", "analytic"], "--engine"),
    (["--tolerance", "0"], "--tolerance"),
])
def test_the_command_names_a_bad_option(argv, option, capsys):
    from rockbench.cli.main import main

    assert main(["validity-map", "housner-block", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rockbench: error:") and option in err


@needs_engine
def test_the_command_prints_the_counts_and_writes_its_files(tmp_path, capsys):
    from rockbench.cli.main import main

    out = tmp_path / "vm"
    rc = main(["validity-map", "housner-block", "--set", "contact.friction=0.3", "--grid", "2",
               "--tail", "0.5", "--engine", ENGINES[0], "--workers", "1", "--out", str(out),
               "-q"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "of 4 cells the analytic model holds" in text and "cells per region:" in text
    df = pd.read_csv(out / "validity_map.csv")
    assert list(df.columns) == list(VALIDITY_COLUMNS) and len(df) == 4
    assert (out / "validity_map.png").stat().st_size > 0
    assert "with the scene's friction mu = 0.3" in text
    rc = main(["validity-map", "housner-block", "--grid", "1", "--tail", "0.5", "--engine",
               ENGINES[0], "--workers", "1", "-q"])          # no friction of its own
    text = capsys.readouterr().out
    assert rc == 0 and "with mu = 1, the validity rule's default" in text
    assert "the scene's friction" not in text


# ------------------------------------------------------------------------------------------
# The report of a user's scene
# ------------------------------------------------------------------------------------------
SCENE_WITH_FRICTION = """name = "friction-block"
version = 1
description = "a block on a floor of friction 0.3"

[structure]
type = "block"
width = 1.0
height = 5.0
depth = 1.0
density = 2500.0

[contact]
friction = 0.3
"""


def test_every_plan_maps_where_the_model_holds_on_its_decisions_scene(tmp_path):
    from rockbench.campaign.plan import campaign_plan, plan_for_scenes

    f = tmp_path / "friction-block.toml"
    f.write_text(SCENE_WITH_FRICTION, encoding="utf-8")
    spec = plan_for_scenes([str(f)], quick=True, folder=tmp_path)["validity_map"]
    assert spec["grid"] == 5 and spec["scene"] == str(f)
    # a scene without its own friction is mapped with the validity rule's default
    spec = plan_for_scenes(["housner-block"], folder=tmp_path)["validity_map"]
    assert spec["grid"] == 8 and spec["scene"] == "housner-block"
    paper = campaign_plan()
    assert paper["validity_map"]["scene"] == paper["choice_scene"] == "paper-asymmetric"
    assert campaign_plan(quick=True)["validity_map"]["grid"] == 5


def test_a_scene_without_friction_is_mapped_with_the_rules_default_for_every_engine():
    """The rule assumes mu = 1 where a scene gives none; the engines' own defaults differ
    (pymunk 2.0, MuJoCo 1.0), so the map gives every engine that one friction, and a scene's
    own friction is kept."""
    from rockbench.studies.validity_map import with_rule_friction

    bare = rb.load_scene("housner-block")
    assert bare.friction is None and with_rule_friction(bare).friction == 1.0
    given = rb.load_scene("housner-block", overrides={"contact.friction": 0.3})
    assert with_rule_friction(given) is given


def test_the_map_gives_its_cells_the_rules_friction(monkeypatch):
    """What every cell's worker builds (the scene of each item) carries the rule's friction."""
    seen = []

    def fake_execute(fn, items, **kw):
        seen.extend(it for _, it in items)

    monkeypatch.setattr("rockbench.sweep.executors.execute", fake_execute)
    with pytest.raises(KeyError):           # no cell ran: the frame has nothing to read
        validity_map("housner-block", A=[8.0], W=[2.0], engines=["pymunk"], workers=1)
    assert len(seen) == 1 and rb.Scene.from_dict(seen[0]["scene"]).friction == 1.0


def test_the_section_runs_the_fast_engines_and_names_the_others(tmp_path, monkeypatch):
    """Outside the model the default report runs the fast engines (every engine with --full)
    and says which it left out; a scene without friction is said to use the default."""
    from rockbench.campaign import parts as P
    from rockbench.report.validity_figures import validity_sentences

    seen = {}

    def fake(scene, *, engines, **kw):
        seen["engines"], seen["friction"] = list(engines), scene.friction
        return pd.DataFrame({"region": ["model", "agree"], "cheapest": [None, engines[0]]})

    monkeypatch.setattr("rockbench.studies.validity_map.validity_map", fake)
    monkeypatch.setattr("rockbench.campaign.maps.is_fast", lambda e: e in ("pymunk", "mujoco"))
    spec = {"scene": "housner-block", "grid": 2, "tail": 0.5}
    names = ["analytic", "pymunk", "mujoco", "drake", "opensees"]
    sec = P._validity_section(spec, names, tmp_path, 1, False)
    assert seen["engines"] == ["pymunk", "mujoco"] and sec["left_out"] == ["drake", "opensees"]
    assert sec["friction_given"] is False
    words = " ".join(validity_sentences(sec["frame"], friction=sec["friction"], tolerance=0.1,
                                        engines=sec["engines"], friction_given=False,
                                        left_out=sec["left_out"]))
    assert ("holds with mu = 1, the validity rule's default, given to every engine for this "
            "map (the scene gives none)") in words
    assert "Not run outside the model here: drake, opensees" in words
    P._validity_section(spec, names, tmp_path, 1, False, every_engine=True)
    assert seen["engines"] == names[1:]
    P._validity_section(spec, ["analytic", "drake"], tmp_path, 1, False)
    assert seen["engines"] == ["drake"]                 # no fast engine: the ones chosen


@needs_engine
def test_the_report_section_counts_the_cells_with_the_scenes_friction(tmp_path):
    from rockbench.campaign.parts import _validity_section
    from rockbench.report.validity_figures import validity_html

    assert _validity_section(None, ["analytic", *ENGINES], tmp_path, 1, False) == {}
    f = tmp_path / "friction-block.toml"
    f.write_text(SCENE_WITH_FRICTION, encoding="utf-8")
    spec = {"scene": str(f), "grid": 2, "tail": 0.5}
    assert "error" in _validity_section(spec, ["analytic"], tmp_path, 1, False)
    sec = _validity_section(spec, ["analytic", ENGINES[0]], tmp_path, 1, False)
    assert sec["friction"] == 0.3 and sec["engines"] == [ENGINES[0]]
    df = sec["frame"]
    assert len(df) == 4 and list(df.columns) == list(VALIDITY_COLUMNS)
    html = validity_html(sec, tmp_path / "figures")
    n = int((df["region"] == "model").sum())
    assert f"In {n} of 4 cells the analytic model holds" in html and "mu = 0.3" in html
    assert 'id="fig-validity_map"' in html and (tmp_path / "figures" / "validity_map.png").exists()
    assert "failed" in validity_html({"error": "boom"})

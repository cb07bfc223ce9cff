"""The whole campaign for a user's structure: plans derived from the scenes (nothing from the
paper's frames), plan files, and ``rockbench report SCENE`` / ``--plan``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import rockbench as rb
from rockbench.campaign.plan import load_plan, plan_for_scenes
from rockbench.errors import ParameterError
from rockbench.runner import run

ROOT = Path(__file__).resolve().parents[1]
BENT = ROOT / "docs" / "examples" / "bridge-bent.toml"
PEDESTAL = ROOT / "docs" / "examples" / "museum-pedestal.toml"


def _paper_names(plan) -> list[str]:
    text = repr(plan)
    return [n for n in rb.builtin_scenes() if n in text]


@pytest.fixture(scope="module")
def plan():
    return plan_for_scenes([str(PEDESTAL)], folder=".")


def test_a_plan_for_a_users_scene_names_only_that_scene(plan):
    assert _paper_names(plan) == []
    assert plan["scenes"] == (str(PEDESTAL.resolve()),)
    assert plan["choice_scene"] == plan["stress_scene"] == plan["scenes"][0]
    assert plan["maps"]["analytic_scenes"] == plan["scenes"]
    assert "museum" in plan["description"] or "pedestal" in plan["description"]


def test_its_pulse_cases_rock_the_structure_and_it_survives(plan):
    """The pulse points are chosen at half the analytic overturning threshold: the analytic
    structure uplifts and survives every one of them."""
    sc = rb.load_scene(PEDESTAL)
    for A, W in plan["pulse_points"]:
        for shape, sign in plan["pulse_shapes"]:
            p = rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)
            r = run(sc, p, duration=round(6 * p.period + 3.0, 3))
            assert r.summary.uplifted and not r.summary.overturned, (A, W, shape, sign)


def test_a_scene_object_is_saved_for_the_workers(tmp_path):
    scene = rb.Scene(rb.Block(width=0.8, height=3.2), name="my-plinth")
    p = plan_for_scenes([scene], quick=True, folder=tmp_path)
    assert Path(p["scenes"][0]) == (tmp_path / "my-plinth.toml").resolve()
    assert rb.load_scene(p["scenes"][0]).structure == scene.structure


def test_a_plan_file_needs_scenes_and_derives_the_rest(tmp_path):
    f = tmp_path / "plan.toml"
    f.write_text(f'kind = "campaign-plan"\nscenes = ["{PEDESTAL}"]\npulse_tail = 4.0\n')
    p = load_plan(f)
    assert p["pulse_tail"] == 4.0 and _paper_names(p) == []
    f.write_text('kind = "campaign-plan"\npulse_tail = 4.0\n')
    with pytest.raises(ParameterError, match="scenes"):
        load_plan(f)
    f.write_text('kind = "scene"\nscenes = ["housner-block"]\n')
    with pytest.raises(ParameterError, match="campaign-plan"):
        load_plan(f)


def test_the_paper_plan_is_one_file_shipped_with_the_package():
    from importlib import resources

    from rockbench.campaign.plan import campaign_plan

    assert resources.files("rockbench").joinpath("scenarios/paper-plan.toml").is_file()
    p = campaign_plan()
    assert p["choice_scene"] == "paper-asymmetric" and p["maps"]["analytic_grid"] == (100, 100)


def _cli(*args, timeout=900):
    return subprocess.run([sys.executable, "-m", "rockbench", *args], capture_output=True,
                          text=True, timeout=timeout)


def test_report_refuses_a_missing_plan_and_both_forms(tmp_path):
    r = _cli("report", "--plan", str(tmp_path / "nope.toml"), "--out", str(tmp_path))
    assert r.returncode == 2 and "--plan" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    f = tmp_path / "plan.toml"
    f.write_text('kind = "campaign-plan"\nscenes = ["housner-block"]\n')
    r = _cli("report", "housner-block", "--plan", str(f), "--out", str(tmp_path))
    assert r.returncode == 2 and "not both" in r.stderr


@pytest.mark.slow
def test_report_on_a_users_scene_is_about_it(tmp_path):
    pytest.importorskip("pymunk")
    r = _cli("report", str(BENT), "--quick", "--engine", "pymunk", "--out", str(tmp_path),
             "--quiet")
    assert r.returncode == 0, r.stderr[-2000:]
    page = (tmp_path / "index.html").read_text(encoding="utf-8")
    assert "bridge-bent" in page and "Your structures" in page
    assert "paper-asymmetric" not in page.split('id="settings-section"')[0]

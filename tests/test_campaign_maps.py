"""Which engine map the report shows: the finest verified one (the paper's resolution measured
by ``--full``, then the plan's measured grid, then the fast engines' default grid), and what
``--full`` measures (the paper's resolution, adaptively, when it is not there yet)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import rockbench.campaign.maps as CM

MAPS = {"engine_amplitude": "1:8", "engine_frequency": "1:10", "engine_tail": 3.0,
        "analytic_grid": (100, 100), "analytic_amplitude": "0.5:8",
        "analytic_frequency": "0.5:10", "measured_grid": (12, 12), "full_grid": (100, 100),
        "fast_grids": {"paper-asymmetric": (6, 6)}}


@pytest.fixture
def fake(monkeypatch):
    """reuse_map verifies the grids in ``calls['verified']``; run_map records its calls."""
    calls = {"verified": set(), "run": []}

    def reuse_map(path, sc, eng, *, grid, **_):
        if tuple(grid) in calls["verified"]:
            return pd.DataFrame({"grid": [str(grid)]}), f"verified {grid}"
        return None, f"no measured map at {Path(path).name}"

    def run_map(sc, eng, *, store, grid, adaptive=False, **_):
        calls["run"].append((Path(store).name, tuple(grid), adaptive))
        return pd.DataFrame({"grid": [str(grid)]})

    monkeypatch.setattr(CM, "reuse_map", reuse_map)
    monkeypatch.setattr(CM, "run_map", run_map)
    monkeypatch.setattr(CM, "is_fast", lambda eng: eng == "pymunk")
    return calls


def _map(tmp_path, calls, eng="pymunk", full=False):
    return CM._engine_map("paper-asymmetric", eng, tmp_path / "store", tmp_path / "measured",
                          full=full, quick=False, run={}, maps=MAPS)


def test_the_finest_verified_map_is_shown(fake, tmp_path):
    fake["verified"] = {(12, 12), (100, 100)}
    df, g, why = _map(tmp_path, fake)
    assert g == (100, 100) and why == "verified (100, 100)" and not fake["run"]
    fake["verified"] = {(12, 12)}
    df, g, why = _map(tmp_path, fake)
    assert g == (12, 12) and not fake["run"]


def test_without_a_measured_map_a_fast_engine_runs_its_default_grid(fake, tmp_path):
    df, g, why = _map(tmp_path, fake)
    assert g == (6, 6) and fake["run"] == [("paper-asymmetric_pymunk_6x6.parquet", (6, 6),
                                            False)]
    assert "no measured map" in why
    fake["run"].clear()
    df, g, why = _map(tmp_path, fake, eng="opensees")          # a slow engine: no map
    assert df is None and not fake["run"]


def test_full_measures_the_paper_resolution_adaptively(fake, tmp_path):
    fake["verified"] = {(12, 12)}                  # a coarser map does not satisfy --full
    df, g, why = _map(tmp_path, fake, full=True)
    assert g == (100, 100) and why.startswith("measured now")
    assert fake["run"] == [("paper-asymmetric_pymunk_100x100.parquet", (100, 100), True)]
    fake["run"].clear()
    fake["verified"] = {(100, 100)}                # already there and reproduced: reused
    df, g, why = _map(tmp_path, fake, full=True)
    assert g == (100, 100) and not fake["run"]


# --- the evidence the report's advice rests on ---------------------------------------------
def test_a_plan_names_its_evidence_and_a_users_plan_takes_the_default_set(tmp_path):
    """The paper plan keeps the quick evidence (make report's 10 minutes); a plan derived from
    a user's scenes chooses on the default evidence, as `rockbench advise` does; a plan with
    another value is refused naming the key."""
    from rockbench.campaign.plan import plan_for_scenes
    from rockbench.errors import ParameterError
    from rockbench.campaign.plan import campaign_plan, read_plan

    assert campaign_plan()["choice_evidence"] == "quick"
    assert plan_for_scenes(["paper-asymmetric"])["choice_evidence"] == "default"
    assert plan_for_scenes(["paper-asymmetric"], quick=True)["choice_evidence"] == "quick"
    src = (Path(__import__("rockbench").__file__).parent / "scenarios" / "paper-plan.toml")
    import tomllib

    text = src.read_text()
    assert read_plan(tomllib.loads(text))[0]["choice_evidence"] == "quick"
    bad = text.replace('choice_evidence = "quick"', 'choice_evidence = "huge"')
    with pytest.raises(ParameterError, match="choice_evidence"):
        read_plan(tomllib.loads(bad))


def test_the_choice_part_takes_the_plans_evidence(monkeypatch, tmp_path):
    """run_choice builds the validation set of the plan's size (--full: the next larger)."""
    import rockbench.campaign.choice as CC
    import rockbench.studies.validation as V

    seen = []

    class Stop(Exception):
        pass

    def validation_set(scene, size, **kw):
        seen.append(size)
        raise Stop

    monkeypatch.setattr(V, "validation_set", validation_set)
    for evidence, full, want in (("quick", False, "quick"), ("default", False, "default"),
                                 ("quick", True, "default"), ("default", True, "full")):
        with pytest.raises(Stop):
            CC.run_choice(["pymunk"], tmp_path, full=full, evidence=evidence,
                          scene="paper-asymmetric")
        assert seen[-1] == want, (evidence, full)


# --- the default map store after an upgrade -------------------------------------------------
def test_default_map_store_of_other_code_is_set_aside_not_refused(tmp_path, monkeypatch,
                                                                   capsys):
    """`rockbench map SCENE` with no --store, after the physics code changed: the old store is
    kept under another name and the map computed afresh (one line on stderr); a store the user
    names is still refused."""
    import json

    from rockbench.cli.main import main

    monkeypatch.chdir(tmp_path)
    args = ["map", "housner-block", "--grid", "2x2", "--pulses", "symmetric+", "--json"]
    assert main(args) == 0
    store = tmp_path / "maps" / "housner-block_analytic.parquet"
    meta = json.loads((store / "_inputs.json").read_text())
    meta["code"] = "000000000000"                        # as if written by other code
    (store / "_inputs.json").write_text(json.dumps(meta))
    capsys.readouterr()
    assert main(args) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert out["cells_run"] == 4 and out["reused"] == 0
    assert (tmp_path / "maps" / "housner-block_analytic.parquet.code-000000000000").is_dir()
    assert "computing the map afresh" in cap.err
    named = tmp_path / "mine.parquet"
    assert main([*args, "--store", str(named)]) == 0
    meta = json.loads((named / "_inputs.json").read_text())
    meta["code"] = "000000000000"
    (named / "_inputs.json").write_text(json.dumps(meta))
    assert main([*args, "--store", str(named)]) == 2           # a named store: refused


# --- how a dense engine map is drawn -----------------------------------------------------------
def test_a_dense_overlay_draws_the_engines_boundary_not_a_marker_per_cell():
    """At the paper's resolution a marker per cell fills the panel and hides the analytic map:
    above DENSE_CELLS cells a panel shows the engine's boundary as a line, and the cells that
    differ ringed; a coarse map keeps its markers."""
    import numpy as np
    from matplotlib.collections import PathCollection

    from rockbench.report.map_figures import DENSE_CELLS, plot_map_overlay

    def grid(n, shift=0.0):
        A, W = np.meshgrid(np.linspace(1, 8, n), np.linspace(1, 10, n), indexing="ij")
        rows = []
        for shape, sign in (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1),
                            ("antisymmetric", -1)):
            rows.append(pd.DataFrame({"pulse": shape, "sign": sign, "amplitude": A.ravel(),
                                      "frequency": W.ravel(), "status": "ok",
                                      "overturned": A.ravel() > 2 + 0.5 * W.ravel() + shift}))
        return pd.concat(rows, ignore_index=True)

    n = int(np.ceil(np.sqrt(DENSE_CELLS))) + 5
    fig = plot_map_overlay(grid(n), grid(n, shift=0.05), name="eng", title="t")
    ax = fig.axes[0]
    sizes = [len(c.get_offsets()) for c in ax.collections if isinstance(c, PathCollection)]
    assert max(sizes) < n * n // 10                    # only the ringed cells, no cell markers
    assert any(line.get_label() == "eng: its overturning boundary" for line in ax.lines)
    fig = plot_map_overlay(grid(6), grid(6), name="eng", title="t")
    sizes = [len(c.get_offsets()) for c in fig.axes[0].collections
             if isinstance(c, PathCollection)]
    assert sum(sizes) == 36                            # a coarse map: a marker per cell

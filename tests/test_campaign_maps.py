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

"""The slower engines' fragility runs kept with the report: reused only when complete, of this
engine version, and reproduced by a re-run; keyed by what the runs are, not where files are."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest

from rockbench.campaign.fragility_measured import measure_runs, portable_key, reuse_runs
from rockbench.studies.ensembles import resolve_records
from rockbench.studies.fragility import fragility_cases
from rockbench.sweep import run_cases

pytest.importorskip("pymunk")


def _cases(rec, scales=(0.5,)):
    return fragility_cases("paper-asymmetric", [rec], ["pymunk"], list(scales),
                           durations={rec["path"]: 3.0})


@pytest.fixture(scope="module")
def kept(tmp_path_factory):
    rec = resolve_records("bundled")[0]
    folder = tmp_path_factory.mktemp("measured")
    cases = _cases(rec)
    measure_runs(folder, "free", "pymunk", cases, {"beta": 0.01, "cases": 3},
                 executor="serial", progress=False)
    return folder, rec, cases


def _copy(kept, tmp_path):
    folder = tmp_path / "measured"
    shutil.copytree(kept[0], folder)
    return folder


def test_kept_runs_are_reused_as_the_section_would_run_them(kept, tmp_path):
    folder, rec, cases = kept
    store = tmp_path / "store"
    num, how = reuse_runs(folder, "free", "pymunk", cases, store)
    assert how.startswith("measured earlier (2 runs") and "reproduced" in how
    assert num == {"beta": 0.01, "cases": 3}
    again = run_cases(cases, store=store, executor="serial", progress=False)
    stored = pd.read_parquet(folder / "free_pymunk.parquet")
    # the rows come from the folder: the same measured wall time, not a new run
    assert sorted(again["wall_s"]) == sorted(stored["wall_s"])
    assert list(again["motion.scale"]) == [0.5, -0.5]


def test_a_record_is_known_by_its_content_not_its_path(kept, tmp_path):
    _, rec, cases = kept
    moved = tmp_path / "elsewhere.AT2"
    shutil.copy(rec["path"], moved)
    c = dict(cases[0], motion=dict(cases[0]["motion"], path=str(moved)))
    assert portable_key(c, "free") == portable_key(cases[0], "free")
    assert portable_key(cases[0], "hybrid") != portable_key(cases[0], "free")


def test_runs_the_section_needs_but_the_folder_lacks_are_not_reused(kept, tmp_path):
    folder, rec, _ = kept
    num, why = reuse_runs(folder, "free", "pymunk", _cases(rec, (0.5, 0.7)), tmp_path / "s")
    assert num is None and "lack 2 of the 4" in why
    num, why = reuse_runs(folder, "hybrid", "pymunk", _cases(rec), tmp_path / "s")
    assert num is None and "no measured runs" in why


def test_another_engine_version_is_not_reused(kept, tmp_path):
    folder = _copy(kept, tmp_path)
    meta = folder / "free_pymunk.json"
    info = json.loads(meta.read_text())
    meta.write_text(json.dumps(dict(info, engine_version="pymunk 0.0.1")))
    num, why = reuse_runs(folder, "free", "pymunk", kept[2], tmp_path / "s")
    assert num is None and "pymunk 0.0.1" in why


def test_runs_that_do_not_reproduce_are_not_reused(kept, tmp_path):
    folder = _copy(kept, tmp_path)
    table = folder / "free_pymunk.parquet"
    df = pd.read_parquet(table)
    df["max_abs_phi_over_alpha"] *= 1.01
    df.to_parquet(table, index=False)
    store = tmp_path / "s"
    num, why = reuse_runs(folder, "free", "pymunk", kept[2], store)
    assert num is None and "do not reproduce" in why
    assert not list(store.glob("*.parquet"))            # nothing written to the run store


def test_a_measurement_resumes(kept, tmp_path):
    folder = _copy(kept, tmp_path)
    rec, cases = kept[1], _cases(kept[1], (0.5, 0.7))
    before = pd.read_parquet(folder / "free_pymunk.parquet")
    measure_runs(folder, "free", "pymunk", cases, None, executor="serial", progress=False)
    after = pd.read_parquet(folder / "free_pymunk.parquet")
    assert len(after) == 4
    old = after[after["portable_key"].isin(before["portable_key"])]
    assert sorted(old["wall_s"]) == sorted(before["wall_s"])   # not run again

"""Overturning maps (issue 11): every backend on a 10 x 10 map, resume after an interruption,
a store written for other inputs, a real Dask cluster, agreement metrics."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.engines import get_backend
from rockbench.testing import engine_params
from rockbench.studies.map_agreement import map_agreement
from rockbench.studies.maps import MAP_COLUMNS, load_map, map_cells, run_map

GRID = dict(grid=(10, 10), amplitude="1.5:8", frequency="4:10", pulses="symmetric+", tail=0.5)
ENGINES = engine_params()          # every registered engine; those missing here skip, saying why
FAST = {n for n in rb.backend_names() if get_backend(n).fast}


def test_cells_are_inclusive_and_complete():
    cells = map_cells(grid="8x8", amplitude="1:8", frequency="1:8", pulses="all")
    assert len(cells) == 8 * 8 * 4
    assert sorted({c[2] for c in cells}) == [1, 2, 3, 4, 5, 6, 7, 8]
    assert {(c[0], c[1]) for c in cells} == {("symmetric", 1), ("symmetric", -1),
                                             ("antisymmetric", 1), ("antisymmetric", -1)}
    with pytest.raises(rb.ParameterError, match="amplitude"):
        map_cells(amplitude="8:1")
    with pytest.raises(rb.ParameterError, match="pulses"):
        map_cells(pulses="sideways")


@pytest.fixture(scope="module")
def analytic_map(tmp_path_factory):
    store = tmp_path_factory.mktemp("maps") / "a.parquet"
    return run_map("paper-asymmetric", store=store, progress=False, **GRID), store


def test_analytic_map_columns_and_physics(analytic_map):
    df, _ = analytic_map
    assert list(df.columns) == list(MAP_COLUMNS) + ["outside"] and len(df) == 100
    assert (df["status"] == "ok").all()
    ot = df["overturned"].astype(bool)
    assert 0 < ot.sum() < len(df)                  # both regions present
    # an overturned cell has exceeded its critical angle; larger A never survives at the
    # smallest A that overturns... (per W, the largest A overturns if any does)
    assert df.loc[ot, "exceeded_critical"].astype(bool).all()
    for _, g in df.groupby("frequency"):
        if g["overturned"].astype(bool).any():
            assert bool(g.sort_values("amplitude")["overturned"].iloc[-1])


def test_compiled_and_reference_maps_agree(analytic_map):
    df, _ = analytic_map
    ref = run_map("paper-asymmetric", method="solve_ivp", progress=False,
                  grid=(4, 4), amplitude="1.5:8", frequency="4:10", pulses="symmetric+",
                  tail=0.5)
    fast = run_map("paper-asymmetric", method="compiled", progress=False,
                   grid=(4, 4), amplitude="1.5:8", frequency="4:10", pulses="symmetric+",
                   tail=0.5)
    assert map_agreement(ref, fast)["fraction"] == 1.0
    assert np.allclose(ref["max_abs_phi_over_alpha"], fast["max_abs_phi_over_alpha"],
                       atol=1e-4)


@pytest.mark.parametrize("engine", [pytest.param(*p.values, marks=[*p.marks, *(
    () if p.values[0] in FAST else (pytest.mark.slow,))], id=p.id) for p in ENGINES])
def test_every_backend_maps_10x10(engine, analytic_map, tmp_path):
    ref, _ = analytic_map
    df = run_map("paper-asymmetric", engine, store=tmp_path / "e.parquet", progress=False,
                 **GRID)
    assert len(df) == 100 and set(df["status"]) <= {"ok", "diverged", "invalid"}
    ag = map_agreement(ref, df)
    assert ag["n"] >= 90 and ag["fraction"] >= 0.9, ag


def test_interrupted_map_resumes_to_the_uninterrupted_one(analytic_map, tmp_path):
    full, store = analytic_map
    copy = tmp_path / "half.parquet"
    shutil.copytree(store, copy)
    parts = sorted(copy.glob("part-*.parquet"))
    assert len(parts) == 1                           # a finished run compacts its parts
    rows = load_map(copy)
    parts[0].unlink()
    for i in range(3):                               # an interrupted run wrote only some chunks
        rows.iloc[i::6].to_parquet(copy / f"part-{i}.parquet", index=False)
    kept = len(load_map(copy))
    assert 0 < kept < 100
    again = run_map("paper-asymmetric", store=copy, progress=False, **GRID)
    assert again.attrs["reused"] == kept and again.attrs["cells_run"] == 100 - kept
    pd.testing.assert_frame_equal(again.drop(columns="cpu_s"), full.drop(columns="cpu_s"))
    assert len(list(copy.glob("part-*.parquet"))) == 1
    pd.testing.assert_frame_equal(
        pd.read_parquet(copy).sort_values(list(full.columns[:4])).reset_index(drop=True)
        .drop(columns="cpu_s"),
        full.sort_values(list(full.columns[:4])).reset_index(drop=True)
        .drop(columns=["cpu_s", "outside"]),                # outside is not stored
        check_dtype=False)


def test_a_store_for_other_inputs_is_refused(analytic_map):
    _, store = analytic_map
    with pytest.raises(rb.RockbenchError, match="other inputs"):
        run_map("paper-symmetric", store=store, progress=False, **GRID)
    with pytest.raises(rb.RockbenchError, match="other inputs"):
        run_map("paper-asymmetric", "pymunk", store=store, progress=False, **GRID)


def test_agreement_metrics_on_a_controlled_pair():
    cells = map_cells(grid=(4, 2), amplitude="1:4", frequency="1:2", pulses="symmetric+")
    a = pd.DataFrame([dict(amplitude=A, frequency=W, pulse=s, sign=g, overturned=A >= 3,
                           exceeded_critical=A >= 3, max_abs_phi_over_alpha=1.0, n_impacts=1,
                           fractured=False, status="ok", wall_s=0.0) for s, g, A, W in cells])
    b = a.copy()
    b["overturned"] = b["amplitude"] >= 2                 # b overturns earlier, by 1 in A
    ag = map_agreement(a, b)
    assert ag["n"] == 8 and ag["fraction"] == 0.75 and ag["b_overturns_a_survives"] == 2
    assert list(ag["shift"]["shift"]) == [-1.0, -1.0]
    assert math.isclose(ag["kappa"], 0.5)


@pytest.mark.slow
def test_map_on_a_real_dask_cluster(analytic_map):
    distributed = pytest.importorskip("distributed")
    full, _ = analytic_map
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        df = run_map("paper-asymmetric", scheduler=cluster.scheduler_address, progress=False,
                     **GRID)
    pd.testing.assert_frame_equal(df.drop(columns="cpu_s"), full.drop(columns="cpu_s"))


def test_map_command_line(tmp_path, capsys):
    import json

    from rockbench.cli.main import main

    store = tmp_path / "m.parquet"
    args = ["map", "paper-asymmetric", "--grid", "3x2", "--amplitude", "2:6", "--frequency",
            "2:4", "--pulses", "symmetric+,antisymmetric-", "--store", str(store), "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["cells"] == 12 and out["reused"] == 0 and out["method"] == "compiled"
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["reused"] == 12
    assert main(["map", "paper-symmetric", "--store", str(store), "--grid", "2x2"]) == 2
    assert "other inputs" in capsys.readouterr().err
    # a copy with one verdict flipped: the comparison finds that one cell and no other
    import shutil

    from rockbench.sweep.map_store import load_map, part_files, tidy_map, write_part

    other = tmp_path / "flipped.parquet"
    shutil.copytree(store, other)
    df = load_map(other)
    for p in part_files(other):
        p.unlink()
    df.loc[df.index[0], "overturned"] = not bool(df.loc[df.index[0], "overturned"])
    write_part(other, tidy_map(df))
    assert main(["map", "--compare", str(store), str(other), "--json"]) == 0
    ag = json.loads(capsys.readouterr().out)
    assert (ag["n"], ag["differ"]) == (12, 1) and ag["kappa"] < 1.0
    assert main(["map", "paper-asymmetric", "--grid", "0x4"]) == 2


def test_a_measured_map_is_reused_only_when_it_reproduces(tmp_path):
    """``reuse_map``: a complete store written for the same inputs is reused after sample cells
    re-run now reproduce it; a tampered, incomplete or foreign store is not (and says why)."""
    from rockbench.studies.maps import reuse_map

    cells = dict(grid=(3, 2), amplitude="2:8", frequency="6:10", pulses="all", tail=0.5)
    store = tmp_path / "m.parquet"
    df = run_map("paper-asymmetric", "pymunk", store=store, keyed_by_code=False,
                 progress=False, **cells)
    got, why = reuse_map(store, "paper-asymmetric", "pymunk", **cells)
    assert got is not None, why
    assert "reproduced now at 4 re-run cells" in why
    pd.testing.assert_frame_equal(got.drop(columns="cpu_s"), df.drop(columns="cpu_s"))
    # another engine, another grid, other inputs
    assert reuse_map(store, "paper-asymmetric", "mujoco", **cells)[0] is None
    none, why = reuse_map(store, "paper-asymmetric", "pymunk", **dict(cells, grid=(4, 2)))
    assert none is None and "lacks" in why
    # a stored number that the engine does not reproduce
    tampered = load_map(store)
    tampered["max_abs_phi_over_alpha"] *= 1.001
    for p in store.glob("part-*.parquet"):
        p.unlink()
    tampered.to_parquet(store / "part-0.parquet", index=False)
    none, why = reuse_map(store, "paper-asymmetric", "pymunk", **cells)
    assert none is None and "does not reproduce" in why and "max |phi|/alpha" in why


def _committed_maps() -> list[tuple[str, str, tuple[int, int]]]:
    """(scene, engine, grid) of every engine map committed under ``reports/engine-maps`` (the
    plan's 12 x 12 x 4 and the paper's 100 x 100 x 4 measured by ``report --full``)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "reports" / "engine-maps"
    out = []
    for p in sorted(root.glob("*_*_*x*.parquet")):
        scene, engine, grid = p.name[:-len(".parquet")].rsplit("_", 2)
        out.append((scene, engine, tuple(int(v) for v in grid.split("x"))))
    return out


def test_the_maps_of_the_committed_engines_are_committed():
    """Every engine keeps its 12 x 12 x 4 map and its map at the paper's 100 x 100 x 4 on both
    of the report's frames."""
    maps = _committed_maps()
    for grid in ((12, 12), (100, 100)):       # the paper's resolution: issue 27
        have = {(s, e) for s, e, g in maps if g == grid}
        for scene in ("paper-asymmetric", "paper-asymmetric-hybrid-eps1"):
            for engine in ("pymunk", "mujoco", "pybullet", "opensees", "drake"):
                assert (scene, engine) in have, (scene, engine, grid)


def test_every_committed_engine_map_reads_whole():
    """Each committed map loads with every cell (a change of the store's format that left the
    committed maps unreadable would otherwise only show as maps measured again)."""
    import warnings
    from pathlib import Path

    from rockbench.sweep.map_store import load_map

    root = Path(__file__).resolve().parents[1] / "reports" / "engine-maps"
    for scene, engine, grid in _committed_maps():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            df = load_map(root / f"{scene}_{engine}_{grid[0]}x{grid[1]}.parquet")
        assert len(df) == grid[0] * grid[1] * 4, (scene, engine, grid)


@pytest.mark.slow
@pytest.mark.parametrize("scene, engine, grid", _committed_maps(),
                         ids=[f"{s}-{e}-{g[0]}x{g[1]}" for s, e, g in _committed_maps()])
def test_the_committed_engine_maps_reproduce(engine, scene, grid):
    """The report's engine maps (``reports/engine-maps``: 12 x 12 x 4, and 100 x 100 x 4
    measured adaptively by ``rockbench report --full``) are reproduced by the current code at
    their sample cells; when this fails, rerun ``rockbench report --full`` and commit the maps
    it measures."""
    from pathlib import Path

    from rockbench.campaign.maps import engine_axes
    from rockbench.studies.maps import reuse_map

    if engine not in rb.available_backends():
        pytest.skip(f"{engine} is not installed")
    root = Path(__file__).resolve().parents[1] / "reports" / "engine-maps"
    path = root / f"{scene}_{engine}_{grid[0]}x{grid[1]}.parquet"
    df, why = reuse_map(path, scene, engine, **dict(engine_axes(), grid=grid))
    assert df is not None, why
    assert len(df) == grid[0] * grid[1] * 4
    assert (df["status"] == "ok").mean() >= 0.95


def test_run_map_takes_a_scene_object(tmp_path):
    """A Scene made in Python maps as its name or file does (overrides applied either way),
    with the analytic backend and through the engines' sweep path."""
    small = dict(grid=(3, 2), amplitude="2:8", frequency="4:8", pulses="symmetric+",
                 tail=0.5, progress=False)
    by_name = run_map("paper-asymmetric", overrides={"span": 9.0}, **small)
    scene = rb.load_scene("paper-asymmetric", {"span": 9.0})
    by_object = run_map(scene, store=tmp_path / "s.parquet", **small)
    pd.testing.assert_frame_equal(by_object.drop(columns="cpu_s"),
                                  by_name.drop(columns="cpu_s"))
    later = run_map(rb.load_scene("paper-asymmetric"), overrides={"span": 9.0},
                    store=tmp_path / "s.parquet", **small)
    assert later.attrs["reused"] == 6                  # the same scene, the same store
    eng = run_map(scene, "pymunk", **dict(small, grid=(1, 1), amplitude="8:8",
                                          frequency="8:8"))
    assert list(eng["status"]) == ["ok"]


def test_map_figure_and_overlay(tmp_path, capsys):
    import json

    from rockbench.cli.main import main

    store = tmp_path / "m.parquet"
    cells = ["--grid", "3x2", "--amplitude", "2:6", "--frequency", "2:4", "--pulses",
             "symmetric+,antisymmetric-"]
    png = tmp_path / "figs" / "m.png"
    assert main(["map", "paper-asymmetric", *cells, "--store", str(store), "--figure",
                 str(png), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["figure"] == str(png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    # the overlay against an independently computed map: the same cells by the solve_ivp
    # reference path (not the compiled one), which must agree on every verdict
    ref = tmp_path / "ref.parquet"
    ref_df = run_map("paper-asymmetric", method="solve_ivp", store=ref, progress=False,
                     grid=(3, 2), amplitude="2:6", frequency="2:4",
                     pulses="symmetric+,antisymmetric-")
    fast = load_map(store)
    assert ref_df.attrs.get("reused", 0) == 0 and len(fast) == len(ref_df) == 12
    key = ["pulse", "sign", "amplitude", "frequency"]
    m = fast.merge(ref_df, on=key, suffixes=("", "_ref"))
    assert len(m) == 12 and 0 < m["overturned"].astype(bool).sum() < 12   # both regions
    survived = ~m["overturned"].astype(bool)
    assert np.allclose(m.loc[survived, "max_abs_phi_over_alpha"],
                       m.loc[survived, "max_abs_phi_over_alpha_ref"], atol=1e-4)
    over = tmp_path / "overlay.svg"
    assert main(["map", "--compare", str(store), str(ref), "--figure", str(over)]) == 0
    text = capsys.readouterr().out
    assert "figure:" in text and b"<svg" in over.read_bytes()[:400]
    assert "near the boundary" in text            # an analytic first map: cells near it marked
    assert main(["map", "--compare", str(store), str(ref), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n"] == 12 and out["differ"] == 0 and out["kappa"] == pytest.approx(1.0)
    assert out["disagree_near_boundary"] == out["disagree_away"] == 0
    assert 0 <= out["near_boundary"] <= out["n"]
    assert main(["map", "paper-asymmetric", *cells, "--store", str(store), "--figure",
                 str(tmp_path / "m.txt")]) == 2
    assert "--figure" in capsys.readouterr().err


def test_adaptive_map_reproduces_the_full_grid_simulating_a_third(tmp_path, capsys):
    """Issue 27: at 24 x 24 x 4 the adaptive map simulates at most a third of the cells and
    gives >= 99.5 % of the full grid's verdicts; its store holds every cell, the inferred ones
    marked; a rerun simulates and writes nothing; a full run on its store simulates exactly the
    inferred cells and gives the full map."""
    import json

    from rockbench.cli.main import main

    kw = dict(grid=(24, 24), progress=False)
    full = run_map("paper-asymmetric", **kw)
    store = tmp_path / "a.parquet"
    ad = run_map("paper-asymmetric", adaptive=True, store=store, **kw)
    assert len(ad) == 24 * 24 * 4 and ad.attrs["cells_run"] <= len(ad) / 3
    assert ad.attrs["inferred"] == int(ad["inferred"].sum()) == len(ad) - ad.attrs["cells_run"]
    assert map_agreement(full, ad)["fraction"] >= 0.995
    sim = ad[~ad["inferred"]].merge(full, on=["pulse", "sign", "amplitude", "frequency"],
                                    suffixes=("", "_full"))
    assert (sim["overturned"] == sim["overturned_full"]).all()   # simulated cells are exact
    stored = load_map(store)
    assert len(stored) == len(ad) and int(stored["inferred"].sum()) == ad.attrs["inferred"]
    args = ["map", "paper-asymmetric", "--grid", "24x24", "--store", str(store), "--adaptive",
            "--json"]
    parts = sorted(store.glob("part-*.parquet"))
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["cells"] == 2304 and out["cells_run"] == 0
    assert sorted(store.glob("part-*.parquet")) == parts     # a rerun rewrites nothing
    assert out["reused"] == 2304 - ad.attrs["inferred"]
    again = run_map("paper-asymmetric", store=store, **kw)
    assert again.attrs["cells_run"] == ad.attrs["inferred"] and "inferred" not in again
    pd.testing.assert_frame_equal(again.drop(columns="cpu_s"), full.drop(columns="cpu_s"))


def test_adaptive_map_at_the_papers_resolution_simulates_far_fewer():
    """Issue 27: at 100 x 100 x 4 (coarse stride 8, ``sweep.adaptive.coarse_stride``) the
    adaptive map of the fracturing frame on the report's engine cells simulates under 6 % of
    the cells (measured: 4.5 %) and gives >= 99.9 % of the full grid's verdicts (99.95 %);
    every simulated cell is exact."""
    from rockbench.sweep.adaptive import coarse_stride

    assert coarse_stride(100, 100) == 8 and coarse_stride(24, 24) == coarse_stride(100, 24) == 4
    kw = dict(grid=(100, 100), amplitude="1:8", frequency="1:10", tail=3.0, progress=False)
    full = run_map("paper-asymmetric-hybrid-eps1", **kw)
    ad = run_map("paper-asymmetric-hybrid-eps1", adaptive=True, **kw)
    assert ad.attrs["cells_run"] <= 0.06 * len(ad)
    assert map_agreement(full, ad)["fraction"] >= 0.999
    sim = ad[~ad["inferred"]].merge(full, on=["pulse", "sign", "amplitude", "frequency"],
                                    suffixes=("", "_full"))
    assert (sim["overturned"] == sim["overturned_full"]).all()


def test_adaptive_map_finds_the_islands_of_survival_of_a_slender_block(tmp_path):
    """Issue 27: islands of survival inside the overturning region lie where overturning
    without an impact gives way to overturning after one; a block whose corners all overturn
    but in both ways is refined. On a slender block the package never named (0.32 x 2.6 m)
    at 100 x 100 (stride 8), antisymmetric pulse +: the full map has 48 survivors inside
    all-overturned coarse blocks; the adaptive map finds >= 90 % of them (measured: all 48;
    7 before the rule; on the four pulses 6 cells of 40 000 differ, 104 before)."""
    from rockbench.sweep.adaptive import coarse_stride

    toml = tmp_path / "slender.toml"
    toml.write_text('[structure]\ntype = "block"\nwidth = 0.32\nheight = 2.6\n')
    kw = dict(grid=(100, 100), amplitude="1:8", frequency="1:10", tail=3.0,
              pulses="antisymmetric+", progress=False)
    full = run_map(toml, **kw)
    ad = run_map(toml, adaptive=True, **kw)
    key = ["amplitude", "frequency"]
    over = full.pivot(index="amplitude", columns="frequency", values="overturned").astype(bool)
    st = coarse_stride(100, 100)
    idx = sorted(set(range(0, 100, st)) | {99})
    islands = set()
    for a0, a1 in zip(idx, idx[1:]):
        for w0, w1 in zip(idx, idx[1:]):
            blk = over.iloc[a0:a1 + 1, w0:w1 + 1]
            if blk.iloc[[0, 0, -1, -1], [0, -1, 0, -1]].to_numpy().all():
                islands |= {(blk.index[i], blk.columns[j]) for i, j in
                            zip(*(~blk.to_numpy()).nonzero())}
    assert len(islands) >= 20
    got = ad.set_index(key)["overturned"].astype(bool)
    found = sum(not got[c] for c in islands)
    assert found >= 0.9 * len(islands), (found, len(islands))
    assert map_agreement(full, ad)["fraction"] >= 0.999
    assert ad.attrs["cells_run"] <= 0.2 * len(ad)


def test_compare_refuses_maps_of_different_structures(tmp_path):
    """Two maps of different structures are not compared, even on the same (A, W) cells."""
    import subprocess
    import sys

    for scene, name in (("housner-block", "a"), ("paper-symmetric", "b")):
        r = subprocess.run([sys.executable, "-m", "rockbench", "map", scene, "--engine",
                            "analytic", "--grid", "2x2", "--amplitude", "1:4", "--frequency",
                            "2:4", "--store", str(tmp_path / name), "--quiet"],
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr[-1000:]
    r = subprocess.run([sys.executable, "-m", "rockbench", "map", "--compare",
                        str(tmp_path / "a"), str(tmp_path / "b")], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 2 and "different structures" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("scene, mirrored, a_max", [("paper-symmetric", True, 8.0),
                                                    ("paper-symmetric-hybrid", True, 40.0),
                                                    ("paper-asymmetric", False, 8.0)])
def test_a_mirror_symmetric_structure_runs_one_sign_and_mirrors_the_other(
        scene, mirrored, a_max, monkeypatch):
    """The reversed pulse's cells of a mirror-symmetric structure are its +1 cells mirrored:
    verdicts, impacts and fractures equal to running them (peaks to round-off); an
    asymmetric frame runs both."""
    import rockbench.studies.maps as M

    kw = dict(grid=(9, 7), amplitude=(1.0, a_max), frequency=(1.0, 10.0), progress=False)
    fast = run_map(scene, **kw)
    assert rb.load_scene(scene).mirror_symmetric is mirrored
    monkeypatch.setattr(M, "mirror_twins", lambda cells: (list(cells), {}))
    full = run_map(scene, **kw)
    key = ["pulse", "sign", "amplitude", "frequency"]
    a = fast.sort_values(key).reset_index(drop=True)
    b = full.sort_values(key).reset_index(drop=True)
    assert len(a) == len(b) == 9 * 7 * 4
    for col in ("overturned", "exceeded_critical", "n_impacts", "fractured", "status"):
        assert (a[col].astype(str) == b[col].astype(str)).all(), col
    np.testing.assert_allclose(a["max_abs_phi_over_alpha"].astype(float),
                               b["max_abs_phi_over_alpha"].astype(float), rtol=1e-9)
    assert not a["overturned"].astype(bool).all()
    assert a["overturned"].astype(bool).any() or a["max_abs_phi_over_alpha"].max() > 0.5
    n_free = int((a.loc[a["sign"] == -1, "cpu_s"] == 0.0).sum())   # mirrored: no CPU
    assert n_free == (9 * 7 * 2 if mirrored else 0)


# ------------------------------------------------------------------------------------------
# Vertical ground motion: every cell's pulse with a_v = r u_g''
# ------------------------------------------------------------------------------------------
VGRID = dict(grid=(3, 3), amplitude="2:8", frequency="3:9", pulses="symmetric+,antisymmetric-",
             tail=0.5, progress=False)


def _pulse(scene, row, ratio):
    return rb.RickerPulse.dimensionless(row.amplitude, row.frequency, scene.structure,
                                        row.pulse, int(row.sign), vertical_ratio=ratio)


def test_a_vertical_map_runs_every_cell_with_its_vertical_part(tmp_path):
    """run_map(vertical=0.5): each row is the run of its pulse with a_v = 0.5 u_g'' (the
    summary of rb.run on that pulse, to the last bit), on both analytic paths alike; the
    vertical part changes the answer; the store keeps the ratio and refuses another one, in
    either direction, saying which."""
    import json

    from rockbench.run_length import pulse_run_length

    scene = rb.load_scene("paper-asymmetric")
    store = tmp_path / "v.parquet"
    v = run_map("paper-asymmetric", store=store, vertical=0.5, **VGRID)
    assert v.attrs["vertical_ratio"] == 0.5 and (v["status"] == "ok").all() and len(v) == 18
    assert "overturning map, a_v = 0.5 a_g" in rb.plot_map(v)._suptitle.get_text()
    for row in v.iloc[[0, 4, 8, 13, 17]].itertuples():
        r = rb.run(scene, _pulse(scene, row, 0.5), method="compiled",
                   duration=pulse_run_length(row.frequency, scene.p, 0.5))
        assert r.summary.max_abs_phi_over_alpha == row.max_abs_phi_over_alpha
        assert (r.summary.overturned, r.summary.n_impacts) == (row.overturned, row.n_impacts)
    ref = run_map("paper-asymmetric", method="solve_ivp", vertical=0.5, workers=1, **VGRID)
    assert map_agreement(ref, v)["fraction"] == 1.0
    np.testing.assert_allclose(ref["max_abs_phi_over_alpha"], v["max_abs_phi_over_alpha"],
                               rtol=0, atol=1e-6)
    flat = run_map("paper-asymmetric", store=tmp_path / "h.parquet", **VGRID)
    assert flat.attrs["vertical_ratio"] == 0.0
    rel = np.abs(v["max_abs_phi_over_alpha"] / flat["max_abs_phi_over_alpha"] - 1)
    assert rel.max() > 0.05                      # the vertical part matters
    inputs = json.loads((store / "_inputs.json").read_text())
    assert inputs["vertical_ratio"] == 0.5
    assert "vertical_ratio" not in json.loads((tmp_path / "h.parquet" / "_inputs.json")
                                              .read_text())   # a horizontal store: as before
    assert run_map("paper-asymmetric", store=store, vertical=0.5, **VGRID).attrs["reused"] == 18
    for ratio, said in ((0.7, r"vertical_ratio=0.5 \(now 0.7\)"),
                        (0.0, r"vertical_ratio=0.5 \(now 0.0\)")):
        with pytest.raises(rb.RockbenchError, match=said):
            run_map("paper-asymmetric", store=store, vertical=ratio, **VGRID)
    with pytest.raises(rb.RockbenchError, match=r"vertical_ratio=0.0 \(now 0.5\)"):
        run_map("paper-asymmetric", store=tmp_path / "h.parquet", vertical=0.5, **VGRID)
    for bad in (-0.1, 3.5, math.nan, True, None):
        with pytest.raises(rb.ParameterError, match="vertical"):
            run_map("paper-asymmetric", vertical=bad, **VGRID)


def test_the_cells_outside_the_model_are_those_of_the_one_rule():
    """The column ``outside`` is rockbench.validity.motion_validity of each cell's own pulse
    (its own W) with the scene's friction: with r = 3 the ground falls faster than gravity on a
    downward lobe of the larger pulses (g + a_v <= 0), others ask the base for more than
    mu = 0.6; the smallest stay inside. Without vertical motion: PGA > mu g."""
    from rockbench.validity import motion_validity

    scene = rb.load_scene("paper-asymmetric", {"contact.friction": 0.6})
    kw = dict(grid=(8, 1), amplitude="1:8", frequency="3:3", pulses="all", tail=0.5,
              progress=False)
    reasons = set()
    for ratio in (3.0, 0.0):
        df = run_map(scene, vertical=ratio, **kw)
        assert df.attrs["outside"] == int(df["outside"].sum())
        for row in df.itertuples():
            val = motion_validity(scene, _pulse(scene, row, ratio))
            assert row.outside == (not val.inside), (ratio, row)
            reasons.add((ratio, "falls faster" in val.reason, "slides" in val.reason))
    assert {(3.0, True, False), (3.0, False, True), (3.0, False, False),
            (0.0, False, True), (0.0, False, False)} <= reasons


def test_an_engine_map_moves_the_ground_vertically():
    """Engine cells carry the vertical part: each row of a pymunk map with r = 0.5 is pymunk's
    run under that pulse, and differs from the horizontal map's."""
    pytest.importorskip("pymunk")
    from rockbench.run_length import pulse_run_length

    scene = rb.load_scene("paper-asymmetric")
    kw = dict(VGRID, grid=(2, 2), pulses="symmetric+")
    e = run_map("paper-asymmetric", "pymunk", vertical=0.5, workers=1, **kw)
    assert (e["status"] == "ok").all() and e.attrs["vertical_ratio"] == 0.5
    for row in e.itertuples():
        r = rb.run(scene, _pulse(scene, row, 0.5), engine="pymunk",
                   duration=pulse_run_length(row.frequency, scene.p, 0.5))
        assert r.summary.max_abs_phi_over_alpha == pytest.approx(row.max_abs_phi_over_alpha,
                                                                 rel=1e-12)
    flat = run_map("paper-asymmetric", "pymunk", workers=1, **kw)
    assert not np.allclose(flat["max_abs_phi_over_alpha"], e["max_abs_phi_over_alpha"],
                           rtol=1e-3)


def test_map_command_line_vertical(tmp_path, capsys, monkeypatch):
    """--vertical RATIO: out of [0, 3] one line naming it; the JSON and the text say the
    ratio and the cells outside the model; the default store is the ratio's own; the figure's
    title names the ratio."""
    import json

    from rockbench.cli.main import main
    from rockbench.report import map_figures

    monkeypatch.chdir(tmp_path)
    cells = ["--grid", "2x2", "--amplitude", "2:8", "--frequency", "3:6", "--pulses",
             "symmetric+"]
    for bad in ("3.5", "-1", "nan", "x"):
        assert main(["map", "paper-asymmetric", *cells, "--vertical", bad]) == 2
        err = capsys.readouterr().err
        assert "--vertical" in err and len(err.strip().splitlines()) == 1, err
    titles = []
    real = map_figures.plot_map_panels
    monkeypatch.setattr(map_figures, "plot_map_panels",
                        lambda df, *, title: titles.append(title) or real(df, title=title))
    assert main(["map", "paper-asymmetric", *cells, "--vertical", "0.5", "--figure", "v.png",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["vertical_ratio"] == 0.5 and out["outside"] == 0 and out["cells"] == 4
    assert out["store"] == str(Path("maps") / "paper-asymmetric_analytic_vertical0.5.parquet")
    assert titles == ["paper-asymmetric, analytic, a_v = 0.5 a_g"]
    assert main(["map", "paper-asymmetric", *cells, "--set", "contact.friction=0.2"]) == 0
    text = capsys.readouterr().out
    assert "4 cells (0 reused from maps/paper-asymmetric_analytic.parquet)" in text
    assert "outside the analytic model" in text


def test_compare_marks_the_boundary_of_a_vertical_map_with_its_ratio(tmp_path, capsys):
    """``map --compare`` of an analytic vertical map marks the cells near its boundary by
    re-running them with the store's own vertical ratio (horizontal pulses would mark another
    boundary: here one cell differs)."""
    import json

    from rockbench.cli.main import main
    from rockbench.studies.map_agreement import mark_near_boundary

    scene = rb.load_scene("paper-asymmetric")
    kw = dict(grid=(12, 3), amplitude="3:7", frequency="3:6", pulses="symmetric+", tail=0.5,
              progress=False)
    store = tmp_path / "v.parquet"
    v = run_map("paper-asymmetric", store=store, vertical=0.8, **kw)
    near = mark_near_boundary(v, scene, tail=0.5, vertical=0.8)["near_boundary"]
    flat = mark_near_boundary(v, scene, tail=0.5)["near_boundary"]
    assert (near != flat).any()
    for row, is_near in zip(v.itertuples(), near):
        flips = [run_map("paper-asymmetric", vertical=0.8, **dict(
            kw, grid=(1, 1), amplitude=f"{row.amplitude * f}:{row.amplitude * f}",
            frequency=f"{row.frequency}:{row.frequency}"))["overturned"].iloc[0]
            != row.overturned for f in (0.98, 1.02)]
        assert is_near == any(flips)
    assert main(["map", "--compare", str(store), str(store), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["near_boundary"] == int(near.sum())

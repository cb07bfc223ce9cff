"""rockbench.sweep: cases, executors, the resumable store, grids and maps (and the catalogue)."""

from __future__ import annotations

import multiprocessing
import os
import sys

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.sweep import runs, store
from rockbench.campaign.plan import campaign_plan
from rockbench.sweep.cases import catalogue
from rockbench.testing.contract import CHECK_SCENE
from rockbench.sweep.executors import execute
from rockbench.engines import REGISTRY, available_backends
from rockbench.engines.analytic import AnalyticBackend
from rockbench.sweep import (TIMING_COLUMNS, case_id, load_store, normalize_case, overturn_map,
                             pulse_grid, run_cases)

ENGINES = ["analytic"] + (["pymunk"] if "pymunk" in available_backends() else [])   # data, not a parametrization
BAD = {"scene": "no-such-scene", "engine": "analytic", "motion": None, "phi0": 0.1}


def _grid():
    """4 small cases (+ pymunk's 4 when installed): the block under short pulses."""
    return pulse_grid("housner-block", "symmetric", [1, -1], [3.0], [4.0, 6.0], ENGINES,
                      duration=3.0)


def _physics(df: pd.DataFrame) -> pd.DataFrame:
    return df[[c for c in df.columns if c not in TIMING_COLUMNS]]


# --- cases -----------------------------------------------------------------------------------
def test_case_id_is_stable_and_normalized():
    case = {"scene": "housner-block", "engine": "pymunk", "duration": 2,
            "motion": {"kind": "ricker", "shape": "symmetric", "sign": 1, "A": 3, "W": 4}}
    same = {"motion": {"W": np.float64(4.0), "A": 3.0, "sign": 1, "shape": "symmetric",
                       "kind": "ricker"},
            "duration": 2.0, "engine": "pymunk", "scene": "housner-block", "overrides": None,
            "settings": {}, "phi0": 0}
    # a literal: changing the normalization would orphan every existing store
    assert case_id(case) == case_id(same) == "8b125b69c84ba2b2"
    other = dict(case, motion=dict(case["motion"], A=3.01))
    assert case_id(other) != case_id(case)
    n = normalize_case(case)
    assert n["overrides"] == {} and n["settings"] == {} and n["phi0"] == 0.0


@pytest.mark.parametrize("bad, name", [
    ({"scene": "housner-block", "colour": "red"}, "colour"),
    ({"scene": "housner-block", "engine": "nope"}, "engine"),
    ({"engine": "analytic"}, "scene"),
    ({"scene": "housner-block", "motion": {"kind": "ricker", "A": 3.0}}, "motion"),
    ({"scene": "housner-block", "motion": {"kind": "wave"}}, "motion.kind"),
    ({"scene": "housner-block", "motion": {"kind": "record", "dt": 0.01}}, "motion.path"),
    ({"scene": "housner-block", "duration": -1.0}, "duration"),
])
def test_malformed_cases_raise_parameter_error(bad, name):
    with pytest.raises(rb.ParameterError, match=name.replace(".", r"\.")):
        normalize_case(bad)


def test_bad_options_raise_parameter_error():
    with pytest.raises(rb.ParameterError, match="executor"):
        run_cases([], executor="threads")
    with pytest.raises(rb.ParameterError, match="workers"):
        run_cases([], workers=0)
    with pytest.raises(rb.ParameterError, match="dask_address"):
        run_cases([], executor="serial", dask_address="tcp://x:1")


# --- executors -----------------------------------------------------------------------------
def test_serial_and_process_pool_give_identical_rows():
    cases = _grid() + [BAD]
    serial = run_cases(cases, executor="serial", progress=False)
    pool = run_cases(cases, executor="process", workers=2, progress=False)
    assert len(serial) == len(cases)
    assert list(serial["case_id"]) == [case_id(c) for c in cases]
    pd.testing.assert_frame_equal(_physics(serial), _physics(pool))
    ok = serial[serial["status"] == "ok"]
    assert len(ok) == len(cases) - 1
    # physics in the rows: the pulse A = 3 uplifts the block (A > 1), never at rest
    assert (ok["uplifted"]).all() and (ok["max_abs_phi"] > 0).all()
    assert (ok["sim_time"] == 3.0).all()


def test_a_failing_case_is_recorded_and_the_sweep_goes_on():
    beyond_fall = {"scene": "housner-block", "engine": "analytic", "phi0": 3.0}
    good = {"scene": "housner-block", "engine": "analytic", "phi0": 0.1, "duration": 1.0}
    df = run_cases([BAD, beyond_fall, good], executor="serial", progress=False)
    assert list(df["status"]) == ["error", "error", "ok"]
    assert df["reason"].iloc[0].startswith("SceneError") and "no-such-scene" in df["reason"].iloc[0]
    assert df["reason"].iloc[1].startswith("ParameterError") and "phi0" in df["reason"].iloc[1]
    assert pd.isna(df["overturned"].iloc[0]) and df["n_impacts"].iloc[2] >= 1


# --- the store ---------------------------------------------------------------------------------
def test_resume_runs_only_the_missing_cases(tmp_path, monkeypatch):
    store = tmp_path / "store"
    cases = _grid()
    calls = []
    real = runs.run_case

    def counting(case):
        calls.append(case_id(case))
        return real(case)

    monkeypatch.setattr(runs, "run_case", counting)
    half = len(cases) // 2
    first = run_cases(cases[:half], store=store, executor="serial", progress=False)
    assert len(calls) == half and len(load_store(store)) == half
    calls.clear()
    full = run_cases(cases, store=store, executor="serial", progress=False)
    assert sorted(calls) == sorted(case_id(c) for c in cases[half:])
    # the finished rows come from the store untouched (their timings too)
    pd.testing.assert_frame_equal(full.iloc[:half].reset_index(drop=True),
                                  first[full.columns].reset_index(drop=True))
    assert len(load_store(store)) == len(cases)
    calls.clear()
    again = run_cases(cases, store=store, executor="serial", progress=False)
    assert calls == []
    pd.testing.assert_frame_equal(again, full)
    # the store is compacted into one file at the end of a sweep
    assert [p.name.startswith("compact-") for p in store.glob("*.parquet")] == [True]


def test_interrupted_sweep_keeps_what_finished(tmp_path, monkeypatch):
    store = tmp_path / "store"
    cases = _grid()
    real = runs.run_case
    n = [0]

    def dies_on_third(case):
        n[0] += 1
        if n[0] == 3:
            raise KeyboardInterrupt
        return real(case)

    monkeypatch.setattr(runs, "run_case", dies_on_third)
    with pytest.raises(KeyboardInterrupt):
        run_cases(cases, store=store, executor="serial", progress=False)
    assert len(load_store(store)) == 2          # written as they finished, not at the end
    monkeypatch.setattr(runs, "run_case", real)
    df = run_cases(cases, store=store, executor="serial", progress=False)
    assert (df["status"] == "ok").all() and len(load_store(store)) == len(cases)
    # resumed = uninterrupted, column for column (timings aside)
    whole = run_cases(cases, executor="serial", progress=False)
    pd.testing.assert_frame_equal(_physics(df), _physics(whole))


def test_errors_are_skipped_on_resume_unless_retried(tmp_path):
    store = tmp_path / "s"
    run_cases([BAD], store=store, executor="serial", progress=False)
    stamp = load_store(store)["finished_at"].iloc[0]
    df = run_cases([BAD], store=store, executor="serial", progress=False)
    assert df["status"].iloc[0] == "error" and df["finished_at"].iloc[0] == stamp
    df = run_cases([BAD], store=store, executor="serial", progress=False, retry_errors=True)
    assert df["status"].iloc[0] == "error"
    assert len(load_store(store)) == 1


def test_store_must_be_a_directory(tmp_path):
    f = tmp_path / "file.txt"
    f.write_text("x")
    with pytest.raises(rb.ParameterError, match="store"):
        run_cases([BAD], store=f, progress=False)


class _Crasher(AnalyticBackend):
    """Kills its worker process (as a segfault would)."""

    name = "crasher"

    def run(self, motion=None, *, duration=None, phi0=0.0):
        os._exit(3)


@pytest.mark.skipif(multiprocessing.get_start_method() != "fork",
                    reason="the crashing backend reaches workers by fork only")
def test_a_dying_worker_marks_its_case_and_spares_the_others(monkeypatch):
    monkeypatch.setitem(REGISTRY, "crasher", f"{__name__}:_Crasher")
    good = [{"scene": "housner-block", "engine": "analytic", "phi0": p, "duration": 0.5}
            for p in (0.05, 0.1, 0.15)]
    crash = {"scene": "housner-block", "engine": "crasher", "phi0": 0.1, "duration": 0.5}
    df = run_cases(good[:1] + [crash] + good[1:], executor="process", workers=2,
                   progress=False)
    assert list(df["status"]) == ["ok", "error", "ok", "ok"]
    assert "worker process died" in df["reason"].iloc[1]


# --- dask --------------------------------------------------------------------------------------
def test_dask_missing_gives_a_clear_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(rb.RockbenchError, match=r"rockbench\[dask\]"):
        run_cases([BAD], executor="dask", progress=False)


@pytest.mark.slow  # about 10 s: starting two worker processes that import the stack
def test_dask_local_cluster_gives_the_same_rows():
    distributed = pytest.importorskip("distributed")
    cases = _grid()[:4] + [BAD]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        df = run_cases(cases, executor="dask", dask_address=cluster.scheduler_address,
                       progress=False)
    serial = run_cases(cases, executor="serial", progress=False)
    pd.testing.assert_frame_equal(_physics(df), _physics(serial))


# --- progress ----------------------------------------------------------------------------------
def test_progress_bar_names_the_running_case(capsys, monkeypatch):
    from rockbench import progress

    monkeypatch.setattr(progress, "INTERVAL", 0.0)   # off a terminal: a line per update
    monkeypatch.setattr(progress, "_quiet", False)   # a CLI test's --quiet in this process
    run_cases(_grid()[:1], executor="serial", progress=True)
    err = capsys.readouterr().err
    assert "sweep" in err and "analytic housner-block symm+ A=3 W=4" in err


# --- grids and maps ----------------------------------------------------------------------------
def test_pulse_grid_covers_the_product():
    g = pulse_grid("housner-block", ["symmetric", "antisymmetric"], [1, -1], [1.0, 2.0, 3.0],
                   [2.0, 4.0], ["analytic", "pymunk"], settings={"pymunk": {"dt": 5e-4}})
    assert len(g) == 2 * 2 * 2 * 3 * 2
    assert len({case_id(c) for c in g}) == len(g)
    assert all(c["settings"] == ({"dt": 5e-4} if c["engine"] == "pymunk" else {}) for c in g)
    with pytest.raises(rb.ParameterError, match="A_values"):
        pulse_grid("housner-block", "symmetric", 1, [0.0], [2.0], "analytic")
    with pytest.raises(rb.ParameterError, match="settings"):
        pulse_grid("housner-block", "symmetric", 1, [1.0], [2.0], "analytic",
                   settings={"pymunk": {}})


def test_overturn_map_of_the_block():
    """Housner's block under symmetric pulses: no uplift below A = 1 (a_g < g tan alpha), and at
    fixed W a stronger pulse never turns an overturn into survival here."""
    A = [0.8, 2.0, 6.0, 12.0]
    W = [2.0, 4.0]
    df = run_cases(pulse_grid("housner-block", "symmetric", 1, A, W, "analytic"),
                   executor="serial", progress=False)
    m = overturn_map(df)
    assert list(m.index) == A and list(m.columns) == W
    assert (m.loc[0.8] == 0.0).all()
    assert m.loc[12.0, 2.0] == 1.0
    assert (m.diff().fillna(0) >= 0).all().all()       # monotone in A on this grid
    phi = overturn_map(df, value="max_abs_phi")
    assert (phi.loc[0.8] == 0.0).all() and (phi.loc[2.0] > 0).all()
    both = pd.concat([df, df.assign(engine="pymunk")])
    with pytest.raises(rb.ParameterError, match="engine"):
        overturn_map(both)
    assert overturn_map(both, engine="analytic").equals(m)


# --- the store's payloads and keys ------------------------------------------------------------
def test_payloads_are_written_atomically_and_keyed_like_cases(tmp_path):
    item = {"kind": "pulse", "scene": "housner-block", "engines": ["analytic"],
            "motion": {"kind": "ricker", "shape": "symmetric", "sign": 1, "A": 3, "W": 4}}
    k = store.key(item)
    assert k == store.key({**item, "motion": {**item["motion"], "A": np.float64(3.0)}})
    assert len(k) == 16 and k != store.key({**item, "scene": "paper-asymmetric"})
    # a case's id is the store key of the normalized case: one key scheme
    case = {"scene": "housner-block", "motion": item["motion"]}
    assert case_id(case) == store.key(normalize_case(case))
    assert store.load_payload(tmp_path, k) is None
    store.write_payload(tmp_path, k, {"x": np.arange(3)})
    assert list(store.load_payload(tmp_path, k)["x"]) == [0, 1, 2]
    assert [p.name for p in tmp_path.iterdir()] == [f"{k}.pkl"]     # no temporary file left
    (tmp_path / f"{k}.pkl").write_bytes(b"garbage")                   # unreadable: run again
    assert store.load_payload(tmp_path, k) is None


def test_code_fingerprint_is_stable():
    fp = store.code_fingerprint()
    assert len(fp) == 12 and int(fp, 16) >= 0 and fp == store.code_fingerprint()


# --- the executor, generic over a function ------------------------------------------------------
def _square(x):
    return x * x


@pytest.mark.parametrize("executor", ["serial", "process"])
def test_execute_hands_every_result_over(executor):
    got = {}
    execute(_square, [(str(i), i) for i in range(5)], on_result=got.__setitem__,
            crashed=lambda item, reason: None, executor=executor, workers=2, progress=False)
    assert got == {str(i): i * i for i in range(5)}


def _pid(_x):
    return os.getpid()


def _pids(n: int) -> set[int]:
    got: dict = {}
    execute(_pid, [(str(i), i) for i in range(n)], on_result=got.__setitem__,
            crashed=lambda item, reason: None, executor="process", workers=2, progress=False)
    return set(got.values())


def test_kept_pools_serve_every_call_in_the_block_and_end_with_it():
    from rockbench.sweep.executors import kept_pools

    alone = _pids(4), _pids(4)
    assert not alone[0] & alone[1]              # two calls, two pools
    with kept_pools():
        a, b, one = _pids(6), _pids(6), _pids(1)
        with kept_pools():                      # nested: the outer block's pool
            c = _pids(3)
        pool = a | b | c | one
        assert len(pool) <= 2 and os.getpid() not in pool     # one pool of two workers
    for pid in pool:                            # shut down, workers joined (reaped)
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    assert not _pids(2) & pool                 # outside: a pool of its own again


@pytest.mark.skipif(multiprocessing.get_start_method() != "fork",
                    reason="the crashing backend reaches workers by fork only")
def test_a_dying_worker_in_a_kept_pool_is_replaced(monkeypatch):
    from rockbench.sweep.executors import kept_pools

    monkeypatch.setitem(REGISTRY, "crasher", f"{__name__}:_Crasher")
    good = {"scene": "housner-block", "engine": "analytic", "phi0": 0.1, "duration": 0.5}
    crash = dict(good, engine="crasher")
    with kept_pools():
        first = run_cases([crash, good], executor="process", workers=2, progress=False)
        after = run_cases([good, dict(good, phi0=0.05)], executor="process", workers=2,
                          progress=False)
    assert list(first["status"]) == ["error", "ok"]
    assert list(after["status"]) == ["ok", "ok"]


# --- the catalogue ------------------------------------------------------------------------------
def test_catalogue_holds_the_cross_engine_cases_and_the_campaign_plan():
    c = catalogue()
    assert [f.id for f in c.free_cases] == ["free-housner-block", "free-paper-symmetric",
                                            "free-paper-asymmetric"]
    assert len(c.survive_cases) == 16 and len(c.overturn_cases) == 16
    ot = c.overturn_cases[0]
    assert (ot.scene, ot.W, ot.shape, ot.sign, ot.A, ot.fall) == (
        "paper-asymmetric", 3.0, "symmetric", 1, round(1.2 * 3.2342, 4), 4.0)
    plan = campaign_plan()
    assert plan["scenes"][0] == "paper-symmetric" and len(plan["scenes"]) == 3
    # the frames with fracturing tendons run where they fracture, in the maps and records
    from rockbench.campaign.plan import every_scene
    assert every_scene(plan) == ["paper-symmetric", "paper-asymmetric", "paper-asymmetric-hybrid",
                                 "paper-asymmetric-hybrid-eps1", "paper-asymmetric-hybrid-eps2"]
    assert plan["pulse_points"] == ((2.0, 3.0), (4.0, 4.0))
    assert "dt_sweep" not in plan             # the decision's work-precision is the speed sweep
    assert "map_A" not in plan and plan["maps"]["analytic_grid"] == (100, 100)
    quick = campaign_plan(quick=True)
    assert quick["scenes"] == ("paper-asymmetric", "paper-asymmetric-hybrid-eps1")
    assert quick["max_records"] == 1 and plan["max_records"] is None
    plan["scenes"] = ()                                  # a copy: the catalogue is unchanged
    assert campaign_plan()["scenes"][0] == "paper-symmetric"
    assert CHECK_SCENE == "housner-block"
    for name in plan["scenes"] + tuple(c.free_durations) + (CHECK_SCENE,):
        rb.load_scene(name)                              # every scene it names exists


def test_the_fracturing_frames_left_out_of_the_comparisons_would_repeat_the_hybrid_frame():
    """The paper's plan compares the hybrid frame case by case but not its eps_f = 1 % and 2 %
    variants: at every pulse point and shape of the plan, and in free rocking, their tendons do
    not fracture in the analytic model, so each case is the hybrid frame's run for run (the
    same peak to the last digit, no fracture)."""
    from rockbench.scene.motion import make_pulse

    plan = campaign_plan()
    hybrid = rb.load_scene("paper-asymmetric-hybrid")
    for name in ("paper-asymmetric-hybrid-eps1", "paper-asymmetric-hybrid-eps2"):
        assert name not in plan["scenes"]
        variant = rb.load_scene(name)
        for A, W in plan["pulse_points"]:
            for shape, sign in plan["pulse_shapes"]:
                runs = [rb.run(sc, make_pulse(shape, sign, structure=sc.structure, A=A, W=W),
                               engine="analytic", duration=8.0, method="compiled").summary
                        for sc in (hybrid, variant)]
                assert not runs[1].fractured
                assert runs[1].max_abs_phi == runs[0].max_abs_phi
        free = [rb.run(sc, None, engine="analytic", duration=plan["free_duration"],
                       phi0=plan["free_phi0"] * sc.alpha, method="compiled").summary
                for sc in (hybrid, variant)]
        assert not free[1].fractured and free[1].max_abs_phi == free[0].max_abs_phi

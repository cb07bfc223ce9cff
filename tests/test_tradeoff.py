"""Work-precision (rockbench.tradeoff) and its figure: logic and physics on small runs."""

import math

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench import tradeoff as T
from rockbench.report.tradeoff_figures import pareto_front, plot_work_precision

BLOCK = rb.load_scene("housner-block")


def _free(scene, f=0.5, duration=2.0):
    return T.ValidationCase("free", f"free+{f}", None, f * scene.alpha, duration, None, f)


def test_settings_grid_and_labels():
    g = T.settings_grid(["pymunk"], [2e-3, 1e-3], ["iterations=50", "mujoco:impratio=10"])
    labels = [s.label for s in g]
    assert labels == ["dt=0.002", "dt=0.001", "dt=0.002,iterations=50", "dt=0.001,iterations=50"]
    assert g[1].refined().label == "dt=0.00025"
    assert T.parse_setting("pymunk:collision_slop=1e-4") == {"__engine__": "pymunk",
                                                             "collision_slop": 1e-4}


def test_case_error_and_classes():
    assert T.case_error({"status": "ok", "kind": "survive", "peak_rel_error": -0.03,
                         "verdict_agrees": True}) == pytest.approx(0.03)
    assert T.case_error({"status": "ok", "kind": "free", "eta_max_rel_error": 0.004,
                         "verdict_agrees": True}) == pytest.approx(0.004)
    # a wrong overturning verdict or a run that is not ok can never pass a tolerance
    assert T.case_error({"status": "ok", "kind": "overturn", "verdict_agrees": False}) == math.inf
    assert T.case_error({"status": "diverged", "kind": "survive", "peak_rel_error": 0.0}) == math.inf
    assert T.classify_error(0.009) == "within 1%"
    assert T.classify_error(0.04) == "within 5%"
    assert T.classify_error(math.inf) == "off"
    assert T.classify_error(0.0, "diverged") == "diverged"


def test_cost_is_cpu_time_of_the_run(monkeypatch):
    """The cost comes from the CPU clock around each run (a fake clock advancing 0.5 s per
    reading), per simulated second, median over the repeats: not the Result's wall time."""
    ticks = iter(np.arange(0.0, 1000.0, 0.5))
    monkeypatch.setattr(T, "cpu_clock", lambda: float(next(ticks)))
    case = _free(BLOCK, duration=1.0)
    t = T.tradeoff(BLOCK, ["pymunk"], dts=[4e-3], repeat=3, cases=[case], executor="serial",
                   self_consistency="none")
    row = t.table.iloc[0]
    assert row["repeats"] == 3
    sim = float(t.runs["sim_time"].iloc[0])
    assert sim == pytest.approx(1.0, rel=1e-3)
    assert row["cpu_per_sim_s"] == pytest.approx(0.5 / sim)
    assert row["real_time_factor"] == pytest.approx(sim / 0.5)
    assert t.runs["cpu_s_median"].iloc[0] == pytest.approx(0.5)


def test_self_consistency_shrinks_with_dt_for_a_converging_engine():
    """pymunk converges on Housner's block: the difference to the same engine at dt / 4 falls
    as dt falls (first order or better), and the error against the analytic model is small."""
    case = _free(BLOCK, duration=2.0)
    t = T.tradeoff(BLOCK, ["pymunk"], dts=[4e-3, 1e-3, 2.5e-4], repeat=1, cases=[case],
                   executor="serial")
    tab = t.table.set_index("dt")
    s_coarse = tab.loc[4e-3, "self_nrmse_worst"]
    s_mid = tab.loc[1e-3, "self_nrmse_worst"]
    assert np.isfinite(s_coarse) and np.isfinite(s_mid)
    assert s_mid < s_coarse / 2
    assert math.isnan(tab.loc[2.5e-4, "self_nrmse_worst"])   # its dt / 4 was not run
    assert (t.table["verdict"] != "diverged").all()
    assert tab.loc[2.5e-4, "worst_error"] < 0.01


def test_validation_set_is_chosen_with_the_analytic_model():
    cases = T.validation_set(BLOCK, quick=True)
    kinds = [c.kind for c in cases]
    assert kinds.count("free") == 1 and kinds.count("survive") >= 3 and kinds.count("overturn") == 1
    for c in cases:
        sc, motion = c.load(BLOCK)
        r = rb.run(sc, motion, duration=c.duration, phi0=c.phi0)
        assert r.summary.overturned == (c.kind == "overturn")
        if c.kind == "survive":
            assert r.summary.uplifted
    # the near-boundary pulse sits at 0.95 of the analytic threshold, which does overturn
    near = [c for c in cases if c.kind == "survive"][1]
    m = dict(near.motion)
    A_ov = T.overturn_threshold(BLOCK, m["W"], m["shape"], m["sign"], rtol=1e-2)
    assert m["A"] == pytest.approx(0.95 * A_ov, rel=1e-3)


def _table():
    return pd.DataFrame({
        "engine": ["a", "a", "a", "b", "b"],
        "setting": ["dt=0.004", "dt=0.002", "dt=0.001", "dt=0.002", "dt=0.001"],
        "dt": [4e-3, 2e-3, 1e-3, 2e-3, 1e-3],
        "worst_error": [0.05, 0.01, 0.002, 0.03, math.inf],
        "self_peak_error_worst": [0.04, 0.01, 0.003, 0.02, np.nan],
        "cpu_per_sim_s": [0.01, 0.02, 0.04, 0.005, 0.01],
        "cpu_per_sim_s_min": [0.009, 0.018, 0.035, 0.004, 0.009],
        "cpu_per_sim_s_max": [0.012, 0.025, 0.05, 0.006, 0.012],
    })


def test_pareto_front():
    t = _table()
    front = set(pareto_front(t))
    # b@2e-3 is the cheapest; a@4e-3 is dominated by it? no: 0.05 > 0.03 at higher cost -> yes
    assert front == {3, 1, 2}


def test_work_precision_figure():
    fig = plot_work_precision(_table(), tolerance=0.02)
    axes = fig.get_axes()
    assert len(axes) == 2
    assert axes[0].get_xscale() == "log" and axes[0].get_yscale() == "log"
    labels = axes[0].get_legend_handles_labels()[1]
    assert {"a", "b", "Pareto front"} <= set(labels)


def test_cli_tradeoff_writes_table_and_figure(tmp_path, capsys):
    import json

    from rockbench.cli import main

    f = tmp_path / "blk.toml"
    f.write_text('name = "blk"\n[structure]\ntype = "block"\nwidth = 1.0\nheight = 4.0\n')
    out = tmp_path / "out"
    code = main(["tradeoff", str(f), "--engines", "pymunk", "--dt", "4e-3", "--repeat", "1",
                 "--quick", "--workers", "1", "--out", str(out), "--json"])
    assert code == 0
    j = json.loads(capsys.readouterr().out)
    assert j["table"][0]["engine"] == "pymunk" and j["table"][0]["cpu_per_sim_s"] > 0
    assert (out / "tradeoff.csv").is_file() and (out / "work_precision.png").is_file()

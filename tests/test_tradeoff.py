"""Work-precision (rockbench.studies.tradeoff) and its figure: logic and physics on small runs."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.studies import tradeoff as T
from rockbench.report.tradeoff_figures import pareto_front, plot_work_precision

BLOCK = rb.load_scene("housner-block")


def _free(scene, f=0.5, duration=2.0):
    return T.ValidationCase("free", f"free+{f}", None, f * scene.alpha, duration, None, f)


def test_settings_grid_and_labels():
    g = T.settings_grid(["pymunk"], [2e-3, 1e-3], ["iterations=50", "mujoco:impratio=10"])
    labels = [s.label for s in g]
    assert labels == ["dt=0.002", "dt=0.001", "dt=0.002,iterations=50", "dt=0.001,iterations=50"]
    assert g[1].refined().label == "dt=0.00025"
    # the older spelling ENGINE:KEY=VALUE reads as ENGINE.KEY=VALUE, typed by the Settings
    from rockbench.engines.setting_text import Overrides, parse_overrides
    for text in ("pymunk:collision_slop=1e-4", "pymunk.collision_slop=1e-4"):
        over = parse_overrides(text)
        assert over.engine == "pymunk" and over.for_engine("pymunk") == {"collision_slop": 1e-4}
    g = T.settings_grid(["pymunk"], [1e-3], ["pymunk:iterations=50", "pymunk.iterations=50"])
    assert [s.label for s in g] == ["dt=0.001", "dt=0.001,iterations=50"]
    assert dict(g[1].overrides)["iterations"] == 50 and isinstance(
        dict(g[1].overrides)["iterations"], int)
    assert T.settings_grid(["pymunk"], [1e-3], [Overrides("pymunk", (("iterations", 50),))]
                           ) == g


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


def test_cost_is_steady_state_cpu_time_with_one_off_costs_apart(monkeypatch):
    """The cost comes from the CPU clock around each run (a fake clock advancing 0.5 s per
    reading), minus the model build (measured apart, here 0.2 s), per simulated second, median
    over the repeats; the process's warm-up run is measured once and shown apart: a second
    setting in the same process has none, and neither enters cpu_per_sim_s."""
    ticks = iter(np.arange(0.0, 1000.0, 0.5))
    monkeypatch.setattr(T, "cpu_clock", lambda: float(next(ticks)))
    monkeypatch.setattr(T, "_build_cpu", lambda *a, **k: 0.2)
    monkeypatch.setattr(T, "_WARMED", {})
    case = _free(BLOCK, duration=1.0)
    t = T.tradeoff(BLOCK, ["pymunk"], dts=[4e-3], repeat=3, cases=[case], executor="serial",
                   self_consistency="none")
    row = t.table.iloc[0]
    assert row["repeats"] == 3
    sim = float(t.runs["sim_time"].iloc[0])
    assert sim == pytest.approx(1.0, rel=1e-3)
    assert row["cpu_per_sim_s"] == pytest.approx(0.3 / sim)
    assert row["real_time_factor"] == pytest.approx(sim / 0.3)
    assert row["build_cpu_s"] == pytest.approx(0.2) and row["warmup_cpu_s"] == pytest.approx(0.5)
    t2 = T.tradeoff(BLOCK, ["pymunk"], dts=[4e-3, 2e-3], repeat=1, cases=[case],
                    executor="serial", self_consistency="none").table.set_index("dt")
    assert math.isnan(t2.loc[4e-3, "warmup_cpu_s"])          # warmed up already
    assert t2.loc[2e-3, "warmup_cpu_s"] == pytest.approx(0.5)   # a new setting: once
    assert t2.loc[2e-3, "cpu_per_sim_s"] == pytest.approx(0.3 / sim)


def test_case_error_near_the_boundary_and_records_outside_their_band():
    # a wrong verdict near the boundary is reported (NaN: not counted), away from it is wrong
    near = {"status": "ok", "kind": "survive", "peak_rel_error": 0.5, "verdict_agrees": False,
            "near_boundary": True}
    assert math.isnan(T.case_error(near))
    assert T.case_error({**near, "near_boundary": False}) == math.inf
    # a record is judged by the distance of its peak to the analytic model's own sensitivity
    # band: inside it, 0 (however far from the unperturbed peak); outside, the distance
    rec = {"status": "ok", "kind": "record", "peak_rel_error": 0.24, "verdict_agrees": True,
           "in_band": True, "band_distance": 0.0}
    assert T.case_error(rec) == 0.0
    out = {**rec, "peak_rel_error": 0.65, "in_band": False, "band_distance": 0.114}
    assert T.case_error(out) == pytest.approx(0.114)
    assert T.case_error({**out, "band_distance": -0.03}) == pytest.approx(0.03)   # below it


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
    kinds = {c.group.split(":")[0] for c in cases}
    assert kinds == {"free", "away", "near", "overturn", "record"}
    for c in cases:
        sc, motion = c.load(BLOCK)
        if c.kind == "record":
            continue          # records: the compiled reference, checked in test_sensitivity
        r = rb.run(sc, motion, duration=c.duration, phi0=c.phi0)
        assert r.summary.overturned == (c.kind == "overturn")
        if c.kind == "survive":
            assert r.summary.max_abs_phi_over_alpha >= 0.05     # MIN_PEAK: a real uplift
    # near-boundary cells sit within NEAR_MARGIN of the analytic threshold, on either side
    from rockbench.studies.validation import NEAR_MARGIN
    for c in cases:
        if c.group == "near":
            m = dict(c.motion)
            A_ov = T.overturn_threshold(BLOCK, m["W"], m["shape"], m["sign"])
            assert abs(m["A"] / A_ov - 1) <= NEAR_MARGIN and c.near_boundary


def _phys(cases):
    return {json.dumps(c.physics(), sort_keys=True) for c in cases}


def test_split_is_disjoint_deterministic_and_seeded():
    a = T.validation_set(BLOCK)
    names = [c.name for c in a]
    assert len(names) == len(set(names))
    choice = {c.name for c in a if c.part == "choice"}
    held = {c.name for c in a if c.part == "held-out"}
    assert choice and held and not choice & held and choice | held == set(names)
    # every group of two or more cases has cases in both parts
    for g in ("free", "away", "near", "overturn"):
        parts = {c.part for c in a if c.group.split(":")[0] == g}
        assert parts == {"choice", "held-out"}, g
    # deterministic: rebuilt from scratch (caches cleared), the same split
    from rockbench.studies import validation as V
    V._validation_set.cache_clear()
    V._make_case.cache_clear()
    assert [(c.name, c.part) for c in T.validation_set(BLOCK)] == [(c.name, c.part) for c in a]
    # another seed: another order, hence another split or selection
    b = T.validation_set(BLOCK, seed=7)
    assert [(c.name, c.part) for c in b] != [(c.name, c.part) for c in a]
    with pytest.raises(rb.ParameterError):
        T.validation_set(BLOCK, size="huge")


def test_a_mirror_symmetric_structure_has_no_mirror_twins_in_its_evidence():
    """On Housner's block (its own mirror image) a case and its sign-flipped twin are the same
    physics: the evidence keeps one sign, so no held-out case mirrors a choice case. The
    asymmetric frame keeps both signs."""
    from rockbench.studies.map_cells import reversed_mirrors

    assert reversed_mirrors(BLOCK) and not reversed_mirrors(BLOCK, 0.3)
    assert not reversed_mirrors(rb.load_scene("paper-asymmetric"))
    assert reversed_mirrors("paper-symmetric")
    for c in T.validation_set(BLOCK, size="full"):
        if c.motion is None:
            assert c.phi0 > 0
        else:
            m = dict(c.motion)
            assert m.get("sign", 1) == 1 and m.get("scale", 1.0) > 0


def test_quick_is_a_subset_of_default_and_full():
    q, d, f = (T.validation_set(BLOCK, size=s) for s in ("quick", "default", "full"))
    assert _phys(q) <= _phys(d) <= _phys(f)       # the same cells, to the digit
    assert len(q) < len(d) < len(f)


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

    from rockbench.cli.main import main

    f = tmp_path / "blk.toml"
    f.write_text('name = "blk"\n[structure]\ntype = "block"\nwidth = 1.0\nheight = 4.0\n')
    out = tmp_path / "out"
    code = main(["tradeoff", str(f), "--engines", "pymunk", "--dt", "4e-3", "--repeat", "1",
                 "--quick", "--workers", "1", "--out", str(out), "--json"])
    assert code == 0
    j = json.loads(capsys.readouterr().out)
    assert j["table"][0]["engine"] == "pymunk" and j["table"][0]["cpu_per_sim_s"] > 0
    assert (out / "tradeoff.csv").is_file() and (out / "work_precision.png").is_file()


def test_the_evidence_stays_within_the_model_no_sliding():
    """A case whose peak ground acceleration exceeds mu g (mu = 1, the engines' default
    friction) is outside the analytic model (its pivots would slide): left out of the evidence
    like a case that barely rocks. A squat cabinet keeps free rocking and its pulses below 1 g;
    a slender frame keeps its overturning cases."""
    from rockbench.scene.motion import RickerPulse
    from rockbench.scene.scene import Scene
    from rockbench.validity import pga_limit

    squat = Scene.from_dict({"name": "cabinet", "structure": {
        "type": "block", "width": 1.0, "height": 1.6, "depth": 0.8, "density": 900.0}})

    def peaks(scene, size):
        out = []
        for c in T.validation_set(scene, size=size):
            m = dict(c.motion or {})
            if m.get("kind") == "ricker":
                out.append(RickerPulse.dimensionless(m["A"], m["W"], scene.structure,
                                                     m["shape"], m["sign"]).peak)
        return out, T.validation_set(scene, size=size)

    from rockbench.studies.validation import candidate_cases

    strong = [n for g, n in candidate_cases(squat) if " A=" in n
              and float(n.split("A=")[1]) * math.tan(squat.alpha) * 9.81 > 1.5 * pga_limit(squat)]
    assert len(strong) > 10                      # the catalogue has them: the rule is at work
    p, cases = peaks(squat, "default")
    assert pga_limit(squat) == pytest.approx(9.81)          # mu = 1: the default friction
    assert p and max(p) <= pga_limit(squat)
    assert not {c.name for c in cases} & set(strong)
    assert [c for c in cases if c.motion is None]               # free rocking stays
    p, cases = peaks(rb.load_scene("paper-asymmetric"), "default")
    assert max(p) <= pga_limit(squat) and [c for c in cases if c.kind == "overturn"]

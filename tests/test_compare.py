"""rockbench.comparison: metrics against the analytic reference, one case across backends."""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.analytic.reference import Reference
from rockbench.comparison import (ETA_COLUMNS, METRIC_COLUMNS, REFERENCE, Comparison, compare,
                               eta_rows, metrics)
from rockbench.engines import REGISTRY, available_backends

ROOT = Path(__file__).resolve().parents[1]
BLOCK = rb.load_scene("housner-block")
PULSE = rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=BLOCK.structure)
needs_pymunk = pytest.mark.skipif("pymunk" not in available_backends(),
                                  reason="pymunk not installed")


@pytest.fixture(scope="module")
def ref():
    return rb.run(BLOCK, PULSE, duration=3.0)


@pytest.fixture(scope="module")
def free_frame():
    """Free rocking of the asymmetric frame (eta_ccw != eta_cw)."""
    sc = rb.load_scene("paper-asymmetric")
    return rb.run(sc, None, phi0=0.5 * sc.alpha, duration=4.0)


def _with_phi(r, phi, t=None):
    h = r.history.copy()
    h["phi"] = phi
    if t is not None:
        h["t"] = t
    mx = float(np.max(np.abs(phi)))
    s = replace(r.summary, max_abs_phi=mx, max_abs_phi_over_alpha=mx / r.scene.alpha)
    return replace(r, backend="fake", history=h, summary=s)


def _with_eta(r, etas):
    ev = r.events.copy()
    idx = ev.index[ev["kind"] == "impact"]
    ev.loc[idx, "eta"] = etas
    return replace(r, backend="fake", events=ev)


# --- the reference against itself ------------------------------------------------------
def test_reference_row_is_exact(ref):
    row = metrics(ref, ref)
    assert list(row) == list(METRIC_COLUMNS)
    assert row["peak_rel_error"] == 0.0 and row["nrmse"] == 0.0
    assert row["max_abs_error_over_alpha"] == 0.0
    assert row["t_uplift_error"] == 0.0 and row["t_first_impact_error"] == 0.0
    assert row["n_impacts"] == row["n_impacts_ref"] == ref.summary.n_impacts >= 1
    assert row["eta_max_rel_error"] == 0.0
    assert row["verdict_agrees"] and row["energy_gained_at_impact"] is False
    # Housner's block: eta = 1 - 1.5 sin^2(alpha) in both directions
    assert row["eta_ccw_ref"] == pytest.approx(BLOCK.structure.eta_housner, rel=1e-12)
    assert row["eta_cw_ref"] == pytest.approx(BLOCK.structure.eta_housner, rel=1e-12)


# --- history metrics on a common grid ---------------------------------------------------
def test_scaled_history_gives_exact_peak_and_nrmse(ref):
    phi = ref.history["phi"].to_numpy()
    fake = _with_phi(ref, 1.1 * phi)
    row = metrics(fake, ref)
    assert row["peak_rel_error"] == pytest.approx(0.1, rel=1e-9)
    expect = 0.1 * np.sqrt(np.mean(phi ** 2)) / BLOCK.alpha
    assert row["nrmse"] == pytest.approx(expect, rel=1e-9)
    assert row["max_abs_error_over_alpha"] == pytest.approx(0.1 * np.max(np.abs(phi)) /
                                                            BLOCK.alpha, rel=1e-9)


def test_engine_history_is_interpolated_onto_the_reference_grid(ref):
    """A history sampled half a step later, from the same smooth phi(t): the interpolation
    error is second order, far below the error of comparing sample by sample."""
    t = ref.history["t"].to_numpy()
    tt = t + 0.5 * (t[1] - t[0])
    phi_shifted = np.interp(tt, t, ref.history["phi"].to_numpy())
    fake = _with_phi(ref, phi_shifted, t=tt)
    naive = np.sqrt(np.mean((phi_shifted - ref.history["phi"].to_numpy()) ** 2)) / BLOCK.alpha
    row = metrics(fake, ref)
    assert row["nrmse"] < 0.05 * naive
    assert row["nrmse"] < 1e-5


def test_metrics_stop_at_the_earlier_end(ref):
    """A run that stops early (overturned) is compared until it stops, not padded: a large
    difference after its end is never seen."""
    from rockbench.comparison import history_error

    half = len(ref.history) // 2
    phi = ref.history["phi"].to_numpy().copy()
    phi[half + 10:] += 0.5 * BLOCK.alpha
    fake = _with_phi(ref, phi)
    assert metrics(fake, ref)["nrmse"] > 0.1
    short = replace(fake, history=fake.history.iloc[:half].reset_index(drop=True))
    t, err = history_error(short, ref)
    assert t[-1] == short.history["t"].iloc[-1] and t.size == half
    assert metrics(short, ref)["nrmse"] == 0.0
    # symmetric: a short reference limits the grid the same way
    assert history_error(ref, replace(ref, history=short.history))[0].size == half


# --- eta ----------------------------------------------------------------------------------
def test_eta_rows_use_the_analytic_eta_of_the_direction(free_frame):
    r = free_frame
    R = Reference(r.scene)
    assert R.eta[1] != pytest.approx(R.eta[-1], rel=1e-3)  # the test needs distinct etas
    etas = [0.95 * R.eta[int(d)] for d in r.impacts()["direction"]]
    rows = eta_rows(_with_eta(r, etas), r)
    assert [k["impact"] for k in rows] == list(range(len(etas))) and len(rows) >= 2
    for k, ev in zip(rows, r.impacts().itertuples(), strict=True):
        assert k["direction"] == ev.direction
        assert k["eta_ref"] == R.eta[ev.direction]
        assert k["rel_error"] == pytest.approx(-0.05, abs=1e-12)
    row = metrics(_with_eta(r, etas), r)
    assert row["eta_max_rel_error"] == pytest.approx(0.05, abs=1e-12)
    assert row["eta_ccw_mean"] == pytest.approx(0.95 * R.eta[1])
    assert row["eta_cw_mean"] == pytest.approx(0.95 * R.eta[-1])


def test_energy_gain_accounts_for_the_inertia_of_each_direction(free_frame):
    """Asymmetric frame: I_ccw(0) > I_cw(0), so an impact into ccw rocking with
    eta > sqrt(I_cw / I_ccw) ~ 0.9925 gains kinetic energy although eta < 1."""
    r = free_frame
    R = Reference(r.scene)
    i_ccw, i_cw = (R.dyn[s].terms(0.0).inertia for s in (1, -1))
    assert i_ccw > i_cw
    dirs = r.impacts()["direction"].to_list()
    assert dirs[:2] == [-1, 1]
    eta_gain = 0.5 * (1 + math.sqrt(i_cw / i_ccw))
    assert metrics(_with_eta(r, [R.eta[-1], eta_gain]), r)["energy_gained_at_impact"] is True
    # the same eta into cw rocking loses energy
    assert metrics(_with_eta(r, [eta_gain, R.eta[1]]), r)["energy_gained_at_impact"] is False
    assert metrics(_with_eta(r, [1.0, R.eta[1]]), r)["energy_gained_at_impact"] is True


# --- whole comparisons ----------------------------------------------------------------------
def test_reference_only_comparison():
    c = compare(BLOCK, PULSE, engines=[REFERENCE], duration=3.0)
    assert isinstance(c, Comparison)
    assert list(c.results) == [REFERENCE] and list(c.table["backend"]) == [REFERENCE]
    assert list(c.table.columns) == list(METRIC_COLUMNS)
    assert list(c.eta.columns) == list(ETA_COLUMNS)
    assert c.motion == PULSE.describe() and c.phi0 == 0.0


@needs_pymunk
def test_pymunk_agrees_with_the_reference_on_the_block():
    c = compare(BLOCK, PULSE, engines=["pymunk"], duration=3.0)
    assert list(c.results) == [REFERENCE, "pymunk"]
    row = c.table.set_index("backend").loc["pymunk"]
    assert row["status"] == "ok" and row["engine_version"].startswith("pymunk")
    assert abs(row["peak_rel_error"]) < 0.01
    assert row["nrmse"] < 0.005
    assert bool(row["verdict_agrees"]) and not bool(row["energy_gained_at_impact"])
    assert 0 <= row["max_penetration"] < 1e-3 and 0 <= row["max_sliding"] < 1e-3
    assert not bool(row["contact_opened"])
    assert row["steps"] == 3000 and row["real_time_factor"] > 0
    assert abs(row["t_first_impact_error"]) < 0.01
    assert set(c.eta["backend"]) == {REFERENCE, "pymunk"}


@needs_pymunk
def test_both_overturn_gives_an_overturn_time_error():
    sc = rb.Scene(rb.Block(width=1.0, height=4.0), name="b14")
    pulse = rb.RickerPulse.dimensionless(A=5.0, W=5.0, structure=sc.structure)
    c = compare(sc, pulse, engines=["pymunk"], duration=5.0)
    row = c.table.set_index("backend").loc["pymunk"]
    assert bool(row["overturned"]) and bool(row["overturned_ref"]) and bool(row["verdict_agrees"])
    assert abs(row["t_overturn_error"]) < 0.05
    ref_row = c.table.set_index("backend").loc[REFERENCE]
    assert ref_row["t_overturn_error"] == 0.0


@needs_pymunk
def test_a_diverged_backend_keeps_its_row_with_nan_physics():
    c = compare(BLOCK, None, phi0=0.5 * BLOCK.alpha, duration=1.0, engines=["pymunk"],
                settings={"pymunk": {"max_penetration": 1e-12}})
    row = c.table.set_index("backend").loc["pymunk"]
    assert row["status"] == "diverged" and "penetration" in row["reason"]
    for col in ("peak_rel_error", "nrmse", "eta_max_rel_error", "max_abs_phi_over_alpha",
                "max_penetration"):
        assert math.isnan(row[col]), col
    assert pd.isna(row["overturned"]) and pd.isna(row["verdict_agrees"])
    assert row["wall_s"] >= 0 and row["steps"] >= 1        # the cost is still reported
    assert row["n_impacts_ref"] == c.results[REFERENCE].summary.n_impacts
    assert "pymunk" not in set(c.eta["backend"])


def test_an_unavailable_backend_gets_a_row(monkeypatch):
    monkeypatch.setitem(REGISTRY, "ghost", "rockbench_no_such_module:Ghost")
    c = compare(BLOCK, PULSE, engines=["ghost"], duration=2.0)
    row = c.table.set_index("backend").loc["ghost"]
    assert row["status"] == "unavailable" and "ghost" in row["reason"]
    assert math.isnan(row["nrmse"]) and "ghost" not in c.results


def test_tables_round_trip_through_csv_and_parquet(tmp_path, free_frame):
    c = compare(free_frame.scene, None, phi0=0.5 * free_frame.scene.alpha, duration=3.0,
                engines=[REFERENCE])
    csvs = c.to_csv(tmp_path / "csv")
    assert [p.name for p in csvs] == ["metrics.csv", "eta.csv", "history.csv"]
    back = pd.read_csv(csvs[0])
    assert list(back.columns) == list(METRIC_COLUMNS)
    assert back["nrmse"].iloc[0] == 0.0
    assert len(pd.read_csv(csvs[1])) == len(c.eta) == 2
    hist = pd.read_csv(csvs[2])
    assert len(hist) == len(c.results[REFERENCE].history)
    pq = c.to_parquet(tmp_path / "pq")
    t2 = pd.read_parquet(pq[0])
    assert t2["overturned"].dtype == "boolean" and t2["steps"].dtype == "Int64"
    pd.testing.assert_frame_equal(t2, c.table, check_dtype=False)


def test_bad_input_names_the_parameter(ref):
    with pytest.raises(rb.ParameterError, match="scene"):
        compare("housner-block")
    with pytest.raises(rb.ParameterError, match="engines"):
        compare(BLOCK, PULSE, engines=["nope"])
    with pytest.raises(rb.ParameterError, match="settings"):
        compare(BLOCK, PULSE, engines=[REFERENCE], settings={"nope": {}})
    with pytest.raises(rb.ParameterError, match="result"):
        metrics(1, ref)


def test_every_column_is_documented():
    doc = (ROOT / "docs" / "metrics.md").read_text()
    for col in list(METRIC_COLUMNS) + list(ETA_COLUMNS):
        assert re.search(rf"`{re.escape(col)}`", doc), f"{col} missing from docs/metrics.md"
    for col, text in {**METRIC_COLUMNS, **ETA_COLUMNS}.items():
        unit = text.split(",")[0]
        assert unit in ("-", "s", "m", "s/s"), f"{col}: unit {unit!r}"


# --- fracture (issue 14) -------------------------------------------------------------------
@pytest.fixture(scope="module")
def fracture_run():
    """The eps_f = 1 % hybrid frame under an antisymmetric pulse 1.27 x its overturning
    threshold (A = 8, W = 2): the tendons fracture, then the frame overturns."""
    sc = rb.load_scene("paper-asymmetric-hybrid-eps1")
    m = rb.RickerPulse.dimensionless(A=8.0, W=2.0, structure=sc.structure,
                                     shape="antisymmetric", sign=1)
    return rb.run(sc, m)


def test_fracture_metrics(fracture_run, ref):
    r = fracture_run
    assert r.summary.fractured and r.summary.overturned
    assert r.summary.t_fracture < r.summary.t_overturn
    row = metrics(r, r)
    assert row["fractured"] and row["fractured_ref"] and row["fracture_agrees"]
    assert row["t_fracture_error"] == 0.0
    late = replace(r, backend="fake", summary=replace(r.summary,
                                                      t_fracture=r.summary.t_fracture + 0.01))
    assert metrics(late, r)["t_fracture_error"] == pytest.approx(0.01, abs=1e-12)
    intact = replace(r, backend="fake", summary=replace(r.summary, fractured=False,
                                                        t_fracture=None))
    row = metrics(intact, r)
    assert row["fractured"] is False and row["fractured_ref"] is True
    assert row["fracture_agrees"] is False and math.isnan(row["t_fracture_error"])
    # a scene without devices never fractures: the metrics say so, and agree
    row = metrics(ref, ref)
    assert row["fractured"] is False and row["fracture_agrees"] is True


def test_compare_is_a_function_of_the_package_and_a_comparison_reads_well():
    """`rb.compare(...)` is the function (the module is rockbench.comparison), and a
    Comparison's repr is one line per backend, not the whole scene."""
    import rockbench as rb
    import rockbench.comparison  # noqa: F401 - importing the module must not shadow it

    assert callable(rb.compare) and rb.compare is rockbench.comparison.compare
    sc = rb.load_scene("housner-block")
    c = rb.compare(sc, None, engines=["analytic"], phi0=0.05, duration=0.5)
    text = repr(c)
    assert text.startswith("<Comparison of 1 backends on 'housner-block' (free rocking")
    assert "analytic: ok" in text and "Block(" not in text and len(text) < 300
    assert "<table" in c._repr_html_()

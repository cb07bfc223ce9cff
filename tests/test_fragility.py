"""Fragility (issue 26, docs/fragility.md): the lognormal MLE, the record bootstrap, the censored
KS test, the verdicts, the resumable driver and the ``rockbench fragility`` command."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from rockbench.errors import ParameterError
from rockbench.studies.ensembles import resolve_records
from rockbench.studies.fragility import parse_scales, run_fragility
from rockbench.studies.fragility_stats import (_holm, analyse, bootstrap, fit_lognormal,
                                               fragility_curve, peak_test)
from rockbench.studies.intensity import (MEASURES, Structure, intensity,
                                         pseudo_spectral_acceleration, strong_motion_end)
from rockbench.scene.motion import Record


# ---------------------------------------------------------------------------------------------
# synthetic ensembles
# ---------------------------------------------------------------------------------------------
def _ensemble(capacities, scales, backend="analytic", im_of_record=1.0):
    """Runs of records whose capacity (the intensity at which they overturn) is known: a run
    overturns iff its intensity >= the record's capacity; survivors peak at 0.8 im/capacity."""
    rows = []
    for r, c in enumerate(capacities):
        for pol in (1, -1):
            for s in scales:
                im = s * im_of_record
                ot = im >= c
                rows.append({"backend": backend, "record": f"R{r:03d}", "polarity": pol,
                             "scale": float(s), "im": im, "peak": 1.2 if ot else 0.8 * im / c,
                             "overturned": bool(ot), "status": "ok", "cpu_s": 0.0})
    return pd.DataFrame(rows)


def _quantile_capacities(n, median, beta):
    """n capacities at the (k + 1/2)/n quantiles of a lognormal (deterministic)."""
    return median * np.exp(beta * norm.ppf((np.arange(n) + 0.5) / n))


# ---------------------------------------------------------------------------------------------
# the MLE
# ---------------------------------------------------------------------------------------------
def test_mle_recovers_a_known_lognormal():
    """Binomial counts drawn exactly at P = Phi(ln(x/theta)/beta) (400 runs at each of 12
    intensities): the fit returns theta and beta."""
    theta, beta = 3.0, 0.45
    x = np.geomspace(0.8, 9.0, 12)
    im, ot = [], []
    for xi in x:
        z = int(round(400 * float(norm.cdf(np.log(xi / theta) / beta))))
        im += [xi] * 400
        ot += [True] * z + [False] * (400 - z)
    f = fit_lognormal(im, ot)
    assert f["median"] == pytest.approx(theta, rel=0.01)
    assert f["dispersion"] == pytest.approx(beta, rel=0.02)
    assert f["n"] == 4800 and f["note"] == ""
    np.testing.assert_allclose(fragility_curve([theta], f["median"], f["dispersion"]), [0.5],
                               atol=1e-3)


@pytest.mark.parametrize("threshold", [1.7, 2.5, 6.0])
def test_a_separable_dataset_puts_the_median_between_its_last_survivor_and_first_overturn(
        threshold):
    """Synthetic, perfectly separable verdicts (overturn iff IM >= threshold) at uneven
    intensities: the fitted median lies between the largest surviving and the smallest
    overturning intensity, the curve is monotone, below 1/2 at every survivor and above it at
    every overturn."""
    im = np.array([0.4, 0.9, 1.3, 1.6, 1.8, 2.2, 2.45, 2.6, 3.1, 4.0, 5.5, 6.5, 8.0])
    ot = im >= threshold
    f = fit_lognormal(np.repeat(im, 3), np.repeat(ot, 3))
    lo, hi = im[~ot].max(), im[ot].min()
    assert lo <= f["median"] <= hi, (f, lo, hi)
    x = np.geomspace(0.3, 10.0, 200)
    p = fragility_curve(x, f["median"], f["dispersion"])
    assert np.all(np.isfinite(p)) and np.all(np.diff(p) >= 0) and p[0] < p[-1]
    pi = fragility_curve(im, f["median"], f["dispersion"])
    assert (pi[~ot] <= 0.5).all() and (pi[ot] >= 0.5).all()


def test_overlapping_verdicts_put_the_median_where_they_flip():
    """Verdicts that overlap (the first overturn at 2, the last survivor at 4): the median
    lies inside [2, 4], the dispersion is positive and finite, P rises monotonically from
    below the first overturn's share to above the last survivor's."""
    im = [1.0] * 4 + [2.0] * 4 + [3.0] * 4 + [4.0] * 4 + [5.0] * 4
    ot = [False] * 4 + [True, False, False, False] + [True, True, False, False] + \
        [True, True, True, False] + [True] * 4
    f = fit_lognormal(im, ot)
    assert 2.0 <= f["median"] <= 4.0 and f["median"] == pytest.approx(3.0, rel=0.1)
    assert 0.0 < f["dispersion"] < 2.0 and f["note"] == ""
    p = fragility_curve([1.0, 2.0, 3.0, 4.0, 5.0], f["median"], f["dispersion"])
    assert np.all(np.diff(p) > 0) and p[0] < 0.25 and p[-1] > 0.75


def test_mle_degenerate_and_bad_inputs():
    none = fit_lognormal([1.0, 2.0, 3.0], [False, False, False])
    assert math.isnan(none["median"]) and "above the largest intensity 3" in none["note"]
    every = fit_lognormal([1.0, 2.0], [True, True])
    assert math.isnan(every["median"]) and "below the smallest intensity 1" in every["note"]
    step = fit_lognormal([1.0, 2.0, 3.0, 4.0], [False, False, True, True])
    assert 2.0 <= step["median"] <= 3.0 and "step" in step["note"]
    with pytest.raises(ParameterError, match="im"):
        fit_lognormal([0.0, 1.0], [False, True])
    with pytest.raises(ParameterError, match="im"):
        fit_lognormal([1.0], [False, True])


# ---------------------------------------------------------------------------------------------
# the bootstrap
# ---------------------------------------------------------------------------------------------
def test_bootstrap_is_seeded_and_brackets_the_truth():
    theta, beta = 2.0, 0.4
    runs = _ensemble(_quantile_capacities(40, theta, beta), np.linspace(0.5, 5.0, 10))
    a = bootstrap(runs, n_boot=150, seed=3)["analytic"]
    b = bootstrap(runs, n_boot=150, seed=3)["analytic"]
    c = bootstrap(runs, n_boot=150, seed=4)["analytic"]
    assert a["median_ci"] == b["median_ci"] and a["median_ci"] != c["median_ci"]
    lo, hi = a["median_ci"]
    assert lo < theta < hi and hi - lo < 0.6 * theta
    assert a["dispersion_ci"][0] < beta < a["dispersion_ci"][1]
    assert a["n_valid"] == 150
    # the curve's band holds the true curve where it is informative (P between 10 and 90 %)
    grid = np.asarray(a["grid"])
    true = norm.cdf(np.log(grid / theta) / beta)
    mid = (true > 0.1) & (true < 0.9)
    assert np.all(np.asarray(a["band"]["low"])[mid] <= true[mid] + 1e-9)
    assert np.all(np.asarray(a["band"]["high"])[mid] >= true[mid] - 1e-9)


@pytest.mark.slow
def test_bootstrap_interval_covers_the_truth_at_about_the_nominal_rate():
    """100 ensembles of 30 records with lognormal capacities (seeded): the 95 % percentile
    interval of the median holds the true median in 85-99 % of them (the nominal 95 %, with the
    binomial spread of 100 trials and the percentile bootstrap's small-sample bias)."""
    theta, beta = 2.0, 0.4
    rng = np.random.default_rng(12345)
    hits = 0
    for k in range(100):
        caps = theta * np.exp(beta * rng.standard_normal(30))
        runs = _ensemble(caps, np.linspace(0.5, 5.0, 10))
        lo, hi = bootstrap(runs, n_boot=200, seed=k)["analytic"]["median_ci"]
        hits += lo <= theta <= hi
    assert 85 <= hits <= 99


# ---------------------------------------------------------------------------------------------
# the test of the peaks
# ---------------------------------------------------------------------------------------------
def test_ks_on_identical_samples_gives_p_one():
    p = np.linspace(0.05, 0.9, 17)
    ot = np.zeros(17, bool)
    ot[-3:] = True
    t = peak_test(p, ot, p, ot)
    assert t["statistic"] == 0.0 and t["p_value"] == 1.0 and t["n_a"] == t["n_b"] == 17


def test_ks_censors_overturned_runs_above_every_survivor():
    """An overturned run is above every survivor, whatever angle it stopped at: two samples
    that differ only in where their overturned runs stopped are identical (without the rule
    the distance would be 1/3)."""
    t = peak_test([0.1, 0.2, 0.05], [False, False, True], [0.1, 0.2, 3.0], [False, False, True])
    assert t["statistic"] == 0.0 and t["p_value"] == 1.0
    far = peak_test(np.linspace(0.1, 0.2, 20), np.zeros(20, bool),
                    np.linspace(0.5, 0.6, 20), np.zeros(20, bool))
    assert far["statistic"] == 1.0 and far["p_value"] < 1e-6


def test_holm():
    assert _holm([0.01, 0.04, 0.03, 0.5]).tolist() == [True, False, False, False]
    assert _holm([0.001, 0.012, 0.02, math.nan]).tolist() == [True, True, True, False]


# ---------------------------------------------------------------------------------------------
# verdicts
# ---------------------------------------------------------------------------------------------
def test_an_identical_engine_is_indistinguishable_and_a_weaker_one_is_not():
    caps = _quantile_capacities(20, 2.0, 0.4)
    scales = np.linspace(0.5, 5.0, 10)
    ref = _ensemble(caps, scales)
    same = _ensemble(caps, scales, backend="twin")
    weak = _ensemble(caps / 2.0, scales, backend="weak")   # overturns at half the intensity
    a = analyse(pd.concat([ref, same, weak]), n_boot=100)
    tw, wk = a["backends"]["twin"], a["backends"]["weak"]
    assert tw["indistinguishable"] is True and tw["p_value"] == 1.0
    assert tw["median_difference"] == 0.0 and tw["median_difference_ci"] == [0.0, 0.0]
    assert "statistically indistinguishable" in tw["verdict"]
    assert wk["indistinguishable"] is False and wk["p_value"] < 1e-3
    assert wk["median_difference"] == pytest.approx(-1.0, rel=0.1)
    assert wk["median_difference_ci"][1] < 0
    assert "distinguishable" in wk["verdict"] and "scale" in wk["verdict"]
    assert a["intensity"]["name"] == "PGA" and a["intensity"]["unit"] == "m/s^2"


# ---------------------------------------------------------------------------------------------
# inputs
# ---------------------------------------------------------------------------------------------
def test_intensity_measures_of_a_sine():
    """a = A sin(w t) over whole periods: PGA = A, PGV = max |A (1 - cos w t) / w| = 2 A / w;
    the dimensionless ones divide them by g tan alpha and p g tan alpha of the structure."""
    A, w, dt = 2.5, 2 * math.pi, 1e-4
    t = np.arange(0.0, 3.0 + dt / 2, dt)
    rec = Record(t, A * np.sin(w * t))
    st = Structure(alpha=0.2, p=1.5)
    assert intensity(rec, "pga") == pytest.approx(A, rel=1e-6)
    assert intensity(rec, "pgv") == pytest.approx(2 * A / w, rel=1e-6)
    assert intensity(rec, "pga_norm", st) == pytest.approx(A / (9.81 * math.tan(0.2)), rel=1e-6)
    assert intensity(rec, "pgv_norm", st) == pytest.approx(
        2 * A / w / (1.5 * 9.81 * math.tan(0.2)), rel=1e-6)
    assert st.period == pytest.approx(2 * math.pi / 1.5)
    assert MEASURES["pgv"][:2] == ("PGV", "m/s") and MEASURES["pga_norm"][1] == "-"
    assert MEASURES["sa"][1] == "m/s^2"
    with pytest.raises(ParameterError, match="structure"):
        intensity(rec, "sa")                      # Sa needs the structure's period
    with pytest.raises(ParameterError, match="intensity"):
        intensity(rec, "pgd")
    with pytest.raises(ParameterError, match="alpha"):
        Structure(alpha=2.0, p=1.0)


def test_sa_is_the_steady_state_of_a_damped_oscillator():
    """A long sine a = A sin(w t), faded in and out over 100 s (so that no transient beats above
    the steady state): the 5 %-damped oscillator of period T settles at amplitude
    A / sqrt((wn^2 - w^2)^2 + (2 z wn w)^2), so Sa = wn^2 times it, below, near and above
    resonance; a record of zeros has Sa 0."""
    A, w, z = 1.7, 2 * math.pi * 0.5, 0.05
    dt = 0.01
    t = np.arange(0.0, 400.0, dt)
    edge = np.minimum(t, 400.0 - t)
    fade = np.where(edge < 100.0, 0.5 * (1.0 - np.cos(math.pi * edge / 100.0)), 1.0)
    rec = Record(t, A * fade * np.sin(w * t))
    for T in (1.0, 2.1, 2 * math.pi / 1.44, 8.0):
        wn = 2 * math.pi / T
        exact = wn ** 2 * A / math.hypot(wn ** 2 - w ** 2, 2 * z * wn * w)
        assert pseudo_spectral_acceleration(rec, T) == pytest.approx(exact, rel=0.005), T
    assert pseudo_spectral_acceleration(Record(t[:50], np.zeros(50)), 1.0) == 0.0
    # the strong-motion end: a record whose energy is all in its first half ends there
    half = np.where(t < 200.0, np.sin(w * t), 0.0)
    assert strong_motion_end(Record(t, half)) == pytest.approx(0.95 * 200.0, abs=1.0)


def test_scales():
    assert parse_scales("0.5:2:4").tolist() == [0.5, 1.0, 1.5, 2.0]
    assert parse_scales("1:1:1").tolist() == [1.0]
    assert parse_scales([2, 1, 1]).tolist() == [1.0, 2.0]
    for bad in ("0:1:3", "2:1:3", "1:2", "a:b:c", "1:2:0", [0.0], [-1.0]):
        with pytest.raises(ParameterError, match="scales"):
            parse_scales(bad)


def _write_tiny_records(folder):
    """Two short headerless records (cm/s^2, dt 0.01 s) and their records.csv."""
    folder.mkdir(parents=True, exist_ok=True)
    t = np.arange(0.0, 2.0, 0.01)
    for name, f in (("TINY1", 2.0), ("TINY2", 3.0)):
        a = 150.0 * np.sin(2 * math.pi * f * t) * np.exp(-t)
        np.savetxt(folder / f"{name}.dat", a.reshape(-1, 4), fmt="%.6e")
    (folder / "records.csv").write_text("record,npts,dt_s,units\nTINY1,200,0.01,cm/s^2\n"
                                        "TINY2,200,0.01,cm/s^2\n")
    return folder


def test_resolve_records(tmp_path):
    d = _write_tiny_records(tmp_path / "recs")
    assert [r["name"] for r in resolve_records(d)] == ["TINY1", "TINY2"]
    one = resolve_records([d / "TINY2.dat", d])            # a file, then its folder: once each
    assert [r["name"] for r in one] == ["TINY2", "TINY1"] and one[0]["dt"] == 0.01
    bundled = resolve_records("bundled")
    assert {r["name"] for r in bundled} >= {"IV1940_ElCentro_180"}
    with pytest.raises(ParameterError, match="records"):
        resolve_records(tmp_path / "nowhere")
    (tmp_path / "lone.dat").write_text("1 2 3\n")
    with pytest.raises(ParameterError, match="records.csv"):
        resolve_records(tmp_path / "lone.dat")


# ---------------------------------------------------------------------------------------------
# vertical ground motion: a records.csv's channels, or --vertical RATIO
# ---------------------------------------------------------------------------------------------
def _with_vertical_channel(folder, down=1.2):
    """The tiny records, TINY1 with a listed vertical channel TINY1V (headerless, cm/s^2, dt
    0.01 s): a downward half-sine of ``down`` g over 0.5-1.0 s (down > 1: the ground falls
    faster than gravity there)."""
    _write_tiny_records(folder)
    t = np.arange(0.0, 2.0, 0.01)
    v = np.where((t >= 0.5) & (t <= 1.0), -down * 980.665 * np.sin(2 * math.pi * (t - 0.5)),
                 0.0)
    np.savetxt(folder / "TINY1V.dat", v.reshape(-1, 4), fmt="%.6e")
    (folder / "records.csv").write_text("record,npts,dt_s,units,vertical\n"
                                        "TINY1,200,0.01,cm/s^2,TINY1V\n"
                                        "TINY2,200,0.01,cm/s^2,\n")
    return folder


FAST = dict(engines=["analytic"], scales="1:2:2", executor="serial", progress=False,
            n_boot=20, numerical=None)


def _peak(scene, motion, scale):
    import rockbench as rb

    return rb.run(scene, motion.scaled(scale), method="compiled").summary


def test_a_records_csv_names_each_records_vertical_channel(tmp_path):
    """A ``vertical`` column names a record's vertical channel: the channel is not a record of
    its own, every run of that record carries it (each run is the run of the record with its
    channel, scaled and reversed with it), the analysis says which records carry one, and the
    runs outside the model follow the one rule with it (here the ground falls faster than
    gravity as recorded: outside, though the PGA alone is far below mu g)."""
    import rockbench as rb
    from rockbench.scene.records import load_record
    from rockbench.studies.fragility import fragility_cases
    from rockbench.validity import motion_validity

    d = _with_vertical_channel(tmp_path / "recs")
    recs = resolve_records(d)
    assert [r["name"] for r in recs] == ["TINY1", "TINY2"]
    assert recs[0]["vertical"] == str((d / "TINY1V.dat").resolve())
    assert (recs[0]["vertical_dt"], recs[0]["vertical_units"]) == (0.01, "cm/s2")
    assert "vertical" not in recs[1]
    cases = fragility_cases("paper-asymmetric", recs, ["analytic"], [1.0])
    assert all(c["motion"]["vertical_path"] == recs[0]["vertical"] for c in cases[:2])
    assert all("vertical_path" not in c["motion"] for c in cases[2:])
    f = run_fragility("paper-asymmetric", d, **FAST)
    v = f.analysis["vertical"]
    assert (v["recorded"], v["scaled"], v["horizontal"]) == (["TINY1"], [], ["TINY2"])
    assert "recorded vertical channel of 1 of 2 records" in v["text"]
    scene = rb.load_scene("paper-asymmetric")
    rec = load_record(d / "TINY1.dat", vertical=d / "TINY1V.dat", vertical_dt=0.01,
                      vertical_units="cm/s2")
    for r in f.runs[f.runs["record"] == "TINY1"].itertuples():
        s = _peak(scene, rec, r.polarity * r.scale)
        assert r.peak == s.max_abs_phi_over_alpha
        assert r.outside == (not motion_validity(scene, rec,
                                                 scale=r.polarity * r.scale).inside)
    t1 = f.runs[f.runs["record"] == "TINY1"]         # reversed, the channel pushes up
    assert list(t1["outside"]) == list(t1["polarity"] == 1)
    assert not f.runs[f.runs["record"] == "TINY2"]["outside"].any()
    assert "falls faster than gravity (g + a_v <= 0)" in f.analysis["validity"]["text"]
    flat = run_fragility("paper-asymmetric", _write_tiny_records(tmp_path / "flat"), **FAST)
    assert "vertical" not in flat.analysis
    assert not np.allclose(flat.runs["peak"].iloc[:4], t1["peak"])      # the channel matters


def test_vertical_ratio_gives_the_other_records_their_scaled_horizontal(tmp_path):
    """``vertical=r``: a record without a channel of its own runs with a_v = r u_g'' in every
    run (its run is the run of Record.with_vertical_ratio(r)); one with a recorded channel
    keeps it; the analysis and the command's JSON say which."""
    import rockbench as rb
    from rockbench.scene.records import load_record

    d = _with_vertical_channel(tmp_path / "recs", down=0.3)
    f = run_fragility("paper-asymmetric", d, vertical=0.5, **FAST)
    v = f.analysis["vertical"]
    assert (v["ratio"], v["recorded"], v["scaled"], v["horizontal"]) == (
        0.5, ["TINY1"], ["TINY2"], [])
    assert "a_v = 0.5 u_g''" in v["text"] and "for the other 1" in v["text"]
    scene = rb.load_scene("paper-asymmetric")
    rec = load_record(d / "TINY2.dat", dt=0.01, units="cm/s2").with_vertical_ratio(0.5)
    np.testing.assert_allclose(rec.vertical.samples, 0.5 * rec.samples, rtol=1e-15)
    for r in f.runs[f.runs["record"] == "TINY2"].itertuples():
        assert r.peak == _peak(scene, rec, r.polarity * r.scale).max_abs_phi_over_alpha
    for bad in (3.5, -0.1, True):
        with pytest.raises(ParameterError, match="vertical"):
            run_fragility("paper-asymmetric", d, vertical=bad, **FAST)


def test_vertical_ratio_on_the_synthetic_ensemble(tmp_path):
    """The synthetic ensemble has no vertical channel: ``vertical=r`` gives each of its
    records a_v = r u_g'' in every run, and the runs differ from the horizontal ones."""
    from rockbench.sweep.store import load_store

    kw = dict(FAST, scales="1:1:1", tail=5.0, store=tmp_path / "store", keyed_by_code=False)
    f = run_fragility("paper-asymmetric", "synthetic:n=1,seed=3", vertical=2.0, **kw)
    assert f.analysis["ensemble"]["kind"] == "synthetic"
    assert f.analysis["vertical"]["scaled"] == list(f.records["record"])
    rows = load_store(tmp_path / "store")
    assert (rows["motion.vertical_ratio"].dropna() == 2.0).sum() == len(f.runs) == 2
    flat = run_fragility("paper-asymmetric", "synthetic:n=1,seed=3", **kw)
    assert "vertical" not in flat.analysis
    assert not np.allclose(flat.runs["peak"], f.runs["peak"])


def test_without_vertical_motion_the_cases_are_unchanged(tmp_path):
    """No channel listed and no ratio (None or 0): the cases are those of a horizontal
    ensemble key for key (the store's ids unchanged), no ``vertical`` in the analysis, the
    info or the JSON, and ``outside`` is the PGA rule."""
    from rockbench.cli.fragility import summary
    from rockbench.studies.fragility import fragility_cases
    from rockbench.sweep.cases import case_id
    from rockbench.validity import pga_limit
    import rockbench as rb

    d = _write_tiny_records(tmp_path / "recs")
    recs = resolve_records(d)
    for c in fragility_cases("paper-asymmetric", recs, ["analytic"], [1.0]):
        assert set(c["motion"]) == {"kind", "path", "scale", "dt", "units"}
    a = fragility_cases("paper-asymmetric", recs, ["analytic"], [1.0, 2.0])
    b = fragility_cases("paper-asymmetric", recs, ["analytic"], [1.0, 2.0], vertical=0.0)
    assert [case_id(c) for c in a] == [case_id(c) for c in b]
    f0 = run_fragility("paper-asymmetric", d, **FAST)
    f1 = run_fragility("paper-asymmetric", d, vertical=0.0, **FAST)
    pd.testing.assert_frame_equal(f0.runs.drop(columns="cpu_s"), f1.runs.drop(columns="cpu_s"))
    for f in (f0, f1):
        assert "vertical" not in f.analysis and "vertical" not in f.info
        assert "vertical" not in summary(f)
    pga = dict(zip(f0.records["record"], f0.records["pga"]))
    lim = pga_limit(rb.load_scene("paper-asymmetric"))
    assert list(f0.runs["outside"]) == [s * pga[r] > lim for r, s in
                                        zip(f0.runs["record"], f0.runs["scale"])]


def test_cli_vertical(tmp_path, capsys):
    """--vertical RATIO: out of [0, 3] one line naming it; the JSON and the text say which
    records carry which vertical motion."""
    from rockbench.cli.main import main

    d = _write_tiny_records(tmp_path / "recs")
    base = ["fragility", "paper-asymmetric", "--records", str(d), "--engine", "analytic",
            "--scales", "1:2:2", "--store", str(tmp_path / "store"), "--workers", "1",
            "--boot", "20", "--no-numerical"]
    for bad in ("3.5", "-1", "x"):
        assert main(base + ["--vertical", bad]) == 2
        err = capsys.readouterr().err
        assert "--vertical" in err and len(err.strip().splitlines()) == 1, err
    assert main(base + ["--vertical", "0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["vertical"]["ratio"] == 0.5 and out["vertical"]["scaled"] == ["TINY1", "TINY2"]
    assert main(base + ["--vertical", "0.5", "--quiet"]) == 0
    assert "a_v = 0.5 u_g''" in capsys.readouterr().out
    assert main(base + ["--json"]) == 0
    assert "vertical" not in json.loads(capsys.readouterr().out)


# ---------------------------------------------------------------------------------------------
# the driver: resumable
# ---------------------------------------------------------------------------------------------
def test_resume_after_an_interruption(tmp_path, monkeypatch):
    """Ctrl-C after 3 runs: the rerun runs only the 5 missing cases, and gives what an
    uninterrupted run gives."""
    import rockbench.sweep.runs as R

    d = _write_tiny_records(tmp_path / "recs")
    real = R.run_case
    calls = []

    def interrupted(case):
        if len(calls) == 3:
            raise KeyboardInterrupt
        calls.append(case)
        return real(case)

    kw = dict(engines=["analytic"], scales="1:2:2", store=tmp_path / "store",
              executor="serial", progress=False, n_boot=20)
    monkeypatch.setattr(R, "run_case", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_fragility("paper-asymmetric", d, **kw)
    calls.clear()
    monkeypatch.setattr(R, "run_case", lambda c: calls.append(c) or real(c))
    f = run_fragility("paper-asymmetric", d, **kw)
    assert len(calls) == 8 - 3 and len(f.runs) == 8
    calls.clear()
    again = run_fragility("paper-asymmetric", d, **kw)
    assert calls == []
    cols = ["backend", "record", "polarity", "scale", "im", "peak", "overturned", "status"]
    pd.testing.assert_frame_equal(f.runs[cols], again.runs[cols])
    # a record's intensity is scale x its PGA, both polarities alike
    g = f.runs[f.runs["record"] == "TINY1"]
    assert np.allclose(g["im"] / g["scale"], g["im"].iloc[0] / g["scale"].iloc[0])


# ---------------------------------------------------------------------------------------------
# the command
# ---------------------------------------------------------------------------------------------
def test_cli_end_to_end_json(tmp_path, capsys):
    from rockbench.cli.main import main

    pytest.importorskip("pymunk")
    d = _write_tiny_records(tmp_path / "recs")
    store = tmp_path / "store"
    argv = ["fragility", "paper-asymmetric", "--records", str(d), "--engine", "pymunk",
            "--scales", "0.5:1:2", "--store", str(store), "--workers", "1", "--boot", "50",
            "--no-numerical", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["intensity"]["name"] == "PGA" and out["intensity"]["unit"] == "m/s^2"
    assert out["records"] == 2 and out["scales"] == [0.5, 1.0]
    assert set(out["backends"]) == {"analytic", "pymunk"}
    for b in out["backends"].values():
        assert {"median", "dispersion", "median_ci", "dispersion_ci", "runs"} <= set(b)
        assert b["runs"] == 2 * 2 * 2
    pm = out["backends"]["pymunk"]
    assert {"statistic", "p_value", "median_difference", "median_difference_ci",
            "verdict", "tests"} <= set(pm)
    # the tiny records' PGA at scale 1 (1.38 m/s^2) is below the frame's uplift acceleration
    # g tan(alpha) = 1.40 m/s^2: nothing rocks, so nothing overturns; the fit says its median is
    # above the largest intensity instead of inventing one, and the two engines' peaks (all
    # "no rocking") are indistinguishable at every intensity (statistic 0, p = 1)
    for b in out["backends"].values():
        assert b["overturned"] == 0 and b["not_ok"] == 0 and b["records"] == 2
        assert b["median"] is None and b["dispersion"] is None
        assert "no run overturned: median above the largest intensity 1.382" in b["note"]
    assert pm["statistic"] == 0.0 and pm["p_value"] == 1.0 and pm["median_difference"] is None
    assert [(t["scale"], t["rejected"], t["p_value"], t["n_a"], t["n_b"]) for t in pm["tests"]] \
        == [(0.5, False, 1.0, 4, 4), (1.0, False, 1.0, 4, 4)]
    assert pm["tests"][1]["im_median"] == pytest.approx(2 * pm["tests"][0]["im_median"])
    assert "not judged" in pm["verdict"]
    # the rerun runs nothing and prints the verdict in words
    assert main(argv[:-1] + ["--quiet"]) == 0
    text = capsys.readouterr().out
    assert "PGA [m/s^2]" in text and "pymunk:" in text


def test_cli_bad_input_is_one_line(capsys):
    from rockbench.cli.main import main

    assert main(["fragility", "paper-asymmetric", "--records", "bundled",
                 "--scales", "2:1:3"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rockbench: error:") and "scales" in err and len(err.splitlines()) == 1
    assert main(["fragility", "paper-asymmetric", "--records", "no-such-ensemble"]) == 2
    assert "bundled" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# the report's section
# ---------------------------------------------------------------------------------------------
def test_section_html_and_table(tmp_path):
    """The page block shows each engine's verdict and the figures (curves, peaks, Fig. 9); the
    table has one row per backend with the fit and the test."""
    from rockbench.campaign.fragility import section_table
    from rockbench.report.fragility_figures import fragility_html, plot_fragility

    caps = _quantile_capacities(10, 2.0, 0.4)
    scales = np.linspace(0.5, 5.0, 6)
    runs = pd.concat([_ensemble(caps, scales), _ensemble(caps / 2.0, scales, backend="pymunk")])
    a = analyse(runs, n_boot=50)
    section = {"what": "synthetic", "fig9": True,
               "frames": [{"label": "free-standing", "scene": "x", "runs": runs,
                           "analysis": a}]}
    html = fragility_html(section, tmp_path)
    assert "pymunk: distinguishable from the analytic model" in html
    assert {p.name for p in tmp_path.iterdir()} == {"fragility_0.png", "fragility_peaks_0.png",
                                                    "fragility_fig9.png"}
    assert "Vertical ground motion" not in html
    a_v = dict(a, vertical={"text": "Vertical ground motion in every run: a_v = 0.5 u_g''"})
    assert "Vertical ground motion in every run: a_v = 0.5 u_g" in fragility_html(
        {**section, "fig9": False, "frames": [dict(section["frames"][0], analysis=a_v)]},
        tmp_path / "v")
    tab = section_table(section)
    assert tab["backend"].tolist() == ["analytic", "pymunk"]
    assert tab.loc[1, "median_difference"] < -0.3     # the weaker engine: an earlier median
    fig = plot_fragility(a, runs)
    assert fig.get_figwidth() <= 11.6
    assert all(t.get_fontsize() >= 9 for ax in fig.axes for t in
               ax.get_xticklabels() + ax.get_yticklabels() + [ax.xaxis.label, ax.title])


@pytest.mark.slow
def test_section_quick_end_to_end(tmp_path):
    """The campaign's part at its quick size, for real: the synthetic ensemble of 8 records,
    the free-standing frame's ladder found from the analytic runs, pymunk on the 8 records at
    2 steps (judged: >= MIN_RECORDS), its beta_num measured on the frame's pulses, the
    intensity-measure table and the exports."""
    pytest.importorskip("pymunk")
    from rockbench.campaign.fragility import fragility_section
    from rockbench.studies.fragility_stats import MIN_RECORDS

    sec = fragility_section({"free-standing": "paper-asymmetric"}, ["analytic", "pymunk"],
                            size="quick", store=tmp_path, workers=1, progress=False)
    assert "error" not in sec, sec.get("error")
    assert sec["ensemble"]["kind"] == "synthetic" and len(sec["records"]) == 8
    f = sec["frames"][0]
    r, a = f["runs"], f["analysis"]
    assert (r["status"] == "ok").all()
    assert len(r[r["backend"] == "analytic"]) == 8 * 2 * len(f["scales"])
    assert len(r[r["backend"] == "pymunk"]) == 8 * 2 * 2
    pm = a["backends"]["pymunk"]
    assert pm["records"] >= MIN_RECORDS and pm["indistinguishable"] is not None
    num = a["numerical"]["pymunk"]
    assert num["cases"] >= 2 and 0.0 <= pm["dispersion_numerical"] < 0.05     # [-]
    assert pm["dispersion_total"] >= pm["dispersion"]
    assert a["measures"]["backends"]["pymunk"]["same_best"] in (True, False)
    assert {"paper-asymmetric.xml", "paper-asymmetric.csv"} <= set(sec["exports"])


def test_peaks_below_the_uplift_threshold_count_as_no_rocking():
    """A rigid model's 0 and an engine's elastic contact deflection (1e-5 alpha) are the same
    answer, not rocking: below uplift_tol (1e-3 alpha) the peaks tie at 0. Above it they count."""
    rigid, soft = np.zeros(20), np.full(20, 1.2e-5)
    none = np.zeros(20, bool)
    assert peak_test(rigid, none, soft, none)["p_value"] < 1e-6          # without the floor
    assert peak_test(rigid, none, soft, none, floor=1e-3)["p_value"] == 1.0
    assert peak_test(rigid, none, soft + 0.01, none, floor=1e-3)["p_value"] < 1e-6
    caps = _quantile_capacities(10, 2.0, 0.4)
    ref = _ensemble(caps, [0.2, 3.0])
    eng = ref.assign(backend="engine")
    eng.loc[eng["peak"] == 0.0, "peak"] = 1e-5
    ref.loc[ref["scale"] == 0.2, "peak"] = 0.0
    eng.loc[eng["scale"] == 0.2, "peak"] = 1.5e-5
    a = analyse(pd.concat([ref, eng]), n_boot=20)
    assert a["backends"]["engine"]["p_value"] == 1.0


def test_records_option_repeats_like_engine():
    """`--records A --records B C` keeps all three (the last one alone was kept before)."""
    from rockbench.cli.main import build_parser

    a = build_parser().parse_args(["fragility", "housner-block", "--records", "a",
                                   "--records", "b", "c"])
    assert a.records == ["a", "b", "c"]

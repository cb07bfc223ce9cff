"""The predictability band (rockbench.studies.sensitivity): the unperturbed peak lies in its own band, a
wrong engine result falls outside it, the perturbations do what they say."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.scene.motion import Record
from rockbench.studies.sensitivity import (PERTURBATIONS, Perturbation, _simulate, assert_within_band,
                                   band, perturbed_case)


@pytest.fixture(scope="module")
def scene():
    return rb.load_scene("paper-asymmetric")


@pytest.fixture(scope="module")
def pulse(scene):
    return rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure)


@pytest.fixture(scope="module")
def pulse_band(scene, pulse):
    return band(scene, pulse)


@pytest.fixture(scope="module")
def nominal(scene, pulse):
    return rb.run(scene, pulse)            # the analytic reference as compare() runs it


def test_band_contains_the_unperturbed_peak(pulse_band, nominal):
    b = pulse_band
    assert b.low <= b.nominal <= b.high
    assert b.low < b.high                                # the perturbations do move the peak
    # the plain reference run (what an engine is compared with) is inside, by its history too
    assert b.judge(nominal.summary.max_abs_phi_over_alpha).inside
    assert b.judge(nominal).inside
    assert_within_band(nominal, b)
    # every perturbation ran, the phase one is skipped for a pulse
    kinds = list(b.runs["kind"])
    assert kinds[0] == "none" and "phase" not in kinds
    assert len(b.runs) == 1 + sum(p.kind != "phase" for p in PERTURBATIONS)
    assert b.verdict_agreement == 1.0 and not b.overturned


def test_band_is_ordered_in_eta_and_scale(pulse_band):
    """Physics: a larger eta keeps more energy through the impacts and a larger pulse rocks
    further, so the peaks are ordered with the factors (this case peaks after its impacts)."""
    r = pulse_band.runs.set_index("perturbation")["peak_over_alpha"]
    assert r["eta x0.99"] < r["eta x0.995"] < r["unperturbed"] < r["eta x1.005"] < r["eta x1.01"]
    assert r["scale x0.99"] < r["unperturbed"] < r["scale x1.01"]


def test_wrong_engine_result_falls_outside(pulse_band, nominal):
    """A Result whose history is 1.3 x the reference's lies outside the band, by a distance
    measured from the band's upper edge."""
    h = nominal.history.copy()
    h["phi"] = 1.3 * h["phi"]
    wrong = dataclasses.replace(nominal, backend="wrong", history=h)
    j = pulse_band.judge(wrong)
    assert not j.inside
    peak = 1.3 * np.max(np.abs(nominal.history["phi"])) / pulse_band.alpha
    assert j.peak == pytest.approx(peak, rel=1e-12)
    assert j.distance == pytest.approx(peak - pulse_band.high, rel=1e-12)
    assert j.relative == pytest.approx(peak / pulse_band.high - 1.0, rel=1e-12)
    assert "outside it, by" in j.text and "above" in j.text
    with pytest.raises(AssertionError, match="outside it"):
        assert_within_band(wrong, pulse_band)
    low = pulse_band.judge(0.5 * pulse_band.low)
    assert not low.inside and low.distance < 0 and "below" in low.text


def test_pivot_perturbation_moves_every_pivot_by_1mm(scene):
    sc, mot, ef = perturbed_case(scene, None, Perturbation("pivot", 1e-3))
    assert ef == 1.0 and mot is None
    for s in (1, -1):
        p0, p1 = scene.structure.pivots(s), sc.structure.pivots(s)
        for k in ("A", "D"):      # bottom pivots of the two columns, 1 mm further out
            assert abs(p1[k][0] - p0[k][0]) == pytest.approx(1e-3, abs=1e-12)
    # equivalent change of the uplift threshold: about db / b = 0.2 %
    lam0 = rb.info(scene)["lambda_ccw"]
    lam1 = rb.info(sc)["lambda_ccw"]
    assert lam1 / lam0 - 1 == pytest.approx(0.002, rel=0.1)


def _short_record(n=400, dt=0.01):
    t = dt * np.arange(n)
    a = 3.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-((t - 1.5) / 0.8) ** 2)
    return Record.from_samples(a, dt, name="synthetic")


def test_whole_sample_shift_is_neutral_and_half_sample_phase_is_not():
    """The model is time-invariant and starts from rest: a record shifted by one whole sample
    gives the same peak (why the band uses the half-sample phase instead)."""
    scene = rb.load_scene("housner-block")
    rec = _short_record()
    shifted = Record(rec.time + rec.dt, rec.samples, name="shifted")
    a = _simulate(scene, rec, duration=8.0, phi0=0.0)
    b = _simulate(scene, shifted, duration=8.0, phi0=0.0)
    assert a.summary.uplifted
    assert b.summary.max_abs_phi == pytest.approx(a.summary.max_abs_phi, rel=1e-6)
    assert b.summary.n_impacts == a.summary.n_impacts
    _, ph, _ = perturbed_case(scene, rec, Perturbation("phase", 0.5))
    assert np.allclose(ph.samples, 0.5 * (rec.samples[:-1] + rec.samples[1:]))
    assert np.allclose(ph.time, rec.time[:-1])


def test_eta_hook_matches_the_scaled_restitution():
    """The eta perturbation really scales every applied eta (events of the analytic run)."""
    scene = rb.load_scene("housner-block")
    phi0 = 0.5 * scene.alpha
    a = _simulate(scene, None, duration=3.0, phi0=phi0)
    b = _simulate(scene, None, duration=3.0, phi0=phi0, eta_factor=0.99)
    ea = a.events.loc[a.events["kind"] == "impact", "eta"].to_numpy()
    eb = b.events.loc[b.events["kind"] == "impact", "eta"].to_numpy()
    assert ea.size and eb.size
    assert eb[0] == pytest.approx(0.99 * ea[0], rel=1e-12)


def test_record_band_has_a_phase_run_and_bad_inputs_are_named(scene):
    block = rb.load_scene("housner-block")
    rec = _short_record()
    b = band(block, rec, duration=8.0)
    assert "phase" in set(b.runs["kind"]) and b.low <= b.nominal <= b.high
    assert math.isfinite(b.relative_width)
    with pytest.raises(rb.ParameterError):
        band("not a scene", rec)
    with pytest.raises(rb.ParameterError):
        perturbed_case(block, None, Perturbation("scale", 1.01))


def test_an_overturned_engine_is_judged_by_its_verdict():
    """Overturning: the peak is the fall angle plus an engine's last-step overshoot, so an
    overturned run is inside when the band's analytic runs overturn too (the fracture-and-
    overturn case of issue 14: eps_f = 1 %, antisymmetric pulse A = 8, W = 2)."""
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    m = rb.RickerPulse.dimensionless(A=8.0, W=2.0, structure=scene.structure,
                                     shape="antisymmetric", sign=1)
    b = band(scene, m, perturbations=(Perturbation("scale", 0.99),))
    assert b.overturned and b.fractured and b.verdict_agreement == 1.0
    r = rb.run(scene, m)
    h = r.history.copy()
    h["phi"] = 1.001 * h["phi"]                 # overshoots the band's (fall-angle) peaks
    over = dataclasses.replace(r, backend="fake", history=h)
    assert not b.judge(float(np.max(np.abs(h["phi"]))) / b.alpha).inside
    j = b.judge(over)
    assert j.inside and "overturned" in j.text


def test_analytic_settings_eta_factor_is_validated_and_applied():
    from rockbench.analytic.solver import AnalyticSettings, simulate

    assert AnalyticSettings().eta_factor == 1.0
    for bad in (0.0, -1.0, 2.5, float("nan")):
        with pytest.raises(rb.ParameterError, match="eta_factor"):
            AnalyticSettings(eta_factor=bad)
    scene = rb.load_scene("paper-asymmetric")
    s = AnalyticSettings(eta_factor=0.995)
    r = simulate(scene, None, phi0=0.5 * scene.alpha, duration=3.0, settings=s)
    imp = r.events[r.events["kind"] == "impact"]
    ref = rb.info(scene)
    for e, d in zip(imp["eta"], imp["direction"]):
        if d in (1, -1):
            assert e == pytest.approx(0.995 * ref["eta_ccw" if d == 1 else "eta_cw"], rel=1e-14)
    assert r.settings["eta_factor"] == 0.995


def test_compiled_band_equals_the_plain_one(scene, pulse, pulse_band):
    """The band's fast path (compiled kernel, eta_factor included) gives the plain solver's
    peaks."""
    pytest.importorskip("numba")
    plain = band(scene, pulse, compiled=False)
    np.testing.assert_allclose(pulse_band.runs["peak_over_alpha"], plain.runs["peak_over_alpha"],
                               rtol=1e-7)
    assert list(pulse_band.runs["overturned"]) == list(plain.runs["overturned"])

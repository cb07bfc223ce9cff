"""Fragility exports (``rockbench.studies.fragility_export``): OpenQuake NRML 0.5 and pelicun CSV.

The schema checks always run (the XML parsed with :mod:`xml.etree`, the CSV with pandas); the
tools' own readers run where OpenQuake or pelicun is installed (``pip install
rockbench[export]``; skipped otherwise).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest
from scipy.stats import lognorm, norm

from rockbench.errors import ParameterError
from rockbench.studies import fragility_export as X

NS = "{http://openquake.org/xmlns/nrml/0.5}"
G = 9.80665
#: Two curves like the SAC-set fits of docs/fragility.md (median PGA [m/s^2], beta).
CURVES = [X.FragilityCurve("analytic", 6.70, 0.81), X.FragilityCurve("engine_a", 6.74, 0.79)]


def openquake_cdf(x, mean, stddev):
    """OpenQuake's reading of a continuous ``logncdf`` function (its manual: the mean and
    standard deviation of the IML, not of ln IML): the lognormal with that mean and stddev."""
    sigma = math.sqrt(math.log(stddev ** 2 / mean ** 2 + 1.0))
    median = mean ** 2 / math.sqrt(stddev ** 2 + mean ** 2)
    return lognorm.cdf(x, sigma, scale=median)


def test_the_moments_of_the_lognormal_are_exact():
    for median, beta in [(6.7, 0.81), (0.3, 0.05), (120.0, 2.0)]:
        mean, std = X.lognormal_moments(median, beta)
        # against scipy's moments of the same distribution
        d = lognorm(beta, scale=median)
        assert mean == pytest.approx(d.mean(), rel=1e-12)
        assert std == pytest.approx(d.std(), rel=1e-10)
        assert X.lognormal_from_moments(mean, std) == pytest.approx((median, beta), rel=1e-12)


def test_nrml_schema_numbers_and_the_logncdf_conversion(tmp_path):
    path = tmp_path / "fragility.xml"
    X.to_nrml(CURVES, path, id="paper-asymmetric", min_iml=0.8, max_iml=15.7,
              no_damage_limit=0.5)
    text = path.read_text(encoding="utf-8")
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>')
    root = ET.fromstring(text)
    assert root.tag == NS + "nrml" and len(root) == 1
    model = root[0]
    assert model.tag == NS + "fragilityModel"
    assert model.attrib == {"id": "paper-asymmetric", "assetCategory": "buildings",
                            "lossCategory": "structural"}
    assert [c.tag for c in model] == [NS + "description", NS + "limitStates"] + \
        [NS + "fragilityFunction"] * 2
    assert model.find(NS + "limitStates").text.split() == ["overturning"]
    assert "m/s^2" in model.find(NS + "description").text
    for curve, ff in zip(CURVES, model.findall(NS + "fragilityFunction")):
        assert ff.attrib == {"id": curve.id, "format": "continuous", "shape": "logncdf"}
        imls, params = list(ff)
        assert imls.tag == NS + "imls" and params.tag == NS + "params"
        # PGA in g (OpenQuake's unit), standard gravity
        assert imls.attrib["imt"] == "PGA"
        assert float(imls.attrib["minIML"]) == pytest.approx(0.8 / G, rel=1e-15)
        assert float(imls.attrib["maxIML"]) == pytest.approx(15.7 / G, rel=1e-15)
        assert float(imls.attrib["noDamageLimit"]) == pytest.approx(0.5 / G, rel=1e-15)
        assert params.attrib["ls"] == "overturning"
        mean, std = float(params.attrib["mean"]), float(params.attrib["stddev"])
        # the numbers round-trip: back to the fitted median [m/s^2] and beta
        median_g, beta = X.lognormal_from_moments(mean, std)
        assert median_g * G == pytest.approx(curve.median, rel=1e-13)
        assert beta == pytest.approx(curve.dispersion, rel=1e-13)
        # and OpenQuake's CDF is rockbench's curve at every intensity
        for x in (0.5, 2.0, curve.median, 10.0, 30.0):       # m/s^2
            ours = norm.cdf(math.log(x / curve.median) / curve.dispersion)
            assert openquake_cdf(x / G, mean, std) == pytest.approx(ours, abs=1e-13)
            assert curve.probability(x) == pytest.approx(ours, abs=1e-14)
        # a mean/stddev misread as median/beta would be a different curve
        assert abs(lognorm.cdf(curve.median / G, std, scale=mean) - 0.5) > 0.05


def test_nrml_pgv_is_written_in_cm_per_s():
    curve = X.FragilityCurve("analytic", 0.9, 0.5, measure="pgv")      # m/s
    root = ET.fromstring(X._text(X.to_nrml, [curve], min_iml=0.05, max_iml=3.0))
    imls = root.find(f"{NS}fragilityModel/{NS}fragilityFunction/{NS}imls")
    params = root.find(f"{NS}fragilityModel/{NS}fragilityFunction/{NS}params")
    assert imls.attrib["imt"] == "PGV" and float(imls.attrib["maxIML"]) == pytest.approx(300.0)
    median, beta = X.lognormal_from_moments(float(params.attrib["mean"]),
                                            float(params.attrib["stddev"]))
    assert (median, beta) == pytest.approx((90.0, 0.5), rel=1e-13)


def test_pelicun_csv_columns_and_values(tmp_path):
    path = tmp_path / "fragility.csv"
    X.to_pelicun_csv(CURVES, path, id_prefix="RB.")
    df = pd.read_csv(path)
    assert tuple(df.columns) == X.PELICUN_COLUMNS
    assert list(df["ID"]) == ["RB.analytic", "RB.engine_a"]
    assert (df["Incomplete"] == 0).all() and (df["Demand-Offset"] == 0).all()
    assert (df["Demand-Type"] == "Peak Ground Acceleration").all()
    assert (df["Demand-Unit"] == "mps2").all() and (df["Demand-Directional"] == 1).all()
    assert (df["LS1-Family"] == "lognormal").all()
    assert list(df["LS1-Theta_0"]) == [c.median for c in CURVES]          # exact round trip
    assert list(df["LS1-Theta_1"]) == [c.dispersion for c in CURVES]
    assert df["LS1-DamageStateWeights"].isna().all()
    pgv = pd.read_csv(pd.io.common.StringIO(X._text(
        X.to_pelicun_csv, [X.FragilityCurve("a", 0.9, 0.5, "pgv")], directional=False)))
    assert pgv.loc[0, "Demand-Type"] == "Peak Ground Velocity"
    assert pgv.loc[0, "Demand-Unit"] == "mps" and pgv.loc[0, "Demand-Directional"] == 0


def test_curves_from_an_analysis():
    analysis = {"intensity": {"name": "PGV", "unit": "m/s", "key": "pgv"},
                "backends": {"analytic": {"median": 0.8, "dispersion": 0.6},
                             "b": {"median": float("nan"), "dispersion": float("nan")},
                             "c": {"median": 0.9, "dispersion": 0.7}}}
    curves = X.curves_from_analysis(analysis)
    assert [(c.id, c.median, c.dispersion, c.measure) for c in curves] == \
        [("analytic", 0.8, 0.6, "pgv"), ("c", 0.9, 0.7, "pgv")]
    with pytest.raises(ParameterError):
        X.curves_from_analysis({"backends": {"b": {"median": float("nan"), "dispersion": 1.0}}})


@pytest.mark.parametrize("make, name", [
    (lambda: X.FragilityCurve("a b", 1.0, 0.5), "id"),
    (lambda: X.FragilityCurve("a", -1.0, 0.5), "median"),
    (lambda: X.FragilityCurve("a", 1.0, float("nan")), "dispersion"),
    (lambda: X.FragilityCurve("a", 1.0, 0.5, "sa"), "measure"),
    (lambda: X._text(X.to_nrml, CURVES, min_iml=2.0, max_iml=1.0), "max_iml"),
    (lambda: X._text(X.to_nrml, CURVES, min_iml=1.0, max_iml=2.0, loss_category="x"),
     "loss_category"),
    (lambda: X._text(X.to_nrml, CURVES + [X.FragilityCurve("v", 1.0, 0.5, "pgv")],
                     min_iml=1.0, max_iml=2.0), "curves"),
    (lambda: X._text(X.to_pelicun_csv, [CURVES[0], CURVES[0]]), "curves"),
    (lambda: X._text(X.to_pelicun_csv, []), "curves"),
    (lambda: X._text(X.to_pelicun_csv, [X.FragilityCurve("engine-a", 1.0, 0.5)]), "id"),
])
def test_bad_inputs(make, name):
    with pytest.raises(ParameterError) as e:
        make()
    assert e.value.name == name


# ------------------------------------------------------------------------------------------------
# The tools' own readers (optional extra ``export``)
def test_openquake_reads_the_nrml(tmp_path):
    """OpenQuake's own reader and its own curve (``scientific.FragilityFunctionContinuous``):
    within [minIML, maxIML] (outside it OpenQuake holds the curve at the ends) it is rockbench's
    Phi(ln(x / median) / beta)."""
    nrml = pytest.importorskip("openquake.hazardlib.nrml")
    read_nrml = pytest.importorskip("openquake.risklib.read_nrml")  # noqa: F841 (registers it)
    path = tmp_path / "fragility.xml"
    X.to_nrml(CURVES, path, id="paper-asymmetric", min_iml=0.8, max_iml=15.7)
    model = nrml.to_python(str(path))
    assert list(model.limitStates) == ["overturning"] and model.lossCategory == "structural"
    assert sorted(model) == sorted(("PGA", c.id) for c in CURVES)
    xs = np.array([1.0, 3.0, 6.7, 12.0])                          # m/s^2
    for curve in CURVES:
        ffl = model[("PGA", curve.id)]
        assert ffl.minIML == pytest.approx(0.8 / G) and ffl.maxIML == pytest.approx(15.7 / G)
        (function,) = ffl.build(model.limitStates)
        ours = norm.cdf(np.log(xs / curve.median) / curve.dispersion)
        assert np.allclose(function(xs / G), ours, rtol=0, atol=1e-12)


def test_pelicun_reads_the_csv(tmp_path):
    """pelicun's own damage-model loader (``DamageModel.load_model_parameters``, which checks
    the table, drops incomplete rows and converts the units to its base units) keeps every
    curve with its median and dispersion."""
    assessment = pytest.importorskip("pelicun.assessment")
    path = tmp_path / "fragility.csv"
    X.to_pelicun_csv(CURVES, path, id_prefix="RB.")
    a = assessment.Assessment({"PrintLog": False, "Verbose": False})
    ids = {f"RB.{c.id}" for c in CURVES}
    a.damage.load_model_parameters([str(path)], ids)
    params = a.damage.ds_model.damage_params
    assert set(params.index) == ids and not a.damage.missing_components
    for c in CURVES:
        row = params.loc[f"RB.{c.id}"]
        assert row[("Demand", "Type")] == "Peak Ground Acceleration"
        assert row[("LS1", "Family")] == "lognormal"
        assert float(row[("LS1", "Theta_0")]) == pytest.approx(c.median, rel=1e-12)
        assert float(row[("LS1", "Theta_1")]) == pytest.approx(c.dispersion, rel=1e-12)

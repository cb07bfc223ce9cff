"""Fragility exports (``rockbench.studies.fragility_export``): OpenQuake NRML 0.5 and pelicun CSV.

The schema checks always run (the XML parsed with :mod:`xml.etree`, the CSV with pandas). The
tools' own readers run through ``tests/fragility_export_reader.py`` in the interpreter that has
the tool: this one where it imports the tool, else the one named by ``ROCKBENCH_OPENQUAKE_PYTHON``
/ ``ROCKBENCH_PELICUN_PYTHON`` (``make export-readers`` builds both venvs; a named interpreter
that cannot load the file fails the test); skipped, with the remedy, otherwise.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

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
              no_damage_limit=1.0)
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
        assert float(imls.attrib["noDamageLimit"]) == pytest.approx(1.0 / G, rel=1e-15)
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
    # OpenQuake clamps the intensity to minIML before comparing it with noDamageLimit: a limit
    # below minIML would do nothing (its reader shows it: tests below)
    (lambda: X._text(X.to_nrml, CURVES, min_iml=1.0, max_iml=2.0, no_damage_limit=0.5),
     "no_damage_limit"),
    (lambda: X._text(X.to_nrml, CURVES, min_iml=1.0, max_iml=2.0, no_damage_limit=2.0),
     "no_damage_limit"),
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
# The tools' own readers, each in an interpreter that has the tool (fragility_export_reader.py)
READER = Path(__file__).with_name("fragility_export_reader.py")
#: tool -> (its top-level module, the variable naming another interpreter, that venv's folder)
TOOLS = {"openquake": ("openquake", "ROCKBENCH_OPENQUAKE_PYTHON", ".venv-openquake"),
         "pelicun": ("pelicun", "ROCKBENCH_PELICUN_PYTHON", ".venv-pelicun")}
#: The exports' curves: PGA (the analytic model and an engine, as write_fragility_exports writes
#: an analysis) and PGV [m/s] (non-directional, prefixed ids, a no-damage limit).
PGA_ANALYSIS = {"intensity": {"name": "PGA", "unit": "m/s^2", "key": "pga"},
                "grid": [0.8, 15.7],
                "backends": {"analytic": {"median": 6.70, "dispersion": 0.81},
                             "engine_a": {"median": 6.74, "dispersion": 0.79}}}
PGV_CURVES = [X.FragilityCurve("analytic", 0.9, 0.5, "pgv"),
              X.FragilityCurve("engine_a", 1.1, 0.4, "pgv")]
PGV_RANGE = {"min_iml": 0.05, "max_iml": 3.0, "no_damage_limit": 0.08}     # m/s


def _remedy(tool: str) -> str:
    _, var, venv = TOOLS[tool]
    return (f"`make export-readers` builds {venv}, then set {var}={venv}/bin/python "
            "(docs/fragility-export.md)")


def read_with(tool: str, paths, at=None, samples: int | None = None) -> dict:
    """What ``tool``'s own reader makes of ``paths`` (the JSON of fragility_export_reader.py):
    run in this interpreter if it has the tool, else in the one the tool's variable names;
    skipped (with the remedy) when neither. ``at``: one list of points per path."""
    module, var, _ = TOOLS[tool]
    named = os.environ.get(var, "").strip()
    if named:
        python = named
    elif importlib.util.find_spec(module) is not None:
        python = sys.executable
    else:
        pytest.skip(f"{tool} is not importable by {sys.executable} and {var} is not set: "
                    + _remedy(tool))
    cmd = [python, str(READER), tool, *map(str, paths)]
    for x in at or ():
        cmd += ["--at", ",".join(repr(float(v)) for v in x)]
    if samples is not None:
        cmd += ["--samples", str(samples)]
    try:
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=900)
    except FileNotFoundError:
        pytest.fail(f"{var}={named!r}: no such interpreter; " + _remedy(tool))
    if proc.returncode == 3 and not named:              # installed but broken here: say why
        pytest.skip(proc.stderr.strip() + "; " + _remedy(tool))
    assert proc.returncode == 0, f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stderr}"
    return json.loads(proc.stdout)


@pytest.fixture(scope="module")
def exports(tmp_path_factory):
    """The files: ``fragility.xml`` / ``.csv`` as ``rockbench fragility --export`` writes them
    (write_fragility_exports) and a PGV pair (to_nrml, to_pelicun_csv)."""
    root = tmp_path_factory.mktemp("exports")
    written = X.write_fragility_exports(PGA_ANALYSIS, root)
    X.to_nrml(PGV_CURVES, root / "pgv.xml", id="pgv", **PGV_RANGE)
    X.to_pelicun_csv(PGV_CURVES, root / "pgv.csv", id_prefix="RB.", directional=False)
    return {"pga": X.curves_from_analysis(PGA_ANALYSIS), "pga.xml": written["fragility.xml"],
            "pga.csv": written["fragility.csv"], "pgv": PGV_CURVES, "pgv.xml": root / "pgv.xml",
            "pgv.csv": root / "pgv.csv"}


#: Intensities at which OpenQuake's curves are evaluated [m/s^2 for PGA, m/s for PGV]: inside
#: [minIML, maxIML], then below (PGV: under the no-damage limit) and above it.
OQ_AT = {"pga": [1.0, 3.0, 6.7, 6.74, 12.0, 0.5, 30.0],
         "pgv": [0.1, 0.5, 0.9, 1.1, 2.0, 0.04, 0.08, 5.0]}


@pytest.fixture(scope="module")
def openquake_read(exports):
    at = [[x * X.OPENQUAKE_IMT[m][2] for x in OQ_AT[m]] for m in ("pga", "pgv")]
    return read_with("openquake", [exports["pga.xml"], exports["pgv.xml"]], at)


def test_openquake_reads_the_medians_and_dispersions_written(exports, openquake_read):
    """``openquake.hazardlib.nrml.to_python`` (the engine's reader of fragility files) reads
    both models; its mean and stddev are the written numbers, which are the fitted median
    [OpenQuake's unit] and beta to round-off; the ranges and the no-damage limit too."""
    assert openquake_read["tool"] == "openquake.engine"
    pga, pgv = openquake_read["files"]
    assert (pga["id"], pgv["id"]) == ("fragility", "pgv")
    for model, measure in ((pga, "pga"), (pgv, "pgv")):
        imt, _, factor = X.OPENQUAKE_IMT[measure]
        assert model["limitStates"] == ["overturning"]
        assert model["lossCategory"] == "structural" and model["assetCategory"] == "buildings"
        curves = {c.id: c for c in exports[measure]}
        assert [f["id"] for f in model["functions"]] == list(curves)
        for f in model["functions"]:
            c = curves[f["id"]]
            assert f["imt"] == imt and f["format"] == "continuous"
            assert (f["mean"], f["stddev"]) == X.lognormal_moments(c.median * factor,
                                                                   c.dispersion)
            median, beta = X.lognormal_from_moments(f["mean"], f["stddev"])
            assert median / factor == pytest.approx(c.median, rel=1e-13)
            assert beta == pytest.approx(c.dispersion, rel=1e-13)
    lo, hi = PGA_ANALYSIS["grid"]
    assert all(f["minIML"] == pytest.approx(lo / G, rel=1e-15)
               and f["maxIML"] == pytest.approx(hi / G, rel=1e-15)
               and f["noDamageLimit"] == 1e-10 for f in pga["functions"])  # its log(0) guard
    assert all(f["minIML"] == pytest.approx(5.0) and f["maxIML"] == pytest.approx(300.0)
               and f["noDamageLimit"] == pytest.approx(8.0) for f in pgv["functions"])  # cm/s


def test_openquake_curves_are_the_fitted_curves(exports, openquake_read):
    """OpenQuake's own curve (``scientific.FragilityFunctionContinuous``) is
    Phi(ln(x / median) / beta) inside [minIML, maxIML]; outside, it holds the value at the
    nearer end, and at or under the no-damage limit (after that clamp) it is 0."""
    for model, measure in zip(openquake_read["files"], ("pga", "pgv")):
        curves = {c.id: c for c in exports[measure]}
        lo, hi = ((PGA_ANALYSIS["grid"][0], PGA_ANALYSIS["grid"][-1]) if measure == "pga"
                  else (PGV_RANGE["min_iml"], PGV_RANGE["max_iml"]))
        for f in model["functions"]:
            c = curves[f["id"]]
            for x, p in zip(OQ_AT[measure], f["poes"]):
                if measure == "pgv" and x <= PGV_RANGE["no_damage_limit"]:
                    assert p == 0.0, x
                    continue
                ours = c.probability(min(max(x, lo), hi))
                assert p == pytest.approx(ours, abs=1e-12), (f["id"], x)
            # the median is where OpenQuake's curve crosses 1/2
            assert f["poes"][OQ_AT[measure].index(c.median)] == pytest.approx(0.5, abs=1e-13)


@pytest.fixture(scope="module")
def pelicun_read(exports):
    at = [[4.0, 6.7, 10.0], [0.5, 0.9, 1.5]]          # demands [m/s^2], [m/s]
    return read_with("pelicun", [exports["pga.csv"], exports["pgv.csv"]], at, samples=20000)


def test_pelicun_reads_the_medians_and_dispersions_written(exports, pelicun_read):
    """pelicun's damage-model loader (``DamageModel.load_model_parameters``: checks the table,
    drops incomplete rows, converts the units to its base units) keeps every curve, complete,
    with the median [m/s^2 or m/s: its base units] and beta written."""
    assert pelicun_read["tool"] == "pelicun"
    for table, measure, prefix, directional in zip(pelicun_read["files"], ("pga", "pgv"),
                                                   ("", "RB."), (1, 0)):
        assert table["missing"] == []
        curves = {prefix + c.id: c for c in exports[measure]}
        assert set(table["components"]) == set(curves)
        for cid, row in table["components"].items():
            c = curves[cid]
            assert row["demand_type"] == X.PELICUN_DEMAND[measure][0]
            assert row["family"] == "lognormal" and row["incomplete"] == 0
            assert row["directional"] == directional and row["offset"] == 0
            assert row["theta_0"] == pytest.approx(c.median, rel=1e-13)
            assert row["theta_1"] == pytest.approx(c.dispersion, rel=1e-13)


def test_pelicun_damage_follows_the_fitted_curves(exports, pelicun_read):
    """pelicun's own damage calculation under a fixed demand puts a component in DS1 (overturned)
    with the curve's probability (sampled: 20000 realizations, within 5 standard errors). A
    directional curve meets the demand of its direction as fitted; a non-directional one meets
    max(direction 1, direction 2) x pelicun's NonDirectionalMultipliers (1.2 by default)."""
    for table, measure, prefix in zip(pelicun_read["files"], ("pga", "pgv"), ("", "RB.")):
        n = table["samples"]
        curves = {prefix + c.id: c for c in exports[measure]}
        m = 1.0 if measure == "pga" else table["nondirectional_multipliers"]["ALL"]
        assert m == (1.0 if measure == "pga" else 1.2)
        for cid, row in table["components"].items():
            for x, p in zip(table["at"], row["p_ds1"]):
                ours = curves[cid].probability(m * x)
                assert abs(p - ours) <= 5 * math.sqrt(ours * (1 - ours) / n) + 1e-3, (cid, x)


def test_an_analytic_run_exported_loads_in_both_tools(tmp_path):
    """End to end: a small fragility run of the analytic model (4 synthetic records), exported
    as ``rockbench fragility --export`` does, read by each available tool to the fitted median
    and dispersion."""
    have = [t for t, (module, var, _) in TOOLS.items()
            if os.environ.get(var, "").strip() or importlib.util.find_spec(module)]
    if not have:
        pytest.skip("neither OpenQuake nor pelicun is available: " + _remedy("openquake")
                    + "; " + _remedy("pelicun"))
    from rockbench.studies.fragility import run_fragility

    f = run_fragility("paper-asymmetric", "synthetic:n=4", engines=[], scales="0.8:4:4",
                      tail=2.0, executor="serial", progress=False, n_boot=20, numerical=None,
                      store=tmp_path / "store")
    fit = f.analysis["backends"]["analytic"]
    assert 0 < fit["overturned"] < fit["runs"]
    written = X.write_fragility_exports(f.analysis, tmp_path / "out", runs=f.runs,
                                        record_ims=f.records)
    if "openquake" in have:
        (model,) = read_with("openquake", [written["fragility.xml"]])["files"]
        (fn,) = model["functions"]
        median, beta = X.lognormal_from_moments(fn["mean"], fn["stddev"])
        assert (fn["id"], fn["imt"]) == ("analytic", "PGA")
        assert median * G == pytest.approx(fit["median"], rel=1e-13)
        assert beta == pytest.approx(fit["dispersion"], rel=1e-13)
    if "pelicun" in have:
        (table,) = read_with("pelicun", [written["fragility.csv"]])["files"]
        row = table["components"]["analytic"]
        assert row["theta_0"] == pytest.approx(fit["median"], rel=1e-13)
        assert row["theta_1"] == pytest.approx(fit["dispersion"], rel=1e-13)

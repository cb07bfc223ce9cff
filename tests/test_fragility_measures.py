"""Fragility over several intensity measures and with the engines' numerical error (issue 39,
docs/fragility.md): the efficiency table against hand fits, the flag of an engine that ranks
the measures otherwise than the analytic model, beta_num and beta_total."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from rockbench.errors import ParameterError
from rockbench.studies.fragility import numerical_terms, run_lengths
from rockbench.studies.fragility_measures import im_efficiency
from rockbench.studies.fragility_stats import (analyse, combine_dispersions, fit_lognormal,
                                               numerical_dispersion)

G_TAN = 9.81 * math.tan(0.15)        # the planted structure's g tan alpha [m/s^2]
P = 1.5                              # its p [rad/s]


def _records(n: int = 12) -> pd.DataFrame:
    """n records whose PGA, PGV and Sa vary independently (deterministic); pga_norm and pgv_norm
    are PGA and PGV over the structure's constants, as record_ims makes them."""
    k = np.arange(n)
    pga = 2.0 * np.exp(0.5 * np.sin(1.7 * k + 0.3))
    pgv = 0.2 * np.exp(0.6 * np.cos(2.3 * k + 1.1))
    sa = 1.5 * np.exp(0.4 * np.sin(3.1 * k + 2.0))
    return pd.DataFrame({"record": [f"R{i:02d}" for i in k], "path": [f"/x/R{i:02d}" for i in k],
                         "pga": pga, "pgv": pgv, "pga_norm": pga / G_TAN,
                         "pgv_norm": pgv / (P * G_TAN), "sa": sa})


def _runs(ims: pd.DataFrame, capacity: dict[str, float], measure: str, backend: str,
          scales=np.geomspace(0.3, 6.0, 9)) -> pd.DataFrame:
    """Runs of every record at every scale, both polarities: a run overturns iff the scaled
    record's ``measure`` reaches the record's capacity in that measure."""
    rows = []
    for rec, im in zip(ims["record"], ims[measure]):
        for s in scales:
            ot = s * im >= capacity[rec]
            for pol in (1, -1):
                rows.append({"backend": backend, "record": rec, "polarity": pol,
                             "scale": float(s), "im": float(s * im), "peak": 1.2 if ot else 0.5,
                             "overturned": bool(ot), "status": "ok", "cpu_s": 0.0})
    return pd.DataFrame(rows)


def _capacities(ims, measure, beta, median):
    """Each record's capacity in ``measure``: lognormal quantiles in a shuffled order."""
    n = len(ims)
    z = norm.ppf((np.arange(n) + 0.5) / n)[np.argsort(np.sin(7.0 * np.arange(n)))]
    return dict(zip(ims["record"], median * np.exp(beta * z)))


def test_im_table_matches_hand_fits_and_ranks_families():
    """The table's medians and dispersions are fit_lognormal on scale x the record's measure,
    done by hand here for each measure; capacities planted tight in PGV make PGV the most
    efficient; a dimensionless measure has its dimensional one's dispersion and rank, its
    median over the constant."""
    ims = _records()
    runs = _runs(ims, _capacities(ims, "pgv", 0.1, 0.6), "pgv", "analytic")
    t = im_efficiency(runs, ims)
    fits = t["backends"]["analytic"]["fits"]
    by = ims.set_index("record")
    for k in ("pga", "pgv", "pga_norm", "pgv_norm", "sa"):
        x = runs["scale"].to_numpy() * by.loc[runs["record"], k].to_numpy()
        hand = fit_lognormal(x, runs["overturned"].to_numpy())
        assert fits[k]["median"] == pytest.approx(hand["median"], rel=1e-9), k
        assert fits[k]["dispersion"] == pytest.approx(hand["dispersion"], rel=1e-9), k
    assert t["backends"]["analytic"]["best"] == "pgv"
    assert fits["pgv"]["rank"] == fits["pgv_norm"]["rank"] == 1
    assert fits["pga"]["rank"] == fits["pga_norm"]["rank"]
    assert fits["pga_norm"]["dispersion"] == pytest.approx(fits["pga"]["dispersion"], rel=1e-6)
    assert fits["pga_norm"]["median"] == pytest.approx(fits["pga"]["median"] / G_TAN, rel=1e-6)
    assert fits["pgv"]["dispersion"] < 0.2 < fits["pga"]["dispersion"]
    assert t["backends"]["analytic"]["ranking"][0] == "pgv"
    assert len(t["backends"]["analytic"]["ranking"]) == 3          # pga, pgv, sa families
    assert t["measures"]["pgv_norm"]["unit"] == "-" and t["measures"]["sa"]["unit"] == "m/s^2"


def test_an_engine_that_ranks_the_measures_otherwise_is_flagged():
    """Same records: the analytic model's capacities tight in PGV, one engine's tight in PGA
    (its best measure is another), a twin's the analytic ones: only the first is flagged, in
    the table and in the sentence."""
    ims = _records()
    ref = _runs(ims, _capacities(ims, "pgv", 0.1, 0.6), "pgv", "analytic")
    twin = ref.assign(backend="twin")
    other = _runs(ims, _capacities(ims, "pga", 0.1, 6.0), "pga", "other")
    t = im_efficiency(pd.concat([ref, twin, other]), ims)
    assert t["backends"]["twin"]["same_best"] is True
    assert t["backends"]["twin"]["same_ranking"] is True
    assert "as in the analytic model" in t["backends"]["twin"]["sentence"]
    o = t["backends"]["other"]
    assert o["best"] == "pga" and o["same_best"] is False and o["same_ranking"] is False
    assert "NOT the analytic model's" in o["sentence"] and "PGV" in o["sentence"]
    # analyse carries the flag per backend
    a = analyse(pd.concat([ref, other]), n_boot=20, record_ims=ims)
    assert a["backends"]["other"]["im_same_best"] is False
    assert a["backends"]["analytic"]["im_best"] == "pgv"


def test_beta_total_combines_as_the_root_of_squares():
    """beta_total = sqrt(beta_RR^2 + beta_num^2): 0.3 and 0.4 give 0.5; the analytic model's
    beta_num is 0 (the reference), an engine without a measured one has NaN."""
    assert combine_dispersions(0.3, 0.4) == pytest.approx(0.5, rel=1e-12)
    assert combine_dispersions(0.3, 0.0) == pytest.approx(0.3)
    assert math.isnan(combine_dispersions(0.3, math.nan))
    assert math.isinf(combine_dispersions(0.3, math.inf))
    with pytest.raises(ParameterError, match="dispersion"):
        combine_dispersions(0.3, -0.1)
    ims = _records()
    caps = _capacities(ims, "pga", 0.3, 6.0)
    runs = pd.concat([_runs(ims, caps, "pga", b) for b in ("analytic", "engine", "other")])
    a = analyse(runs, n_boot=20, numerical={"engine": 0.4}, record_ims=ims)
    e, r, o = (a["backends"][b] for b in ("engine", "analytic", "other"))
    assert e["dispersion_numerical"] == 0.4
    assert e["dispersion_total"] == pytest.approx(math.hypot(e["dispersion"], 0.4), rel=1e-12)
    assert r["dispersion_numerical"] == 0.0 and r["dispersion_total"] == r["dispersion"]
    assert math.isnan(o["dispersion_numerical"]) and math.isnan(o["dispersion_total"])


def test_numerical_dispersion_of_peak_errors():
    """beta_num = RMS of ln(1 + e) over the peak errors e: +-10 % give sqrt(mean(ln 1.1^2,
    ln 0.9^2)); a failed run (inf, NaN) makes it infinite; per engine from an evidence frame."""
    want = math.sqrt(0.5 * (math.log(1.1) ** 2 + math.log(0.9) ** 2))
    assert numerical_dispersion([0.1, -0.1]) == pytest.approx(want, rel=1e-12)
    assert numerical_dispersion([0.0, 0.0]) == 0.0
    assert math.isinf(numerical_dispersion([0.1, math.nan]))
    assert math.isnan(numerical_dispersion([]))
    ev = pd.DataFrame({"engine": ["a", "a", "b", "b"], "setting": ["dt=0.001"] * 4,
                       "peak_rel_error": [0.1, -0.1, 0.02, 5.0], "status": ["ok", "ok", "ok",
                                                                           "diverged"]})
    terms = numerical_terms(ev)
    assert terms["a"]["beta"] == pytest.approx(want) and terms["a"]["cases"] == 2
    assert terms["a"]["worst"] == pytest.approx(0.1) and terms["a"]["setting"] == "dt=0.001"
    assert math.isinf(terms["b"]["beta"])          # the diverged run counts as unbounded


def test_run_lengths_cut_after_the_strong_motion():
    """t95 + tail rounded up to 5 s, never beyond the record + 10 s; no tail: the default."""
    ims = pd.DataFrame({"path": ["a", "b", "c"], "t95": [21.2, 3.0, 40.0],
                        "duration": [55.0, 60.0, 40.0]})
    assert run_lengths(ims, None) == {"a": None, "b": None, "c": None}
    assert run_lengths(ims, 10.0) == {"a": 35.0, "b": 15.0, "c": None}   # c: 50 = 40 + 10
    with pytest.raises(ParameterError, match="tail"):
        run_lengths(ims, -1.0)


def test_the_newton_fit_is_the_bounded_optimizer_s_maximum():
    """The fast fit (Newton's method on the probit form) against the plain one it replaces
    (BFGS on ln theta, ln beta): on 120 random binomial data sets its log-likelihood is never
    lower, and where the maximum is inside the bounds the two agree to 1e-5."""
    import rockbench.studies.fragility_stats as FS
    from scipy.special import log_ndtr

    def loglik(x, n, z, f):
        u = np.log(x / f["median"]) / f["dispersion"]
        return float(np.sum(z * log_ndtr(u) + (n - z) * log_ndtr(-u)))

    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(120):
        k = int(rng.integers(4, 30))
        x = np.sort(np.exp(rng.normal(1.0, 1.0, k)))
        n = rng.integers(1, 5, k).astype(float)
        theta, beta = math.exp(rng.normal(1.0, 0.5)), math.exp(rng.normal(-1.0, 0.7))
        z = rng.binomial(n.astype(int), norm.cdf(np.log(x / theta) / beta)).astype(float)
        fast = FS._fit_counts(x, n, z)
        real = FS._probit_newton
        FS._probit_newton = lambda *a, **kw: None
        try:
            plain = FS._fit_counts(x, n, z)
        finally:
            FS._probit_newton = real
        if not math.isfinite(fast["median"]):
            assert not math.isfinite(plain["median"])
            continue
        assert loglik(x, n, z, fast) >= loglik(x, n, z, plain) - 1e-9
        if 0.01 < plain["dispersion"] < 4.0 and 0.01 < fast["dispersion"]:
            compared += 1
            assert fast["median"] == pytest.approx(plain["median"], rel=1e-5)
            assert fast["dispersion"] == pytest.approx(plain["dispersion"], rel=1e-4)
    assert compared > 60


def test_runs_outside_the_model_are_counted_and_said():
    """A run whose scaled PGA is above mu g is outside the analytic model: counted per backend
    and said in a sentence with the limit [m/s^2]; an engine whose records lost their runs is
    'not judged' in words that say so."""
    from rockbench.studies.fragility import _validity

    ims = _records()
    caps = _capacities(ims, "pga", 0.3, 6.0)
    runs = pd.concat([_runs(ims, caps, "pga", b) for b in ("analytic", "engine")])
    runs["outside"] = runs["im"] > 9.81
    v = _validity(runs, 9.81, 1.0)
    n_out = int((runs[runs["backend"] == "analytic"]["im"] > 9.81).sum())
    assert 0 < n_out < len(runs) / 2
    assert v["backends"]["analytic"]["outside"] == n_out
    assert f"analytic {n_out} of" in v["text"] and "9.81 m/s^2" in v["text"]
    # five of the engine's records lose every run: 7 left of 12, not judged, and said why
    lost = runs["record"].isin(ims["record"][:5]) & (runs["backend"] == "engine")
    runs.loc[lost, "status"] = "diverged"
    a = analyse(runs, n_boot=20)
    e = a["backends"]["engine"]
    assert e["outside_model"] == int(runs[runs["backend"] == "engine"]["outside"].sum())
    assert e["indistinguishable"] is None
    assert "7 record(s) with runs that finished ok (of 12 run" in e["verdict"]

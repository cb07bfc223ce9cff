"""The statistics of fragility (``docs/fragility.md``): pure functions of the runs frame
(:data:`rockbench.studies.fragility.RUN_COLUMNS`) and of counts.

* :func:`fit_lognormal` - the maximum-likelihood lognormal fragility
  P(overturn | IM = x) = Phi(ln(x / median) / dispersion) on binomial counts (Baker 2015);
* :func:`bootstrap` - the fits again on ensembles of records drawn with replacement (a record
  keeps all its runs: both polarities, every scale), seeded; percentile intervals of the
  median, the dispersion, the curve, and the paired difference of medians to the analytic one;
* :func:`peak_test` - Kolmogorov-Smirnov two-sample test of two peak samples, overturned runs
  right-censored (ranked above every finite peak);
* :func:`stripes` - per scale step: counts, overturning fraction, the survivors' peaks;
* :func:`numerical_dispersion`, :func:`combine_dispersions` - an engine's own error as a
  lognormal dispersion beside the record-to-record one, beta_total = sqrt(beta_RR^2 + beta_num^2);
* :func:`analyse` - all of the above for a frame of runs, with one verdict sentence per engine,
  and the efficiency table of the intensity measures
  (:func:`rockbench.studies.fragility_measures.im_efficiency`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from .intensity import MEASURES

__all__ = ["ALPHA", "N_BOOT", "BETA_MIN", "BETA_MAX", "MIN_RECORDS", "AT_BOUND",
           "fit_lognormal", "fragility_curve", "check_bootstrap", "bootstrap", "peak_test",
           "stripes", "numerical_dispersion", "combine_dispersions", "analyse"]

#: Significance level of the tests (intervals: two-sided 1 - ALPHA); bootstrap resamples.
ALPHA, N_BOOT = 0.05, 1000
#: Bounds of the fit: dispersion beta in [BETA_MIN, BETA_MAX]; a fit at a bound is flagged.
BETA_MIN, BETA_MAX = 1e-3, 5.0
#: Fewest records for a verdict (n records give at most C(2n - 1, n) distinct bootstrap
#: resamples: 6435 for 8, 3 for 2; and the KS test on 2 n runs has little power below that).
MIN_RECORDS = 8
#: Dispersions at or below this [-] are the fit's lower bound (separation): they tie.
AT_BOUND = BETA_MIN * 1.01
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def _grouped(im: np.ndarray, overturned: np.ndarray) -> tuple[np.ndarray, ...]:
    x, inv = np.unique(np.round(im, 12), return_inverse=True)
    return (x, np.bincount(inv, minlength=x.size).astype(float),
            np.bincount(inv, weights=overturned.astype(float), minlength=x.size))


def fit_lognormal(im: Sequence[float], overturned: Sequence[bool]) -> dict[str, Any]:
    """Maximum-likelihood lognormal fragility of runs at intensities ``im`` (> 0) with verdicts
    ``overturned``: the median theta [unit of im] and dispersion beta [-] maximizing
    sum_j [z_j ln Phi(ln(x_j/theta)/beta) + (n_j - z_j) ln(1 - Phi(ln(x_j/theta)/beta))] over
    the distinct intensities x_j with n_j runs of which z_j overturned (Baker 2015, Eq. 11).

    Returns ``median``, ``dispersion``, ``n`` runs, ``n_overturned`` and ``note``: "" for a
    regular fit; when no run (or every run) overturns the median is NaN and ``note`` says it
    lies above the largest (below the smallest) intensity; when every survivor is below every
    overturned run in intensity (separation: the likelihood grows without bound as beta -> 0)
    the median is the geometric mean of the two intensities at the step, the dispersion
    :data:`BETA_MIN`, and ``note`` says so. Optimizer: BFGS on (ln median, ln dispersion) with
    the analytic gradient, from two starts."""
    im = np.asarray(im, dtype=float)
    ot = np.asarray(overturned, dtype=bool)
    if im.shape != ot.shape or im.size == 0:
        raise ParameterError("im", f"{im.size} values", f"as many as overturned ({ot.size}), >= 1")
    if not np.all(np.isfinite(im) & (im > 0)):
        raise ParameterError("im", "a value <= 0 or not finite", "finite intensities > 0")
    return _fit_counts(*_grouped(im, ot))


def _fit_counts(x: np.ndarray, n: np.ndarray, z: np.ndarray) -> dict[str, Any]:
    """:func:`fit_lognormal` on counts: ``n[j]`` runs at intensity ``x[j]`` (> 0), ``z[j]`` of
    them overturned (entries with n = 0 are ignored)."""
    from scipy.optimize import minimize
    from scipy.special import log_ndtr

    keep = n > 0
    x, n, z = x[keep], n[keep], z[keep]
    out = {"median": math.nan, "dispersion": math.nan, "n": int(n.sum()),
           "n_overturned": int(z.sum()), "note": ""}
    if n.size == 0:
        out["note"] = "no run"
        return out
    if z.sum() == 0:
        out["note"] = f"no run overturned: median above the largest intensity {x.max():.4g}"
        return out
    if z.sum() == n.sum():
        out["note"] = f"every run overturned: median below the smallest intensity {x.min():.4g}"
        return out
    lx = np.log(x)
    survive, fall = lx[z < n], lx[z > 0]
    if survive.max() < fall.min():     # separated: the likelihood grows as beta -> 0
        out["median"] = math.exp(0.5 * (survive.max() + fall.min()))
        out["dispersion"] = BETA_MIN
        out["note"] = ("overturning separated by intensity (a step between "
                       f"{math.exp(survive.max()):.4g} and {math.exp(fall.min()):.4g}): "
                       "median at their geometric mean, dispersion at its bound")
        return out
    tau_lo, tau_hi = math.log(BETA_MIN), math.log(BETA_MAX)
    newton = _probit_newton(lx, n, z)
    if newton is not None:
        mu, beta = newton
        out["median"], out["dispersion"] = math.exp(mu), beta
        if beta <= BETA_MIN * 1.01:
            out["note"] = ("overturning separated by intensity (a step): dispersion at its "
                           "bound")
        return out

    def nll(p: np.ndarray) -> tuple[float, np.ndarray]:
        # p = (ln theta, ln beta); BFGS (pure NumPy on 2-vectors: no threaded BLAS call,
        # which L-BFGS-B makes and which costs 100 times more on a loaded machine)
        beta = math.exp(min(max(p[1], tau_lo - 2.0), tau_hi + 1.0))
        u = (lx - p[0]) / beta
        lc, ls, lp = log_ndtr(u), log_ndtr(-u), -0.5 * u * u - _LOG_SQRT_2PI
        g = z * np.exp(lp - lc) - (n - z) * np.exp(lp - ls)       # d loglik / du
        return (-float(np.sum(z * lc + (n - z) * ls)),
                np.array([float(np.sum(g)) / beta, float(np.sum(g * u))]))

    # start where the empirical overturning fraction crosses 1/2
    t0 = lx[np.argmin(np.abs(z / n - 0.5))]
    best = None
    for b0 in (0.3, 1.0):
        r = minimize(nll, np.array([t0, math.log(b0)]), jac=True, method="BFGS",
                     options={"gtol": 1e-7})
        if best is None or r.fun < best.fun:
            best = r
    mu = min(max(float(best.x[0]), lx.min() - 3.0), lx.max() + 3.0)
    beta = math.exp(min(max(float(best.x[1]), tau_lo), tau_hi))
    out["median"], out["dispersion"] = math.exp(mu), beta
    if beta <= BETA_MIN * 1.01:
        out["note"] = "overturning separated by intensity (a step): dispersion at its bound"
    return out


def _probit_newton(lx: np.ndarray, n: np.ndarray, z: np.ndarray, *, iterations: int = 60
                   ) -> tuple[float, float] | None:
    """The maximum of the same likelihood by Newton's method: with u = a + b (ln x - m) (m the
    mean of ln x; theta = exp(m - a / b), beta = 1 / b) it is a binomial probit regression,
    whose log-likelihood is concave in (a, b), so Newton's steps (halved until the likelihood
    grows) reach the one maximum. When that maximum lies outside beta in [BETA_MIN, BETA_MAX]
    (or at infinity: runs almost separated by intensity) the bounded maximum is on one of the
    two faces beta = BETA_MIN, beta = BETA_MAX (a concave function on a slab), found by
    Newton's method in a alone on each. Returns (ln theta, beta), or None when a Newton
    iteration fails (:func:`_fit_counts` then takes its bounded optimizer). A fit costs a few
    dozen array operations: the bootstrap refits thousands."""
    from scipy.special import log_ndtr

    m = float(np.mean(lx))
    c = lx - m
    f = n - z
    b_lo, b_hi = 1.0 / BETA_MAX, 1.0 / BETA_MIN

    def loglik(a: float, b: float) -> float:
        u = a + b * c
        return float(np.sum(z * log_ndtr(u) + f * log_ndtr(-u)))

    def derivatives(a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
        u = a + b * c
        lp = -0.5 * u * u - _LOG_SQRT_2PI
        l1, l2 = np.exp(lp - log_ndtr(u)), np.exp(lp - log_ndtr(-u))
        return (z * l1 - f * l2,                               # d loglik / du
                -z * l1 * (u + l1) - f * l2 * (l2 - u))        # d2 loglik / du2 (< 0)

    def newton(a: float, b: float, free_b: bool) -> tuple[float, float, float, bool]:
        ll = loglik(a, b)
        for _ in range(iterations):
            g, h = derivatives(a, b)
            ga, haa = float(np.sum(g)), float(np.sum(h))
            if free_b:
                gb, hab, hbb = float(np.sum(g * c)), float(np.sum(h * c)), float(
                    np.sum(h * c * c))
                det = haa * hbb - hab * hab
                if not (det > 0.0 and haa < 0.0):
                    return a, b, ll, False
                da, db = -(hbb * ga - hab * gb) / det, -(haa * gb - hab * ga) / det
            else:
                if not haa < 0.0:
                    return a, b, ll, False
                da, db = -ga / haa, 0.0
            step = 1.0
            while True:
                na, nb = a + step * da, b + step * db
                nl = loglik(na, nb)
                if nl >= ll - 1e-12 * abs(ll) or step < 1e-6:
                    break
                step *= 0.5
            a, b, ll = na, nb, nl
            if not (math.isfinite(a) and math.isfinite(b)):
                return a, b, ll, False
            if abs(step * da) < 1e-11 * (1.0 + abs(a)) and \
                    abs(step * db) < 1e-11 * (1.0 + abs(b)):
                return a, b, ll, True
        return a, b, ll, False

    t0 = c[np.argmin(np.abs(z / n - 0.5))]
    a, b, _, done = newton(-2.0 * t0, 2.0, True)   # from beta = 0.5 through the crossing of 1/2
    if not (done and b_lo <= b <= b_hi):
        faces = []
        for bb in (b_lo, b_hi):
            fa, fb, fl, ok = newton(-bb * t0, bb, False)
            if not ok:
                return None
            faces.append((fl, fa, fb))
        _, a, b = max(faces)
    beta = 1.0 / b
    mu = m - a * beta
    if not lx.min() - 3.0 <= mu <= lx.max() + 3.0:
        return None
    return mu, beta


def fragility_curve(x: Sequence[float], median: float, dispersion: float) -> np.ndarray:
    """P(overturn | IM = x) = Phi(ln(x / median) / dispersion) [-]; NaN where the fit is."""
    from scipy.special import ndtr

    x = np.asarray(x, dtype=float)
    if not (math.isfinite(median) and math.isfinite(dispersion)):
        return np.full(x.shape, math.nan)
    return ndtr(np.log(x / median) / dispersion)


def check_bootstrap(n_boot: Any, seed: Any, *, names: tuple[str, str] = ("n_boot", "seed")
                    ) -> tuple[int, int]:
    """(n_boot, seed) checked before any work: an integer number of resamples within the limit
    ``bootstrap`` (:mod:`rockbench.limits`) and a seed in [0, 2**32 - 1]; ``names``: how the
    caller calls them (the command line: ``--boot``, ``--seed``)."""
    from ..limits import check_in_limit

    if isinstance(n_boot, bool) or not isinstance(n_boot, (int, np.integer)):
        raise ParameterError(names[0], n_boot, "an integer number of resamples >= 1")
    check_in_limit("bootstrap", names[0], int(n_boot))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) \
            or not 0 <= int(seed) <= 2 ** 32 - 1:
        raise ParameterError(names[1], seed, "an integer in [0, 4294967295]")
    return int(n_boot), int(seed)


def bootstrap(runs: pd.DataFrame, *, n_boot: int = N_BOOT, seed: int = 0,
              grid: Sequence[float] | None = None, reference: str = "analytic",
              level: float = 1 - ALPHA) -> dict[str, dict[str, Any]]:
    """Percentile bootstrap over the records: ``n_boot`` ensembles of records drawn with
    replacement (generator ``numpy.random.default_rng(seed)``), each record keeping all its
    runs, and every backend refitted on the same draw (so differences are paired).

    Returns per backend: ``median_ci``, ``dispersion_ci`` ([low, high] at ``level``),
    ``band`` (low and high of the curve on ``grid``), ``n_valid`` (draws with a regular fit),
    and, for backends other than ``reference``, ``median_difference_ci`` of
    median(backend) - median(reference) [unit of im]."""
    n_boot, seed = check_bootstrap(n_boot, seed)
    ok = runs[runs["status"] == "ok"]
    records = sorted(ok["record"].unique())
    backends = list(dict.fromkeys(ok["backend"]))
    grid = np.asarray(grid if grid is not None else np.geomspace(
        ok["im"].min(), ok["im"].max(), 60), dtype=float)
    # counts per record and intensity: a resample's counts are its records' counts, weighted
    # by how often each was drawn
    x, j = np.unique(np.round(ok["im"].to_numpy(float), 12), return_inverse=True)
    r = np.searchsorted(records, ok["record"].to_numpy())
    counts = {}
    for b in backends:
        m = ok["backend"].to_numpy() == b
        N = np.zeros((len(records), x.size))
        Z = np.zeros((len(records), x.size))
        np.add.at(N, (r[m], j[m]), 1.0)
        np.add.at(Z, (r[m], j[m]), ok["overturned"].to_numpy(bool)[m].astype(float))
        counts[b] = (N, Z)
    draws = np.random.default_rng(seed).integers(0, len(records), size=(n_boot, len(records)))
    fits = {b: np.full((n_boot, 2), math.nan) for b in backends}
    for k, d in enumerate(draws):
        w = np.bincount(d, minlength=len(records)).astype(float)
        for b in backends:
            N, Z = counts[b]
            f = _fit_counts(x, w @ N, w @ Z)
            fits[b][k] = (f["median"], f["dispersion"])
    q = [50 * (1 - level), 50 * (1 + level)]
    out: dict[str, dict[str, Any]] = {}
    for b in backends:
        f = fits[b]
        good = np.all(np.isfinite(f), axis=1)
        res: dict[str, Any] = {"n_valid": int(good.sum()), "grid": grid.tolist()}
        if good.sum() >= 2:
            res["median_ci"] = np.percentile(f[good, 0], q).tolist()
            res["dispersion_ci"] = np.percentile(f[good, 1], q).tolist()
            curves = np.array([fragility_curve(grid, m, s) for m, s in f[good]])
            res["band"] = {"low": np.percentile(curves, q[0], axis=0).tolist(),
                           "high": np.percentile(curves, q[1], axis=0).tolist()}
        else:
            res["median_ci"] = res["dispersion_ci"] = [math.nan, math.nan]
            res["band"] = {"low": [math.nan] * grid.size, "high": [math.nan] * grid.size}
        if b != reference and reference in fits:
            d = f[:, 0] - fits[reference][:, 0]
            d = d[np.isfinite(d)]
            res["median_difference_ci"] = (np.percentile(d, q).tolist() if d.size >= 2
                                           else [math.nan, math.nan])
            res["n_valid_difference"] = int(d.size)
        out[b] = res
    return out


def peak_test(peaks_a: Sequence[float], overturned_a: Sequence[bool],
              peaks_b: Sequence[float], overturned_b: Sequence[bool], *,
              floor: float = 0.0) -> dict[str, Any]:
    """Two-sample Kolmogorov-Smirnov test (``scipy.stats.ks_2samp``, two-sided, exact for small
    samples) of two peak samples max |phi| / alpha [-]. Overturned runs are right-censored: their
    peak is set to +inf, above every survivor, tied with each other. Peaks below ``floor``
    [-] count as 0 (not uplifted; :func:`analyse` passes the engines' ``uplift_tol``, 1e-3:
    contacts are never perfectly rigid). Returns ``statistic`` (the largest distance of the two
    empirical distribution functions, [-]), ``p_value``, ``n_a``, ``n_b``; NaN when a sample is
    empty."""
    from scipy.stats import ks_2samp
    def censor(p, o):
        p = np.asarray(p, dtype=float).copy()
        p[p < floor] = 0.0
        p[np.asarray(o, dtype=bool)] = np.inf
        return p

    a, b = censor(peaks_a, overturned_a), censor(peaks_b, overturned_b)
    r = ks_2samp(a, b) if a.size and b.size else None
    return {"statistic": float(r.statistic) if r else math.nan,
            "p_value": float(r.pvalue) if r else math.nan, "n_a": int(a.size), "n_b": int(b.size)}


def stripes(runs: pd.DataFrame) -> pd.DataFrame:
    """Per backend and scale step: runs, runs not ok, overturned count and fraction, the median
    intensity of the step [IM unit] and the survivors' peaks (quartiles and median of
    max |phi| / alpha [-])."""
    rows = []
    for (b, s), g in runs.groupby(["backend", "scale"], sort=True):
        ok = g[g["status"] == "ok"]
        ot = ok["overturned"].astype(bool)
        sv = ok.loc[~ot, "peak"].to_numpy(float)
        q = np.percentile(sv, [25, 50, 75]) if sv.size else [math.nan] * 3
        rows.append({"backend": b, "scale": float(s), "im_median": float(g["im"].median()),
                     "runs": len(g), "not_ok": int(len(g) - len(ok)),
                     "overturned": int(ot.sum()),
                     "p_overturn": float(ot.mean()) if len(ok) else math.nan,
                     "peak_q25": q[0], "peak_median": q[1], "peak_q75": q[2]})
    return pd.DataFrame(rows)


def _holm(p: Sequence[float], alpha: float = ALPHA) -> np.ndarray:
    """Holm's step-down rejections of the hypotheses with p-values ``p`` (NaN: not tested)."""
    p = np.asarray(p, dtype=float)
    reject, idx = np.zeros(p.size, dtype=bool), [i for i in np.argsort(p) if np.isfinite(p[i])]
    m = len(idx)
    for k, i in enumerate(idx):
        if p[i] > alpha / (m - k):
            break
        reject[i] = True
    return reject


# ------------------------------------------------------------------- numerical error
def numerical_dispersion(peak_errors: Sequence[float]) -> float:
    """An engine's own error as a lognormal dispersion [-]: the root mean square of
    ln(1 + e) over its relative peak errors e = max|phi| / max|phi_ref| - 1 [-] on the evidence
    (the maximum-likelihood dispersion of a lognormal error of median 1, a bias counted as
    spread); inf when an error is not finite (a run that failed), NaN for no error."""
    e = np.asarray(list(peak_errors), dtype=float)
    if e.size == 0:
        return math.nan
    if not np.all(np.isfinite(e)) or np.any(e <= -1.0):
        return math.inf
    return float(np.sqrt(np.mean(np.log1p(e) ** 2)))


def combine_dispersions(*betas: float) -> float:
    """sqrt(sum beta_i^2) [-]: the dispersion of a sum of independent normal terms in ln IM (how
    the field combines independent lognormal uncertainties, e.g. FEMA P-695 (2009) Sec. 7.3:
    beta_total = sqrt(beta_RR^2 + beta_num^2)). NaN if any term is NaN, inf if any is inf."""
    b = np.asarray(betas, dtype=float)
    if np.any(np.isnan(b)):
        return math.nan
    if np.any(b < 0):
        raise ParameterError("dispersion", betas, "terms >= 0")
    return float(np.sqrt(np.sum(b * b)))


# ------------------------------------------------------------------------- the analysis
def _fmt(x: float) -> str:
    return f"{x:.3g}" if math.isfinite(x) else "nan"


def _verdict(engine: str, tests: list[dict], diff: float, ci: Sequence[float], unit: str,
             name: str, reference: str, n_records: int,
             ran_records: int | None = None) -> tuple[bool | None, str]:
    """(indistinguishable, sentence) of one engine (rules: :func:`analyse`)."""
    tested = [t for t in tests if math.isfinite(t["p_value"])]
    if not tested:
        return None, f"{engine}: no intensity where both ran: not judged."
    pmin = min(t["p_value"] for t in tested)
    if n_records < MIN_RECORDS:
        ran = (f" with runs that finished ok (of {ran_records} run; the others' runs diverged "
               "or failed)" if ran_records is not None and ran_records > n_records else "")
        return None, (f"{engine}: not judged: {n_records} record(s){ran}, fewer than "
                      f"{MIN_RECORDS} "
                      f"(peak distributions at {len(tested)} intensities, smallest p = "
                      f"{_fmt(pmin)}; fragility median difference {_fmt(diff)} {unit}).")
    where = [t for t in tested if t["rejected"]]
    lo, hi = ci
    judged = math.isfinite(lo) and math.isfinite(hi)
    median_differs = judged and (lo > 0 or hi < 0)
    med = (f"fragility median {'higher' if diff > 0 else 'lower'} by {_fmt(abs(diff))} {unit} "
           f"(95 % interval {_fmt(lo)} to {_fmt(hi)} {unit})" if math.isfinite(diff)
           else "fragility medians not both estimated")
    med += "" if judged else ", not judged"
    if not where and not median_differs:
        return True, (f"{engine}: statistically indistinguishable from the {reference} model at "
                      f"the 5 % level (peak distributions at {len(tested)} intensities, "
                      f"smallest p = {_fmt(pmin)}, none rejected by Holm; {med}"
                      + (", the interval holds 0)." if judged else ")."))
    bits = []
    if where:
        bits.append("peak distributions differ at " + ", ".join(
            f"scale {t['scale']:g} ({name} ~ {_fmt(t['im_median'])} {unit}, "
            f"p = {_fmt(t['p_value'])})" for t in where))
    if median_differs:
        bits.append(med)
    return False, (f"{engine}: distinguishable from the {reference} model at the 5 % level: "
                   + "; ".join(bits) + ".")


def analyse(runs: pd.DataFrame, *, measure: str = "pga", n_boot: int = N_BOOT, seed: int = 0,
            reference: str = "analytic", record_ims: pd.DataFrame | None = None,
            numerical: Mapping[str, float] | None = None) -> dict[str, Any]:
    """The fragility analysis of ``runs`` (:data:`RUN_COLUMNS`; ``im`` in the unit of
    ``measure``).

    Per backend (key ``backends``): ``median`` [IM unit] and ``dispersion`` [-] of the
    lognormal fit (:func:`fit_lognormal`) with ``median_ci``, ``dispersion_ci`` and the curve's
    band (:func:`bootstrap`, ``n_boot`` resamples, ``seed``), ``note``, runs and counts; for an
    engine, against ``reference``: ``tests`` (per scale step, :func:`peak_test`: ``statistic``,
    ``p_value``, ``rejected`` by Holm's procedure over the steps at level :data:`ALPHA`; peaks
    below the engines' ``uplift_tol`` count as 0),
    ``statistic`` and ``p_value`` of the step with the smallest p-value, ``median_difference``
    [IM unit] with ``median_difference_ci``, ``indistinguishable`` and ``verdict`` (a sentence).

    An engine is *statistically indistinguishable* from the reference when no step's peak
    distributions differ (Holm, family-wise 5 %) and the 95 % interval of the difference of
    the fragility medians holds 0; with fewer than :data:`MIN_RECORDS` records the engine is not
    judged (``indistinguishable`` None). Runs not ``ok`` (diverged, error) are left out of both.

    With ``record_ims`` (the records' measures, :func:`rockbench.studies.ensembles.record_ims`)
    the analysis has ``measures`` (:func:`im_efficiency`) and each backend ``im_best`` (its
    most efficient measure) and, engines, ``im_same_best``. ``numerical``: engine -> beta_num
    [-], its own error as a dispersion (:func:`numerical_dispersion`); each backend gets
    ``dispersion_numerical`` (0 for ``reference``, NaN when not given) and
    ``dispersion_total`` = sqrt(dispersion^2 + dispersion_numerical^2)
    (:func:`combine_dispersions`).
    """
    if measure not in MEASURES:
        raise ParameterError("intensity", measure, f"one of {', '.join(MEASURES)}")
    name, unit, definition = MEASURES[measure]
    ok = runs[runs["status"] == "ok"]
    backends = list(dict.fromkeys(runs["backend"]))
    grid = np.geomspace(max(float(runs["im"].min()), 1e-9), float(runs["im"].max()), 60)
    boot = bootstrap(runs, n_boot=n_boot, seed=seed, grid=grid, reference=reference)
    fits = {b: fit_lognormal(g["im"].to_numpy(), g["overturned"].astype(bool).to_numpy())
            for b, g in ok.groupby("backend")}
    out: dict[str, Any] = {"intensity": {"name": name, "unit": unit, "key": measure,
                                         "definition": definition},
                           "reference": reference, "n_boot": n_boot, "seed": seed,
                           "level": 1 - ALPHA, "grid": grid.tolist(), "backends": {}}
    if record_ims is not None:
        from .fragility_measures import IM_BOOT, im_efficiency

        out["measures"] = im_efficiency(runs, record_ims, reference=reference,
                                        n_boot=min(n_boot, IM_BOOT), seed=seed)
    numerical = dict(numerical or {})
    ref = ok[ok["backend"] == reference]
    from ..engines.base import EngineSettings      # below uplift_tol: not uplifted
    floor = EngineSettings.uplift_tol
    for b in backends:
        g = runs[runs["backend"] == b]
        f = fits.get(b, {"median": math.nan, "dispersion": math.nan, "n": 0,
                         "n_overturned": 0, "note": "no run finished ok"})
        bt = boot.get(b, {})
        res: dict[str, Any] = {
            "median": f["median"], "dispersion": f["dispersion"],
            "median_ci": bt.get("median_ci", [math.nan, math.nan]),
            "dispersion_ci": bt.get("dispersion_ci", [math.nan, math.nan]),
            "band": bt.get("band"), "n_valid_resamples": bt.get("n_valid", 0),
            "runs": int(len(g)), "not_ok": int((g["status"] != "ok").sum()),
            "overturned": int(f["n_overturned"]), "note": f["note"],
            "records": int(g["record"].nunique()), "cpu_s": float(g["cpu_s"].sum())}
        if "outside" in g:
            res["outside_model"] = int(g["outside"].astype(bool).sum())
        num = 0.0 if b == reference else float(numerical.get(b, math.nan))
        res["dispersion_numerical"] = num
        res["dispersion_total"] = combine_dispersions(f["dispersion"], num)
        if "measures" in out:
            im = out["measures"]["backends"].get(b, {})
            res["im_best"] = im.get("best")
            if b != reference:
                res["im_same_best"] = im.get("same_best")
        if b != reference and len(ref):
            tests = []
            mine = ok[ok["backend"] == b]
            for s, rg in ref.groupby("scale", sort=True):
                eg = mine[mine["scale"] == s]
                t = peak_test(rg["peak"], rg["overturned"].astype(bool), eg["peak"],
                              eg["overturned"].astype(bool), floor=floor)
                t.update(scale=float(s), im_median=float(rg["im"].median()))
                tests.append(t)
            rej = _holm([t["p_value"] for t in tests])
            for t, r in zip(tests, rej):
                t["rejected"] = bool(r)
            fin = [t for t in tests if math.isfinite(t["p_value"])]
            worst = min(fin, key=lambda t: (t["p_value"], -t["statistic"])) if fin else None
            diff = res["median"] - fits.get(reference, {}).get("median", math.nan)
            ci = bt.get("median_difference_ci", [math.nan, math.nan])
            same, text = _verdict(b, tests, diff, ci, unit, name, reference,
                                  int(mine["record"].nunique()), int(g["record"].nunique()))
            res.update(tests=tests, statistic=worst["statistic"] if worst else math.nan,
                       p_value=worst["p_value"] if worst else math.nan,
                       median_difference=diff, median_difference_ci=ci,
                       indistinguishable=same, verdict=text)
        out["backends"][b] = res
    return out


# --------------------------------------------------------------------------- the driver

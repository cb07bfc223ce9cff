"""Does a run agree with the analytic reference? :func:`assert_agree`, in the spirit of
Gymnasium's ``env_match``: one function that checks two runs of the same case produce matching
results, and raises ``AssertionError`` saying what failed, by how much and where in time, so
that it reads well in a pytest report. The metrics are those of :mod:`rockbench.comparison`; the
tolerances are entries of its one table, :data:`rockbench.comparison.TOLERANCES`.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import numpy as np

from ..comparison import TOLERANCES
from ..errors import ParameterError

__all__ = ["assert_agree"]

_DEFAULTS = TOLERANCES["assert_agree"]

#: The Scene fields that are labels, not parameters (two runs of one case may differ in them).
_LABELS = ("name", "description")


def _ensure(condition: Any, message: str) -> None:
    """Raise AssertionError(message) unless ``condition`` (unlike ``assert``, also under
    ``python -O``)."""
    __tracebackhide__ = True  # pytest shows the caller's line, not this helper's frames
    if not condition:
        raise AssertionError(message)


def _same_case(result, reference) -> None:
    """ParameterError unless ``result`` and ``reference`` ran the same scene parameters, the
    same ground motion and the same initial rotation."""
    a, b = result.scene, reference.scene
    if type(a) is not type(b):
        raise ParameterError("reference", f"a run of a {type(b).__name__}",
                             f"a run of the same scene as the result ({type(a).__name__})")
    try:
        names = [f.name for f in fields(a)]
    except TypeError:  # not a dataclass: compare as a whole
        names = []
    differ = [n for n in names if n not in _LABELS and getattr(a, n) != getattr(b, n)]
    if differ or (not names and a != b):
        raise ParameterError(
            "reference", f"a run of scene {getattr(b, 'name', '?')!r}",
            f"a run of the same scene parameters as the result (scene "
            f"{getattr(a, 'name', '?')!r})",
            f"they differ in {', '.join(differ) or 'the scene'}: assert_agree compares two runs "
            "of one case")
    if result.motion != reference.motion:
        raise ParameterError(
            "reference", f"a run under {reference.motion}",
            f"a run under the same ground motion as the result ({result.motion})",
            "assert_agree compares two runs of one case")
    h, hr = result.history, reference.history
    if len(h) and len(hr):
        p, pr = float(h["phi"].iloc[0]), float(hr["phi"].iloc[0])
        alpha = float(b.alpha)
        if not abs(p - pr) <= _PHI0_ATOL * alpha:
            raise ParameterError(
                "reference", f"a run from phi0 = {pr:.6g} rad",
                f"a run from the same initial rotation as the result (phi0 = {p:.6g} rad, "
                f"first samples within {_PHI0_ATOL:g} alpha)",
                "assert_agree compares two runs of one case")


#: Two runs start from the same rotation when their first phi samples differ by at most this
#: many alpha (engines reproduce phi0 to ~1e-12 rad; check_backend allows 1e-3 alpha).
_PHI0_ATOL = 1e-6


def _tol(name: str, value: Any) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0 \
            or not math.isfinite(value):
        raise ParameterError(name, value, ">= 0 (or None to skip the check)")
    return float(value)


def _pct(x: float) -> str:
    return f"{100 * x:+.3g} %"


def assert_agree(result, reference, *, peak_rtol: float | None = _DEFAULTS["peak_rtol"],
                 eta_rtol: float | None = _DEFAULTS["eta_rtol"],
                 nrmse: float | None = _DEFAULTS["nrmse"],
                 verdict: bool = _DEFAULTS["verdict"], band=None) -> None:
    """Assert that ``result`` agrees with ``reference`` (normally the analytic run of the same
    scene, motion and phi0); raise ``AssertionError`` listing every metric that does not.

    Parameters
    ----------
    peak_rtol : float or None
        Bound on |max|phi| / max|phi_ref| - 1| [-]. When the reference never uplifts, bound on
        the result's max|phi| / alpha instead.
    eta_rtol : float or None
        Bound on |eta / eta_ref - 1| of every impact the result reports (eta_ref: the analytic
        eta of the impact's direction); impacts whose eta could not be measured are skipped.
    nrmse : float or None
        Bound on the RMS of (phi - phi_ref) / alpha over the common time grid [-].
    verdict : bool
        Require the same overturning verdict.
    band : rockbench.studies.sensitivity.Band, optional
        The analytic model's own sensitivity on this case (:func:`rockbench.studies.sensitivity.band`,
        ``docs/records.md``). When given, the peak check is "within the band": max|phi| / alpha
        of the result in [band.low, band.high] (``peak_rtol`` is not used), and the verdict
        check accepts any overturning verdict that one of the band's analytic runs reaches.
        Use it on records, where a fixed peak tolerance cannot tell an engine error from the
        model's own unpredictability.

    A tolerance of None skips that check. The defaults are
    ``rockbench.comparison.TOLERANCES["assert_agree"]``; the cross-engine bars are other entries of
    that table: ``assert_agree(result, reference, **TOLERANCES["free_rocking"])``. The message
    names each failed metric, by how much it missed, and where in time (time of the peaks, of
    the largest history error, impact index and time, time of overturning). A run that is not
    ``ok`` (diverged) fails at once.

    The two runs must be of the same case: equal scene parameters (name and description aside),
    the same ground motion (``result.motion == reference.motion``) and the same initial rotation
    (first sample of phi); otherwise ``ParameterError`` says what differs.
    """
    __tracebackhide__ = True  # a failure points at the caller's line, not at this function
    from ..comparison import eta_rows, history_error, metrics, peak_of
    from ..result import Result, motion_label

    for nm, r in (("result", result), ("reference", reference)):
        if not isinstance(r, Result):
            raise ParameterError(nm, type(r).__name__, "a rockbench Result")
    peak_rtol, eta_rtol, nrmse = (_tol("peak_rtol", peak_rtol), _tol("eta_rtol", eta_rtol),
                                  _tol("nrmse", nrmse))
    _same_case(result, reference)
    head = (f"{result.backend} vs {reference.backend} on scene "
            f"{getattr(result.scene, 'name', '?')!r} ({motion_label(result.motion)})")
    for tag, r in (("run", result), ("reference run", reference)):
        if not r.ok:
            raise AssertionError(f"{head}: the {tag} of {r.backend} is {r.status}: "
                                 f"{r.summary.reason}")
    alpha = reference.scene.alpha
    m = metrics(result, reference)
    failures: list[str] = []
    n_checks = 0

    if band is not None:
        from ..studies.sensitivity import Band

        if not isinstance(band, Band):
            raise ParameterError("band", type(band).__name__, "a rockbench.studies.sensitivity.Band")
        if band.scene != getattr(result.scene, "name", band.scene):
            raise ParameterError("band", band.scene,
                                 f"the band of this case's scene {result.scene.name!r}")
        n_checks += 1
        pk, t_pk = peak_of(result)
        j = band.judge(pk / alpha)
        if not j.inside:
            failures.append(
                f"peak: max|phi| = {pk / alpha:.4g} alpha at t = {t_pk:.4g} s, outside the "
                f"analytic model's sensitivity band [{band.low:.4g}, {band.high:.4g}] alpha "
                f"(unperturbed {band.nominal:.4g}): {j.text}")
    elif peak_rtol is not None:
        n_checks += 1
        pk, t_pk = peak_of(result)
        pr, t_pr = peak_of(reference)
        if pr > 0:
            err = pk / pr - 1.0
            if abs(err) > peak_rtol:
                failures.append(
                    f"peak: max|phi| = {pk / alpha:.4g} alpha at t = {t_pk:.4g} s vs "
                    f"{pr / alpha:.4g} alpha at t = {t_pr:.4g} s (reference): off by {_pct(err)}"
                    f", tolerance {100 * peak_rtol:.3g} %")
        elif pk / alpha > peak_rtol:
            failures.append(
                f"peak: the reference stays at rest but max|phi| = {pk / alpha:.4g} alpha at "
                f"t = {t_pk:.4g} s, tolerance {peak_rtol:.3g} alpha")

    if nrmse is not None:
        n_checks += 1
        t, err = history_error(result, reference)
        if not err.size:
            failures.append("nrmse: the two histories do not overlap in time")
        elif m["nrmse"] > nrmse:
            i = int(np.argmax(np.abs(err)))
            failures.append(
                f"nrmse: RMS of (phi - phi_ref)/alpha = {m['nrmse']:.4g} > {nrmse:.4g} over "
                f"t = {t[0]:.4g}..{t[-1]:.4g} s; largest error {err[i]:+.4g} alpha at "
                f"t = {t[i]:.4g} s")

    if eta_rtol is not None:
        n_checks += 1
        rows = [r for r in eta_rows(result, reference) if math.isfinite(r["rel_error"])]
        bad = [r for r in rows if abs(r["rel_error"]) > eta_rtol]
        if bad:
            w = max(bad, key=lambda r: abs(r["rel_error"]))
            failures.append(
                f"eta: impact {w['impact']} at t = {w['t']:.4g} s (rocking "
                f"{'ccw' if w['direction'] > 0 else 'cw'} after): eta = {w['eta']:.5g} vs "
                f"analytic {w['eta_ref']:.5g}, off by {_pct(w['rel_error'])}, tolerance "
                f"{100 * eta_rtol:.3g} % ({len(bad)} of {len(rows)} measured impacts outside: "
                f"{', '.join(str(r['impact']) for r in bad[:10])}"
                f"{' ...' if len(bad) > 10 else ''})")

    if verdict:
        n_checks += 1
        so, sr = result.summary, reference.summary
        seen = {bool(sr.overturned)}
        if band is not None:
            ok_runs = band.runs[band.runs["status"] == "ok"]
            seen |= {bool(v) for v in ok_runs["overturned"]}
        if bool(so.overturned) not in seen:
            def desc(s, who):
                if s.overturned:
                    return f"{who} overturned at t = {s.t_overturn:.4g} s"
                return f"{who} did not overturn (max|phi| = {s.max_abs_phi_over_alpha:.4g} alpha)"
            failures.append(f"verdict: {desc(so, result.backend)}, "
                            f"{desc(sr, 'the reference ' + reference.backend)}")

    if failures:
        raise AssertionError(f"{head}: {len(failures)} of {n_checks} checks failed\n  - "
                             + "\n  - ".join(failures))

"""Consistency checks for test suites: :func:`assert_agree` (does a run agree with the
reference?) and :func:`check_backend` (does an adapter honour the backend contract?).

In the spirit of Gymnasium's ``env_checker`` and ``env_match``: one function that any backend
can be run through, one that checks two runs produce matching results. Both raise
``AssertionError`` with a message that says what failed, by how much and where, so that they
read well in a pytest report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any, Callable

import numpy as np
import pandas as pd

from ..errors import ParameterError

__all__ = ["assert_agree", "check_backend", "BackendReport", "Check", "CHECK_SCENE",
           "FREE_ROCKING_ETA_RTOL"]

#: The scene every contract check runs on (Housner's 1 m x 5 m block).
CHECK_SCENE = "housner-block"

#: Tolerance of the free-rocking eta check: |eta / eta_Housner - 1| of every impact [-].
#: pymunk, MuJoCo and PyBullet measure within 0.1-0.3 % at dt = 1e-3 s
#: (``/work/shared/notes/engines.md``, ``docs/testing.md``).
FREE_ROCKING_ETA_RTOL = 0.005

#: Tolerance of the free-rocking history check: RMS of (phi - phi_ref) / alpha [-].
FREE_ROCKING_NRMSE = 0.05


def _ensure(condition: Any, message: str) -> None:
    """Raise AssertionError(message) unless ``condition`` (unlike ``assert``, also under
    ``python -O``)."""
    if not condition:
        raise AssertionError(message)


# =========================================================================================
# assert_agree
# =========================================================================================
def _tol(name: str, value: Any) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0 \
            or not math.isfinite(value):
        raise ParameterError(name, value, ">= 0 (or None to skip the check)")
    return float(value)


def _pct(x: float) -> str:
    return f"{100 * x:+.3g} %"


def _motion_label(result) -> str:
    m = result.motion or {}
    kind = m.get("kind", "none")
    if kind == "ricker":
        s = f"ricker {m.get('shape')} {'+' if m.get('sign', 1) > 0 else '-'}"
        if "A" in m:
            s += f" A={m['A']:.3g} W={m['W']:.3g}"
        return s
    if kind == "none":
        return "free rocking"
    return str(kind)


def assert_agree(result, reference, *, peak_rtol: float | None = 0.03,
                 eta_rtol: float | None = 0.005, nrmse: float | None = 0.005,
                 verdict: bool = True) -> None:
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

    A tolerance of None skips that check. The message names each failed metric, by how much it
    missed, and where in time (time of the peaks, of the largest history error, impact index
    and time, time of overturning). A run that is not ``ok`` (diverged) fails at once.
    """
    from ..compare import _peak, eta_rows, history_error, metrics
    from ..result import Result

    for nm, r in (("result", result), ("reference", reference)):
        if not isinstance(r, Result):
            raise ParameterError(nm, type(r).__name__, "a rockbench Result")
    peak_rtol, eta_rtol, nrmse = (_tol("peak_rtol", peak_rtol), _tol("eta_rtol", eta_rtol),
                                  _tol("nrmse", nrmse))
    head = (f"{result.backend} vs {reference.backend} on scene "
            f"{getattr(result.scene, 'name', '?')!r} ({_motion_label(result)})")
    for tag, r in (("run", result), ("reference run", reference)):
        if not r.ok:
            raise AssertionError(f"{head}: the {tag} of {r.backend} is {r.status}: "
                                 f"{r.summary.reason}")
    alpha = reference.scene.alpha
    m = metrics(result, reference)
    failures: list[str] = []
    n_checks = 0

    if peak_rtol is not None:
        n_checks += 1
        pk, t_pk = _peak(result)
        pr, t_pr = _peak(reference)
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
        if bool(so.overturned) != bool(sr.overturned):
            def desc(s, who):
                if s.overturned:
                    return f"{who} overturned at t = {s.t_overturn:.4g} s"
                return f"{who} did not overturn (max|phi| = {s.max_abs_phi_over_alpha:.4g} alpha)"
            failures.append(f"verdict: {desc(so, result.backend)}, "
                            f"{desc(sr, 'the reference ' + reference.backend)}")

    if failures:
        raise AssertionError(f"{head}: {len(failures)} of {n_checks} checks failed\n  - "
                             + "\n  - ".join(failures))


# =========================================================================================
# check_backend
# =========================================================================================
@dataclass
class Check:
    """One contract check: ``status`` is "pass", "fail" or "skip"; ``detail`` says why."""

    name: str
    status: str
    detail: str = ""


@dataclass
class BackendReport:
    """Outcome of :func:`check_backend`: one :class:`Check` per contract item."""

    backend: str
    version: str
    settings: dict[str, Any]
    checks: list[Check] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(c.status != "fail" for c in self.checks)

    @property
    def failed(self) -> list[Check]:
        return [c for c in self.checks if c.status == "fail"]

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame([vars(c) for c in self.checks], columns=["name", "status", "detail"])

    def __str__(self) -> str:
        lines = [f"check_backend({self.backend!r}) - {self.version}"]
        w = max((len(c.name) for c in self.checks), default=0)
        for c in self.checks:
            lines.append(f"  {c.status.upper():4}  {c.name:<{w}}  {c.detail}")
        return "\n".join(lines)


class _Checker:
    def __init__(self, report: BackendReport):
        self.report = report

    def __call__(self, name: str, fn: Callable[[], str | None]) -> Any:
        try:
            detail = fn()
        except _Skip as e:
            self.report.checks.append(Check(name, "skip", str(e)))
            return
        except AssertionError as e:
            self.report.checks.append(Check(name, "fail", str(e)))
            return
        except Exception as e:  # an adapter that raises where it should report
            self.report.checks.append(Check(name, "fail", f"raised {type(e).__name__}: {e}"))
            return
        self.report.checks.append(Check(name, "pass", detail or ""))


class _Skip(Exception):
    pass


def _check_schema(result, name: str, motion, t0: float, t_end: float, is_engine: bool) -> str:
    from ..result import (CONTACT_COLUMNS, EVENT_COLUMNS, EVENT_KINDS, HISTORY_COLUMNS, STATUSES,
                          Cost, Result, Summary)

    _ensure(isinstance(result, Result), f"run() returned {type(result).__name__}, not a Result")
    _ensure(result.backend == name, f"result.backend = {result.backend!r}, expected {name!r}")
    _ensure(isinstance(result.summary, Summary) and isinstance(result.cost, Cost),
            "summary / cost are not Summary / Cost")
    _ensure(result.summary.status in STATUSES,
            f"status {result.summary.status!r} not in {STATUSES}")
    h = result.history
    _ensure(isinstance(h, pd.DataFrame), "history is not a DataFrame")
    need = list(HISTORY_COLUMNS) + (list(CONTACT_COLUMNS) if is_engine else [])
    missing = [c for c in need if c not in h.columns]
    _ensure(not missing, f"history lacks columns {missing}")
    _ensure(len(h) >= 2, f"history has {len(h)} rows")
    for c in need:
        if c == "mode":
            _ensure(pd.api.types.is_integer_dtype(h[c]),
                    f"history.mode dtype {h[c].dtype}, not int")
            _ensure(set(np.unique(h[c])) <= {-1, 0, 1}, "history.mode outside {-1, 0, +1}")
        elif c == "devices_intact":
            _ensure(pd.api.types.is_bool_dtype(h[c]),
                    f"devices_intact dtype {h[c].dtype}, not bool")
        else:
            _ensure(h[c].dtype == np.float64, f"history.{c} dtype {h[c].dtype}, not float64")
    t = h["t"].to_numpy()
    dt = np.diff(t)
    _ensure(np.all(dt > 0), "history.t is not strictly increasing")
    _ensure(np.ptp(dt) <= 1e-9 * max(1.0, abs(t[-1])) + 1e-9 * dt.mean(),
            f"history.t is not a uniform grid (steps {dt.min():.6g}..{dt.max():.6g} s)")
    odt = getattr(result.settings, "get", lambda *_: None)("output_dt")
    if odt is not None:
        _ensure(math.isclose(dt.mean(), odt, rel_tol=1e-6),
                f"history.t step {dt.mean():.6g} s != settings output_dt {odt:g} s")
    _ensure(math.isclose(t[0], t0, abs_tol=1e-9),
            f"history starts at {t[0]:.6g} s, not {t0:.6g} s")
    if not result.summary.overturned:
        _ensure(math.isclose(t[-1], t_end, abs_tol=1e-6 + dt.mean()),
                f"history ends at {t[-1]:.6g} s, not {t_end:.6g} s")
    ev = result.events
    missing = [c for c in EVENT_COLUMNS if c not in ev.columns]
    _ensure(not missing, f"events lack columns {missing}")
    bad = set(ev["kind"]) - set(EVENT_KINDS)
    _ensure(not bad, f"unknown event kinds {sorted(bad)}")
    _ensure(result.motion == (motion.describe() if motion is not None else {"kind": "none"}),
            "result.motion is not motion.describe()")
    return f"{len(h)} rows x {h.shape[1]} columns, dt_out = {dt.mean():.3g} s, {len(ev)} events"


def _check_units(result, motion, scene) -> str:
    h = result.history
    t = h["t"].to_numpy()
    acc = motion.acceleration(t)
    err = float(np.max(np.abs(h["ground_acc"].to_numpy() - acc)))
    _ensure(err <= 1e-9 * motion.peak + 1e-12,
            f"ground_acc differs from motion.acceleration(t) by up to {err:.3g} m/s^2 "
            "(units m/s^2?)")
    phi = h["phi"].to_numpy()
    mx = float(np.max(np.abs(phi)))
    _ensure(math.isclose(result.summary.max_abs_phi, mx, rel_tol=1e-9, abs_tol=1e-15),
            f"summary.max_abs_phi = {result.summary.max_abs_phi:.6g} rad != max|history.phi| "
            f"= {mx:.6g} rad")
    _ensure(math.isclose(result.summary.max_abs_phi_over_alpha, mx / scene.alpha,
                         rel_tol=1e-9, abs_tol=1e-15),
            "summary.max_abs_phi_over_alpha != max|phi| / alpha")
    grad = np.gradient(phi, t)
    pdot = h["phidot"].to_numpy()
    scale = float(np.max(np.abs(pdot)))
    _ensure(scale > 0, "phidot is identically zero while phi moves")
    moving = np.abs(pdot) > 0.05 * scale
    dev = float(np.median(np.abs(grad[moving] - pdot[moving]) / np.abs(pdot[moving])))
    _ensure(dev <= 0.05,
            f"phidot is not d(phi)/dt in rad/s: median |dphi/dt / phidot - 1| = {dev:.3g} while "
            f"rocking (max |phidot| = {scale:.3g} rad/s)")
    sim = result.cost.sim_time
    span = t[-1] - t[0]
    _ensure(math.isclose(sim, span, rel_tol=1e-6, abs_tol=1e-6),
            f"cost.sim_time = {sim:.6g} s, history spans {span:.6g} s")
    _ensure(result.cost.wall_s >= 0 and result.cost.steps >= 1,
            f"cost: wall_s = {result.cost.wall_s}, steps = {result.cost.steps}")
    return (f"ground_acc in m/s^2 (max error {err:.2g}), phidot = dphi/dt (median relative "
            f"deviation {dev:.2g} while rocking), summary consistent")


def _same_frames(a: pd.DataFrame, b: pd.DataFrame) -> str | None:
    if list(a.columns) != list(b.columns) or len(a) != len(b):
        return f"shapes differ: {a.shape} vs {b.shape}"
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if x.dtype.kind == "f":
            same = np.array_equal(x, y, equal_nan=True)
        else:
            same = bool(np.all(pd.Series(x).fillna(-9e99).to_numpy()
                               == pd.Series(y).fillna(-9e99).to_numpy()))
        if not same:
            if x.dtype.kind == "f":
                d = np.abs(x - y)
                i = int(np.nanargmax(d)) if np.any(np.isfinite(d)) else 0
                return f"column {c!r} differs (by up to {np.nanmax(d):.3g} at row {i})"
            return f"column {c!r} differs"
    return None


def check_backend(name, **settings: Any) -> BackendReport:
    """Run backend ``name`` (a registered name, or a Backend subclass not registered yet)
    through the backend contract, with ``settings`` as setting overrides for every run.

    Checks (each "pass", "fail" or "skip"):

    * ``available`` - ``available()`` returns (True, version);
    * ``settings`` - a frozen dataclass whose defaults construct, overrides applied;
    * ``schema`` - a Ricker-pulse run on :data:`CHECK_SCENE`: a Result, every history column
      (engines: and contact columns) with the right dtype, a uniform time grid of
      ``output_dt`` from the motion's start to the end, event columns and kinds, motion record;
    * ``units`` - ground_acc in m/s^2 equals the motion, phidot = d(phi)/dt [rad/s], the summary
      and the cost agree with the history;
    * ``phi definition`` - free rocking from phi0 = +-alpha/2: the history starts at phi0 and
      rocks back towards 0, and follows the analytic history (RMS error / alpha below
      :data:`FREE_ROCKING_NRMSE`);
    * ``repeatability`` - two identical runs give identical histories and events;
    * ``free-rocking eta`` - every impact's eta within :data:`FREE_ROCKING_ETA_RTOL` of
      Housner's 1 - 1.5 sin^2(alpha);
    * ``bad input`` - ParameterError for a negative duration, a non-finite or too large phi0,
      an unknown setting and a non-Scene scene;
    * ``divergence reported`` - a run set up to fail (max_penetration = 1e-12 m) returns a Result
      with status "diverged" and a reason instead of raising (skipped for backends without
      ``max_penetration``).

    Returns the :class:`BackendReport` when every check passes; raises ``AssertionError``
    listing every failed check otherwise.
    """
    from ..engines import get_backend
    from ..engines.base import Backend
    from ..scene.motion import RickerPulse
    from ..scene.scene import load_scene

    if isinstance(name, type) and issubclass(name, Backend):
        cls = name
        name = getattr(cls, "name", cls.__name__)
    else:
        cls = get_backend(name)
    scene = load_scene(CHECK_SCENE)
    alpha = scene.alpha
    pulse = RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure)
    duration = 3.0
    t0, t_end = pulse.t_start, pulse.t_start + duration
    ok, version = False, "?"
    report = BackendReport(backend=str(name), version=version, settings=dict(settings))
    check = _Checker(report)
    is_engine = name != "analytic"
    ctx: dict[str, Any] = {}

    def available():
        nonlocal ok, version
        res = cls.available()
        _ensure(isinstance(res, tuple) and len(res) == 2, "available() must return (bool, str)")
        ok, version = bool(res[0]), str(res[1])
        report.version = version
        _ensure(ok, f"not available: {version}")
        return version

    check("available", available)
    if not ok:
        raise AssertionError(f"check_backend({name!r}) failed:\n{report}")

    def make(**extra):
        return cls(scene, **{**settings, **extra})

    def settings_check():
        S = cls.Settings
        _ensure(is_dataclass(S), f"{cls.__name__}.Settings is not a dataclass")
        _ensure(S.__dataclass_params__.frozen, f"{cls.__name__}.Settings is not frozen")
        S()
        b = make()
        _ensure(isinstance(b.settings, S), "backend.settings is not a Settings instance")
        for k, v in settings.items():
            _ensure(getattr(b.settings, k) == v, f"setting {k} = {v!r} was not applied")
        return f"{len(fields(S))} fields"

    check("settings", settings_check)

    def schema():
        r = make().run(pulse, duration=duration)
        ctx["pulse"] = r
        _ensure(r.ok, f"the check run is {r.status}: {r.summary.reason}")
        return _check_schema(r, str(name), pulse, t0, t_end, is_engine)

    check("schema", schema)

    def units():
        if "pulse" not in ctx or not ctx["pulse"].ok:
            raise _Skip("no valid pulse run")
        return _check_units(ctx["pulse"], pulse, scene)

    check("units", units)

    def phi_definition():
        from ..engines import get_backend as gb
        out = []
        for sgn in (1, -1):
            phi0 = 0.5 * alpha * sgn
            r = make().run(None, duration=1.0, phi0=phi0)
            _ensure(r.ok,
                    f"free rocking from phi0 = {phi0:+.4g} rad is {r.status}: "
                    f"{r.summary.reason}")
            h = r.history
            p0 = float(h["phi"].iloc[0])
            _ensure(abs(p0 - phi0) <= 1e-3 * alpha,
                    f"history starts at phi = {p0:+.6g} rad, not phi0 = {phi0:+.6g} rad")
            later = float(h.loc[h["t"] <= 0.2, "phi"].iloc[-1])
            _ensure(sgn * later < sgn * phi0,
                    f"from phi0 = {phi0:+.4g} rad, phi(0.2 s) = {later:+.4g} rad: not rocking back "
                    "towards 0 (sign convention: + counterclockwise, rotation of the left column)")
            ref = gb("analytic")(scene).run(None, duration=1.0, phi0=phi0)
            from ..compare import history_error
            _, err = history_error(r, ref)
            e = float(np.sqrt(np.mean(err ** 2)))
            _ensure(e <= FREE_ROCKING_NRMSE,
                    f"from phi0 = {phi0:+.4g} rad the history departs from the analytic one: RMS "
                    f"error {e:.3g} alpha > {FREE_ROCKING_NRMSE}")
            out.append(f"{e:.2g}")
        return f"phi(0) = phi0, RMS error vs analytic {', '.join(out)} alpha (+phi0, -phi0)"

    check("phi definition", phi_definition)

    def repeatability():
        a = ctx.get("pulse") or make().run(pulse, duration=duration)
        b = make().run(pulse, duration=duration)
        d = _same_frames(a.history, b.history)
        _ensure(d is None, f"two identical runs differ: history {d}")
        d = _same_frames(a.events, b.events)
        _ensure(d is None, f"two identical runs differ: events {d}")
        return "two runs identical"

    check("repeatability", repeatability)

    def free_eta():
        eta_h = scene.structure.eta_housner
        r = make().run(None, duration=4.0, phi0=0.5 * alpha)
        _ensure(r.ok, f"free rocking run is {r.status}: {r.summary.reason}")
        imp = r.impacts()
        _ensure(len(imp) >= 2,
                f"{len(imp)} impacts in 4 s of free rocking from alpha/2 "
                "(expected 3)")
        e = imp["eta"].to_numpy(dtype=float)
        _ensure(np.all(np.isfinite(e)), f"impact eta not measured: {e}")
        rel = e / eta_h - 1
        i = int(np.argmax(np.abs(rel)))
        _ensure(abs(rel[i]) <= FREE_ROCKING_ETA_RTOL,
                f"impact {i} at t = {imp['t'].iloc[i]:.4g} s: eta = {e[i]:.5g} vs Housner "
                f"{eta_h:.5g}, off by {_pct(rel[i])} "
                f"(tolerance {100 * FREE_ROCKING_ETA_RTOL:.2g} %)")
        return f"{len(e)} impacts, max |eta/eta_Housner - 1| = {abs(rel[i]):.2%}"

    check("free-rocking eta", free_eta)

    def bad_input():
        cases = [("duration=-1", lambda: make().run(pulse, duration=-1.0)),
                 ("phi0=nan", lambda: make().run(None, duration=1.0, phi0=float("nan"))),
                 ("phi0=2 rad (beyond the fall angle)",
                  lambda: make().run(None, duration=1.0, phi0=2.0)),
                 ("unknown setting", lambda: make(not_a_setting=1)),
                 ("scene='housner-block' (a str)", lambda: cls("housner-block", **settings))]
        missed = []
        for label, fn in cases:
            try:
                fn()
            except ParameterError:
                continue
            except Exception as e:
                missed.append(f"{label} raised {type(e).__name__}, not ParameterError")
                continue
            missed.append(f"{label} did not raise")
        _ensure(not missed, "; ".join(missed))
        return f"{len(cases)} bad inputs raise ParameterError"

    check("bad input", bad_input)

    def divergence():
        if "max_penetration" not in {f.name for f in fields(cls.Settings)}:
            raise _Skip("no max_penetration setting to force a divergence")
        r = make(max_penetration=1e-12).run(None, duration=0.5, phi0=0.5 * alpha)
        _ensure(r.status == "diverged",
                f"status {r.status!r}, expected 'diverged' "
                "(max_penetration = 1e-12 m)")
        _ensure(r.summary.reason, "a diverged run must say why (summary.reason)")
        from ..result import HISTORY_COLUMNS
        missing = [c for c in HISTORY_COLUMNS if c not in r.history.columns]
        _ensure(not missing, f"the diverged Result's history lacks {missing}")
        return f"reported: {r.summary.reason}"

    check("divergence reported", divergence)

    if not report.ok:
        lines = [f"  - {c.name}: {c.detail}" for c in report.failed]
        raise AssertionError(f"check_backend({str(name)!r}) [{version}]: {len(lines)} of "
                             f"{len(report.checks)} checks failed\n" + "\n".join(lines))
    return report

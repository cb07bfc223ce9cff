"""Does a backend adapter honour the contract of :mod:`rockbench.engines.base`?
:func:`check_backend`, in the spirit of Gymnasium's ``env_checker``: one function any backend
(registered or not) can be run through, made of small ``check_*`` functions, one per contract
item, each returning a one-line detail or raising ``AssertionError`` saying what failed.

The checks run on :data:`CHECK_SCENE` (Housner's block); the free-rocking bars are
``rockbench.comparison.TOLERANCES["check_backend"]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any, Callable

import numpy as np
import pandas as pd

from ..comparison import TOLERANCES
from ..errors import ParameterError
from .agree import _ensure, _pct

__all__ = ["check_backend", "BackendReport", "Check", "CHECKS", "CHECK_SCENE",
           "FREE_ROCKING_ETA_RTOL", "FREE_ROCKING_NRMSE"]

#: The scene every contract check runs on (Housner's 1 m x 5 m block).
CHECK_SCENE = "housner-block"

#: Tolerance of the free-rocking eta check: |eta / eta_Housner - 1| of every impact [-].
FREE_ROCKING_ETA_RTOL = TOLERANCES["check_backend"]["eta_rtol"]

#: Tolerance of the free-rocking history check: RMS of (phi - phi_ref) / alpha [-] over 1 s.
FREE_ROCKING_NRMSE = TOLERANCES["check_backend"]["nrmse"]


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


class _Skip(Exception):
    """Raised by a check that does not apply (its detail says why)."""


def _schema(result, name: str, motion, t0: float, t_end: float, is_engine: bool) -> str:
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


def _units(result, motion, scene) -> str:
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


@dataclass
class _Context:
    """What the checks share: the adapter, its setting overrides, the check scene and pulse,
    and the pulse run (made by :func:`check_schema`, reused by the later checks)."""

    cls: type
    name: str
    settings: dict[str, Any]
    scene: Any
    pulse: Any
    duration: float = 3.0
    pulse_run: Any = None

    @property
    def is_engine(self) -> bool:
        return self.name != "analytic"

    def make(self, **extra: Any):
        """A backend on the check scene with the overrides (and ``extra``)."""
        return self.cls(self.scene, **{**self.settings, **extra})

    def run_pulse(self):
        return self.make().run(self.pulse, duration=self.duration)


# =========================================================================================
# The checks, one per contract item (each returns its detail or raises AssertionError)
# =========================================================================================
def check_available(c: _Context) -> str:
    """``available()`` returns ``(True, version)``."""
    res = c.cls.available()
    _ensure(isinstance(res, tuple) and len(res) == 2, "available() must return (bool, str)")
    _ensure(bool(res[0]), f"not available: {res[1]}")
    return str(res[1])


def check_settings(c: _Context) -> str:
    """``Settings`` is a frozen dataclass whose defaults construct; overrides are applied."""
    S = c.cls.Settings
    _ensure(is_dataclass(S), f"{c.cls.__name__}.Settings is not a dataclass")
    _ensure(S.__dataclass_params__.frozen, f"{c.cls.__name__}.Settings is not frozen")
    S()
    b = c.make()
    _ensure(isinstance(b.settings, S), "backend.settings is not a Settings instance")
    for k, v in c.settings.items():
        _ensure(getattr(b.settings, k) == v, f"setting {k} = {v!r} was not applied")
    return f"{len(fields(S))} fields"


def check_schema(c: _Context) -> str:
    """A pulse run returns a Result of the schema (columns, dtypes, uniform output grid from
    the motion's start to the end, events, motion record)."""
    r = c.pulse_run = c.run_pulse()
    _ensure(r.ok, f"the check run is {r.status}: {r.summary.reason}")
    t0 = c.pulse.t_start
    return _schema(r, c.name, c.pulse, t0, t0 + c.duration, c.is_engine)


def check_units(c: _Context) -> str:
    """ground_acc in m/s^2 equals the motion, phidot = d(phi)/dt [rad/s], summary and cost
    agree with the history."""
    if c.pulse_run is None or not c.pulse_run.ok:
        raise _Skip("no valid pulse run")
    return _units(c.pulse_run, c.pulse, c.scene)


def check_phi_definition(c: _Context) -> str:
    """Free rocking from phi0 = +-alpha/2 starts at phi0, rocks back towards 0 and follows the
    analytic history (RMS error / alpha <= :data:`FREE_ROCKING_NRMSE`)."""
    from ..comparison import history_error
    from ..engines import get_backend

    alpha, out = c.scene.alpha, []
    for sgn in (1, -1):
        phi0 = 0.5 * alpha * sgn
        r = c.make().run(None, duration=1.0, phi0=phi0)
        _ensure(r.ok, f"free rocking from phi0 = {phi0:+.4g} rad is {r.status}: "
                      f"{r.summary.reason}")
        h = r.history
        p0 = float(h["phi"].iloc[0])
        _ensure(abs(p0 - phi0) <= 1e-3 * alpha,
                f"history starts at phi = {p0:+.6g} rad, not phi0 = {phi0:+.6g} rad")
        later = float(h.loc[h["t"] <= 0.2, "phi"].iloc[-1])
        _ensure(sgn * later < sgn * phi0,
                f"from phi0 = {phi0:+.4g} rad, phi(0.2 s) = {later:+.4g} rad: not rocking back "
                "towards 0 (sign convention: + counterclockwise, rotation of the left column)")
        ref = get_backend("analytic")(c.scene).run(None, duration=1.0, phi0=phi0)
        _, err = history_error(r, ref)
        e = float(np.sqrt(np.mean(err ** 2)))
        _ensure(e <= FREE_ROCKING_NRMSE,
                f"from phi0 = {phi0:+.4g} rad the history departs from the analytic one: RMS "
                f"error {e:.3g} alpha > {FREE_ROCKING_NRMSE}")
        out.append(f"{e:.2g}")
    return f"phi(0) = phi0, RMS error vs analytic {', '.join(out)} alpha (+phi0, -phi0)"


def check_repeatability(c: _Context) -> str:
    """Two identical runs give identical histories and events."""
    a = c.pulse_run or c.run_pulse()
    b = c.run_pulse()
    d = _same_frames(a.history, b.history)
    _ensure(d is None, f"two identical runs differ: history {d}")
    d = _same_frames(a.events, b.events)
    _ensure(d is None, f"two identical runs differ: events {d}")
    return "two runs identical"


def check_free_rocking_eta(c: _Context) -> str:
    """Every impact of free rocking from alpha/2 has its eta within
    :data:`FREE_ROCKING_ETA_RTOL` of Housner's 1 - 1.5 sin^2(alpha)."""
    eta_h = c.scene.structure.eta_housner
    r = c.make().run(None, duration=4.0, phi0=0.5 * c.scene.alpha)
    _ensure(r.ok, f"free rocking run is {r.status}: {r.summary.reason}")
    imp = r.impacts()
    _ensure(len(imp) >= 2, f"{len(imp)} impacts in 4 s of free rocking from alpha/2 "
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


def check_bad_input(c: _Context) -> str:
    """ParameterError for a negative duration, a NaN phi0, a phi0 beyond the fall angle, an
    unknown setting and a scene that is not a Scene."""
    cases = [("duration=-1", lambda: c.make().run(c.pulse, duration=-1.0)),
             ("phi0=nan", lambda: c.make().run(None, duration=1.0, phi0=float("nan"))),
             ("phi0=2 rad (beyond the fall angle)",
              lambda: c.make().run(None, duration=1.0, phi0=2.0)),
             ("unknown setting", lambda: c.make(not_a_setting=1)),
             ("scene='housner-block' (a str)", lambda: c.cls("housner-block", **c.settings))]
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


def check_divergence_reported(c: _Context) -> str:
    """A run forced to fail (max_penetration = 1e-12 m) returns a Result with status
    "diverged" and a reason instead of raising (skipped without ``max_penetration``)."""
    from ..result import HISTORY_COLUMNS

    if "max_penetration" not in {f.name for f in fields(c.cls.Settings)}:
        raise _Skip("no max_penetration setting to force a divergence")
    r = c.make(max_penetration=1e-12).run(None, duration=0.5, phi0=0.5 * c.scene.alpha)
    _ensure(r.status == "diverged",
            f"status {r.status!r}, expected 'diverged' (max_penetration = 1e-12 m)")
    _ensure(r.summary.reason, "a diverged run must say why (summary.reason)")
    missing = [c_ for c_ in HISTORY_COLUMNS if c_ not in r.history.columns]
    _ensure(not missing, f"the diverged Result's history lacks {missing}")
    return f"reported: {r.summary.reason}"


#: The contract, in order: (name, check). ``available`` comes first: nothing else can run
#: without it.
CHECKS: list[tuple[str, Callable[[_Context], str]]] = [
    ("available", check_available),
    ("settings", check_settings),
    ("schema", check_schema),
    ("units", check_units),
    ("phi definition", check_phi_definition),
    ("repeatability", check_repeatability),
    ("free-rocking eta", check_free_rocking_eta),
    ("bad input", check_bad_input),
    ("divergence reported", check_divergence_reported),
]


def _outcome(fn: Callable[[_Context], str], c: _Context) -> tuple[str, str]:
    """(status, detail) of one check: an adapter that raises where it should report fails."""
    try:
        return "pass", fn(c) or ""
    except _Skip as e:
        return "skip", str(e)
    except AssertionError as e:
        return "fail", str(e)
    except Exception as e:
        return "fail", f"raised {type(e).__name__}: {e}"


def check_backend(name, **settings: Any) -> BackendReport:
    """Run backend ``name`` (a registered name, or a Backend subclass not registered yet)
    through the backend contract (:data:`CHECKS`, each "pass", "fail" or "skip"), with
    ``settings`` as setting overrides for every run, on :data:`CHECK_SCENE`.

    Returns the :class:`BackendReport` when every check passes; raises ``AssertionError``
    listing every failed check otherwise (at once if the backend is not available).
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
    c = _Context(cls=cls, name=str(name), settings=dict(settings), scene=scene,
                 pulse=RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure))
    report = BackendReport(backend=str(name), version="?", settings=dict(settings))
    for label, fn in CHECKS:
        status, detail = _outcome(fn, c)
        report.checks.append(Check(label, status, detail))
        if label == "available":
            if status != "pass":
                raise AssertionError(f"check_backend({str(name)!r}) failed:\n{report}")
            report.version = detail
    if not report.ok:
        lines = [f"  - {ck.name}: {ck.detail}" for ck in report.failed]
        raise AssertionError(f"check_backend({str(name)!r}) [{report.version}]: {len(lines)} "
                             f"of {len(report.checks)} checks failed\n" + "\n".join(lines))
    return report

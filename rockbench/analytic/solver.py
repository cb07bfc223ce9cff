"""Event-driven integration of the SDOF rocking model (the analytic reference backend).

The state is (phi, phi') with a discrete mode: at rest (0) or rocking counterclockwise (+1) or
clockwise (-1), and whether the devices are intact. Between events, Eq. 17 of the mechanism of
the current mode is integrated with ``scipy.integrate.solve_ivp`` (an explicit Runge-Kutta method
of order 8, DOP853, with tight tolerances) and these events:

* uplift (from rest): the ground acceleration *exceeds* lambda_ccw g (1 + UPLIFT_RTOL) or falls
  below lambda_cw g (1 + UPLIFT_RTOL) (Eq. 20), found by a strict comparison on the motion's
  knots and Brent's method, stepped just past the root so that the excess is strictly positive:
  a grazing (tangent) touch of the threshold is not an uplift;
* impact: phi returns to 0; phi'+ = eta phi'-, with eta of the mechanism the structure rocks into
  after the impact (:mod:`rockbench.analytic.impact`). A post-impact |phi'| below the rest
  threshold ends the rocking (the structure is at rest; it may uplift again at once), and so
  does impact chatter (two successive small post-impact velocities, close in time: the
  structure settles onto its base instead of stepping through a Zeno sequence of impacts);
* fracture: a tendon's strain reaches eps_f; tendons and dampers are removed for the rest of the run;
* overturn: |phi| reaches the scene's fall angle (terminal);
* critical (recorded only): |phi| exceeds the critical angle of the current potential, by an
  upward crossing or because a segment starts at or beyond it (after a change of the potential:
  fracture; or from the initial rotation);
* peak (recorded only): phi' = 0 while rocking, i.e. a local extremum of phi.

The rules and their constants (uplift margin, rest, chatter, progress) are stated once in
:mod:`rockbench.analytic.rules`. The event loop cannot spin: if it stops advancing in time (or
the integrator or the uplift search fails) the run ends there with
``summary.status == "invalid"`` and the reason, never with an exception.

A run ends at ``t_end`` or, earlier, once the structure is at rest and the ground motion can no
longer uplift it.

Vertical ground motion (``motion.vertical``, a_v up positive): Eq. 17 with g replaced by
g + a_v(t) (:mod:`rockbench.analytic.reactions` derives it), and the uplift thresholds with it,
u_g'' > lambda_ccw (g + a_v) (1 + UPLIFT_RTOL) or u_g'' < lambda_cw (g + a_v) (1 + UPLIFT_RTOL).
The model holds while g + a_v > 0: the run stops at the first instant the ground falls faster
than gravity (:func:`rockbench.validity.lift_off_time`; ``summary.t_lift_off``).

Validity along the run (both analytic paths, :func:`finish_validity`): the friction the
contacts need at every output step (:func:`rockbench.analytic.reactions.demand_history`) is
compared with the scene's friction; the first excess is ``summary.sliding_onset`` (and
``sliding_contact``), and ``summary.validity`` says from when the run is outside the model. The
history goes on after a sliding onset (the rocking model's own answer, to compare engines with
up to the onset); ``status`` stays "ok" (the integration succeeded).
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from ..constants import G
from ..errors import ParameterError, check_positive, check_range
from ..result import (CONTACT_COLUMNS, HISTORY_COLUMNS, Cost, Result, Summary, events_frame,
                      output_grid)
from ..run_length import run_length
from ..scene.scene import Scene
from ..validity import lift_off_time
from . import rules
from .reference import Reference, reference_of

__all__ = ["AnalyticSettings", "METHODS", "simulate", "finish_validity"]


#: Values of ``AnalyticSettings.method``: the path chooser, the compiled path, solve_ivp's methods.
METHODS = ("auto", "compiled", "DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class AnalyticSettings:
    """Settings of the analytic backend.

    rtol, atol : relative and absolute tolerances of solve_ivp (atol in rad and rad/s); rtol in
        [1e-13, 1e-3], atol in [1e-16, 1e-3] (limits ``rtol``, ``atol`` of
        :mod:`rockbench.limits`, overridable with ROCKBENCH_RTOL / ROCKBENCH_ATOL).
    method : "auto" (default): a record through the compiled path when numba imports, any
        other motion (pulses, free rocking) through ``solve_ivp`` with DOP853; "compiled": the
        same DOP853 scheme and event rules compiled with numba
        (:mod:`rockbench.analytic.compiled`, the default of maps); or a solve_ivp method
        ("DOP853", the plain reference path; "RK45", "Radau" ...). Both DOP853 paths agree on
        every well-conditioned quantity (docs/reproducibility.md); ``Result.settings["path"]``
        says which one ran.
    output_dt : interval [s] of the history samples (independent of the integrator's steps),
        in [1e-5, 1] s (limit ``output_dt``).
    rest_ratio : a post-impact |phi'| below rest_ratio * p * alpha [rad/s] ends rocking
        (default :data:`rockbench.analytic.rules.REST_RATIO`).
    history : "full" (every column) or "minimal" (t, phi, phidot, ground_acc, mode,
        devices_intact; other columns NaN) - minimal is faster for sweeps.
    eta_factor : factor in (0, 2] [-] on the coefficient of restitution of every impact
        (default 1: the analytic eta of the mechanism rocked into, Eq. 22 / the frame's
        impulse-momentum projection). A sensitivity hook, not a physics setting: the
        predictability band of :mod:`rockbench.studies.sensitivity` runs the model with eta x (1 +-
        0.5 %) and x (1 +- 1 %).
    """

    rtol: float = 1e-10
    atol: float = 1e-12
    method: str = "auto"
    output_dt: float = 1e-3
    rest_ratio: float = rules.REST_RATIO
    history: str = "full"
    eta_factor: float = 1.0

    def __post_init__(self) -> None:
        from ..limits import check_in_limit

        # rtol in [1e-13, 1e-3], atol in [1e-16, 1e-3] (rad, rad/s), output_dt in [1e-5, 1] s:
        # limits of rockbench.limits (docs/errors.md); rtol >= 1 is no accuracy at all
        for name in ("rtol", "atol", "output_dt"):
            object.__setattr__(self, name, check_in_limit(name, name, getattr(self, name)))
        object.__setattr__(self, "rest_ratio", check_positive("rest_ratio", self.rest_ratio))
        object.__setattr__(self, "eta_factor",
                           check_range("eta_factor", self.eta_factor, 0.0, 2.0, lo_open=True))
        if self.history not in ("full", "minimal"):
            raise ParameterError("history", self.history, "'full' or 'minimal'")
        if self.method not in METHODS:
            raise ParameterError("method", self.method,
                                 "auto (records compiled, other motions solve_ivp), compiled "
                                 "(the numba path, same scheme as DOP853) or one of DOP853, "
                                 "RK45, RK23, Radau, BDF, LSODA (solve_ivp)")


class _Zero:
    """Ground motion of a free-rocking run."""

    t_start = 0.0
    t_end = 0.0
    peak = 0.0

    def acceleration(self, t):
        return np.zeros_like(t) if isinstance(t, np.ndarray) else 0.0

    def knots(self, t0, t1):
        return np.array([t0, t1])

    def max_abs_after(self, t):
        return 0.0

    def describe(self):
        return {"kind": "none"}


def _event(fun, direction: float, terminal: bool):
    fun.direction = direction
    fun.terminal = terminal
    return fun


def simulate(scene: Scene, motion=None, *, duration: float | None = None, phi0: float = 0.0,
             phidot0: float = 0.0, settings: AnalyticSettings | None = None,
             reference: Reference | None = None) -> Result:
    """Run the analytic SDOF model of ``scene`` under ``motion``.

    Parameters
    ----------
    scene : Scene
    motion : GroundMotion or None
        None for free rocking (then ``phi0`` must be non-zero).
    duration : float, optional
        Simulated time [s] from the motion's start (``t_start``; -3 T_g for a Ricker pulse, 0 for
        a record or free rocking). Default: until the motion ends plus 10 s.
    phi0, phidot0 : float
        Initial rotation [rad] and angular velocity [rad/s] (default: rest).
    settings : AnalyticSettings
        ``method`` "auto" or "compiled" integrates DOP853 here (this function is the solve_ivp
        path; the backend chooses between paths).
    reference : Reference, optional
        Precomputed constants of ``scene`` (saves their set-up in sweeps).
    """
    settings = settings or AnalyticSettings()
    ivp_method = "DOP853" if settings.method in ("auto", "compiled") else settings.method
    ref = reference if reference is not None and reference.scene == scene else reference_of(scene)
    mot = motion if motion is not None else _Zero()
    t0 = float(mot.t_start)
    if duration is None:
        duration = run_length(motion)
    duration = check_positive("duration", duration)
    phi0 = float(phi0)
    phidot0 = float(phidot0)
    for name, v in (("phi0", phi0), ("phidot0", phidot0)):
        if not math.isfinite(v):
            raise ParameterError(name, v, "a finite number")
    fall0 = ref.fall[1 if phi0 >= 0 else -1]
    if abs(phi0) >= fall0:
        raise ParameterError("phi0", phi0, f"|phi0| < the fall angle of its direction, "
                                           f"{fall0:.4g} rad")
    if motion is None and phi0 == 0.0 and phidot0 == 0.0:
        raise ParameterError("phi0", phi0, "non-zero for a free-rocking run (no ground motion)")
    t_end = t0 + duration
    # the ground falls faster than gravity: the model (and the run) ends there
    t_lift = lift_off_time(mot, t0, t_end)
    if t_lift is not None:
        t_end = t_lift

    acc = mot.acceleration
    vert = getattr(mot, "vertical", None)
    accv = vert.acceleration if vert is not None else None
    v_rest = settings.rest_ratio * ref.p * ref.alpha
    # the rules' constants, read when the run starts (rockbench.analytic.rules)
    v_chat = rules.CHATTER_VELOCITY_RATIO * ref.p * ref.alpha
    dt_chat = rules.CHATTER_INTERVAL / ref.p
    min_advance = rules.PROGRESS_MIN_ADVANCE / ref.p
    window = max(1, int(rules.PROGRESS_WINDOW))
    max_iter = int(rules.MAX_EVENT_ITERATIONS)
    # uplift thresholds with the margin: lambda_ccw > 0 > lambda_cw, so both move outwards
    thr_p = ref.lam[1] * G * (1.0 + rules.UPLIFT_RTOL)
    thr_n = ref.lam[-1] * G * (1.0 + rules.UPLIFT_RTOL)
    intact = scene.has_devices

    segments: list[tuple[float, float, Any, int, bool]] = []
    rows: list[dict[str, Any]] = []
    steps = nfev = 0
    overturned = False
    t_over = t_frac = None
    fractured = False
    exceeded = False
    max_abs = abs(phi0)
    status, reason = "ok", None

    def gfac(t):
        """(g + a_v) / g [-] at t (1 without vertical motion): the thresholds' factor."""
        return 1.0 if accv is None else 1.0 + np.asarray(accv(t), dtype=float) / G

    def uplift_direction(t: float) -> int:
        a = float(acc(t))
        f = float(gfac(t))
        return 1 if a > thr_p * f else (-1 if a < thr_n * f else 0)

    def next_uplift(ta: float, tb: float) -> tuple[float | None, int]:
        s = uplift_direction(ta)
        if s:
            return ta, s
        ks = mot.knots(ta, tb)
        a = np.asarray(acc(ks), dtype=float)
        f = gfac(ks)
        hit = np.nonzero((a > thr_p * f) | (a < thr_n * f))[0]
        if hit.size == 0:
            return None, 0
        i = int(hit[0])
        s = 1 if a[i] > thr_p * (f if np.ndim(f) == 0 else f[i]) else -1
        thr = thr_p if s == 1 else thr_n
        # excess over the threshold: <= 0 at ks[i-1], > 0 at ks[i], monotonic in between
        # (u_g'' - thr (1 + a_v / g) is monotonic between knots: GroundMotion's contract)
        if accv is None:
            excess = ((lambda tt: float(acc(tt)) - thr) if s == 1
                      else (lambda tt: thr - float(acc(tt))))
        else:
            excess = ((lambda tt: float(acc(tt)) - thr * float(gfac(tt))) if s == 1
                      else (lambda tt: thr * float(gfac(tt)) - float(acc(tt))))
        lo, hi = float(ks[i - 1]), float(ks[i])
        from scipy.optimize import brentq     # here: a map's compiled path never needs it

        tu = brentq(excess, lo, hi, xtol=1e-13, rtol=1e-14)
        # step just past the root so that the excess is strictly positive (the increments
        # double, so this ends in a few dozen evaluations at most, at hi if not before)
        step = 1e-13 * max(1.0, abs(tu))
        while tu < hi and not excess(tu) > 0.0:
            tu = min(hi, tu + step)
            step *= 2.0
        return tu, s

    if phi0 != 0.0:
        mode = 1 if phi0 > 0 else -1
    elif phidot0 != 0.0:
        mode = 1 if phidot0 > 0 else -1
    else:
        mode = 0
    t, phi, phid = t0, phi0, phidot0
    if intact and mode != 0 and mode * phi0 >= ref.fracture_angle[mode]:
        # released beyond the fracture angle of its direction: a tendon strained past its
        # fracture strain has failed before the motion starts (every engine breaks it at once)
        intact, fractured, t_frac = False, True, t0
        rows.append(dict(t=t0, kind="fracture", phi=phi0, phidot_before=phidot0,
                         phidot_after=phidot0, eta=math.nan, direction=mode))
    # the last impact of the current rocking episode: time and |post-impact velocity|
    last_impact: tuple[float, float] | None = None

    wall0 = time.perf_counter()
    recent: deque[float] = deque(maxlen=window)    # loop start times, for the progress check
    n_iter = 0
    while t < t_end and not overturned:
        n_iter += 1
        recent.append(t)
        if len(recent) == window and t - recent[0] < min_advance:
            status = "invalid"
            reason = (f"analytic event loop made no progress: {window} iterations advanced time by "
                      f"{t - recent[0]:.3g} s < {min_advance:.3g} s at t = {t:.9g} s (mode {mode})")
            break
        if n_iter > max_iter:
            status = "invalid"
            reason = (f"analytic event loop exceeded {max_iter} iterations at t = {t:.9g} s "
                      f"of {t_end:.9g} s")
            break
        if mode == 0:
            try:
                tu, s = next_uplift(t, t_end)
            except (ValueError, ArithmeticError, RuntimeError) as exc:
                status = "invalid"
                reason = f"uplift search failed at t = {t:.9g} s: {type(exc).__name__}: {exc}"
                break
            if tu is None:
                # no uplift before t_end: nothing can change any more once the motion is
                # over, so the run ends at the later of now and the motion's end
                t_stop = min(t_end, max(t, mot.t_end))
                segments.append((t, t_stop, None, 0, intact))
                t = t_end = t_stop
                break
            segments.append((t, tu, None, 0, intact))
            rows.append(dict(t=tu, kind="uplift", phi=0.0, phidot_before=0.0, phidot_after=0.0,
                             eta=math.nan, direction=s))
            t, phi, phid, mode = tu, 0.0, 0.0, s
            last_impact = None
            continue

        s = mode
        dyn_s = ref.dyn[s]
        flag = intact

        if accv is None:
            def rhs(tt, y, dyn=dyn_s, flag=flag):
                return (y[1], dyn.acceleration(y[0], y[1], float(acc(tt)), flag))
        else:
            def rhs(tt, y, dyn=dyn_s, flag=flag):
                return (y[1], dyn.acceleration(y[0], y[1], float(acc(tt)), flag,
                                               float(accv(tt))))

        # impact: s phi falls to 0. A segment may start at phi = 0 (after an uplift or an
        # impact); the event is taken as positive at the segment's first instant, so that the
        # root is the return to phi = 0 and never the start itself (after a just-exceeded
        # uplift the first step can be far longer than the motion's tiny excursion)
        evs = [_event(lambda tt, y, ts=t, s=s: s * y[0] if tt != ts else 1.0, -1, True),
               _event(lambda tt, y, s=s: s * y[0] - ref.fall[s], 1, True)]
        names = ["impact", "overturn"]
        if intact and math.isfinite(ref.fracture_angle[s]):
            evs.append(_event(lambda tt, y, s=s: s * y[0] - ref.fracture_angle[s], 1, True))
            names.append("fracture")
        crit = ref.critical[(s, intact)]
        if math.isfinite(crit):
            if s * phi >= crit:
                # the segment starts at or beyond the critical angle of its potential (after a
                # fracture, or from the initial rotation): no upward crossing will report it
                exceeded = True
                rows.append(dict(t=t, kind="critical", phi=phi, phidot_before=phid,
                                 phidot_after=phid, eta=math.nan, direction=s))
            evs.append(_event(lambda tt, y, s=s, c=crit: s * y[0] - c, 1, False))
            names.append("critical")
        # peak: s phi' falls to 0 (positive at the segment's first instant, as for the impact)
        evs.append(_event(lambda tt, y, ts=t, s=s: s * y[1] if tt != ts else 1.0, -1, False))
        names.append("peak")

        try:
            from scipy.integrate import solve_ivp   # here: the compiled path never needs it

            sol = solve_ivp(rhs, (t, t_end), (phi, phid), method=ivp_method,
                            rtol=settings.rtol, atol=settings.atol, events=evs, dense_output=True)
        except (ValueError, ArithmeticError, RuntimeError) as exc:
            status = "invalid"
            reason = f"integration failed at t = {t:.9g} s: {type(exc).__name__}: {exc}"
            break
        steps += max(len(sol.t) - 1, 0)
        nfev += sol.nfev
        if sol.status < 0:
            status = "invalid"
            reason = f"solve_ivp failed at t = {sol.t[-1]:.9g} s: {sol.message}"
            break
        t1 = float(sol.t[-1])
        y1 = sol.y[:, -1]
        max_abs = max(max_abs, float(np.max(np.abs(sol.y[0]))))
        for name, te, ye in zip(names, sol.t_events, sol.y_events):
            if name not in ("peak", "critical"):
                continue
            for tt, yy in zip(te, ye):
                if name == "peak":
                    max_abs = max(max_abs, abs(float(yy[0])))
                else:
                    exceeded = True
                rows.append(dict(t=float(tt), kind=name, phi=float(yy[0]),
                                 phidot_before=float(yy[1]), phidot_after=float(yy[1]),
                                 eta=math.nan, direction=s))
        segments.append((t, t1, sol.sol, s, intact))
        t, phi, phid = t1, float(y1[0]), float(y1[1])
        if sol.status != 1:      # reached t_end
            break
        fired = [n for n, te in zip(names, sol.t_events) if n not in ("peak", "critical")
                 and len(te) and te[-1] == sol.t[-1]]
        kind = fired[0] if fired else "impact"
        if kind == "impact":
            phi = 0.0
            post = -s
            e = ref.eta[post] * settings.eta_factor
            after = e * phid
            # eta <= 0 (possible for squat asymmetric frames): the post-impact mechanism cannot
            # start, the impact is perfectly plastic and the structure comes to rest
            settles = e <= 0.0 or abs(after) <= v_rest
            # chatter (rules.py): two successive small post-impact velocities, close in time
            if (not settles and last_impact is not None and abs(after) <= v_chat
                    and last_impact[1] <= v_chat and t - last_impact[0] <= dt_chat):
                settles = True
            new_mode = 0 if settles else post
            rows.append(dict(t=t, kind="impact", phi=0.0, phidot_before=phid, phidot_after=after,
                             eta=e, direction=new_mode))
            if new_mode == 0:
                after = 0.0
                last_impact = None
                rows.append(dict(t=t, kind="rest", phi=0.0, phidot_before=phid * e,
                                 phidot_after=0.0, eta=math.nan, direction=0))
            else:
                last_impact = (t, abs(after))
            phid, mode = after, new_mode
        elif kind == "overturn":
            overturned, t_over = True, t
            rows.append(dict(t=t, kind="overturn", phi=phi, phidot_before=phid,
                             phidot_after=phid, eta=math.nan, direction=s))
        elif kind == "fracture":
            intact, fractured, t_frac = False, True, t
            rows.append(dict(t=t, kind="fracture", phi=phi, phidot_before=phid,
                             phidot_after=phid, eta=math.nan, direction=s))
    wall = time.perf_counter() - wall0

    if overturned or not segments or status != "ok":
        t_end = t
    history = _history(ref, mot, segments, t0, t_end, settings)
    events = events_frame(sorted(rows, key=lambda r: r["t"]))
    ups = events[events["kind"] == "uplift"]
    n_imp = int((events["kind"] == "impact").sum())
    uplifted = bool(len(ups)) or phi0 != 0.0 or phidot0 != 0.0
    summary = Summary(
        max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / ref.alpha, overturned=overturned,
        t_overturn=t_over, exceeded_critical=exceeded or overturned, uplifted=uplifted,
        t_uplift=float(ups["t"].iloc[0]) if len(ups) else (t0 if uplifted else None),
        n_impacts=n_imp, fractured=fractured, t_fracture=t_frac, status=status, reason=reason)
    finish_validity(summary, ref, mot, history,
                    t_lift if t_lift is not None and t_end >= t_lift else None)
    cost = Cost(wall_s=wall, sim_time=t_end - t0, steps=steps, rhs_calls=nfev)
    return Result(backend="analytic", scene=scene, motion=mot.describe(), history=history,
                  events=events, summary=summary, cost=cost,
                  settings={**asdict(settings), "path": "solve_ivp"})


def finish_validity(summary: Summary, ref: Reference, motion, history: pd.DataFrame,
                    t_lift_off: float | None) -> None:
    """Fill ``summary``'s ``sliding_onset``, ``sliding_contact``, ``t_lift_off`` and
    ``validity`` from the run's history (both analytic paths): the friction demand of the
    contacts at every output step (:func:`rockbench.analytic.reactions.demand_history`, with
    the motion's vertical part) against the scene's friction
    (:func:`rockbench.validity.friction_of`, :func:`~rockbench.validity.beam_friction_of`); the
    verdict from :func:`rockbench.validity.run_validity`, the one rule."""
    from ..validity import beam_friction_of, friction_of, run_validity
    from .reactions import demand_history, first_excess

    scene = ref.scene
    vert = getattr(motion, "vertical", None)
    t = history["t"].to_numpy(dtype=float)
    a_v = (np.asarray(vert.acceleration(t), dtype=float) if vert is not None
           else np.zeros_like(t))
    demand = demand_history(scene, t, history["phi"].to_numpy(dtype=float),
                            history["phidot"].to_numpy(dtype=float),
                            history["mode"].to_numpy(dtype=np.int64),
                            history["devices_intact"].to_numpy(dtype=bool),
                            history["ground_acc"].to_numpy(dtype=float), a_v, reference=ref)
    onset = first_excess(demand, friction_of(scene), beam_friction_of(scene))
    summary.t_lift_off = t_lift_off
    if onset is not None:
        summary.sliding_onset, summary.sliding_contact, d = onset
    else:
        d = None
    summary.validity = run_validity(scene, sliding_onset=summary.sliding_onset,
                                    sliding_contact=summary.sliding_contact, demand=d,
                                    t_lift_off=t_lift_off).reason


def _history(ref: Reference, mot, segments, t0: float, t_end: float,
             settings: AnalyticSettings) -> pd.DataFrame:
    """Sample the piecewise solution on the uniform output grid."""
    tg = output_grid(t0, t_end, settings.output_dt)
    phi = np.zeros_like(tg)
    phid = np.zeros_like(tg)
    mode = np.zeros(tg.size, dtype=np.int64)
    intact = np.zeros(tg.size, dtype=bool)
    for ta, tb, sol, s, ok in segments:
        i0 = int(np.searchsorted(tg, ta, side="left"))
        i1 = int(np.searchsorted(tg, tb, side="right"))
        if i1 <= i0:
            continue
        sl = slice(i0, i1)
        intact[sl] = ok
        mode[sl] = s
        if sol is not None:
            y = sol(tg[sl])
            phi[sl], phid[sl] = y[0], y[1]
    return history_frame(ref, tg, phi, phid, mode, intact,
                         np.asarray(mot.acceleration(tg), dtype=float),
                         settings.history == "full")


def history_frame(ref: Reference, tg, phi, phid, mode, intact, ground_acc,
                  full: bool) -> pd.DataFrame:
    """The analytic history frame (HISTORY_COLUMNS, CONTACT_COLUMNS NaN) from the sampled
    phi [rad], phidot [rad/s], mode, devices-intact flags and ground acceleration [m/s^2] on
    the output grid ``tg`` [s]: the beam and right-column rotations and the device columns
    (frames, ``full`` history) from the vectorized mechanism. Shared by both analytic paths.
    """
    cols: dict[str, Any] = {"t": tg, "phi": phi, "phidot": phid, "ground_acc": ground_acc,
                            "mode": mode, "devices_intact": intact}
    nan = np.full(tg.size, np.nan)
    st = ref.scene.structure
    if st.kind == "frame" and full:
        # vectorized over the samples of each rocking direction; device columns only when the
        # scene has devices
        dev = ref.scene.devices if ref.scene.has_devices else None
        thb, thr = np.zeros_like(tg), np.zeros_like(tg)
        el, er, dl, dr = (np.zeros_like(tg) for _ in range(4))
        for s in (1, -1):
            idx = np.flatnonzero(mode == s)
            if not idx.size:
                continue
            dyn = ref.dyn[s]
            ang = dyn.mechanism.angles_many(phi[idx])
            thb[idx], thr[idx] = ang[0], ang[1]
            if dev is not None:
                e_l, e_r, c_l, c_r = dyn.device_state_many(phi[idx], ang)
                el[idx], er[idx] = e_l, e_r
                dl[idx], dr[idx] = c_l * phid[idx], c_r * phid[idx]
        cols.update(theta_beam=thb, theta_right=thr)
        k = dev.tendon_stiffness if dev else 0.0
        c = dev.damping if dev else 0.0
        cols.update(tendon_elong_left=np.where(intact, el, 0.0) if dev else np.zeros_like(tg),
                    tendon_elong_right=np.where(intact, er, 0.0) if dev else np.zeros_like(tg),
                    tendon_force_left=np.where(intact, k * el, 0.0),
                    tendon_force_right=np.where(intact, k * er, 0.0),
                    damper_force_left=np.where(intact, c * dl, 0.0),
                    damper_force_right=np.where(intact, c * dr, 0.0))
    else:
        for c in ("theta_beam", "theta_right", "tendon_elong_left", "tendon_elong_right",
                  "tendon_force_left", "tendon_force_right", "damper_force_left",
                  "damper_force_right"):
            cols[c] = nan if (st.kind == "frame" or c.startswith("theta")) else np.zeros_like(tg)
    for c in CONTACT_COLUMNS:
        cols[c] = nan
    return pd.DataFrame(cols, columns=list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS))

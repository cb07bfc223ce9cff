"""Newmark's rigid sliding block: the exact reference for sliding on a Coulomb surface.

A rigid block rests on a horizontal foundation with Coulomb friction, one coefficient ``mu``
(static = kinetic). The foundation accelerates horizontally, a_g(t) [m/s^2] (positive to the
right, ``docs/conventions.md``), and optionally vertically, a_v(t) [m/s^2] (positive up: by
default the motion's own vertical part, ``GroundMotion.vertical``). In the
foundation's frame the block feels the inertial force -m (a_g, a_v) and gravity -m g, so the
normal force is m n(t) with n = g + a_v [m/s^2]. The unknown is the block's displacement
relative to the foundation, u(t) [m] (positive to the right), with v = u' [m/s]:

* **stick** (v = 0) while |a_g| <= mu n: the block moves with the foundation, u is constant;
* **slip** in direction sigma = sign(v): u'' = -a_g - sigma mu n (Newmark 1965, Eq. 2 with the
  yield acceleration N g = mu n);
* slip **starts** from stick when |a_g| *exceeds* mu n (by the relative margin
  :data:`rockbench.analytic.rules.UPLIFT_RTOL`, the convention of the rocking model's uplift: a
  grazing touch of the threshold does not start a slip), in the direction sigma = -sign(a_g)
  (the block lags behind the foundation);
* slip **stops** when v returns to 0: the block sticks if |a_g| <= mu n there, otherwise it
  slips back at once in the other direction (a *reversal*);
* **loss of contact**: n = g + a_v <= 0 leaves the model (free flight is not modelled); the run
  stops there and reports the time.

The solution is event-driven and exact:

* records (:class:`~rockbench.scene.motion.Record`, piecewise linear between samples, zero
  outside them): on each interval between the union of the sample times a_g and n are linear
  in t, so u'' is linear, v quadratic and u cubic in closed form; the stop time is the first
  root of the quadratic v (stable quadratic formula), a slip onset or a loss of contact the root
  of a linear function. No integrator, no tolerance: round-off only.
* any other :class:`~rockbench.scene.motion.GroundMotion` (a Ricker pulse, a smooth analytic
  motion): ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-12) with terminal events on v = 0
  and n = 0 during slip; during stick the onset is bracketed on the motions' knots (between
  which the horizontal acceleration is monotonic, so with a_v = 0 the bracket is exact) and
  refined by Brent's method. Why not the piecewise-linear path on a fine grid: interpolating a
  smooth pulse linearly is an O(h^2) model error (about 1e-5 relative at the pulses' T_g / 400
  knots), far above the integrator's 1e-12; the linear path is exact only for data that *is*
  piecewise linear. A record mixed with a smooth motion uses the integrator between the
  record's samples.

After the motions end (a_g = a_v = 0) a block still sliding decelerates at mu g and stops after
|v| / (mu g): by default the run ends there (or at the motions' end if the block is at rest),
so the final displacement is the permanent one.

Energy (per unit mass, in the foundation's frame): d(v^2/2)/dt = -a_g v - mu n |v|, so the work
of the inertial force, -int a_g v dt, equals the friction dissipation int mu n |v| dt plus the
relative kinetic energy v^2/2 (checked by the tests to 1e-9).

Reference: Newmark, N. M. (1965) "Effects of earthquakes on dams and embankments",
Geotechnique 15(2): 139-160 (the rigid sliding block, the rectangular pulse's permanent slip
:func:`rectangular_pulse_displacement`). See ``docs/sliding.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from ..constants import G
from ..errors import ParameterError, check_finite, check_positive
from ..scene.motion import GroundMotion, Record
from . import rules

__all__ = ["SlidingSummary", "SlidingResult", "sliding_response", "MOTION_VERTICAL",
           "rectangular_pulse_displacement"]

#: Integrator settings of the smooth path (DOP853): relative and absolute tolerances [-, m].
IVP_RTOL = 1e-12
IVP_ATOL = 1e-15

#: Default output interval of the history [s].
OUTPUT_DT = 0.005


def rectangular_pulse_displacement(amplitude: float, duration: float, mu: float) -> float:
    """Newmark's (1965) permanent slip [m] of a rigid block under a rectangular ground
    acceleration pulse of height ``amplitude`` [m/s^2] (signed) and ``duration`` [s], friction
    ``mu`` [-]: with a_y = mu g and A = |amplitude| > a_y,

        u = -sign(amplitude) A T^2 (A - a_y) / (2 a_y)

    (the block lags by (A - a_y) T^2 / 2 during the pulse, then slides (A - a_y) T / a_y longer
    at deceleration a_y). Zero when A <= a_y."""
    amplitude = check_finite("amplitude", amplitude)
    T = check_positive("duration", duration)
    mu = check_positive("mu", mu)
    A, ay = abs(amplitude), mu * G
    if A <= ay:
        return 0.0
    return -math.copysign(A * T * T * (A - ay) / (2.0 * ay), amplitude)


# ------------------------------------------------------------------------------------------------
class _Piece(NamedTuple):
    """The exact solution on [t0, t1): u = u0 + v0 tau + q0 tau^2/2 + q1 tau^3/6 (tau = t - t0),
    or the dense output ``sol`` of the integrator; ``sigma`` 0 (stick) or +-1 (slip)."""

    t0: float
    t1: float
    u0: float
    v0: float
    q0: float
    q1: float
    sigma: int
    sol: Any = None


def _evaluate(pieces: tuple[_Piece, ...], t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u [m] and v [m/s] at times ``t`` [s] from the pieces (clipped to the run)."""
    t = np.asarray(t, dtype=float)
    cols = np.array([(p.t0, p.t1, p.u0, p.v0, p.q0, p.q1) for p in pieces]).reshape(-1, 6)
    idx = np.clip(np.searchsorted(cols[:, 0], t, side="right") - 1, 0, len(pieces) - 1)
    t0, t1, u0, v0, q0, q1 = cols[idx].T
    tau = np.clip(t, t0, t1) - t0
    u = u0 + tau * (v0 + tau * (q0 / 2.0 + tau * q1 / 6.0))
    v = v0 + tau * (q0 + tau * q1 / 2.0)
    for i in np.unique(idx):
        if pieces[i].sol is not None:
            m = idx == i
            y = pieces[i].sol(np.clip(t[m], pieces[i].t0, pieces[i].t1))
            u[m], v[m] = y[0], y[1]
    return u, v


@dataclass(frozen=True)
class SlidingSummary:
    """What a sliding run did.

    max_abs_displacement : max |u| [m] over the run (exact: u is monotonic within a slip).
    final_displacement : u [m] at the end of the run (the permanent slip if the run ended at rest).
    final_velocity : v [m/s] at the end (0 when the run ended at rest).
    onset_time : time [s] of the first slip, None if the block never slipped.
    slip_episodes : number of slips in one direction (a reversal starts a new one) [-].
    slip_path : total distance slid, sum of |du| [m].
    lost_contact_time : time [s] at which g + a_v fell to 0 (the run stops there), or None.
    end_time : last time of the run [s].
    status : "ok", "lost contact" or "invalid" (the event loop stopped advancing; ``reason``).
    """

    max_abs_displacement: float
    final_displacement: float
    final_velocity: float
    onset_time: float | None
    slip_episodes: int
    slip_path: float
    lost_contact_time: float | None
    end_time: float
    status: str = "ok"
    reason: str | None = None


@dataclass(frozen=True)
class SlidingResult:
    """History (columns ``t`` [s], ``u`` [m], ``v`` [m/s], ``sliding`` [bool]) at the output
    interval, the summary, and the exact piecewise solution (:meth:`state`)."""

    history: pd.DataFrame
    summary: SlidingSummary
    pieces: tuple[_Piece, ...]
    mu: float

    def state(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Exact u [m] and v [m/s] at times ``t`` [s] (array), within the run."""
        return _evaluate(self.pieces, np.atleast_1d(np.asarray(t, dtype=float)))

    @property
    def breaks(self) -> np.ndarray:
        """Times [s] at which the solution changes piece (stick/slip events, segment ends)."""
        return np.array([p.t0 for p in self.pieces] + [self.pieces[-1].t1])


# ------------------------------------------------------------------------------------------------
class _Segment(NamedTuple):
    """[t0, t1) on which the accelerations are smooth: linear (a = a0 + a1 tau, n = n0 + n1 tau,
    tau = t - t0) when ``linear``, otherwise evaluated from the motions."""

    t0: float
    t1: float
    linear: bool
    a0: float = 0.0
    a1: float = 0.0
    n0: float = G
    n1: float = 0.0


def _record_coefficients(rec: Record, starts: np.ndarray, ends: np.ndarray):
    """Value at each start [m/s^2] and slope [m/s^3] of a record on intervals that do not
    straddle one of its samples (zero outside the record)."""
    t, a = np.asarray(rec.time), np.asarray(rec.samples)
    mid = np.where(np.isfinite(ends), 0.5 * (starts + ends), starts + 1.0)
    i = np.searchsorted(t, mid, side="right") - 1
    inside = (i >= 0) & (i < t.size - 1)
    ic = np.clip(i, 0, t.size - 2)
    slope = (a[ic + 1] - a[ic]) / (t[ic + 1] - t[ic])
    value = a[ic] + slope * (starts - t[ic])
    return np.where(inside, value, 0.0), np.where(inside, slope, 0.0)


class _Run:
    """The mutable state of one run (private to :func:`sliding_response`)."""

    def __init__(self, mu: float, acc_h, acc_v, t: float):
        self.mu, self.lim = mu, mu * (1.0 + rules.UPLIFT_RTOL)
        self.acc_h, self.acc_v = acc_h, acc_v
        self.t, self.u, self.v, self.sigma = t, 0.0, 0.0, 0
        self.pieces: list[_Piece] = []
        self.onset: float | None = None
        self.episodes = 0
        self.lost: float | None = None
        self.done = False

    def n(self, t):
        return G + (self.acc_v(t) if self.acc_v is not None else 0.0)

    def add(self, piece: _Piece) -> None:
        if not piece.t1 > piece.t0:
            return
        last = self.pieces[-1] if self.pieces else None
        if (piece.sigma == 0 and last is not None and last.sigma == 0
                and last.t1 == piece.t0 and last.u0 == piece.u0):
            self.pieces[-1] = last._replace(t1=piece.t1)   # one stick piece, not many
        else:
            self.pieces.append(piece)

    def start_slip(self, sigma: int) -> None:
        self.sigma = sigma
        self.episodes += 1
        if self.episodes > rules.MAX_EVENT_ITERATIONS:
            raise RuntimeError(f"more than {rules.MAX_EVENT_ITERATIONS} slips by "
                               f"t = {self.t:.9g} s")
        if self.onset is None:
            self.onset = self.t

    def stopped(self, a: float, n: float) -> None:
        """v has returned to 0 at self.t: stick, or slip back at once (a reversal)."""
        self.v = 0.0
        if abs(a) <= self.lim * n:
            self.sigma = 0
        else:
            self.start_slip(-1 if a > 0.0 else 1)


def _first_down_root(w0: float, w1: float, w2: float, h: float) -> float | None:
    """First tau in (0, h] at which w(tau) = w0 + w1 tau + w2 tau^2 / 2 (w0 >= 0) falls to 0,
    crossing downwards (w' <= 0 there); None if there is none."""
    a, b, c = 0.5 * w2, w1, w0
    if a == 0.0:
        roots = [-c / b] if b < 0.0 else []
    else:
        disc = b * b - 4.0 * a * c
        if disc < 0.0:
            return None
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
        roots = [q / a] + ([c / q] if q != 0.0 else [])
    good = [r for r in roots if 0.0 < r <= h and w1 + w2 * r <= 0.0]
    return min(good) if good else None


def _advance_linear(seg: _Segment, run: _Run) -> None:
    """Advance ``run`` through the linear segment ``seg`` in closed form."""
    mu, lim = run.mu, run.lim
    while not run.done and run.t < seg.t1:
        t = run.t
        rem = seg.t1 - t
        a0, a1 = seg.a0 + seg.a1 * (t - seg.t0), seg.a1
        n0, n1 = seg.n0 + seg.n1 * (t - seg.t0), seg.n1
        if n0 <= 0.0:
            run.lost, run.done = t, True
            return
        h, lost = rem, False
        if n1 < 0.0 and -n0 / n1 < h:
            h, lost = -n0 / n1, True
        if run.sigma == 0:
            if abs(a0) > lim * n0:
                run.start_slip(-1 if a0 > 0.0 else 1)
                continue
            tau, sig = math.inf, 0
            for s in (1, -1):     # s a - lim n rises through 0: slip in direction -s
                d = s * a1 - lim * n1
                if d > 0.0:
                    r = (lim * n0 - s * a0) / d
                    if r < tau:
                        tau, sig = r, -s
            if tau <= h and math.isfinite(tau):
                run.add(_Piece(t, t + tau, run.u, 0.0, 0.0, 0.0, 0))
                run.t = t + tau
                run.start_slip(sig)
                continue
            if not math.isfinite(h):      # at rest for ever: the run is over
                run.done = True
                return
            run.add(_Piece(t, t + h, run.u, 0.0, 0.0, 0.0, 0))
            run.t = t + h
        else:
            s = run.sigma
            q0, q1 = -a0 - s * mu * n0, -a1 - s * mu * n1
            r = _first_down_root(s * run.v, s * q0, s * q1, h)
            step = h if r is None else r
            u0, v0 = run.u, run.v
            run.add(_Piece(t, t + step, u0, v0, q0, q1, s))
            run.u = u0 + step * (v0 + step * (q0 / 2.0 + step * q1 / 6.0))
            run.v = v0 + step * (q0 + step * q1 / 2.0)
            run.t = t + step
            if r is not None:
                run.stopped(a0 + a1 * r, n0 + n1 * r)
                continue
        if lost:
            run.lost, run.done = run.t, True
            return


def _advance_smooth(seg: _Segment, run: _Run, grid: np.ndarray, max_step: float) -> None:
    """Advance ``run`` through the smooth segment ``seg``: Brent's method on the knots during
    stick, DOP853 with terminal events during slip."""
    mu, lim = run.mu, run.lim
    acc_h = run.acc_h
    while not run.done and run.t < seg.t1:
        t = run.t
        if run.sigma == 0:
            def trigger(tt: float) -> float:   # > 0: slip starts, or contact is lost
                n = run.n(tt)
                return max(abs(acc_h(tt)) - lim * n, -n)

            if trigger(t) > 0.0:
                if run.n(t) <= 0.0:
                    run.lost, run.done = t, True
                    return
                run.start_slip(-1 if acc_h(t) > 0.0 else 1)
                continue
            ks = grid[(grid > t) & (grid < seg.t1)]
            ks = np.concatenate([[t], ks, [seg.t1]])
            n = G + (run.acc_v(ks) if run.acc_v is not None else 0.0)
            f = np.maximum(np.abs(acc_h(ks)) - lim * n, -n)
            hit = np.nonzero(f[1:] > 0.0)[0] + 1
            if hit.size == 0:
                run.add(_Piece(t, seg.t1, run.u, 0.0, 0.0, 0.0, 0))
                run.t = seg.t1
                return
            lo, hi = float(ks[hit[0] - 1]), float(ks[hit[0]])
            if not trigger(hi) > 0.0:      # the array and the scalar evaluation disagree
                run.add(_Piece(t, hi, run.u, 0.0, 0.0, 0.0, 0))
                run.t = hi
                continue
            if trigger(lo) > 0.0:
                te = lo
            else:
                te = brentq(trigger, lo, hi, xtol=1e-14, rtol=1e-15)
                step = 1e-14 * max(1.0, abs(te))  # just past the root: the trigger is > 0
                while te < hi and not trigger(te) > 0.0:
                    te, step = min(hi, te + step), 2.0 * step
            run.add(_Piece(t, te, run.u, 0.0, 0.0, 0.0, 0))
            run.t = te
            if run.n(te) <= 0.0:
                run.lost, run.done = te, True
                return
            run.start_slip(-1 if acc_h(te) > 0.0 else 1)
        else:
            s = run.sigma

            def rhs(tt, y):
                return [y[1], -acc_h(tt) - s * mu * run.n(tt)]

            def stop(tt, y):
                return s * y[1]
            stop.terminal, stop.direction = True, -1
            events = [stop]
            if run.acc_v is not None:
                def loss(tt, y):
                    return run.n(tt)
                loss.terminal, loss.direction = True, -1
                events.append(loss)
            sol = solve_ivp(rhs, (t, seg.t1), [run.u, run.v], method="DOP853", rtol=IVP_RTOL,
                            atol=IVP_ATOL, dense_output=True, events=events,
                            max_step=max_step)
            if sol.status < 0:
                raise RuntimeError(f"integration failed at t = {t:.9g} s: {sol.message}")
            t1 = float(sol.t[-1])
            run.add(_Piece(t, t1, run.u, run.v, 0.0, 0.0, s, sol.sol))
            run.t, run.u, run.v = t1, float(sol.y[0, -1]), float(sol.y[1, -1])
            if sol.status == 1:
                if len(events) > 1 and sol.t_events[1].size:
                    run.lost, run.done = t1, True
                    return
                run.stopped(float(acc_h(t1)), run.n(t1))


def _segments(motions: list[GroundMotion], t0: float, t_motion: float, t_stop: float,
              exact: bool) -> list[_Segment]:
    """The run's segments: between the union of the records' samples (and the motions' ends);
    linear (closed form) when ``exact``, smooth otherwise; then the free tail with a = 0."""
    cuts = {t0, t_motion}
    for m in motions:
        if isinstance(m, Record):
            cuts.update(np.asarray(m.time).tolist())
        cuts.add(m.t_end)
    times = np.array(sorted(c for c in cuts if t0 <= c < min(t_motion, t_stop)))
    ends = np.append(times[1:], min(t_motion, t_stop))
    segs: list[_Segment] = []
    if exact and times.size:
        h, v = motions[0], motions[1] if len(motions) > 1 else None
        a0, a1 = _record_coefficients(h, times, ends)
        n0, n1 = (_record_coefficients(v, times, ends) if v is not None
                  else (np.zeros_like(times), np.zeros_like(times)))
        segs = [_Segment(float(s), float(e), True, float(x0), float(x1), G + float(y0),
                         float(y1))
                for s, e, x0, x1, y0, y1 in zip(times, ends, a0, a1, n0, n1) if e > s]
    elif times.size:
        segs = [_Segment(float(s), float(e), False) for s, e in zip(times, ends) if e > s]
    if t_stop > t_motion:
        segs.append(_Segment(max(t0, t_motion), t_stop, True))
    return segs


#: ``sliding_response(..., vertical=MOTION_VERTICAL)`` (the default): the motion's own vertical
#: part, ``horizontal.vertical`` (None when it has none).
MOTION_VERTICAL = "motion"


def sliding_response(horizontal: GroundMotion, mu: float,
                     vertical: GroundMotion | str | None = MOTION_VERTICAL, *,
                     t_end: float | None = None, output_dt: float = OUTPUT_DT,
                     method: str = "auto", max_step: float | None = None) -> SlidingResult:
    """The rigid block's slip u(t) relative to the foundation (Newmark 1965), exact.

    Parameters
    ----------
    horizontal : GroundMotion
        a_g(t) [m/s^2], positive to the right (its ``acceleration``; a vertical part it carries
        is the default of ``vertical``).
    mu : float
        Coulomb friction coefficient [-] (static = kinetic), > 0.
    vertical : GroundMotion, None or "motion"
        a_v(t) [m/s^2], positive up; normal force m (g + a_v). "motion" (default,
        :data:`MOTION_VERTICAL`): the motion's own vertical part, ``horizontal.vertical`` (a
        pulse's ``vertical_ratio``, a record's vertical channel, a
        :class:`~rockbench.scene.motion.WithVertical`'s; none when it has none). A
        GroundMotion: that one instead. None: no vertical motion, whatever the motion carries.
    t_end : float or None
        End of the run [s] (> start). None: the motions' end, or later the time the block comes
        to rest after them (so the final displacement is the permanent slip).
    output_dt : float
        Interval of the history [s], > 0 (the end time is always a row).
    method : {"auto", "exact", "ivp"}
        "exact": the closed form (records only); "ivp": the integrator (any motion); "auto":
        exact when every motion is a :class:`Record`.
    max_step : float or None
        Largest integrator step and knot spacing of the onset search [s] (ivp path). None: the
        motions' duration / 2000.

    Returns
    -------
    SlidingResult
        The run starts at rest at the earliest motion's ``t_start``; it stops early (status
        "lost contact") when g + a_v falls to 0.
    """
    if not isinstance(horizontal, GroundMotion):
        raise ParameterError("horizontal", horizontal, "a GroundMotion (a_g(t) [m/s^2])")
    if isinstance(vertical, str) and vertical == MOTION_VERTICAL:
        vertical = getattr(horizontal, "vertical", None)
    if vertical is not None and not isinstance(vertical, GroundMotion):
        raise ParameterError("vertical", vertical, "a GroundMotion (a_v(t) [m/s^2]), None (no "
                             f"vertical motion) or {MOTION_VERTICAL!r} (the motion's own)")
    mu = check_positive("mu", mu)
    output_dt = check_positive("output_dt", output_dt)
    if method not in ("auto", "exact", "ivp"):
        raise ParameterError("method", method, "one of auto, exact, ivp")
    motions = [horizontal] + ([vertical] if vertical is not None else [])
    all_records = all(isinstance(m, Record) for m in motions)
    if method == "exact" and not all_records:
        raise ParameterError("method", method, "auto or ivp for a motion that is not a Record",
                             "the closed form needs piecewise-linear accelerations")
    exact = all_records and method != "ivp"
    t0 = min(float(m.t_start) for m in motions)
    t_motion = max(float(m.t_end) for m in motions)
    if t_end is not None:
        t_end = check_finite("t_end", t_end)
        if not t_end > t0:
            raise ParameterError("t_end", t_end, f"> the motions' start {t0:g} s")
    t_stop = math.inf if t_end is None else t_end
    if max_step is None:
        max_step = (t_motion - t0) / 2000.0
    max_step = check_positive("max_step", max_step)

    run = _Run(mu, horizontal.acceleration,
               vertical.acceleration if vertical is not None else None, t0)
    grid = np.array([])
    if not exact:
        tm = min(t_motion, t_stop)
        parts = [m.knots(t0, tm) for m in motions]
        parts.append(np.linspace(t0, tm, max(2, math.ceil((tm - t0) / max_step) + 1)))
        grid = np.unique(np.concatenate(parts))
    status, reason = "ok", None
    for seg in _segments(motions, t0, t_motion, t_stop, exact):
        if run.done:
            break
        run.t = max(run.t, seg.t0)
        try:
            if seg.linear:
                _advance_linear(seg, run)
            else:
                _advance_smooth(seg, run, grid, max_step)
        except (RuntimeError, ValueError) as exc:
            status, reason = "invalid", f"{type(exc).__name__}: {exc}"
            break
    if run.lost is not None:
        status, reason = "lost contact", (f"g + a_v <= 0 at t = {run.lost:.9g} s: the block leaves "
                                          "the ground, outside the model")
    end = run.t if t_end is None else min(run.t, t_end)
    if t_end is None and run.sigma == 0 and run.lost is None and status == "ok":
        end = max(end if math.isfinite(end) else t_motion, t_motion)
    if not run.pieces or run.pieces[-1].t1 < end:
        run.add(_Piece(run.pieces[-1].t1 if run.pieces else t0, end, run.u, 0.0, 0.0, 0.0, 0))
    pieces = tuple(p if p.t1 <= end else p._replace(t1=end) for p in run.pieces if p.t0 < end) \
        or (_Piece(t0, end, 0.0, 0.0, 0.0, 0.0, 0),)
    return _result(pieces, run, mu, t0, end, output_dt, status, reason)


def _result(pieces, run: _Run, mu: float, t0: float, end: float, output_dt: float,
            status: str, reason: str | None) -> SlidingResult:
    """Summary and history of a finished run."""
    ends = np.array([p.t1 for p in pieces])
    u_end, v_end = _evaluate(pieces, ends)
    u_start, _ = _evaluate(pieces, np.array([p.t0 for p in pieces]))
    sliding = np.array([p.sigma != 0 for p in pieces])
    path = float(np.sum(np.abs(u_end - u_start)[sliding]))
    max_abs = float(max(np.max(np.abs(u_end)), np.max(np.abs(u_start))))
    summary = SlidingSummary(
        max_abs_displacement=max_abs, final_displacement=float(u_end[-1]),
        final_velocity=0.0 if run.sigma == 0 else float(v_end[-1]), onset_time=run.onset,
        slip_episodes=run.episodes, slip_path=path, lost_contact_time=run.lost,
        end_time=float(end), status=status, reason=reason)
    n = int(math.floor((end - t0) / output_dt + 1e-9)) + 1
    times = t0 + output_dt * np.arange(n)
    if times[-1] < end:
        times = np.append(times, end)
    u, v = _evaluate(pieces, times)
    starts = np.array([p.t0 for p in pieces])
    idx = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(pieces) - 1)
    history = pd.DataFrame({"t": times, "u": u, "v": v, "sliding": sliding[idx]})
    return SlidingResult(history, summary, pieces, mu)

"""Events and the effective coefficient of restitution measured from any sampled history.

Pure functions of sampled arrays (t [s], phi [rad], phidot [rad/s]): they know nothing of
engines, so every backend (and a user with a history from elsewhere) is measured the same way.

* :func:`excursions` splits a sampled motion into uplifted excursions (:class:`Excursion`);
* :func:`measure_impacts` finds the impacts between them and measures each one's effective
  coefficient of restitution (energy of successive peaks in free rocking, short windowed fits
  of the angular velocity otherwise). ``docs/metrics.md`` describes both estimators and their
  measured bias.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

__all__ = ["Excursion", "excursions", "measure_impacts", "extrapolate_to_closure",
           "slip_onset"]


# =========================================================================================
class Excursion(NamedTuple):
    """One uplifted excursion of the sampled motion: samples ``i0..i1`` (inclusive) with
    |phi| > the uplift tolerance and the sign ``sign``; ``ipk`` the sample of largest |phi|,
    ``peak`` [rad] that largest |phi| refined by a parabola through the three samples around
    it; ``after_impact`` whether it began with an impact (a zero crossing from an excursion of
    the other sign, with no rest in between); ``complete`` whether its peak lies strictly
    inside it (its motion turned back before the record or the excursion ended), or it starts
    the record at rest (free rocking from phi0)."""

    i0: int
    i1: int
    ipk: int
    sign: int
    peak: float
    after_impact: bool
    complete: bool


def excursions(t: np.ndarray, phi: np.ndarray, phidot: np.ndarray, *, uplift_tol: float,
               rest_rate: float = 0.0) -> list[Excursion]:
    """Split a sampled motion into uplifted excursions (see :class:`Excursion`).

    Consecutive uplifted samples of one sign form one excursion. Two excursions of opposite
    sign are joined by an impact unless a sample between them is at rest (|phi| <=
    ``uplift_tol`` [rad] and |phidot| <= ``rest_rate`` [rad/s]); two of the same sign are one
    excursion unless a rest sample separates them.
    """
    t = np.asarray(t, dtype=float)
    phi = np.asarray(phi, dtype=float)
    phidot = np.asarray(phidot, dtype=float)
    idx = np.flatnonzero(np.abs(phi) > uplift_tol)
    if idx.size == 0:
        return []
    rest = (np.abs(phi) <= uplift_tol) & (np.abs(phidot) <= rest_rate)
    rest_before = np.cumsum(rest)                 # rest samples up to and including i
    sg = np.sign(phi[idx]).astype(int)
    gap_rest = rest_before[idx[1:]] - rest_before[idx[:-1]] > 0
    brk = np.flatnonzero((sg[1:] != sg[:-1]) | gap_rest)
    starts = np.r_[0, brk + 1]
    ends = np.r_[brk, idx.size - 1]
    out: list[Excursion] = []
    for k, (a, b) in enumerate(zip(starts, ends)):
        i0, i1 = int(idx[a]), int(idx[b])
        seg = np.abs(phi[i0:i1 + 1])
        ipk = i0 + int(np.argmax(seg))
        peak = float(np.abs(phi[ipk]))
        if i0 < ipk < i1:                         # parabola through the three samples
            y0, y1, y2 = np.abs(phi[ipk - 1:ipk + 2])
            den = y0 - 2.0 * y1 + y2
            if den < 0.0:
                peak = float(y1 - 0.125 * (y2 - y0) ** 2 / den)
        after = bool(k > 0 and sg[a] != sg[a - 1] and not gap_rest[a - 1])
        complete = (i0 < ipk < i1) or (ipk == i0 == 0)
        out.append(Excursion(i0, i1, ipk, int(sg[a]), peak, after, bool(complete)))
    return out


def measure_impacts(t: np.ndarray, phi: np.ndarray, phidot: np.ndarray, *, alpha: float,
                    free: bool, energy=None, inertia0=None, uplift_tol: float,
                    guard: float = 0.01, window: float = 0.05, guard_rate: float = 0.004,
                    rate_window: float = 0.02,
                    rest_rate: float = 0.0, dynamics=None, ground_acc=None,
                    intact=None, closure=None) -> list[dict[str, Any]]:
    """Impacts (zero crossings of phi between uplifted excursions, see :func:`excursions`)
    with the effective coefficient of restitution measured from the sampled motion.

    t [s], phi [rad], phidot [rad/s] are the sampled history; ``alpha`` [rad] the slenderness
    (unused, kept for the signature); ``uplift_tol`` [rad] the |phi| below which the structure
    counts as closed; ``rest_rate`` [rad/s] the |phidot| below which a closed sample is at rest.

    Two estimates (``shared/notes/engines.md``: the ratio of angular velocities just before and
    after a crossing is distorted when an engine's impact lasts milliseconds):

    * energy of successive peaks, when ``free`` (no ground motion, no devices: the energy of an
      excursion is its potential at the peak) and both excursions' peaks were sampled
      (:attr:`Excursion.complete`): with V_s(phi) the potential of mechanism s and I_s(0) its
      generalized inertia at rest, eta = sqrt(V_post(peak after) I_pre(0) / (V_pre(peak
      before) I_post(0))); ``energy(phi)`` returns V [J] (mechanism of sign(phi)) and
      ``inertia0(s)`` I_s(0) [kg m^2]. The peaks are refined by a parabola through the three
      samples around the largest |phi|.
    * otherwise (ground motion, devices, or a peak not reached before the record ends): phi'
      just before and after the crossing, each extrapolated to the crossing time by a quadratic
      fit of the sampled phidot on a ``rate_window`` [s] that ends ``guard_rate`` [s] before
      (starts ``guard_rate`` after) it, clipped to the excursion so that a fit never spans
      another impact; NaN if fewer than three samples remain. (A fit of phi's slope on a longer
      window, used for the crossing time, was biased by up to 1.7 % under strong pulses.)
    * when ``dynamics`` is given (and the energy estimate does not apply): the equation of motion
      instead of a polynomial. Each sample of the same windows (``rate_window`` [s], ``guard_rate``
      [s] from the crossing, inside the excursion) is integrated with the mechanism's own
      dynamics (its device forces, the ground acceleration) forward (before the impact) or
      backward (after it) to phi = 0 (:func:`extrapolate_to_closure`); phi' just before/after is
      the median of those extrapolations (:data:`EOM_SAMPLES` samples spread over each window).
      On the exact analytic history of the hybrid frames this recovers the applied eta to
      1e-8, where the polynomial fits were off by 1.8-4.3 % (impacts 0.1-0.2 s apart, device
      forces bending the fits; ``tests/test_measure_hybrid.py``). ``dynamics`` maps the rocking
      direction (+1, -1) to an object with ``acceleration(phi, phidot, ground_acc,
      devices_intact)`` [rad/s^2] (``reference_of(scene).dyn``); ``ground_acc`` is a callable
      t [s] -> u_g'' [m/s^2] (None: no ground motion); ``intact`` the devices-intact flag per
      sample (None: intact). ``closure``: the same extrapolation compiled, for many samples
      at once (:func:`rockbench.analytic.closure.closure_function`; None: Python).

    The crossing time is the zero of the fitted arc before the impact (the rigid-contact impact
    time, which a soft contact blurs), or the linear interpolation between the two samples
    around the sign change when that arc has too few samples.

    Returns one dict per impact: t, kind="impact", phi=0, phidot_before, phidot_after (the
    fits, NaN if too short), eta, direction (sign of the excursion after the impact).
    """
    t = np.asarray(t, dtype=float)
    phi = np.asarray(phi, dtype=float)
    phidot = np.asarray(phidot, dtype=float)
    exc = excursions(t, phi, phidot, uplift_tol=uplift_tol, rest_rate=rest_rate)
    rows: list[dict[str, Any]] = []
    for k in range(1, len(exc)):
        a, b = exc[k - 1], exc[k]
        if not b.after_impact:
            continue
        # crossing: last sample with the sign of a, next sample (between a.i1 and b.i0)
        seg = np.sign(phi[a.i1:b.i0 + 1])
        j = a.i1 + int(np.argmax(seg != a.sign))
        j0 = max(j - 1, 0)
        p0, p1 = phi[j0], phi[j]
        tc = t[j0] + (t[j] - t[j0]) * (p0 / (p0 - p1) if p0 != p1 else 0.0)
        cb = _fit(t, phi, max(t[a.i0], tc - guard - window), tc - guard, tc)
        ca = _fit(t, phi, tc + guard, min(t[b.i1], tc + guard + window), tc)
        if cb is not None:           # the crossing of the arc before the impact
            x = _root_near_zero(cb, t[j] - t[j0])
            tc += x
            cb = _shift(cb, x)
            ca = _shift(ca, x) if ca is not None else None
        # angular velocities just before / after: quadratic fits of the sampled phidot on
        # short windows (``rate_window`` [s]) outside the contact (``guard`` [s]) - the fit of
        # phi's slope above is biased under a strong pulse (measured on the exact analytic
        # history: up to 1.7 % against 0.07 % for these fits)
        wb = (max(t[a.i0], tc - guard_rate - rate_window), tc - guard_rate)
        wa = (tc + guard_rate, min(t[b.i1], tc + guard_rate + rate_window))
        use_energy = free and energy is not None and a.complete and b.complete
        if dynamics is not None and not use_energy:
            vb = _eom_value(t, phi, phidot, wb, dynamics[a.sign], ground_acc, intact, +1.0,
                            closure, a.sign)
            va = _eom_value(t, phi, phidot, wa, dynamics[b.sign], ground_acc, intact, -1.0,
                            closure, b.sign)
        else:
            vb = _fit_value(t, phidot, wb[0], wb[1], tc)
            va = _fit_value(t, phidot, wa[0], wa[1], tc)
        e = math.nan
        if use_energy:
            Vb, Va = energy(a.sign * a.peak), energy(b.sign * b.peak)
            if Vb > 0 and Va > 0:
                e = math.sqrt(Va * inertia0(a.sign) / (Vb * inertia0(b.sign)))
        if not math.isfinite(e) and math.isfinite(vb) and math.isfinite(va) and vb != 0.0:
            e = va / vb
        rows.append(dict(t=float(tc), kind="impact", phi=0.0, phidot_before=vb,
                         phidot_after=va, eta=e, direction=b.sign))
    return rows


#: Step [s] of the Runge-Kutta extrapolation to the impact (measured on the exact analytic
#: history of the hybrid frames: eta recovered to 1e-9 with it).
EOM_STEP = 1e-3
#: Samples of a window extrapolated by the equation-of-motion estimator (spread evenly over it).
EOM_SAMPLES = 5


def extrapolate_to_closure(phi0: float, phidot0: float, t0: float, dynamics, *, ground_acc=None,
                           intact: bool = True, direction: float = 1.0,
                           max_time: float = 0.2) -> tuple[float, float]:
    """Integrate the mechanism's equation of motion from (t0 [s], phi0 [rad], phidot0 [rad/s])
    forward (``direction`` +1) or backward (-1) in time until phi reaches 0.

    ``dynamics.acceleration(phi, phidot, ground_acc, devices_intact)`` gives phi'' [rad/s^2]
    (:class:`rockbench.analytic.dynamics.Dynamics`); ``ground_acc(t)`` [m/s^2] or None. Classical
    Runge-Kutta with steps of :data:`EOM_STEP`, then Newton's method on the length of the last
    step for phi = 0. Returns (time [s], phi' [rad/s]) at phi = 0, or (NaN, NaN) if phi does not
    return to 0 within ``max_time`` [s] (the sample is moving away from the impact).
    """
    ag = ground_acc if ground_acc is not None else (lambda _t: 0.0)

    def f(tt, y0, y1):
        return y1, dynamics.acceleration(y0, y1, float(ag(tt)), intact)

    def rk4(tt, y0, y1, h):
        k1 = f(tt, y0, y1)
        k2 = f(tt + h / 2, y0 + h / 2 * k1[0], y1 + h / 2 * k1[1])
        k3 = f(tt + h / 2, y0 + h / 2 * k2[0], y1 + h / 2 * k2[1])
        k4 = f(tt + h, y0 + h * k3[0], y1 + h * k3[1])
        return (y0 + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
                y1 + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))

    sgn = 1.0 if phi0 > 0 else -1.0
    if phi0 == 0.0:
        return t0, phidot0
    tt, y0, y1 = t0, phi0, phidot0
    h = direction * EOM_STEP
    while abs(tt - t0) < max_time:
        n0, n1 = rk4(tt, y0, y1, h)
        if sgn * n0 <= 0.0:          # closed within this step: Newton on the sub-step length
            tau = h * y0 / (y0 - n0)
            for _ in range(8):
                m0, m1 = rk4(tt, y0, y1, tau)
                if m1 == 0.0:
                    break
                d = m0 / m1
                tau -= d
                if abs(d) < 1e-15:
                    break
            return tt + tau, rk4(tt, y0, y1, tau)[1]
        tt, y0, y1 = tt + h, n0, n1
    return math.nan, math.nan


def _eom_value(t, phi, phidot, window, dyn, ground_acc, intact, direction, closure=None,
               sign: int = 1) -> float:
    """Median over the samples of ``window`` = (ta, tb) [s] of phi' at closure, each sample
    extrapolated with :func:`extrapolate_to_closure` (or ``closure``, its compiled form for
    the rocking direction ``sign``); NaN without samples."""
    ta, tb = window
    idx = np.flatnonzero((t >= ta) & (t <= tb))
    if idx.size > EOM_SAMPLES:                  # a few samples spread over the window suffice
        idx = idx[np.round(np.linspace(0, idx.size - 1, EOM_SAMPLES)).astype(int)]
    if not idx.size:
        return math.nan
    ok = np.ones(idx.size, bool) if intact is None else np.asarray(intact)[idx].astype(bool)
    max_time = (tb - ta) + 0.05
    if closure is not None:
        _, v = closure(phi[idx], phidot[idx], t[idx], ok, np.full(idx.size, direction),
                       np.full(idx.size, max_time), sign)
        vals = v[np.isfinite(v)]
    else:
        vals = []
        for i, flag in zip(idx, ok):
            _, x = extrapolate_to_closure(float(phi[i]), float(phidot[i]), float(t[i]), dyn,
                                          ground_acc=ground_acc, intact=bool(flag),
                                          direction=direction, max_time=max_time)
            if math.isfinite(x):
                vals.append(x)
    return float(np.median(vals)) if len(vals) else math.nan


def _fit_value(t, y, ta, tb, tc) -> float:
    """Value at ``tc`` of a least-squares quadratic through the samples ta <= t <= tb (at least
    three), NaN otherwise."""
    m = (t >= ta) & (t <= tb)
    if m.sum() < 3:
        return math.nan
    return float(np.polyfit(t[m] - tc, np.asarray(y, dtype=float)[m], 2)[-1])


def _fit(t, phi, ta, tb, tc):
    """Coefficients (c0, c1, c2) of phi ~ c0 + c1 (t - tc) + c2 (t - tc)^2, least squares on the
    samples with ta <= t <= tb; None if fewer than five."""
    m = (t >= ta) & (t <= tb)
    if m.sum() < 5:
        return None
    return np.polyfit(t[m] - tc, phi[m], 2)[::-1]


def _shift(c, x):
    """The same quadratic about tc + x."""
    return np.array([c[0] + c[1] * x + c[2] * x * x, c[1] + 2.0 * c[2] * x, c[2]])


def _root_near_zero(c, h: float) -> float:
    """The root of c0 + c1 x + c2 x^2 closest to 0, if within one sample spacing ``h`` (else
    0: keep the linear estimate)."""
    c0, c1, c2 = c
    roots = np.roots([c2, c1, c0]) if c2 != 0.0 else (np.array([-c0 / c1]) if c1 else [])
    roots = [r.real for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and abs(r.real) <= h]
    return min(roots, key=abs) if roots else 0.0


def slip_onset(t: np.ndarray, slip: np.ndarray, *, lo: float = 1e-5, hi: float = 1e-3
               ) -> float:
    """The time [s] a contact starts to slide, from a sampled slip history ``slip`` [m] (e.g.
    an engine's ``sliding`` column) at times ``t`` [s]; NaN if the slip never exceeds ``hi``.

    At the onset of Coulomb sliding under a smooth ground motion the relative acceleration
    grows linearly from zero (the ground's acceleration crosses mu (g + a_v) with a non-zero
    slope), so the slip grows as c (t - t0)^3. The first excursion of the slip from ``lo`` to
    ``hi`` [m] is fitted by a straight line of slip^(1/3) against t and t0 is its root: an
    estimate that neither a threshold's lag (a cubic start) nor an engine's creep below
    ``lo`` (regularized contacts) biases. ``0 < lo < hi``."""
    from .errors import ParameterError

    if not (0.0 < lo < hi):
        raise ParameterError("lo", lo, f"0 < lo < hi = {hi!r}")
    t = np.asarray(t, dtype=float)
    s = np.abs(np.asarray(slip, dtype=float))
    over = np.flatnonzero(s > hi)
    if not over.size:
        return math.nan
    i1 = int(over[0])
    i0 = i1
    while i0 > 0 and s[i0 - 1] > lo:
        i0 -= 1
    if i1 - i0 < 2:                       # too few samples between lo and hi: the first above lo
        return float(t[i0])
    a, b = np.polyfit(t[i0:i1 + 1], np.cbrt(s[i0:i1 + 1]), 1)
    return float(-b / a) if a > 0 else float(t[i0])


"""Compiled fast path of the analytic backend: the SDOF rocking model integrated event by event in
numba-compiled code, a drop-in for :func:`rockbench.analytic.solver.simulate` and a batch entry
point for overturning maps (:func:`run_pulse_grid`).

Design (measured choices, see ``benchmarks/results/compiled_analytic.md``):

* Eq. 17 is evaluated from plain parameter arrays extracted once per scene
  (:func:`scene_arrays`), specialised by mechanism (:func:`rockbench.analytic.kernels._phidd`):
  a block in closed form; a frame whose linkage is a parallelogram (the symmetric frame) as the
  Housner block it exactly is (constant I, J = 0, G and B combinations of cos phi and sin phi:
  one sin and one cos per evaluation); any other frame from tables of its terms I, J, G, B and
  the devices' sums (:data:`TABLE_INTERVALS` piecewise polynomials of degree
  :data:`TABLE_DEGREE` over s phi in [-TABLE_MARGIN, fall angle + TABLE_MARGIN], Chebyshev
  interpolation of ``Dynamics.terms``), and beyond the table (near the fall angle) by the exact loop closure of
  :mod:`rockbench.scene.mechanism` with the link directions taken from the linkage's vectors
  (no atan2). Every form gives phi'' within 1e-12 of ``Dynamics.acceleration``'s largest term
  (measured <= 2.2e-13, ``tests/analytic/test_compiled.py``): far below the integration
  tolerance.
* The integrator is the same explicit Runge-Kutta method of order 8 with a 7th-order error
  estimate and 7th-order dense output (Dormand-Prince 8(5,3), "DOP853") that the reference path
  uses through ``scipy.integrate.solve_ivp``, with the same step-size controller and the same
  tolerances (``AnalyticSettings.rtol``/``atol``, 1e-10 / 1e-12 by default); the Butcher tableau
  is read at import time from scipy's own coefficient table. Like ``solve_ivp``, every segment
  (after an uplift, an impact or a fracture) starts from scipy's initial-step selection: a step
  kept across impacts was 1.13 x cheaper but stepped over short excursions of a hybrid frame
  (``kernel_run._run``). The step attempt and the dense output's extra stages are inlined once
  per form of phi'' (``kernel_run._f``): a parallelogram frame under a Ricker pulse in its block
  form, a tabulated frame under a pulse from its table (a step that reaches beyond the table is
  redone with the exact closure), anything else through a call. A stage loop without a call is
  1.3 x faster per step (``benchmarks/results/analytic_floor.md``); the numbers are the same to
  the last bit.
* Events are located as ``solve_ivp`` does: a sign change of the event function between two
  accepted steps (with the event's direction), then Brent's method on the dense output to
  4 machine epsilons; events after the first terminal one in a step are dropped.

Event rules mirrored from :mod:`rockbench.analytic.rules` and :mod:`rockbench.analytic.solver`
(the reference): uplift from rest when u_g'' > lambda g (1 + UPLIFT_RTOL) (direction +1) or
u_g'' < lambda_cw g (1 + UPLIFT_RTOL) (direction -1), found on the motion's knots (pulses:
T_g/400 and the extrema, then Brent to 1e-13 s; records: exact crossing of the linear
interpolation), stepped just past the root; impact at phi = 0 with eta of the post-impact
direction, rest when |phi'+| <= rest_ratio p alpha (or eta <= 0), chatter (two successive
post-impact |phi'| <= CHATTER_VELOCITY_RATIO p alpha at most CHATTER_INTERVAL / p apart settle
the structure); fracture (all devices removed) at the fracture angle of the direction; overturn
at the scene's fall angle (terminal); critical angle exceedance (also, with a "critical" event,
when a segment starts at or beyond the critical angle of its potential); peaks at phi' = 0
(impact and peak event functions are taken as positive at a segment's first instant); at rest,
the run ends at max(t, motion end) once the motion cannot uplift the structure any more before
the end of the run; the progress guarantee (PROGRESS_WINDOW iterations must advance time by
PROGRESS_MIN_ADVANCE / p, at most MAX_EVENT_ITERATIONS iterations; an integrator failure) ends
the run as ``status == "invalid"`` with the reason, never with an exception. The constants are
read from :mod:`rockbench.analytic.rules` when a run starts, as the reference does.

If numba cannot be imported, :data:`NUMBA_AVAILABLE` is False, :data:`NUMBA_ERROR` says why,
and every entry point raises :class:`rockbench.errors.BackendUnavailable` so that callers can
fall back to :func:`rockbench.analytic.solver.simulate`.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import asdict
from typing import Iterable

import numpy as np
import pandas as pd

from .._jit import CpuClock
from ..constants import G
from ..errors import BackendUnavailable, ParameterError, check_positive
from ..result import (Cost, Result, Summary, events_frame,
                      output_grid)
from ..run_length import run_length
from ..scene.motion import Record, RickerPulse
from ..scene.scene import Scene
from ..scene.structure import Frame
from . import rules
from ..validity import lift_off_time
from .reference import Reference, reference_of

__all__ = ["NUMBA_AVAILABLE", "NUMBA_ERROR", "simulate_compiled", "run_pulse_grid",
           "scene_arrays", "MAP_COLUMNS"]

from .kernels import NUMBA_AVAILABLE, NUMBA_ERROR, numba  # noqa: F401
from .kernels import (_A, _ANTI_EXT, _B, _BETA, _C, _D, _E3, _E5, _EV_NAMES, _M_ANTI, _M_NONE, _M_REC, _M_SYM, _NOUT, _TAB0, _NS, _O_ADV, _O_EXC, _O_FRAC, _O_INTACT, _O_MAXABS, _O_MODE, _O_NEV, _O_NFEV, _O_NIMP, _O_OVER, _O_PHI, _O_PHID, _O_STATUS, _O_STEPS, _O_T, _O_TFRAC, _O_TOVER, _O_TUPL, _O_UPL, _REASONS, _SYM_EXT, _XFAC)
from .kernel_grid import _grid_parallel, _grid_serial
from .kernel_run import _run

#: Columns of the frame returned by :func:`run_pulse_grid`, in order.
MAP_COLUMNS = ("amplitude", "frequency", "pulse", "sign", "overturned", "exceeded_critical",
               "max_abs_phi_over_alpha", "n_impacts", "fractured", "uplifted", "t_overturn",
               "status", "reason", "cpu_s", "phi_end", "intact_end")


def _require_numba() -> None:
    if not NUMBA_AVAILABLE:
        raise BackendUnavailable(
            f"the compiled analytic path needs numba: {NUMBA_ERROR}; install it "
            "(pip install numba) or use rockbench.analytic.solver.simulate")


@functools.lru_cache(maxsize=64)
def scene_arrays(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Plain parameter arrays of ``scene`` for the compiled kernel, computed once per scene.

    Returns ``geo`` (2 rows, one per direction, index 0 for +1 and 1 for -1: the kind of
    mechanism (0 block, 1 frame, 2 parallelogram frame, 3 tabulated frame), its geometry,
    masses, inertias, b, k, C, cos and sin of the links' rest angles, a parallelogram's block
    constants, a tabulated frame's tables from column ``_TAB0``) and ``sc`` (scalars: lambda,
    eta, fall, fracture and critical angles, alpha, p, devices flag), all from
    :func:`reference_of`.
    """
    ref = reference_of(scene)
    st = scene.structure
    tabulate = isinstance(st, Frame)
    geo = np.zeros((2, _TAB0 + (6 * TABLE_INTERVALS * (TABLE_DEGREE + 1) if tabulate else 0)))
    for i, s in enumerate((1, -1)):
        dyn = ref.dyn[s]
        row = geo[i]
        m, Ic = list(dyn._m) + [0.0] * (3 - len(dyn._m)), list(dyn._I) + [0.0] * (3 - len(dyn._I))
        row[20:23] = m
        row[23:26] = Ic
        row[26] = st.b
        row[27] = dyn._k
        row[28] = dyn._c
        mech = dyn.mechanism
        if isinstance(st, Frame):
            # a parallelogram (equal, parallel columns: B0 - A = C0 - D) is evaluated in its
            # exact closed form (kernels._kinematics, kind 2), any other linkage by its closure
            para = (abs(mech._rho0 - mech._rho1) <= 1e-12 * mech._rho0
                    and abs(mech._phiAB0 - mech._phiCD0) <= 1e-12)
            row[0] = 2.0 if para else 1.0
            row[1:3] = mech._A
            row[3:5] = mech._D
            row[5], row[6], row[7] = mech._rho0, mech._rho1, mech._L
            row[8], row[9], row[10] = mech._phiAB0, mech._phiCD0, mech._phiBC0
            row[11:13] = mech._rl
            row[13:15] = mech._rb
            row[15:17] = mech._rr
            row[17] = mech._branch
            row[32] = mech._rho0 * math.cos(mech._phiAB0)      # B0 - A
            row[33] = mech._rho0 * math.sin(mech._phiAB0)
            for j, a in enumerate((mech._phiAB0, mech._phiBC0, mech._phiCD0)):
                row[34 + 2 * j] = math.cos(a)
                row[35 + 2 * j] = math.sin(a)
            if not para:
                _tabulate(row, dyn, s, ref.fall[s])
            if para:
                # the block form (kernels._phidd): P = sum m r_x, Q = sum m r_y of the rest
                # offsets (columns about their pivots, the beam's pivot B about A), constant I
                offs = ((row[11], row[12]), (row[32], row[33]), (row[15], row[16]))
                row[40] = sum(mi * o[0] for mi, o in zip(m, offs))
                row[41] = sum(mi * o[1] for mi, o in zip(m, offs))
                row[42] = (sum(mi * (o[0] ** 2 + o[1] ** 2) for mi, o in zip(m, offs))
                           + Ic[0] + Ic[2])
        else:
            row[0] = 0.0
            px, py = mech.pivot
            row[1], row[2] = px, py
            row[3], row[4] = -px, st.H
    sc = np.array([ref.lam[1], ref.lam[-1], ref.eta[1], ref.eta[-1], ref.fall[1], ref.fall[-1],
                   ref.fracture_angle[1], ref.fracture_angle[-1],
                   ref.critical[(1, True)], ref.critical[(-1, True)],
                   ref.critical[(1, False)], ref.critical[(-1, False)],
                   ref.alpha, ref.p, 1.0 if scene.has_devices else 0.0])
    geo.setflags(write=False)
    sc.setflags(write=False)
    return geo, sc


# ================================================================================================
# Compiled kernel
# ================================================================================================
#: Tabulated terms of a frame that is not a parallelogram (kernels._tabulated): intervals over
#: s phi in [-TABLE_MARGIN, TABLE_END x the fall angle (or the linkage's reach, if smaller)] and
#: the polynomials' degree; beyond, where the terms steepen toward the linkage's toggle, the exact
#: closure is evaluated. Measured: phi'' within 2e-13 of the closed form's largest term
#: (tests/analytic/test_compiled.py).
TABLE_INTERVALS = 48
TABLE_DEGREE = 11
TABLE_MARGIN = 0.02
TABLE_END = 0.85


def _tabulate(row: np.ndarray, dyn, s: int, fall: float) -> None:
    """Fill ``row`` (kind 3) with piecewise polynomials of I, J, G, B, sum e de/dphi and sum
    (dc/dphi)^2 of ``dyn`` over u = s phi: Chebyshev interpolation at each interval's
    Chebyshev points, stored as power series in x in [-1, 1] (highest degree first). Beyond
    the linkage's reach (or beyond the table) the kernel evaluates the exact closure."""
    from numpy.polynomial import chebyshev as C

    from ..scene.mechanism import geometric_limit
    if TABLE_DEGREE != 11:      # the kernel evaluates degree 11 by Estrin's scheme
        raise ValueError(f"TABLE_DEGREE must be 11 (kernels._estrin11), not {TABLE_DEGREE}")
    lo = -TABLE_MARGIN
    hi = TABLE_END * min(fall, geometric_limit(dyn.mechanism))
    n, d = TABLE_INTERVALS, TABLE_DEGREE
    du = (hi - lo) / n
    nodes = np.cos(np.pi * (np.arange(d + 1) + 0.5) / (d + 1))     # Chebyshev points
    k, c = dyn._k, dyn._c
    for i in range(n):
        vals = np.zeros((6, d + 1))
        for j, x in enumerate(nodes):
            u = lo + (i + 0.5 * (x + 1.0)) * du
            t = dyn.terms(s * u, True)
            vals[:4, j] = (t.inertia, t.velocity, t.gravity, t.ground)
            vals[4, j] = t.tendon / k if k > 0.0 else 0.0
            vals[5, j] = t.damping / c if c > 0.0 else 0.0
        base = _TAB0 + i * 6 * (d + 1)
        for f in range(6):
            # cheb2poly drops trailing zero coefficients (a term that is zero throughout, or a
            # top coefficient the CPU's least squares returns as exactly 0): pad to degree d
            power = np.zeros(d + 1)
            p = C.cheb2poly(C.chebfit(nodes, vals[f], d))
            power[: len(p)] = p
            row[base + f * (d + 1): base + (f + 1) * (d + 1)] = power[::-1]
    row[0] = 3.0
    row[44], row[45], row[46], row[47], row[48], row[49] = s, lo, hi, du, n, d
    row[43] = 1.0 / du


def _thresholds(sc: np.ndarray) -> tuple[float, float]:
    f = 1.0 + rules.UPLIFT_RTOL
    return sc[0] * G * f, sc[1] * G * f


def _with_eta_factor(sc: np.ndarray, factor: float) -> np.ndarray:
    """``sc`` with both coefficients of restitution times ``factor`` (AnalyticSettings.eta_factor,
    the sensitivity hook of the reference: eta = ref.eta[post] * eta_factor)."""
    if factor == 1.0:
        return sc
    out = np.array(sc)
    out[2:4] *= factor
    return out


def _rule_params(sc: np.ndarray) -> np.ndarray:
    """The rules' constants, read when a run starts (rockbench.analytic.rules): chatter velocity
    [rad/s] and interval [s], least advance [s], progress window and most iterations."""
    p, alpha = sc[13], sc[12]
    return np.array([rules.CHATTER_VELOCITY_RATIO * p * alpha, rules.CHATTER_INTERVAL / p,
                     rules.PROGRESS_MIN_ADVANCE / p, max(1, int(rules.PROGRESS_WINDOW)),
                     int(rules.MAX_EVENT_ITERATIONS)], dtype=float)


def _reason(code: int, out: np.ndarray, rp: np.ndarray, t_end: float) -> str | None:
    """The reason of a run that is not ok (worded as the reference's)."""
    t = out[_O_T]
    if code == 0:
        return None
    if code == 1:
        return (f"compiled DOP853 failed at t = {t:.9g} s: required step size is less than "
                "spacing between numbers")
    if code == 2:
        return (f"analytic event loop made no progress: {int(rp[3])} iterations advanced time by "
                f"{out[_O_ADV]:.3g} s < {rp[2]:.3g} s at t = {t:.9g} s (mode {int(out[_O_MODE])})")
    if code == 4:
        return (f"analytic event loop exceeded {int(rp[4])} iterations at t = {t:.9g} s "
                f"of {t_end:.9g} s")
    return _REASONS.get(code, str(code))


def _motion_arrays(mot) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                 np.ndarray, np.ndarray]:
    """(kind, mp, record t, record a, extrema, extrema suffix max, record suffix max).

    ``mp``: scale [m/s^2], period [s], t_start, t_end [s], x factor of Eq. 30, and the vertical
    part: mp[5] its kind (0 none, 1 a pulse's: the same wavelet times mp[6], the vertical
    pulse's own scale [m/s^2]; 2 a record's channel) (:func:`kernels._acc_hv`). A record's
    vertical channel, sampled at its times (:meth:`Record.with_vertical`), follows its
    horizontal samples in ``ra`` (length 2 n) and its suffix maxima follow theirs in the last
    array (length 2 n)."""
    empty = np.zeros(1)
    mp = np.zeros(7)
    mp[4] = _XFAC
    if mot is None:
        return _M_NONE, mp, empty, empty, empty[:0], empty[:0], empty
    vert = getattr(mot, "vertical", None)
    if isinstance(mot, RickerPulse):
        kind = _M_SYM if mot.shape == "symmetric" else _M_ANTI
        mp[0], mp[1] = mot._scale, mot.period
        mp[2], mp[3] = mot.t_start, mot.t_end
        if vert is not None:
            mp[5], mp[6] = 1.0, vert._scale
        ext = np.ascontiguousarray(mot._extrema, dtype=float)
        suf = np.ascontiguousarray(mot._extrema_sufmax, dtype=float)
        return kind, mp, empty, empty, ext, suf, empty
    if isinstance(mot, Record):
        rt = np.array(mot.time, dtype=float)          # writable copies: one compiled type
        ra = np.array(mot.samples, dtype=float)
        rsuf = np.array(mot._sufmax, dtype=float)
        mp[2], mp[3] = mot.t_start, mot.t_end
        if vert is not None:
            mp[5] = 2.0
            ra = np.concatenate([ra, np.asarray(vert.samples, dtype=float)])
            rsuf = np.concatenate([rsuf, np.asarray(vert._sufmax, dtype=float)])
        return _M_REC, mp, rt, ra, empty[:0], empty[:0], rsuf
    raise ParameterError("motion", type(mot).__name__,
                         "a RickerPulse, a Record or None for the compiled analytic path")


def simulate_compiled(scene: Scene, motion=None, *, duration: float | None = None,
                      phi0: float = 0.0, phidot0: float = 0.0, settings=None,
                      reference: Reference | None = None, assess_validity: bool = True) -> Result:
    """Run the analytic SDOF model of ``scene`` under ``motion`` with the compiled kernel.

    Same signature, arguments and :class:`rockbench.result.Result` schema as
    :func:`rockbench.analytic.solver.simulate` (see its docstring; ``settings`` is an
    ``AnalyticSettings``: rtol, atol, output_dt, rest_ratio and history are honoured; method must
    be "DOP853" (the scheme compiled here), "compiled" or "auto"). ``motion`` may be a
    RickerPulse, a Record or None (free rocking). ``cost.wall_s`` counts the compiled integration only;
    ``cost.steps`` counts accepted steps and ``cost.rhs_calls`` evaluations of phi''.
    ``assess_validity=False`` leaves the summary's ``validity`` None ("not assessed") and its
    sliding fields empty: the friction demand at every output step costs 0.7-4 x the
    integration (benchmarks/results/evidence_labels.md), which a caller reading only verdicts
    and peaks (the sensitivity band) does not need.
    """
    _require_numba()
    from .solver import AnalyticSettings
    settings = settings or AnalyticSettings()
    if settings.method not in ("DOP853", "compiled", "auto"):
        raise ParameterError("settings.method", settings.method,
                             "'DOP853', 'compiled' or 'auto' (the compiled path integrates DOP853 "
                             "only; "
                             "use rockbench.analytic.solver.simulate for other methods)")
    ref = reference if reference is not None and reference.scene == scene else reference_of(scene)
    geo, sc = scene_arrays(scene)
    sc = _with_eta_factor(sc, float(getattr(settings, "eta_factor", 1.0)))
    mk, mp, rt, ra, ext, suf, rsuf = _motion_arrays(motion)
    t0 = float(motion.t_start) if motion is not None else 0.0
    m_end = float(motion.t_end) if motion is not None else 0.0
    if duration is None:
        duration = run_length(motion)
    duration = check_positive("duration", duration)
    phi0, phidot0 = float(phi0), float(phidot0)
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
    # the ground falls faster than gravity: the model (and the run) ends there (solver.py)
    t_lift = lift_off_time(motion, t0, t_end) if motion is not None else None
    if t_lift is not None:
        t_end = t_lift
    v_rest = settings.rest_ratio * ref.p * ref.alpha
    thr_p, thr_n = _thresholds(sc)
    rp = _rule_params(sc)
    tg_full = output_grid(t0, t_end, settings.output_dt)
    hist = np.zeros((tg_full.size, 2))
    hmode = np.zeros((tg_full.size, 2), dtype=np.int64)
    hmode[:, 1] = 1 if scene.has_devices else 0
    cap = 4096
    while True:
        evf = np.zeros((cap, 5))
        evi = np.zeros((cap, 2), dtype=np.int64)
        out = np.zeros(_NOUT)
        w0 = time.perf_counter()
        _run(geo, sc, mk, mp, rt, ra, ext, suf, rsuf, t0, t_end, phi0, phidot0,
             float(settings.rtol), float(settings.atol), v_rest, thr_p, thr_n, m_end,
             rp[0], rp[1], rp[2], int(rp[3]), int(rp[4]), _A, _B, _C, _E3, _E5, _D, _NS,
             True, evf, evi, True, tg_full, hist, hmode, out)
        wall = time.perf_counter() - w0
        if int(out[_O_STATUS]) == 3:
            cap = int(out[_O_NEV]) + 16
            continue
        break
    status = int(out[_O_STATUS])
    reason = _reason(status, out, rp, t_end)
    t_fin = float(out[_O_T])
    tg = output_grid(t0, t_fin, settings.output_dt)
    n = tg.size
    phi = hist[:n, 0].copy()
    phid = hist[:n, 1].copy()
    mode = hmode[:n, 0].astype(np.int64)
    intact = hmode[:n, 1].astype(bool)
    if tg[-1] != tg_full[n - 1]:
        # the run ended between two grid points (overturn, early end at rest): the appended
        # last sample is the final state
        phi[-1], phid[-1] = out[_O_PHI], out[_O_PHID]
        mode[-1] = int(out[_O_MODE])
        intact[-1] = bool(out[_O_INTACT])
    history = _history(scene, geo, sc, motion, tg, phi, phid, mode, intact, settings)
    nev = int(out[_O_NEV])
    rows = [dict(t=float(evf[i, 0]), kind=_EV_NAMES[int(evi[i, 0])], phi=float(evf[i, 1]),
                 phidot_before=float(evf[i, 2]), phidot_after=float(evf[i, 3]),
                 eta=float(evf[i, 4]), direction=int(evi[i, 1])) for i in range(nev)]
    events = events_frame(sorted(rows, key=lambda r: r["t"]))
    overturned = bool(out[_O_OVER])
    t_upl = float(out[_O_TUPL])
    uplifted = bool(out[_O_UPL])
    max_abs = float(out[_O_MAXABS])
    summary = Summary(
        max_abs_phi=max_abs, max_abs_phi_over_alpha=max_abs / ref.alpha, overturned=overturned,
        t_overturn=float(out[_O_TOVER]) if overturned else None,
        exceeded_critical=bool(out[_O_EXC]), uplifted=uplifted,
        t_uplift=t_upl if math.isfinite(t_upl) else (t0 if uplifted else None),
        n_impacts=int(out[_O_NIMP]), fractured=bool(out[_O_FRAC]),
        t_fracture=float(out[_O_TFRAC]) if out[_O_FRAC] else None,
        status="ok" if status == 0 else "invalid", reason=reason)
    if assess_validity:
        from .solver import finish_validity
        finish_validity(summary, ref, motion, history,
                        t_lift if t_lift is not None and t_fin >= t_lift else None)
    cost = Cost(wall_s=wall, sim_time=t_fin - t0, steps=int(out[_O_STEPS]),
                rhs_calls=int(out[_O_NFEV]))
    sdict = asdict(settings)
    sdict["path"] = "compiled"
    mot_desc = motion.describe() if motion is not None else {"kind": "none"}
    return Result(backend="analytic", scene=scene, motion=mot_desc, history=history,
                  events=events, summary=summary, cost=cost, settings=sdict)


def _each_pulse(scene, vr, geo, sc, shapes, signs, As, Ws, dur, rtol, atol, v_rest, thr_p, thr_n,
                rp, A, B, C, E3, E5, Dd, ns, _sym, _anti, _beta, _xfac, res) -> None:
    """The cells of :func:`run_pulse_grid` with a vertical part r = ``vr``: per cell, the
    pulse (:meth:`RickerPulse.dimensionless`), its motion arrays, its end (the window, or
    where the ground falls faster than gravity, :func:`rockbench.validity.lift_off_time`) and
    one call of the run kernel (no history, no events) into ``res[i]``."""
    dummy = np.zeros(1)
    evf = np.zeros((1, 5))
    evi = np.zeros((1, 2), dtype=np.int64)
    hist = np.zeros((1, 2))
    hmode = np.zeros((1, 2), dtype=np.int64)
    for i in range(shapes.shape[0]):
        pulse = RickerPulse.dimensionless(float(As[i]), float(Ws[i]), scene.structure,
                                          "symmetric" if shapes[i] == 1 else "antisymmetric",
                                          int(signs[i]), vertical_ratio=vr)
        mk, mp, rt, ra, ext, suf, rsuf = _motion_arrays(pulse)
        t0, m_end = float(pulse.t_start), float(pulse.t_end)
        t_end = t0 + (dur if dur > 0.0 else run_length(pulse))
        t_lift = lift_off_time(pulse, t0, t_end)
        if t_lift is not None:
            t_end = t_lift
        out = np.zeros(_NOUT)
        _run(geo, sc, mk, mp, rt, ra, ext, suf, rsuf, t0, t_end, 0.0, 0.0, rtol, atol, v_rest,
             thr_p, thr_n, m_end, rp[0], rp[1], rp[2], int(rp[3]), int(rp[4]), A, B, C, E3, E5,
             Dd, ns, False, evf, evi, False, dummy, hist, hmode, out)
        res[i, :] = out


def _history(scene, geo, sc, mot, tg, phi, phid, mode, intact, settings) -> pd.DataFrame:
    """The history frame: the solver's own column builder (one formula for both paths)."""
    from .solver import history_frame

    acc = np.asarray(mot.acceleration(tg), dtype=float) if mot is not None else np.zeros_like(tg)
    return history_frame(reference_of(scene), tg, np.ascontiguousarray(phi, dtype=float),
                         np.ascontiguousarray(phid, dtype=float),
                         np.asarray(mode, dtype=np.int64), np.asarray(intact, dtype=bool), acc,
                         settings.history == "full")


def run_pulse_grid(scene: Scene, cells: Iterable, *, duration: float | None = None,
                   rest_ratio: float | None = None, rtol: float = 1e-10,
                   atol: float = 1e-12, parallel: bool = False,
                   eta_factor: float = 1.0, vertical_ratio: float = 0.0) -> pd.DataFrame:
    """Overturning-map cells of ``scene`` under Ricker pulses, without building Results.

    Parameters
    ----------
    cells : iterable of (shape, sign, A, W)
        shape "symmetric"/"antisymmetric" (or 1/2), sign +1/-1, A = a_g / (g tan alpha) > 0,
        W = omega_g / p > 0 (alpha, p of the scene's taller column).
    duration : float, optional
        Simulated time [s] from the pulse's start (-3 T_g); default
        :func:`rockbench.run_length.run_length` of the pulse (as simulate).
    rest_ratio, rtol, atol, eta_factor : as :class:`AnalyticSettings` (defaults identical;
        rest_ratio None means :data:`rockbench.analytic.rules.REST_RATIO`, read at the call).
    parallel : bool
        Loop over cells with ``numba.prange`` (threads) instead of serially.
    vertical_ratio : float
        r in [0, 3] (limit ``vertical_ratio``): every pulse also moves the ground vertically,
        a_v = r u_g'' (:class:`~rockbench.scene.motion.RickerPulse` ``vertical_ratio``). The
        grid kernel builds horizontal pulses only, so with r > 0 each cell is one call of the
        run kernel on the pulse built in Python (:func:`simulate_compiled`'s integration,
        ending where the ground falls faster than gravity, without its history, events and
        Result), serially (``parallel`` is not used).

    Returns a frame with :data:`MAP_COLUMNS`, one row per cell in the order given. ``status`` is
    "ok" or "invalid" (``reason`` says why the kernel could not advance); ``cpu_s`` is the
    process CPU time of the whole call divided by the number of cells (an amortized share: with
    ``parallel=True`` it adds the CPU time of every thread); ``phi_end`` [rad] and
    ``intact_end`` are the last state of each run (whether its fall is under way:
    :func:`rockbench.verdict.fall_under_way`). A map store keeps the columns of
    :data:`rockbench.sweep.map_store.MAP_COLUMNS`.
    """
    _require_numba()
    rows = list(cells)
    n = len(rows)
    shapes = np.empty(n, dtype=np.int64)
    signs = np.empty(n, dtype=np.int64)
    As = np.empty(n)
    Ws = np.empty(n)
    for i, (shape, sign, A, W) in enumerate(rows):
        if shape in ("symmetric", 1):
            shapes[i] = 1
        elif shape in ("antisymmetric", 2):
            shapes[i] = 2
        else:
            raise ParameterError("shape", shape, "'symmetric' or 'antisymmetric'")
        if sign not in (1, -1):
            raise ParameterError("sign", sign, "+1 or -1")
        signs[i] = int(sign)
        As[i] = check_positive("A", A)
        Ws[i] = check_positive("W", W)
    dur = -1.0 if duration is None else check_positive("duration", duration)
    geo, sc = scene_arrays(scene)
    sc = _with_eta_factor(sc, float(eta_factor))
    thr_p, thr_n = _thresholds(sc)
    if rest_ratio is None:
        rest_ratio = rules.REST_RATIO
    v_rest = check_positive("rest_ratio", rest_ratio) * sc[13] * sc[12]
    rp = _rule_params(sc)
    from ..limits import check_in_limit

    vr = check_in_limit("vertical_ratio", "vertical_ratio", vertical_ratio)
    res = np.zeros((n, _NOUT))
    args = (geo, sc, shapes, signs, As, Ws, dur, float(rtol), float(atol), v_rest, thr_p, thr_n,
            rp, _A, _B, _C, _E3, _E5, _D, _NS, _SYM_EXT, _ANTI_EXT, _BETA, _XFAC, res)
    with CpuClock() as clock:          # a first call's kernel loading is not a cell's cost
        if n and vr:
            _each_pulse(scene, vr, *args)
        elif n and parallel:
            # cells differ in cost by orders of magnitude (at rest vs. long rocking): hand them
            # out in small chunks rather than one contiguous block per thread
            with numba.parallel_chunksize(8):
                _grid_parallel(*args)
        elif n:
            _grid_serial(*args)
    cpu = clock.cpu_s / max(n, 1)
    st = res[:, _O_STATUS].astype(int)
    over = res[:, _O_OVER] != 0.0
    reason = np.full(n, None, dtype=object)
    for i in np.flatnonzero(st != 0):
        reason[i] = _reason(int(st[i]), res[i], rp, float("nan"))
    return pd.DataFrame({
        "amplitude": As, "frequency": Ws,
        "pulse": np.where(shapes == 1, "symmetric", "antisymmetric"),
        "sign": signs, "overturned": over, "exceeded_critical": res[:, _O_EXC] != 0.0,
        "max_abs_phi_over_alpha": res[:, _O_MAXABS] / sc[12],
        "n_impacts": res[:, _O_NIMP].astype(np.int64), "fractured": res[:, _O_FRAC] != 0.0,
        "uplifted": res[:, _O_UPL] != 0.0,
        "t_overturn": np.where(over, res[:, _O_TOVER], np.nan),
        "status": np.where(st == 0, "ok", "invalid"),
        "reason": reason,
        "cpu_s": np.full(n, cpu),
        "phi_end": res[:, _O_PHI], "intact_end": res[:, _O_INTACT] != 0.0,
    })    # keys in MAP_COLUMNS's order (reordering by columns= costs 0.1 ms a call)

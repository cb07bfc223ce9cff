"""Event-driven integration of the SDOF model (:func:`rockbench.analytic.solver.simulate`):
conservation and dissipation of energy, impacts, the equivalent block of the symmetric frame
(Makris & Vassiliou 2012), uplift at lambda g, overturning, critical angle, tendon fracture,
early end of a run, and the Result schema. SI units, radians.
"""

from __future__ import annotations

import json
import math
from itertools import pairwise

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson, solve_ivp
from scipy.optimize import brentq

from rockbench.scene.mechanism import geometric_limit, mechanism
from rockbench.analytic.reference import Reference
from rockbench.analytic.solver import AnalyticSettings, simulate
from rockbench.constants import G
from rockbench.result import CONTACT_COLUMNS, EVENT_COLUMNS, HISTORY_COLUMNS
from rockbench.scene.motion import RickerPulse
from rockbench.scene.scene import Scene, load_scene
from rockbench.scene.structure import Block

ASYM = load_scene("paper-asymmetric")
SYM = load_scene("paper-symmetric")
BLOCK = load_scene("housner-block")
HYBRID = load_scene("paper-asymmetric-hybrid")
EPS1 = load_scene("paper-asymmetric-hybrid-eps1")
REF = {sc.name: Reference(sc) for sc in (ASYM, SYM, BLOCK, HYBRID, EPS1)}
FREE = {"asymmetric": ASYM, "symmetric": SYM, "block": BLOCK}


def energies(ref: Reference, history, intact=None) -> np.ndarray:
    """Mechanical energy [J] (T + V, Dynamics.energy) at every history sample (0 at rest)."""
    out = np.zeros(len(history))
    flags = history["devices_intact"].to_numpy() if intact is None else [intact] * len(history)
    for i, (phi, rate, mode, ok) in enumerate(zip(history["phi"], history["phidot"],
                                                  history["mode"], flags)):
        if mode != 0:
            out[i] = ref.dyn[int(mode)].energy(float(phi), float(rate), bool(ok))
    return out


def excursions(result, n: int):
    """Boolean masks of the history samples strictly inside the first ``n`` excursions (between
    consecutive impacts, or the start and the first impact)."""
    h = result.history
    t = h["t"].to_numpy()
    cuts = [t[0] - 1.0] + list(result.impacts()["t"]) + [t[-1] + 1.0]
    masks = []
    for a, b in pairwise(cuts[:n + 1]):
        m = (t > a + 1e-6) & (t < b - 1e-6) & (h["mode"].to_numpy() != 0)
        if m.sum() >= 10:
            masks.append(m)
    return masks


# --- free rocking: energy --------------------------------------------------------------------
@pytest.mark.parametrize("kind", list(FREE))
@pytest.mark.parametrize("sign", [1, -1])
def test_free_rocking_conserves_energy_between_impacts(kind, sign):
    scene = FREE[kind]
    ref = REF[scene.name]
    r = simulate(scene, None, phi0=sign * 0.5 * scene.alpha, duration=5.0, reference=ref)
    assert r.summary.n_impacts >= 3 and not r.summary.overturned
    E = energies(ref, r.history)
    masks = excursions(r, 4)
    assert len(masks) >= 3
    for m in masks:
        e = E[m]
        assert np.ptp(e) <= 1e-8 * np.max(np.abs(e)), "energy drifts within an excursion"
    # the first excursion starts from rest at phi0: E = V(phi0)
    e0 = ref.dyn[sign].energy(sign * 0.5 * scene.alpha, 0.0)
    assert E[masks[0]] == pytest.approx(e0, rel=1e-8)
    # between excursions the energy drops
    levels = [float(np.mean(E[m])) for m in masks]
    assert all(b < a for a, b in pairwise(levels))


@pytest.mark.parametrize("kind", list(FREE))
def test_each_impact_loses_energy_by_eta(kind):
    scene = FREE[kind]
    ref = REF[scene.name]
    r = simulate(scene, None, phi0=0.5 * scene.alpha, duration=8.0, reference=ref)
    imp = r.impacts()
    imp = imp[imp["direction"] != 0]
    assert len(imp) >= 3
    for _, ev in imp.iterrows():
        post = int(ev["direction"])
        pre = -post
        assert ev["eta"] == ref.eta[post]
        assert 0.0 < ev["eta"] < 1.0
        assert ev["phidot_after"] == pytest.approx(ev["eta"] * ev["phidot_before"], rel=1e-14)
        # the structure swings back through phi = 0 in the direction it will rock into
        assert np.sign(ev["phidot_before"]) == post
        e_before = ref.dyn[pre].energy(0.0, ev["phidot_before"])
        e_after = ref.dyn[post].energy(0.0, ev["phidot_after"])
        assert 0.0 < e_after / e_before < 1.0
    # impacts alternate the direction of rocking
    dirs = list(imp["direction"])
    assert all(a == -b for a, b in pairwise(dirs))


def test_hybrid_frame_dissipates_what_the_dampers_absorb():
    """Tendons and dampers, no fracture: between impacts E(t) + int D phi'^2 dt is constant."""
    ref = REF[HYBRID.name]
    r = simulate(HYBRID, None, phi0=0.4 * HYBRID.alpha, duration=3.0, reference=ref,
                 settings=AnalyticSettings(output_dt=2e-4))
    h = r.history
    E = energies(ref, h)
    masks = excursions(r, 3)
    assert len(masks) >= 2
    for m in masks:
        t = h["t"].to_numpy()[m]
        phi, rate = h["phi"].to_numpy()[m], h["phidot"].to_numpy()[m]
        mode = int(h["mode"].to_numpy()[m][0])
        power = np.array([ref.dyn[mode].terms(p).damping * v * v for p, v in zip(phi, rate)])
        absorbed = cumulative_simpson(power, x=t, initial=0.0)
        total = E[m] + absorbed
        assert absorbed[-1] > 1e-2 * E[m][0]          # the dampers do work
        assert np.ptp(total) <= 1e-7 * E[m][0]


# --- the symmetric frame is Makris & Vassiliou's equivalent block ------------------------------
def equivalent_block_history(frame, pulse, t_grid, v_rest):
    """phi(t) [rad] of the equivalent block of the symmetric frame, integrated here directly:
    phi'' = -p_eq^2 [sin(s alpha - phi) - (u_g''/g) cos(s alpha - phi)] with
    p_eq = p sqrt((1 + 2 gamma) / (1 + 3 gamma)), uplift when |u_g''| > g tan(alpha), impacts
    with eta of Eq. 28, rest when the rebound is below ``v_rest`` [rad/s]. Also returns the
    impact times [s]."""
    a, gam = frame.alpha, frame.mass_beam / (2.0 * frame.mass_left)
    p_eq = frame.p * math.sqrt((1.0 + 2.0 * gam) / (1.0 + 3.0 * gam))
    eta = (1.0 - 1.5 * math.sin(a) ** 2 + 3.0 * gam * math.cos(2.0 * a)) / (1.0 + 3.0 * gam)
    acc, thr = pulse.acceleration, G * math.tan(a)
    t_end = float(t_grid[-1])
    t, phi, rate, mode = float(t_grid[0]), 0.0, 0.0, 0
    out = np.zeros_like(t_grid)
    impacts = []
    while t < t_end:
        if mode == 0:
            ks = pulse.knots(t, t_end)
            av = np.asarray(acc(ks))
            hit = np.nonzero(np.abs(av) > thr)[0]
            if hit.size == 0:
                break
            i = int(hit[0])
            mode = 1 if av[i] > 0 else -1
            t = brentq(lambda tt, m=mode: acc(tt) - m * thr, ks[i - 1], ks[i], xtol=1e-14)
            phi = rate = 0.0
            continue
        s = mode

        def rhs(tt, y, s=s):
            return (y[1], -p_eq**2 * (math.sin(s * a - y[0]) - acc(tt) / G * math.cos(s * a - y[0])))

        def hit_zero(tt, y):
            return y[0]
        hit_zero.terminal, hit_zero.direction = True, -s
        sol = solve_ivp(rhs, (t, t_end), (phi, rate), method="DOP853", rtol=1e-11, atol=1e-13,
                        events=hit_zero, dense_output=True)
        sel = (t_grid >= t) & (t_grid <= sol.t[-1])
        out[sel] = sol.sol(t_grid[sel])[0]
        t, (phi, rate) = float(sol.t[-1]), sol.y[:, -1]
        if sol.status != 1:
            break
        impacts.append(t)
        phi, rate = 0.0, eta * rate
        if abs(rate) < v_rest:
            rate, mode = 0.0, 0
        else:
            mode = -s
    return out, np.array(impacts)


@pytest.mark.parametrize("A, W, shape, sign", [(2.0, 3.0, "symmetric", 1),
                                               (2.5, 4.0, "antisymmetric", -1)])
def test_symmetric_frame_equals_the_equivalent_block(A, W, shape, sign):
    frame = SYM.structure
    pulse = RickerPulse.dimensionless(A, W, frame, shape, sign)
    settings = AnalyticSettings()
    r = simulate(SYM, pulse, settings=settings, reference=REF[SYM.name])
    assert r.summary.n_impacts >= 5 and not r.summary.overturned
    t = r.history["t"].to_numpy()
    v_rest = settings.rest_ratio * frame.p * frame.alpha
    phi_eq, impacts = equivalent_block_history(frame, pulse, t, v_rest)
    err = np.max(np.abs(r.history["phi"].to_numpy() - phi_eq))
    assert err < 1e-6 * frame.alpha
    assert r.summary.max_abs_phi_over_alpha > 0.1
    got = r.impacts()["t"].to_numpy()
    n = min(len(got), len(impacts), 10)
    assert n >= 5
    assert got[:n] == pytest.approx(impacts[:n], abs=1e-8)


def test_symmetric_frame_equals_a_block_with_the_equivalent_p_until_its_first_impact():
    """A Block with the frame's alpha and R_eq = R (1 + 3 gamma) / (1 + 2 gamma) has p_eq: the
    analytic backend's block and frame paths agree until the first impact (where the block's
    Housner eta differs from Eq. 28)."""
    f = SYM.structure
    r_eq = f.R0 * (1.0 + 3.0 * f.gamma) / (1.0 + 2.0 * f.gamma)
    blk = Block(width=2 * r_eq * math.sin(f.alpha), height=2 * r_eq * math.cos(f.alpha))
    assert blk.alpha == pytest.approx(f.alpha, rel=1e-14)
    assert blk.p == pytest.approx(f.p * math.sqrt((1 + 2 * f.gamma) / (1 + 3 * f.gamma)), rel=1e-14)
    pulse = RickerPulse.dimensionless(2.0, 3.0, f)
    rf = simulate(SYM, pulse, reference=REF[SYM.name])
    rb_ = simulate(Scene(blk), pulse)
    t_imp = min(rf.impacts()["t"].iloc[0], rb_.impacts()["t"].iloc[0])
    assert rf.impacts()["t"].iloc[0] == pytest.approx(rb_.impacts()["t"].iloc[0], abs=1e-9)
    n = int(np.searchsorted(rf.history["t"].to_numpy(), t_imp))
    assert n > 100
    np.testing.assert_allclose(rf.history["phi"].to_numpy()[:n], rb_.history["phi"].to_numpy()[:n],
                               rtol=0, atol=1e-7 * f.alpha)


# --- uplift at lambda g --------------------------------------------------------------------
@pytest.mark.parametrize("sign", [1, -1])
def test_uplift_just_above_lambda_g_not_below(sign):
    ref = REF[ASYM.name]
    lam = ref.lam[sign]
    assert sign * lam > 0
    for factor, should in ((1.0 - 1e-3, False), (1.0 + 1e-3, True)):
        pulse = RickerPulse(abs(lam) * G * factor, 5.0, "symmetric", sign)
        r = simulate(ASYM, pulse, reference=ref)
        assert r.summary.uplifted is should
        ups = r.events[r.events["kind"] == "uplift"]
        if should:
            assert list(ups["direction"]) == [sign]
            # uplift exactly where u_g'' reaches lambda g
            assert pulse.acceleration(float(ups["t"].iloc[0])) == pytest.approx(lam * G, rel=1e-9)
            assert r.summary.max_abs_phi > 0.0
            assert not r.summary.overturned
        else:
            assert len(ups) == 0 and r.summary.max_abs_phi == 0.0
            assert (r.history["phi"] == 0.0).all() and (r.history["mode"] == 0).all()


# --- overturning, critical angle -------------------------------------------------------------
@pytest.mark.parametrize("scene", [ASYM, SYM, BLOCK], ids=["asymmetric", "symmetric", "block"])
def test_fall_angle_is_the_default(scene):
    for s in (1, -1):
        lim = geometric_limit(mechanism(scene.structure, s))
        assert scene.fall_angles[s] == pytest.approx(0.98 * min(math.pi / 2, lim), rel=1e-15)
        assert REF[scene.name].fall[s] == scene.fall_angles[s]
    if scene is ASYM:
        assert scene.fall_angles[1] < math.pi / 2 and scene.fall_angles[-1] < math.pi / 2


@pytest.mark.parametrize("sign", [1, -1])
def test_strong_low_frequency_pulse_overturns(sign):
    ref = REF[ASYM.name]
    pulse = RickerPulse.dimensionless(3.0, 1.0, ASYM.structure, "antisymmetric", sign)
    r = simulate(ASYM, pulse, reference=ref)
    s = r.summary
    assert s.overturned and s.exceeded_critical and s.uplifted
    h, ev = r.history, r.events
    assert ev["kind"].iloc[-1] == "overturn"
    assert s.t_overturn == ev["t"].iloc[-1]
    assert h["t"].iloc[-1] == pytest.approx(s.t_overturn, abs=1e-12)   # history ends there
    direction = int(ev["direction"].iloc[-1])
    fall = ref.fall[direction]
    assert direction * h["phi"].iloc[-1] == pytest.approx(fall, rel=1e-9)
    assert direction * ev["phi"].iloc[-1] == pytest.approx(fall, rel=1e-9)
    assert s.max_abs_phi == pytest.approx(fall, rel=1e-9)
    assert s.t_overturn < pulse.t_end + 10.0
    crit = ev[ev["kind"] == "critical"]
    assert len(crit) >= 1 and crit["t"].iloc[-1] < s.t_overturn


def test_custom_fall_angle():
    scene = ASYM.replace(fall_angle=0.3)
    r = simulate(scene, RickerPulse.dimensionless(3.0, 1.0, scene.structure))
    assert r.summary.overturned
    assert abs(r.history["phi"].iloc[-1]) == pytest.approx(0.3, rel=1e-9)


@pytest.mark.parametrize("scene", [ASYM, SYM, BLOCK], ids=["asymmetric", "symmetric", "block"])
def test_critical_angle_of_a_free_standing_structure_is_about_alpha(scene):
    ref = REF[scene.name]
    for s in (1, -1):
        crit = ref.critical[(s, True)]
        assert crit == pytest.approx(scene.alpha, rel=1e-3)
        if scene is not ASYM:
            assert crit == pytest.approx(scene.alpha, rel=1e-10)
        # it is where the gravity moment vanishes: dV/dphi = 0
        t = ref.dyn[s].terms(s * crit)
        assert abs(t.gravity) < 1e-9 * abs(ref.dyn[s].terms(0.0).gravity)
        assert ref.critical[(s, False)] == crit        # no devices: nothing to fracture


def test_tendons_remove_the_critical_angle_until_they_fracture():
    ref, free = REF[EPS1.name], REF[ASYM.name]
    for s in (1, -1):
        assert ref.critical[(s, True)] == math.inf
        assert ref.critical[(s, False)] == pytest.approx(free.critical[(s, True)], rel=1e-12)


@pytest.mark.parametrize("sign", [1, -1])
def test_free_rocking_near_the_critical_angle(sign):
    ref = REF[ASYM.name]
    crit = ref.critical[(sign, True)]
    below = simulate(ASYM, None, phi0=sign * 0.95 * crit, duration=8.0, reference=ref)
    assert not below.summary.overturned and not below.summary.exceeded_critical
    assert below.summary.n_impacts >= 1
    above = simulate(ASYM, None, phi0=sign * 1.02 * crit, duration=10.0, reference=ref)
    assert above.summary.overturned and above.summary.exceeded_critical
    assert above.summary.n_impacts == 0


def test_exceeded_critical_without_overturning():
    """A strong pulse that drives the frame past its critical angle and back: the run reports
    exceeded_critical (with a critical event) but not overturned; the verdict is exactly
    max phi beyond the critical angle of the direction it rocked in."""
    ref = REF[ASYM.name]
    cases = [(11.0, 2.0, "symmetric", True), (2.0, 3.0, "symmetric", False),
             (3.0, 2.0, "antisymmetric", True)]
    for A, W, shape, expected in cases:
        r = simulate(ASYM, RickerPulse.dimensionless(A, W, ASYM.structure, shape), reference=ref)
        h = r.history
        beyond = any(((h["mode"] == s) & (s * h["phi"] > ref.critical[(s, True)])).any()
                     for s in (1, -1))
        assert not r.summary.overturned
        assert r.summary.exceeded_critical is expected is beyond
        assert bool((r.events["kind"] == "critical").any()) is expected


# --- tendon fracture -------------------------------------------------------------------------
def test_tendon_fracture_at_the_fracture_strain():
    ref = REF[EPS1.name]
    eps_f, k = EPS1.devices.fracture_strain, EPS1.devices.tendon_stiffness
    r = simulate(EPS1, RickerPulse.dimensionless(7.0, 2.0, EPS1.structure), reference=ref)
    s, ev, h = r.summary, r.events, r.history
    frac = ev[ev["kind"] == "fracture"]
    assert s.fractured and len(frac) == 1
    t_f, phi_f = float(frac["t"].iloc[0]), float(frac["phi"].iloc[0])
    assert s.t_fracture == t_f
    sgn = int(np.sign(phi_f))
    dyn = ref.dyn[sgn]
    ds = dyn.device_state(dyn.configuration(phi_f))
    assert max(ds.elong_left, ds.elong_right) / EPS1.devices.tendon_length == pytest.approx(
        eps_f, rel=1e-9)
    assert phi_f == pytest.approx(sgn * ref.fracture_angle[sgn], rel=1e-9)
    before, after = h["t"] < t_f, h["t"] > t_f
    assert h.loc[before, "devices_intact"].all() and not h.loc[after, "devices_intact"].any()
    for c in ("tendon_force_left", "tendon_force_right", "damper_force_left",
              "damper_force_right"):
        assert (h.loc[after, c] == 0.0).all()
    # before the fracture the tendons carry k x elongation, and strain stays below eps_f
    assert h.loc[before, "tendon_force_left"].max() > 0.5 * k * eps_f * EPS1.devices.tendon_length
    assert (h.loc[before, ["tendon_elong_left", "tendon_elong_right"]].max().max()
            <= eps_f * EPS1.devices.tendon_length * (1 + 1e-9))
    # after the fracture the frame moves as the free-standing one: phi'' (central differences
    # of phi') follows Eq. 17 without tendons and dampers, not with them
    nxt = ev[(ev["t"] > t_f) & ev["kind"].isin(["impact", "overturn"])]["t"].iloc[0]
    idx = np.nonzero(((h["t"] > t_f + 0.01) & (h["t"] < nxt - 0.01)).to_numpy())[0][::10]
    assert idx.size > 10
    dt = AnalyticSettings().output_dt
    rate = h["phidot"].to_numpy()
    for i in idx:
        phi, v, ug = (float(h[c].iloc[i]) for c in ("phi", "phidot", "ground_acc"))
        fd = (rate[i + 1] - rate[i - 1]) / (2 * dt)
        free = dyn.acceleration(phi, v, ug, devices_intact=False)
        held = dyn.acceleration(phi, v, ug, devices_intact=True)
        assert fd == pytest.approx(free, rel=1e-4, abs=1e-6)
        assert abs(held - free) > 100 * abs(fd - free)


# --- schema, early end --------------------------------------------------------------------------
def test_result_schema():
    settings = AnalyticSettings(output_dt=2e-3)
    pulse = RickerPulse.dimensionless(2.0, 3.0, ASYM.structure)
    r = simulate(ASYM, pulse, settings=settings, duration=8.0)
    h = r.history
    assert list(h.columns) == list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS)
    assert list(r.events.columns) == list(EVENT_COLUMNS)
    dt = np.diff(h["t"].to_numpy())
    assert h["t"].iloc[0] == pulse.t_start
    assert dt[:-1] == pytest.approx(np.full(dt.size - 1, 2e-3), abs=1e-12)
    assert 0.0 < dt[-1] <= 2e-3 * (1 + 1e-9)
    assert h["t"].iloc[-1] == pytest.approx(pulse.t_start + 8.0, abs=1e-12)
    assert set(h["mode"].unique()) <= {-1, 0, 1}
    assert (h["mode"] * h["phi"] >= 0.0).all()
    assert (h.loc[h["mode"] == 0, "phi"] == 0.0).all()
    np.testing.assert_allclose(h["ground_acc"], pulse.acceleration(h["t"].to_numpy()))
    assert h[list(CONTACT_COLUMNS)].isna().all().all()
    keys = r.to_json()
    for k in ("max_abs_phi_over_alpha", "overturned", "exceeded_critical", "uplifted",
              "n_impacts", "fractured", "status", "wall_s"):
        assert k in keys
    assert keys["status"] == "ok" and keys["n_impacts"] == r.summary.n_impacts
    assert keys["max_abs_phi_over_alpha"] == pytest.approx(
        np.max(np.abs(h["phi"])) / ASYM.alpha, rel=1e-3)
    json.dumps(keys, allow_nan=False)
    assert r.summary.n_impacts == (r.events["kind"] == "impact").sum()
    assert r.cost.steps > 0 and r.cost.rhs_calls > 0 and r.cost.wall_s > 0


def test_block_history_has_no_frame_columns():
    r = simulate(BLOCK, None, phi0=0.1, duration=1.0)
    h = r.history
    assert h[["theta_beam", "theta_right"]].isna().all().all()
    assert (h[["tendon_force_left", "damper_force_right"]] == 0.0).all().all()


def test_run_ends_once_at_rest_and_the_motion_cannot_uplift():
    """A weak pulse rocks the frame a little; it comes to rest during the pulse and the run ends
    when the motion does, well before the motion's end + 10 s (the default duration)."""
    ref = REF[ASYM.name]
    pulse = RickerPulse.dimensionless(1.2, 4.0, ASYM.structure)
    r = simulate(ASYM, pulse, reference=ref)
    assert r.summary.uplifted and r.summary.n_impacts > 3
    rest = r.events[r.events["kind"] == "rest"]
    assert len(rest) == 1 and rest["t"].iloc[0] < pulse.t_end
    h = r.history
    assert h["t"].iloc[-1] == pytest.approx(pulse.t_end, abs=1e-9)
    assert (h.loc[h["t"] > rest["t"].iloc[0], "mode"] == 0).all()
    assert r.cost.sim_time < pulse.duration + 1.0


@pytest.mark.parametrize("sign", [1, -1])
def test_run_without_uplift_ends_with_the_motion(sign):
    """A pulse below the threshold of the direction it pushes can never uplift the frame; the
    run stops when the motion ends. For the negative sign the amplitude lies between
    |lambda_ccw| g and |lambda_cw| g: the sign of the excitation decides."""
    ref = REF[ASYM.name]
    pulse = RickerPulse(abs(ref.lam[sign]) * G * 0.999, 2.0, "symmetric", sign)
    if sign == -1:
        assert pulse.peak > abs(ref.lam[1]) * G
    r = simulate(ASYM, pulse, reference=ref)
    assert not r.summary.uplifted and len(r.events) == 0
    assert r.history["t"].iloc[-1] == pytest.approx(pulse.t_end, abs=1e-9)
    assert (r.history["phi"] == 0.0).all()

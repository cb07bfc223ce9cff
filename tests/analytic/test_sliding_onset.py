"""The analytic model knows its own validity: the friction its contacts need along a run
(``Summary.sliding_onset``, ``sliding_contact``, ``validity``) and the a-priori test of a
motion (:func:`rockbench.validity.motion_validity`) with a vertical part.

Independent checks: Shenton's (1996) initiation modes of a block at rest
(:mod:`rockbench.analytic.initiation`: slide and slide-rock start with a slip, rock does not),
the block's pivot force in closed form along the model's history, and Coulomb's condition at
rest |a_g| = mu (g + a_v) solved from the pulse's formula. SI units.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import rockbench.validity as validity
from rockbench.analytic.compiled import NUMBA_AVAILABLE, simulate_compiled
from rockbench.analytic.initiation import initiation_mode
from rockbench.analytic.reactions import demand_history, first_excess
from rockbench.analytic.solver import simulate
from rockbench.constants import G
from rockbench.result import SUMMARY_FIELDS
from rockbench.scene.motion import Record, RickerPulse
from rockbench.scene.scene import load_scene

needs_numba = pytest.mark.skipif(not NUMBA_AVAILABLE, reason="numba not installed")
PATHS = [simulate, pytest.param(simulate_compiled, marks=needs_numba)]
BLOCK = load_scene("housner-block")


def with_friction(monkeypatch, base, beam=None):
    """The scene's friction (the scene's [contact] table is another change: until it lands,
    the one reader, rockbench.validity, is patched)."""
    monkeypatch.setattr(validity, "friction_of", lambda scene: base)
    monkeypatch.setattr(validity, "beam_friction_of",
                        lambda scene: base if beam is None else beam)


def ramp(a0, av0=0.0, t_ramp=1e-3, t_end=0.02, dt=1e-4):
    """a_g rising linearly from 0 to a0 [m/s^2] in t_ramp [s], then constant; a constant
    vertical a_v = av0 [m/s^2] on the same samples (av0 = 0: none)."""
    t = np.arange(0.0, t_end + dt / 2, dt)
    a = a0 * np.minimum(t / t_ramp, 1.0)
    rec = Record(t, a, name="ramp")
    return rec.with_vertical(Record(t, np.full(t.size, av0), name="v")) if av0 else rec


# --- Shenton: the first instant of a block at rest -------------------------------------------------
@pytest.mark.parametrize("fn", PATHS)
@pytest.mark.parametrize("mu, A, av", [
    (0.10, 0.30, 0.0),      # mu < b/h: slide
    (0.15, 0.25, -0.3),     # slide, with vertical motion
    (0.22, 0.40, 0.0),      # b/h < mu < mu_r(A): slide-rock
    (0.21, 0.30, 0.4),      # slide-rock, with vertical motion
    (0.60, 0.40, 0.0),      # mu > mu_r(A): rock
    (0.40, 0.50, -0.2),     # rock, with vertical motion
    (0.30, 0.15, 0.0),      # A < b/h, A < mu: rest
])
def test_sliding_onset_at_the_first_instant_agrees_with_shenton(fn, monkeypatch, mu, A, av):
    """A block (b/h = 0.2) at rest under a horizontal acceleration stepped up to A g (in 1 ms)
    and a constant vertical one: the model reports a sliding onset during the step exactly when
    Shenton's criteria start a slide or a slide-rock; when they start rock or rest it reports
    none in the first 10 ms."""
    beta = BLOCK.structure.b / BLOCK.structure.H
    mode = initiation_mode(beta, mu, A * (1 + av), av)
    with_friction(monkeypatch, mu)
    rec = ramp(A * (1 + av) * G, av * G)
    r = fn(BLOCK, rec, duration=0.01, settings=None)
    onset = r.summary.sliding_onset
    if mode in ("slide", "slide-rock"):
        assert onset is not None and onset <= 1e-3 + r.settings["output_dt"]
        assert r.summary.sliding_contact == "base"
        assert r.summary.validity.startswith("outside the model from t = ")
        assert r.summary.status == "ok"          # the run itself is fine: it is marked
    else:
        assert mode in ("rock", "rest")
        assert onset is None and r.summary.validity == validity.INSIDE
    # the rocking model itself uplifts whenever A > b/h (it knows no sliding): slide-rock and
    # rock uplift, and so does a slide with A > b/h, whose onset comes first
    assert r.summary.uplifted is (A > beta)


def test_first_instant_demand_equals_shentons_boundary():
    """The demand history of a block just after uplift from rest equals Shenton's mu_r(A)
    (rocking_friction_demand), with and without vertical acceleration."""
    from rockbench.analytic.initiation import rocking_friction_demand
    st = BLOCK.structure
    beta = st.b / st.H
    for A, av in ((0.3, 0.0), (0.5, -0.4), (0.25, 0.6)):
        ge = G * (1 + av)
        d = demand_history(BLOCK, [0.0], 0.0, 0.0, 1, True, A * ge, av * G)
        assert d["base"].iloc[0] == pytest.approx(rocking_friction_demand(beta, A * (1 + av), av),
                                                  rel=1e-12)
        rest = demand_history(BLOCK, [0.0], 0.0, 0.0, 0, True, A * ge, av * G)
        assert rest["base"].iloc[0] == pytest.approx(A, rel=1e-14)


# --- along a run -----------------------------------------------------------------------------------
@pytest.mark.parametrize("fn", PATHS)
def test_block_onset_is_the_closed_form_demand_crossing(fn, monkeypatch):
    """Along a rocking run of the block the demand is the closed-form pivot force
    (H = m (a_g - phi'' r_y - phi'^2 r_x), V = m (g + a_v + phi'' r_x - phi'^2 r_y)) over the
    model's own samples, and the onset lies between the last sample at or below mu and the
    first above."""
    st = BLOCK.structure
    m = RickerPulse.dimensionless(2.0, 4.0, st, "symmetric", 1, vertical_ratio=0.5)
    mu = 0.22                      # the run's largest demand is 0.23 (at rest it reaches 0.2)
    with_friction(monkeypatch, mu)
    r = fn(BLOCK, m)
    h = r.history
    t, phi, w, mode = (h[c].to_numpy() for c in ("t", "phi", "phidot", "mode"))
    ag = h["ground_acc"].to_numpy()
    av = m.vertical.acceleration(t)
    ge = G + av
    R, al, mass = st.R, st.alpha, st.mass
    d = np.abs(ag) / ge                                  # at rest: the whole block
    for s in (1, -1):
        k = mode == s
        rx = s * R * np.sin(al - s * phi[k])
        ry = R * np.cos(al - s * phi[k])
        pdd = 3.0 * (ag[k] * ry - ge[k] * rx) / (4.0 * R * R)
        H = mass * (ag[k] - pdd * ry - w[k] ** 2 * rx)
        V = mass * (ge[k] + pdd * rx - w[k] ** 2 * ry)
        d[k] = np.where(V > 0, np.abs(H) / V, np.inf)
    i = int(np.argmax(d > mu))
    assert d[i] > mu and np.all(d[:i] <= mu)
    assert mode[i] != 0                       # it is the rocking demand that exceeds mu
    onset = r.summary.sliding_onset
    assert t[i - 1] <= onset <= t[i]
    assert r.summary.t_outside == onset


@pytest.mark.parametrize("fn", PATHS)
def test_frame_names_the_contact_that_slides(fn, monkeypatch):
    """A frame whose beam has little friction slides on its columns first ("beam"); with the
    beam's friction high and the base's lower than the peak demand (0.18 at D, 0.187 under the
    beam on this run) it is the base."""
    scene = load_scene("paper-asymmetric")
    m = RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1, vertical_ratio=0.4)
    with_friction(monkeypatch, 5.0, 0.16)
    r = fn(scene, m)
    assert r.summary.sliding_contact == "beam"
    assert "the beam on its columns" in r.summary.validity
    with_friction(monkeypatch, 0.175, 5.0)
    r2 = fn(scene, m)
    assert r2.summary.sliding_contact == "base"
    with_friction(monkeypatch, 5.0)
    assert fn(scene, m).summary.validity == validity.INSIDE


def test_hybrid_frame_rocking_with_devices_carries_their_loads():
    """While a hybrid frame rocks with its devices intact their forces are loads in the
    contact equations: the demand is finite and differs from the same state without them (the
    tendons press the columns down); at rest it is |a_g| / (g + a_v)."""
    scene = load_scene("paper-asymmetric-hybrid")
    d = demand_history(scene, [0.0, 0.1, 0.2], [0.0, 0.01, 0.01], [0.0, 0.1, 0.1], [0, 1, 1],
                       [True, True, False], [3.0, 3.0, 3.0], [1.0, 1.0, 1.0])
    assert d["base"].iloc[0] == pytest.approx(3.0 / (G + 1.0), rel=1e-14)
    assert np.isfinite(d[["base", "beam"]].to_numpy()).all()
    assert d["base"].iloc[1] != pytest.approx(d["base"].iloc[2], rel=1e-3)


@pytest.mark.parametrize("name", ["paper-asymmetric-hybrid", "paper-symmetric-hybrid"])
@pytest.mark.parametrize("s", [1, -1])
def test_the_device_loads_do_the_models_virtual_work(name, s):
    """Newton-Euler's own phi'' with the devices' loads (tendons at their anchors, dampers as
    couples) is Eq. 17's with K and D (an independent path: the model's terms come from
    Lagrange's equation), to round-off, over rotations, rates and ground accelerations."""
    from rockbench.analytic import reactions as R
    from rockbench.analytic.dynamics import Dynamics

    scene = load_scene(name)
    fr, dev = scene.structure, scene.devices
    dyn = Dynamics(fr, s, dev)
    phi = s * np.array([0.002, 0.02, 0.05, 0.1, 0.15])
    phidot = np.array([0.3, -0.5, 1.0, -0.2, 0.05])
    a_g = np.array([1.0, -2.0, 0.5, 3.0, -4.0])
    kin = dyn.mechanism.configuration_many(phi)
    piv = fr.pivots(s)
    A, D = piv["A"], piv["D"]
    B = (A[0] + np.cos(phi) * (piv["B"][0] - A[0]) - np.sin(phi) * (piv["B"][1] - A[1]),
         A[1] + np.sin(phi) * (piv["B"][0] - A[0]) + np.cos(phi) * (piv["B"][1] - A[1]))
    th = kin[2]["theta"]
    C = (D[0] + np.cos(th) * (piv["C"][0] - D[0]) - np.sin(th) * (piv["C"][1] - D[1]),
         D[1] + np.sin(th) * (piv["C"][0] - D[0]) + np.cos(th) * (piv["C"][1] - D[1]))
    n = phi.size
    bodies = [(fr.mass_left, fr.inertia_left, kin[0]), (fr.mass_beam, fr.inertia_beam, kin[1]),
              (fr.mass_right, fr.inertia_right, kin[2])]
    joints = [(np.full(n, A[0]), np.full(n, A[1]), [(0, 1.0)]), (B[0], B[1], [(1, 1.0), (0, -1.0)]),
              (C[0], C[1], [(1, 1.0), (2, -1.0)]), (np.full(n, D[0]), np.full(n, D[1]), [(2, 1.0)])]
    loads = R._device_loads(fr, dev, s, kin, phidot)
    _, pdd = R._solve_many(bodies, joints, phidot, a_g, np.full(n, G), loads, with_phiddot=True)
    model = np.array([dyn.acceleration(*x) for x in zip(phi, phidot, a_g)])
    free = np.array([dyn.acceleration(*x, devices_intact=False) for x in zip(phi, phidot, a_g)])
    assert np.abs(pdd - model).max() <= 1e-9 * np.abs(model).max()
    assert np.abs(model - free).max() > 0.1 * np.abs(model).max()       # the devices matter


def test_first_excess_interpolates_and_prefers_the_earlier_contact():
    import pandas as pd
    d = pd.DataFrame({"t": [0.0, 1.0, 2.0, 3.0], "base": [0.1, 0.3, 0.7, 0.9],
                      "beam": [0.0, 0.0, np.inf, np.nan]})
    assert first_excess(d, 0.5, 0.5) == (1.5, "base", 0.7)
    assert first_excess(d, 0.8, 0.1)[:2] == (2.0, "beam")      # opens: the sample itself
    assert first_excess(d.assign(beam=0.0), 0.8) == (2.5, "base", 0.9)
    assert first_excess(d.assign(beam=0.0), 1.0) is None


def test_summary_fields_and_json_carry_the_onset(monkeypatch):
    assert list(SUMMARY_FIELDS)[-4:] == ["sliding_onset", "sliding_contact", "t_lift_off",
                                         "validity"]
    with_friction(monkeypatch, 0.21)
    m = RickerPulse.dimensionless(2.0, 4.0, BLOCK.structure, "symmetric", 1)
    j = simulate(BLOCK, m).to_json()
    assert j["sliding_onset"] is not None and j["sliding_contact"] == "base"
    assert j["validity"].startswith("outside the model from t = ")


# --- a priori ----------------------------------------------------------------------------------------
def test_motion_validity_uses_the_vertical_part(monkeypatch):
    """A pulse whose PGA is below mu g is outside once its in-phase vertical part lowers
    g + a_v enough: |a_g| > mu (g - r |a_g|), i.e. a_g > mu g / (1 + r mu) (sign -1: the
    vertical part falls with the horizontal peak); with sign +1 it rises and the case is
    inside. A vertical part of more than g is outside (lift-off)."""
    with_friction(monkeypatch, 0.5)
    mu, r = 0.5, 0.5
    crit = mu * G / (1 + r * mu)
    for f, inside in ((1 - 1e-6, True), (1 + 1e-6, False)):
        m = RickerPulse(crit * f, 0.5, "symmetric", -1, vertical_ratio=r)
        assert bool(validity.motion_validity(BLOCK, m)) is inside
    up = RickerPulse(crit * 1.01, 0.5, "symmetric", 1, vertical_ratio=r)
    # the positive lobe now meets a rising ground; the side lobes (-0.446 a_g) are far below
    assert validity.motion_validity(BLOCK, up)
    assert not validity.motion_validity(BLOCK, up, scale=-1.0)
    lift = RickerPulse(4.0, 0.5, "symmetric", -1, vertical_ratio=2.6)
    v = validity.motion_validity(BLOCK, lift)
    assert not v and "leaves the ground" in v.reason
    t = validity.lift_off_time(lift)
    assert G + lift.vertical.acceleration(t) <= 0.0 < G + lift.vertical.acceleration(t - 1e-12)
    # without a vertical part the rule is today's: PGA against mu g
    assert validity.motion_validity(BLOCK, RickerPulse(0.99 * mu * G, 0.5))
    assert not validity.motion_validity(BLOCK, RickerPulse(1.01 * mu * G, 0.5))


def test_run_validity_words():
    v = validity.run_validity(BLOCK)
    assert v and v.reason == validity.INSIDE
    v = validity.run_validity(BLOCK, sliding_onset=1.5, sliding_contact="beam", demand=0.7,
                              t_lift_off=1.2)
    assert not v and v.reason.startswith("outside the model from t = 1.2 s: the ground falls")
    v = validity.run_validity(BLOCK, sliding_onset=0.5, sliding_contact="base", demand=math.inf)
    assert v.reason == "outside the model from t = 0.5 s: the base opens (a contact would " \
                       "have to pull)"


def test_coulomb_at_rest_onset_from_the_pulse_formula(monkeypatch):
    """A squat block (b/h = 1.3) under a symmetric pulse below its uplift threshold but above
    its friction: the onset is where a_g(t) = mu (g + r a_g(t)), solved from Eq. 29."""
    scene = load_scene("housner-block", {"width": 2.6, "height": 2.0})
    mu, r, a, T = 0.4, 0.3, 0.55 * G, 0.8
    with_friction(monkeypatch, mu)
    m = RickerPulse(a, T, "symmetric", 1, vertical_ratio=r)

    def ex(t):
        u = math.pi ** 2 * t * t / T ** 2
        ag = a * (1 - 2 * u) * math.exp(-u)
        return ag - mu * (G + r * ag)
    t_on = brentq(ex, -0.3 * T, 0.0, xtol=1e-15)
    res = simulate(scene, m)
    assert not res.summary.uplifted
    assert res.summary.sliding_onset == pytest.approx(t_on, abs=res.settings["output_dt"])
    # linear interpolation of a smooth demand: far closer than one step (measured 1.1e-6 s)
    assert res.summary.sliding_onset == pytest.approx(t_on, abs=1e-5)

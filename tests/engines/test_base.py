"""The shared engine machinery of rockbench.engines.base, checked against the analytic model.

* DeviceGeometry: tendon elongations equal the analytic ones (Dynamics.device_state) for poses
  of the exact mechanism kinematics; the point forces do the analytic virtual work
  (-k e de/dphi for the tendons, -C (dc/dphi)^2 phi' for the dampers, every damper model).
* ContactProbe: exact mechanism poses have no penetration, sliding or opening; displaced bodies
  report the displacement.
* excursions / measure_impacts: the effective eta of synthetic and analytic signals.
* EngineBackend.run, driven by fake engines: one that replays the analytic solution (events,
  eta, fracture, overturn, history grid and device columns must match the analytic backend) and
  ones that fail (exception, NaN, penetration, sliding, energy growth: a Result marked
  "diverged" with the reason, never an exception).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.dynamics import Dynamics
from rockbench.scene.mechanism import mechanism
from rockbench.analytic.reference import Reference
from rockbench.engines.base import EngineBackend, EngineSettings
from rockbench.engines.bodies import body_specs, initial_poses
from rockbench.engines.contacts import ContactProbe
from rockbench.engines.devices import DAMPER_MODELS, DeviceGeometry, PointForce, net_wrenches
from rockbench.measure import excursions, measure_impacts
from rockbench.result import output_grid
from rockbench.errors import ParameterError
from rockbench.result import CONTACT_COLUMNS, HISTORY_COLUMNS


def mech_state(scene, phi: float, phidot: float = 0.0) -> np.ndarray:
    """(n_bodies, 6) state of the exact mechanism at rotation phi [rad], rate phidot [rad/s]."""
    s = 1 if phi >= 0 else -1
    cfg = mechanism(scene.structure, s).configuration(phi)
    return np.array([[b.x, b.y, b.theta, b.dx * phidot, b.dy * phidot, b.dtheta * phidot]
                     for b in cfg.bodies])


def point_power(forces: list[PointForce], state: np.ndarray) -> float:
    """Power [W] of point forces on rigid bodies moving with ``state``'s velocities."""
    p = 0.0
    for f in forces:
        x, y, _, vx, vy, w = state[f.body]
        p += f.fx * (vx - w * (f.py - y)) + f.fy * (vy + w * (f.px - x))
    return p


PHIS = [s * a for s in (1, -1) for a in (1e-4, 0.01, 0.05, 0.1, 0.14, 0.2, 0.3)]


# =========================================================================================
# DeviceGeometry
# =========================================================================================
@pytest.mark.parametrize("name", ["paper-asymmetric-hybrid", "paper-symmetric-hybrid"])
def test_tendon_elongation_equals_analytic(name):
    scene = rb.load_scene(name)
    geo = DeviceGeometry(scene, body_specs(scene))
    for phi in PHIS:
        s = 1 if phi > 0 else -1
        dyn = Dynamics(scene.structure, s, scene.devices)
        ds = dyn.device_state(dyn.configuration(phi))
        el = geo.elongations(mech_state(scene, phi))
        assert el == pytest.approx([ds.elong_left, ds.elong_right], rel=1e-10, abs=1e-13)
        hist_el, hist_t, _ = geo.history(mech_state(scene, phi)[None])
        assert hist_el[0] == pytest.approx(el, rel=1e-12, abs=1e-15)
        assert hist_t[0] == pytest.approx([geo.k * e for e in el], rel=1e-12, abs=1e-9)


@pytest.mark.parametrize("damper", DAMPER_MODELS)
@pytest.mark.parametrize("name", ["paper-asymmetric-hybrid", "paper-symmetric-hybrid"])
def test_device_forces_do_the_analytic_virtual_work(name, damper):
    """Tendon forces: power -k (e_l de_l/dphi + e_r de_r/dphi) phi'; dampers: -C sum
    (dc/dphi)^2 phi'^2, whatever the damper model; reported forces k e and C dc/dt."""
    scene = rb.load_scene(name)
    k, c = scene.devices.tendon_stiffness, scene.devices.damping
    for phi in PHIS:
        for phidot in (0.7, -0.3):
            s = 1 if phi > 0 else -1
            dyn = Dynamics(scene.structure, s, scene.devices)
            ds = dyn.device_state(dyn.configuration(phi))
            st = mech_state(scene, phi, phidot)
            # tendons alone
            tend = rb.Scene(scene.structure, rb.Devices(tendon_stiffness=k, tendon_length=8.5,
                                                        fracture_strain=None, damping=0.0))
            f_t, ten, _ = DeviceGeometry(tend, body_specs(tend), damper).forces(st)
            want = -k * (ds.elong_left * ds.delong_left + ds.elong_right * ds.delong_right)
            assert point_power(f_t, st) == pytest.approx(want * phidot, rel=1e-9, abs=1e-6)
            assert ten == pytest.approx([k * ds.elong_left, k * ds.elong_right], rel=1e-9)
            # dampers alone
            damp = rb.Scene(scene.structure, rb.Devices(tendon_stiffness=0.0, tendon_length=8.5,
                                                        fracture_strain=None, damping=c))
            f_d, _, dmp = DeviceGeometry(damp, body_specs(damp), damper).forces(st)
            want = -c * (ds.dchord_left ** 2 + ds.dchord_right ** 2) * phidot ** 2
            assert point_power(f_d, st) == pytest.approx(want, rel=1e-9, abs=1e-6)
            assert dmp == pytest.approx([c * ds.dchord_left * phidot,
                                         c * ds.dchord_right * phidot], rel=1e-9, abs=1e-6)
            assert DeviceGeometry(damp, body_specs(damp)).history(st[None])[2][0] == \
                pytest.approx(dmp, rel=1e-12, abs=1e-9)


def test_couple_damper_has_no_resultant_and_heel_damper_acts_at_the_heel():
    scene = rb.load_scene("paper-asymmetric-hybrid", {"tendon_stiffness": 0.0})
    st = mech_state(scene, 0.05, 0.4)
    f, _, _ = DeviceGeometry(scene, body_specs(scene), "couple").forces(st)
    w = net_wrenches(f, st)
    assert np.abs(w[:, :2]).max() < 1e-6 * np.abs(w[:, 2]).max()
    f, _, _ = DeviceGeometry(scene, body_specs(scene), "heel").forces(st)
    sp = body_specs(scene)[0]
    x, y, th = st[0, :3]
    heel = (x + math.cos(th) * sp.half_width + math.sin(th) * sp.half_height,
            y + math.sin(th) * sp.half_width - math.cos(th) * sp.half_height)
    left = [g for g in f if g.body == 0]
    assert len(left) == 1 and (left[0].px, left[0].py) == pytest.approx(heel, abs=1e-12)
    assert left[0].fy < 0.0          # the heel lifts (phi' > 0): the damper pulls it down
    with pytest.raises(ParameterError):
        DeviceGeometry(scene, body_specs(scene), "nowhere")


def test_distributed_damper_takes_power_in_proportion_to_momentum():
    """The 'distributed' damper's forces on each body are parallel to its momentum, for any
    (not only mechanism) velocities, and their total power is -C sum (dc_j/dt)^2."""
    scene = rb.load_scene("paper-asymmetric-hybrid", {"tendon_stiffness": 0.0})
    specs = body_specs(scene)
    rng = np.random.default_rng(1)
    st = mech_state(scene, -0.07, 0.0)
    st[:, 3:] = rng.normal(size=(3, 3))
    geo = DeviceGeometry(scene, specs, "distributed")
    f, _, dmp = geo.forces(st)
    w = net_wrenches(f, st)
    for i, sp in enumerate(specs):
        lam = -w[i, 0] / (sp.mass * st[i, 3])
        assert w[i, 1] == pytest.approx(-lam * sp.mass * st[i, 4], rel=1e-9)
        assert w[i, 2] == pytest.approx(-lam * sp.inertia * st[i, 5], rel=1e-9)
    c = scene.devices.damping
    rates = [d / c for d in dmp]
    assert point_power(f, st) == pytest.approx(-c * sum(r * r for r in rates), rel=1e-9)


def test_net_wrenches_moment_about_centre_of_mass():
    st = np.array([[1.0, 2.0, 0.3, 0, 0, 0], [0.0, 0.0, 0.0, 0, 0, 0]])
    f = [PointForce(0, 2.0, 2.0, 0.0, 5.0), PointForce(0, 1.0, 3.0, 7.0, 0.0),
         PointForce(1, 0.5, 0.0, 1.0, 1.0)]
    w = net_wrenches(f, st)
    assert w[0] == pytest.approx([7.0, 5.0, 1.0 * 5.0 - 1.0 * 7.0])
    assert w[1] == pytest.approx([1.0, 1.0, 0.5])


# =========================================================================================
# ContactProbe
# =========================================================================================
@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric", "paper-symmetric"])
def test_probe_exact_mechanism_is_clean(name):
    scene = rb.load_scene(name)
    probe = ContactProbe(scene, body_specs(scene))
    states = np.array([mech_state(scene, phi) for phi in PHIS])
    modes = np.sign([phi for phi in PHIS])
    pen, sl, op = probe.measure_many(states, modes)
    # a heel lifted by less than the contact tolerance counts as touching: its swing
    # b phi^2 <= tol^2 / (4 b) is the only "sliding" of an exact mechanism
    b = body_specs(scene)[0].half_width
    assert pen.max() < 1e-12 and sl.max() < probe.tol ** 2 / (4 * b) and not op.any()
    assert probe.measure(mech_state(scene, 0.0), 0) == (pytest.approx(0.0, abs=1e-15),
                                                       pytest.approx(0.0, abs=1e-15), False)


def test_probe_reports_penetration_sliding_and_opening():
    scene = rb.load_scene("paper-asymmetric")
    probe = ContactProbe(scene, body_specs(scene))
    st = mech_state(scene, 0.05)
    sunk = st.copy()
    sunk[:, 1] -= 1.5e-3                       # every body 1.5 mm down: base corners penetrate
    assert probe.measure(sunk, 1)[0] == pytest.approx(1.5e-3, rel=1e-9)
    slid = st.copy()
    slid[2, 0] += 2e-3                         # right column 2 mm right: its pivot slides ...
    pen, sl, op = probe.measure(slid, 1)
    assert sl == pytest.approx(2e-3, rel=1e-6) and not op   # ... and under the beam
    beam_up = st.copy()
    beam_up[1, 1] += 6e-3                      # beam 6 mm up: the top pivots open
    assert probe.measure(beam_up, 1)[2]
    rest_up = mech_state(scene, 0.0)
    rest_up[1, 1] += 6e-3                      # at rest, every contact must be closed
    assert probe.measure(rest_up, 0)[2]
    assert not probe.measure(mech_state(scene, 0.0), 0)[2]
    lifted = st.copy()
    lifted[0, 1] += 6e-3                       # left column lifted off its pivot
    assert probe.measure(lifted, 1)[2]


# =========================================================================================
# Events and eta from sampled motion
# =========================================================================================
def _arcs(tc, v_before, eta, acc, dt=1e-3, t0=-0.4, t1=0.4):
    """phi(t) of a crossing at tc: phi = v_b (t - tc) + acc (t - tc)^2 / 2 before, eta v_b ...
    after (v_b < 0 so that phi goes from + to -)."""
    t = np.arange(t0, t1 + 1e-12, dt)
    tau = t - tc
    before = tau < 0
    phi = np.where(before, v_before * tau + 0.5 * acc * tau ** 2,
                   eta * v_before * tau - 0.5 * acc * tau ** 2)
    phid = np.where(before, v_before + acc * tau, eta * v_before - acc * tau)
    return t, phi, phid


def test_measure_impacts_fits_recover_velocity_ratio():
    t, phi, phid = _arcs(tc=0.0123, v_before=-0.2, eta=0.9, acc=0.8)
    rows = measure_impacts(t, phi, phid, alpha=0.1, free=False, uplift_tol=1e-5)
    assert len(rows) == 1
    r = rows[0]
    assert r["t"] == pytest.approx(0.0123, abs=1e-6)
    assert r["phidot_before"] == pytest.approx(-0.2, rel=1e-9)
    assert r["phidot_after"] == pytest.approx(-0.18, rel=1e-9)
    assert r["eta"] == pytest.approx(0.9, rel=1e-9)
    assert r["direction"] == -1


def test_measure_impacts_fit_windows_stay_inside_excursions():
    """Two crossings 40 ms apart: each fit must use only its own excursion (a 50 ms window
    would span the other impact)."""
    dt = 1e-3
    t = np.arange(-0.3, 0.3 + 1e-12, dt)
    v1, e1, e2 = -0.3, 0.8, 0.7
    tc1, tc2 = 0.0005, 0.0405
    phi = np.where(t < tc1, v1 * (t - tc1),
                   np.where(t < tc2, e1 * v1 * (t - tc1) * (1 - (t - tc1) / (tc2 - tc1)),
                            0.0))
    # second crossing: slope of the arc at tc2 is -e1 v1, after it eta e2
    v2 = -e1 * v1
    phi = np.where(t >= tc2, e2 * v2 * (t - tc2), phi)
    phid = np.gradient(phi, t)
    rows = measure_impacts(t, phi, phid, alpha=0.1, free=False, uplift_tol=1e-6)
    assert [r["direction"] for r in rows] == [-1, 1]
    assert rows[0]["eta"] == pytest.approx(e1, rel=1e-6)
    assert rows[1]["eta"] == pytest.approx(e2, rel=1e-6)


@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric"])
def test_measure_impacts_energy_method_on_analytic_history(name):
    scene = rb.load_scene(name)
    ref = Reference(scene)
    r = rb.run(scene, phi0=0.5 * scene.alpha, duration=6.0)
    h = r.history
    dyn = {s: Dynamics(scene.structure, s) for s in (1, -1)}
    rows = measure_impacts(h.t.to_numpy(), h.phi.to_numpy(), h.phidot.to_numpy(),
                           alpha=scene.alpha, free=True,
                           energy=lambda p: dyn[1 if p > 0 else -1].energy(p, 0.0),
                           inertia0=lambda s: dyn[s].terms(0.0).inertia,
                           uplift_tol=1e-3 * scene.alpha)
    imp = r.impacts()
    assert len(rows) == len(imp) >= 3
    for k, (row, (_, a)) in enumerate(zip(rows, imp.iterrows())):
        assert row["t"] == pytest.approx(a.t, abs=2e-5)   # 2 % of the sampling interval
        assert row["direction"] == a.direction
        # every peak sampled: energy method; the last one cut by the end of the record: fits
        last = k == len(rows) - 1 and a.t > 6.0 - 0.5
        assert row["eta"] == pytest.approx(ref.eta[int(a.direction)], rel=2e-3 if last else 2e-6)


def test_excursions_refine_peaks_and_detect_rest():
    dt = 1e-3
    t = np.arange(0.0, 3.0, dt)
    # + arc peaking between samples, rest (phi = phidot = 0) for 1 s, then a - arc
    phi = np.where(t < 1.0, 0.01 - 0.04 * (t - 0.5004) ** 2, 0.0)
    phi = np.where(t > 2.0, -0.02 * np.sin(np.pi * (t - 2.0)), phi)
    phi = np.where((t < 1.0) & (phi < 0), 0.0, phi)
    phid = np.gradient(phi, t)
    ex = excursions(t, phi, phid, uplift_tol=1e-5, rest_rate=1e-6)
    assert [x.sign for x in ex] == [1, -1]
    assert ex[0].peak == pytest.approx(0.01, rel=1e-9)
    assert ex[0].complete and ex[1].complete
    assert not ex[1].after_impact               # it began from rest: an uplift, no impact
    assert measure_impacts(t, phi, phid, alpha=0.1, free=False, uplift_tol=1e-5,
                           rest_rate=1e-6) == []
    # cut inside the last excursion before its peak: incomplete
    ex = excursions(t[:2300], phi[:2300], phid[:2300], uplift_tol=1e-5, rest_rate=1e-6)
    assert not ex[-1].complete


def test_output_grid_matches_analytic():
    scene = rb.load_scene("housner-block")
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure)
    r = rb.run(scene, pulse, duration=1.2345)
    t0 = pulse.t_start
    assert np.array_equal(output_grid(t0, t0 + 1.2345, 1e-3), r.history.t.to_numpy())


# =========================================================================================
# The loop, with fake engines
# =========================================================================================
class _Fake(EngineBackend):
    """A fake engine: the state is a function of time (self._at(t))."""

    name = "fake"
    Settings = EngineSettings

    @classmethod
    def _probe(cls):
        return True, "fake 1.0"

    def _build(self):
        self._k = 0
        self._t0 = self._start

    def _step(self, gravity_x, forces):
        self._k += 1

    def _state(self):
        return self._at(self._t0 + self._k * self.settings.dt)

    def run(self, motion=None, *, duration=None, phi0=0.0):
        self._start = motion.t_start if motion is not None else 0.0
        return super().run(motion, duration=duration, phi0=phi0)


class AnalyticDriven(_Fake):
    """Replays an analytic Result through the exact mechanism kinematics."""

    reference = None

    def _at(self, t):
        h = self.reference.history
        tt, ph, pd_ = h.t.to_numpy(), h.phi.to_numpy(), h.phidot.to_numpy()
        if t <= tt[-1]:
            phi, phidot = np.interp(t, tt, ph), np.interp(t, tt, pd_)
        else:                                   # beyond the reference: keep going
            phi, phidot = ph[-1] + pd_[-1] * (t - tt[-1]), pd_[-1]
        return mech_state(self.scene, float(phi), float(phidot))


def _replay(scene, motion=None, duration=None, phi0=0.0, **settings):
    ref = rb.run(scene, motion, duration=duration, phi0=phi0)
    backend = AnalyticDriven(scene, **settings)
    backend.reference = ref
    return backend.run(motion, duration=duration, phi0=phi0), ref


def test_replayed_free_rocking_matches_analytic():
    scene = rb.load_scene("paper-asymmetric")
    r, ref = _replay(scene, duration=4.1, phi0=0.5 * scene.alpha)
    assert r.ok and r.backend == "fake"
    assert list(r.history.columns) == list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS)
    assert np.array_equal(r.history.t.to_numpy(), ref.history.t.to_numpy())
    assert np.abs(r.history.phi.to_numpy() - ref.history.phi.to_numpy()).max() < 1e-12
    for c in ("theta_beam", "theta_right"):
        assert np.abs(r.history[c].to_numpy() - ref.history[c].to_numpy()).max() < 1e-9
    imp, imp_ref = r.impacts(), ref.impacts()
    assert list(imp.direction) == list(imp_ref.direction) == [-1, 1]
    assert imp.t.to_numpy() == pytest.approx(imp_ref.t.to_numpy(), abs=2e-5)
    assert imp.eta.to_numpy() == pytest.approx(imp_ref.eta.to_numpy(), rel=1e-6)
    s = r.summary
    tol = ContactProbe(scene, body_specs(scene)).tol
    assert s.max_penetration < 1e-12 and s.max_sliding < tol ** 2 / 2 and not s.contact_opened
    assert s.uplifted and s.t_uplift == 0.0 and not (r.events.kind == "uplift").any()
    assert s.max_abs_phi == pytest.approx(0.5 * scene.alpha, rel=1e-12)


def test_replayed_hybrid_pulse_fractures_and_reports_devices():
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    pulse = rb.RickerPulse.dimensionless(10.3, 3.0, scene.structure, "antisymmetric", 1)
    r, ref = _replay(scene, pulse, duration=-pulse.t_start + 3.0)
    assert ref.summary.fractured and ref.summary.overturned
    assert r.summary.fractured and r.summary.overturned
    assert r.summary.t_fracture == pytest.approx(ref.summary.t_fracture, abs=1.5e-3)
    assert r.summary.t_overturn == pytest.approx(ref.summary.t_overturn, abs=1.5e-3)
    h, hr = r.history, ref.history
    n = min(len(h), len(hr)) - 2
    intact = h.devices_intact.to_numpy()[:n] & hr.devices_intact.to_numpy()[:n]
    assert intact.sum() > 100
    for c in ("tendon_elong_left", "tendon_elong_right", "tendon_force_left",
              "tendon_force_right", "damper_force_left", "damper_force_right"):
        a, b = h[c].to_numpy()[:n][intact], hr[c].to_numpy()[:n][intact]
        assert np.abs(a - b).max() <= 1e-6 * np.abs(b).max() + 1e-9, c
    after = ~h.devices_intact.to_numpy()
    assert after.any() and (h.loc[after, "tendon_force_left"] == 0).all()
    up = r.events[r.events.kind == "uplift"]
    up_ref = ref.events[ref.events.kind == "uplift"]
    # uplift: back to the last sample at rest in rate (|phidot| <= 1e-3 alpha p)
    assert 0.0 <= up.t.iloc[0] - up_ref.t.iloc[0] < 0.03
    assert np.array_equal(h.ground_acc.to_numpy(), pulse.acceleration(h.t.to_numpy()))


class Raising(_Fake):
    def _at(self, t):
        return mech_state(self.scene, 0.05 * math.cos(t))

    def _step(self, gravity_x, forces):
        super()._step(gravity_x, forces)
        if self._k == 10:
            raise RuntimeError("engine exploded")


class Nan(_Fake):
    def _at(self, t):
        s = mech_state(self.scene, 0.05)
        return s * np.nan if t > 0.005 else s


class Shifted(_Fake):
    dx = dy = 0.0

    def _at(self, t):
        s = mech_state(self.scene, 0.05 * math.cos(2 * t))
        s[:, 0] += self.dx
        s[:, 1] += self.dy
        return s


class Growing(AnalyticDriven):
    """The replayed free rocking, amplitude growing by 50 % per second."""

    def _at(self, t):
        h = self.reference.history
        phi = np.interp(t, h.t.to_numpy(), h.phi.to_numpy()) * (1 + 0.5 * t)
        return mech_state(self.scene, float(phi))


class GrowingAfterPulse(_Fake):
    """At rest during a pulse, then an oscillation whose peaks grow after it."""

    def _at(self, t):
        u = t - self._end
        if u < 0:
            return mech_state(self.scene, 0.0)
        phi = 0.02 * (1 + 0.3 * u) * math.sin(2.0 * u)
        phidot = 0.02 * (0.3 * math.sin(2.0 * u) + 2.0 * (1 + 0.3 * u) * math.cos(2.0 * u))
        return mech_state(self.scene, phi, phidot)


def _check_diverged(r, words):
    assert r.status == "diverged" and not r.ok
    assert all(w in r.summary.reason for w in words), r.summary.reason
    assert list(r.history.columns) == list(HISTORY_COLUMNS) + list(CONTACT_COLUMNS)


def test_engine_exception_becomes_diverged_result():
    scene = rb.load_scene("paper-asymmetric")
    r = Raising(scene).run(None, duration=1.0, phi0=0.05)
    _check_diverged(r, ["RuntimeError", "engine exploded"])
    assert len(r.history) == 10 and r.cost.steps == 9     # raised in the 10th step


def test_nan_state_becomes_diverged_result():
    r = Nan(rb.load_scene("housner-block")).run(None, duration=1.0, phi0=0.05)
    _check_diverged(r, ["non-finite", "t="])


def test_penetration_and_sliding_beyond_tolerance_are_diverged():
    scene = rb.load_scene("paper-asymmetric")
    b = Shifted(scene, max_penetration=1e-3)
    b.dy = -2e-3
    _check_diverged(b.run(None, duration=0.5, phi0=0.05), ["penetration", "max_penetration"])
    b = Shifted(scene, max_sliding=1e-3)
    b.dx = 3e-3
    _check_diverged(b.run(None, duration=0.5, phi0=0.05), ["sliding", "max_sliding"])
    b = Shifted(scene)
    b.dx = 3e-3
    r = b.run(None, duration=0.5, phi0=0.05)
    assert r.ok and r.summary.max_sliding == pytest.approx(3e-3, rel=1e-6)


def test_energy_growth_without_input_is_diverged():
    scene = rb.load_scene("housner-block")
    ref = rb.run(scene, phi0=0.5 * scene.alpha, duration=3.0)
    b = Growing(scene)
    b.reference = ref
    _check_diverged(b.run(None, duration=3.0, phi0=0.5 * scene.alpha), ["energy grew"])
    # after a pulse: peaks growing once the ground is still
    pulse = rb.RickerPulse.dimensionless(0.5, 4.0, scene.structure)
    g = GrowingAfterPulse(scene)
    g._end = pulse.t_end
    r = g.run(pulse, duration=pulse.duration + 6.0)
    _check_diverged(r, ["energy grew without input", "peak"])
    # the same oscillation decaying is fine
    class Decaying(GrowingAfterPulse):
        def _at(self, t):
            u = t - self._end
            if u < 0:
                return mech_state(self.scene, 0.0)
            f = 0.02 * math.exp(-0.1 * u)
            return mech_state(self.scene, f * math.sin(2.0 * u),
                              f * (2.0 * math.cos(2.0 * u) - 0.1 * math.sin(2.0 * u)))
    d = Decaying(scene)
    d._end = pulse.t_end
    assert d.run(pulse, duration=pulse.duration + 6.0).ok


def test_engine_settings_validation():
    with pytest.raises(ParameterError):
        EngineSettings(dt=0.0)
    with pytest.raises(ParameterError):
        EngineSettings(dt=1e-3, output_dt=1e-4)
    with pytest.raises(ParameterError):
        EngineSettings(friction=-1.0)
    with pytest.raises(ParameterError):
        _Fake(rb.load_scene("housner-block"), not_a_setting=1)


def test_initial_poses_follow_the_mechanism():
    scene = rb.load_scene("paper-asymmetric")
    for phi in (0.0, 0.03, -0.05):
        p = initial_poses(scene, phi)
        assert p[:, :3] == pytest.approx(mech_state(scene, phi)[:, :3], abs=1e-15)
        assert p[0, 2] == phi

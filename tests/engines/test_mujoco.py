"""MuJoCo-specific checks: the compiled model (true masses and inertias, planarity, the sign of
phi), settings validation (a contact stiffer than the step resolves is refused; bypassing the
refusal is reported as diverged, never silently simulated), the native tendons (length change =
the analytic elongation; the same generalized forces as the shared model), the native damper
(dissipates exactly the model's power), fracture, and the hybrid frame against the analytic
model. (The cross-engine accuracy bars are tests/engines/test_cross_engine.py's job.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.dynamics import Dynamics
from rockbench.scene.mechanism import mechanism
from rockbench.engines.devices import DeviceGeometry, PointForce
from rockbench.errors import ParameterError

mujoco = pytest.importorskip("mujoco")
from rockbench.engines.mujoco import MujocoBackend, MujocoSettings  # noqa: E402


@pytest.fixture(scope="module")
def frame():
    return rb.load_scene("paper-asymmetric")


@pytest.fixture(scope="module")
def hybrid():
    return rb.load_scene("paper-asymmetric-hybrid")


def _mechanism_velocity(scene, phi: float, phidot: float) -> np.ndarray:
    """qvel (slide x, slide z, hinge per body) of the rocking mechanism at (phi, phidot)."""
    cfg = mechanism(scene.structure, 1 if phi > 0 else -1).configuration(phi)
    return np.concatenate([[bk.dx * phidot, bk.dy * phidot, bk.dtheta * phidot]
                           for bk in cfg.bodies])


# --- the compiled model ---------------------------------------------------------------------
@pytest.mark.parametrize("name", ["housner-block", "paper-symmetric", "paper-asymmetric"])
def test_compiled_masses_and_inertias_are_the_scenes(name):
    scene = rb.load_scene(name)
    b = MujocoBackend(scene)
    m = b.compile()
    assert m.nbody == len(b.specs) + 1 and m.nq == m.nv == 3 * len(b.specs)
    for i, sp in enumerate(b.specs):
        assert m.body_mass[i + 1] == pytest.approx(sp.mass, rel=1e-12)
        ixx, iyy, izz = m.body_inertia[i + 1]
        assert iyy == pytest.approx(sp.inertia, rel=1e-12)   # in-plane: the scene's (beam m rho^2)
        assert ixx + izz >= iyy and ixx + iyy >= izz and iyy + izz >= ixx
        np.testing.assert_allclose(m.body_ipos[i + 1], 0.0, atol=1e-12)  # CoM at the hinge
    if name != "housner-block":
        beam = b.specs[1]
        assert beam.inertia == pytest.approx(beam.mass * scene.structure.beam_gyration_radius ** 2)


def test_planar_motion_and_counterclockwise_phi(frame):
    """Under a strong ground motion and forces off the centre line, MuJoCo's own body poses stay
    in the x-z plane with rotations about y only; the state is the pose in rockbench's x-y plane
    with theta positive counterclockwise; a counterclockwise rotation pivots on the left column's
    bottom-left corner."""
    b = MujocoBackend(frame)
    m = b.compile(0.6 * frame.alpha)
    d = b.data
    for k in range(800):
        b._step(2.0 * math.sin(0.02 * k), [PointForce(1, 4.0, 8.0, 1e5, 2e5)])
    mujoco.mj_kinematics(m, d)
    st = b._state()
    assert st[0, 2] > 0.0
    for i in range(len(b.specs)):
        R = d.xmat[i + 1].reshape(3, 3)
        assert abs(d.xpos[i + 1][1]) < 1e-12
        np.testing.assert_allclose(R[1], [0.0, 1.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(d.xipos[i + 1][[0, 2]], st[i, :2], atol=1e-12)
        th = st[i, 2]
        np.testing.assert_allclose([R[0, 0], R[2, 0]], [math.cos(th), math.sin(th)], atol=1e-12)
    # pivot of a counterclockwise rotation
    b = MujocoBackend(frame)
    b.compile(0.5 * frame.alpha)
    sp = b.specs[0]
    corner0 = _corner(b._state()[0], -sp.half_width, -sp.half_height)
    assert corner0 == pytest.approx((sp.x - sp.half_width, 0.0), abs=1e-9)
    for _ in range(50):
        b._step(0.0, [])
    st = b._state()
    assert st[0, 2] < 0.5 * frame.alpha          # falls back towards rest
    corner = _corner(st[0], -sp.half_width, -sp.half_height)
    assert corner == pytest.approx(corner0, abs=5e-4)


def _corner(s, lx, ly):
    c, sn = math.cos(s[2]), math.sin(s[2])
    return (s[0] + c * lx - sn * ly, s[1] + sn * lx + c * ly)


def test_contact_pairs_and_friction(frame):
    """Only the contacts the scene needs, each with exactly the settings' friction."""
    b = MujocoBackend(frame, friction=0.7)
    m = b.compile()
    assert np.all(m.geom_contype == 0) and np.all(m.geom_conaffinity == 0)
    name = lambda g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)  # noqa: E731
    pairs = {frozenset((name(m.pair_geom1[k]), name(m.pair_geom2[k]))) for k in range(m.npair)}
    assert pairs == {frozenset(p) for p in (("left", "ground"), ("right", "step"),
                                            ("left", "beam"), ("right", "beam"))}
    np.testing.assert_allclose(m.pair_friction[:, :2], 0.7)
    np.testing.assert_allclose(m.pair_solref[:, 0], 2 * b.settings.dt)


# --- settings -------------------------------------------------------------------------------
def test_settings_defaults_and_validation():
    s = MujocoSettings()
    assert s.timeconst == pytest.approx(2 * s.dt)
    assert MujocoSettings(dt=2e-4).timeconst == pytest.approx(4e-4)
    assert MujocoSettings(dt=1e-2, output_dt=1e-2).timeconst == pytest.approx(2e-2)
    with pytest.raises(ParameterError) as e:
        MujocoSettings(dt=1e-2, output_dt=1e-2, contact_timeconst=1e-2)
    assert e.value.name == "contact_timeconst" and "2 dt" in e.value.valid
    for bad in (dict(contact_dampratio=0.0), dict(impedance=1.0), dict(integrator="verlet"),
                dict(cone="round"), dict(iterations=0), dict(iterations=2.5),
                dict(devices="springs"), dict(damper="hydraulic"), dict(impratio=-1),
                dict(contact_timeconst=float("nan")), dict(noslip_iterations=-1)):
        with pytest.raises(ParameterError) as e:
            MujocoSettings(**bad)
        assert e.value.name == next(iter(bad))


def test_default_contact_survives_the_largest_step():
    """At dt = 1e-2 s (the largest allowed) the default contact (time constant 2 dt) rocks the
    block without diverging: bounded penetration, rocking decays."""
    scene = rb.load_scene("housner-block")
    r = rb.run(scene, engine="mujoco", phi0=0.5 * scene.alpha, duration=3.0, dt=1e-2,
               output_dt=1e-2)
    assert r.summary.status == "ok" and not r.summary.overturned
    assert r.summary.max_penetration < 5e-3 and r.summary.max_sliding < 2e-3
    assert r.summary.n_impacts >= 2
    assert r.summary.max_abs_phi_over_alpha == pytest.approx(0.5, abs=0.01)


def test_too_stiff_contact_is_reported_diverged_not_simulated(monkeypatch):
    """The refusal of contact_timeconst < 2 dt is needed: with it bypassed, a contact time
    constant of half a step blows up, and the shared loop reports the run as diverged."""
    monkeypatch.setattr(MujocoSettings, "min_timeconst_steps", 0.1)
    scene = rb.load_scene("housner-block")
    r = rb.run(scene, engine="mujoco", phi0=0.5 * scene.alpha, duration=3.0, dt=2e-3,
               output_dt=2e-3, contact_timeconst=1e-3)
    assert r.summary.status == "diverged"
    assert "penetration" in r.summary.reason or "sliding" in r.summary.reason \
        or "energy" in r.summary.reason or "non-finite" in r.summary.reason


# --- native devices -------------------------------------------------------------------------
PHIS = (-0.1, -0.03, -1e-6, 1e-6, 0.02, 0.1)


@pytest.mark.parametrize("phi", PHIS)
def test_native_tendon_length_change_is_the_analytic_elongation(hybrid, phi):
    b = MujocoBackend(hybrid)
    m = b.compile(phi)
    geo = DeviceGeometry(hybrid, b.specs)
    dyn = Dynamics(hybrid.structure, 1 if phi > 0 else -1, hybrid.devices)
    ds = dyn.device_state(dyn.configuration(phi))
    native = [b.data.ten_length[t] - l0 for t, l0 in b._tendons]
    np.testing.assert_allclose(native, [ds.elong_left, ds.elong_right], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(native, geo.elongations(b._state()), rtol=1e-9, atol=1e-12)
    assert m.ntendon == 2  # the damper is joint damping, no tendon


@pytest.mark.parametrize("phi", PHIS)
def test_native_tendon_forces_equal_the_shared_model(hybrid, phi):
    """MuJoCo's tendon generalized forces (qfrc_passive) equal the shared point forces mapped to
    the joints, down to rotations of a microradian (zero-length tendon segments at rest)."""
    scene = rb.load_scene("paper-asymmetric-hybrid", {"damping": 0.0})
    b = MujocoBackend(scene)
    m = b.compile(phi)
    d = b.data
    mujoco.mj_forward(m, d)
    forces, tensions, _ = DeviceGeometry(scene, b.specs).forces(b._state())
    q = np.zeros(m.nv)
    for f in forces:
        mujoco.mj_applyFT(m, d, np.array([f.fx, 0.0, f.fy]), np.zeros(3),
                          np.array([f.px, 0.0, f.py]), f.body + 1, q)
    scale = max(tensions) * 10.0  # N (a lever of 10 m)
    np.testing.assert_allclose(d.qfrc_passive, q, atol=1e-9 * scale + 1e-9)


def test_distributed_damper_dissipates_the_model_power(hybrid):
    """On a mechanism velocity, MuJoCo's joint damping dissipates exactly D(phi) phi'^2 of the
    analytic model (Eq. 17) and exerts no net force on a body at rest relative to the
    mechanism: the damping force is proportional to each body's momentum."""
    b = MujocoBackend(hybrid)
    m = b.compile(0.04)
    d = b.data
    phidot = -0.3
    d.qvel[:] = _mechanism_velocity(hybrid, 0.04, phidot)
    b._set_dampers()
    mujoco.mj_forward(m, d)
    damping_force = -m.dof_damping * d.qvel
    power = -float(np.dot(damping_force, d.qvel))
    t = Dynamics(hybrid.structure, 1, hybrid.devices).terms(0.04)
    assert power == pytest.approx(t.damping * phidot ** 2, rel=1e-9)
    mass = np.array([[sp.mass, sp.mass, sp.inertia] for sp in b.specs]).ravel()
    ratio = damping_force / (mass * d.qvel)
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-12)


def test_native_report_and_fracture_switch_devices_off():
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    pulse = rb.RickerPulse.dimensionless(12.0, 3.0, scene.structure, "symmetric", 1)
    r = rb.run(scene, pulse, engine="mujoco", duration=1.0 - pulse.t_start)
    ref = rb.run(scene, pulse, engine="analytic", duration=1.0 - pulse.t_start)
    assert r.summary.fractured and ref.summary.fractured
    assert r.summary.t_fracture == pytest.approx(ref.summary.t_fracture, abs=0.01)
    h = r.history
    before = h[h.devices_intact]
    after = h[~h.devices_intact]
    assert len(after) and (after[["tendon_force_left", "tendon_force_right",
                                  "damper_force_left", "damper_force_right"]] == 0.0).all().all()
    # the reported forces are those of the scene model in the sampled states
    k, c, b = scene.devices.tendon_stiffness, scene.devices.damping, scene.structure.b
    for side in ("left", "right"):
        np.testing.assert_allclose(before[f"tendon_force_{side}"],
                                   k * before[f"tendon_elong_{side}"], rtol=1e-12)
    th = before.phi.to_numpy()
    rate = 2 * b * np.cos(th / 2) * np.where(th >= 0, 1.0, -1.0) * before.phidot.to_numpy()
    np.testing.assert_allclose(before.damper_force_left, c * rate, rtol=1e-9, atol=1e-6)
    assert before.damper_force_left.abs().max() > 1e5    # dampers act (N)


def test_hybrid_frame_matches_the_analytic_model(hybrid):
    """Tendons and distributed dampers: peak within 0.5 %, no pivot slip (the couple and heel
    models slip centimetres here, see docs/engines/mujoco.md)."""
    pulse = rb.RickerPulse.dimensionless(8.0, 3.0, hybrid.structure, "symmetric", 1)
    dur = 1.5 - pulse.t_start
    ref = rb.run(hybrid, pulse, engine="analytic", duration=dur)
    for devices in ("native", "forces"):
        r = rb.run(hybrid, pulse, engine="mujoco", duration=dur, devices=devices)
        assert r.summary.status == "ok"
        assert r.summary.max_abs_phi == pytest.approx(ref.summary.max_abs_phi, rel=5e-3)
        assert r.summary.max_sliding < 1e-3 and r.summary.max_penetration < 1e-3

"""PyBullet-specific checks: isolation of physics clients, bit-for-bit repeatability, planarity
and the sign of phi, the pair friction, true masses and inertias, device forces applied at the
right point, and settings validation. (Accuracy against the analytic model is the cross-engine
suite's job: tests/engines/test_cross_engine.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.constants import G
from rockbench.engines.bodies import body_specs, foundation_spec, initial_poses
from rockbench.engines.devices import PointForce
from rockbench.errors import ParameterError
from rockbench.scene.scene import Scene
from rockbench.scene.structure import Block

pb = pytest.importorskip("pybullet")
from rockbench.engines.pybullet import PybulletBackend, PybulletSettings  # noqa: E402


def _built(scene, phi0=0.0, **settings) -> PybulletBackend:
    """A backend with its world built as ``run`` builds it (for stepping by hand)."""
    b = PybulletBackend(scene, **settings)
    b.specs = body_specs(scene)
    b.foundation = foundation_spec(scene)
    b.poses0 = initial_poses(scene, phi0)
    b._build()
    return b


@pytest.fixture(scope="module")
def frame():
    return rb.load_scene("paper-asymmetric")


@pytest.fixture(scope="module")
def block():
    return rb.load_scene("housner-block")


# --- isolation and repeatability -----------------------------------------------------------
def test_two_clients_interleaved_do_not_interfere(frame, block):
    """Two worlds stepped alternately in one process (different scenes, gravities and forces)
    give bit for bit the states of the same world stepped alone."""
    alone = _built(frame, 0.5 * frame.alpha)
    ref = []
    for k in range(300):
        alone._step(0.3 * math.sin(0.01 * k), [])
        ref.append(alone._state())
    alone._close()

    a = _built(frame, 0.5 * frame.alpha)
    other = _built(block, -0.3 * block.alpha, dt=5e-4, solver_iterations=7, friction=0.8)
    assert a._cid != other._cid
    for k in range(300):
        other._step(-2.0, [PointForce(0, 0.0, 3.0, 1e4, 0.0)])
        a._step(0.3 * math.sin(0.01 * k), [])
        other._state()
        np.testing.assert_array_equal(a._state(), ref[k])
    a._close()
    other._close()


def test_run_is_repeatable_bit_for_bit_and_closes_its_client(frame):
    motion = rb.RickerPulse.dimensionless(3.0, 4.0, frame.structure, "antisymmetric", -1)
    cids = []

    class Spy(PybulletBackend):
        def _build(self):
            super()._build()
            cids.append(self._cid)

    # a foreign client left open with other gravity must not leak into the runs
    foreign = pb.connect(pb.DIRECT)
    pb.setGravity(5.0, 0.0, 3.0, physicsClientId=foreign)
    try:
        dur = 1.5 - motion.t_start   # through the main lobe
        r1 = Spy(frame).run(motion, duration=dur)
        r2 = Spy(frame).run(motion, duration=dur)
    finally:
        pb.disconnect(physicsClientId=foreign)
    assert r1.ok and r2.ok and r1.summary.uplifted
    for c in ("phi", "phidot", "theta_beam", "theta_right", "penetration", "sliding"):
        np.testing.assert_array_equal(r1.history[c].to_numpy(), r2.history[c].to_numpy())
    assert len(cids) == 2
    assert not any(pb.isConnected(physicsClientId=c) for c in cids)


# --- geometry: planarity and the sign of phi ---------------------------------------------
def _link_pose(b, i):
    pos, orn = pb.getLinkState(b._bodies[i], 2, computeForwardKinematics=True,
                               physicsClientId=b._cid)[:2]
    return np.array(pos), np.array(pb.getMatrixFromQuaternion(orn)).reshape(3, 3)


def test_bodies_stay_planar_and_phi_is_counterclockwise(frame):
    """Bullet's own link poses: no out-of-plane translation or rotation under a strong ground
    motion with device-like forces off the centre line of forces; the joint coordinates are the
    pose in rockbench's x-y plane with theta positive counterclockwise; and the pivot of a
    counterclockwise rotation (bottom-left corner of the left column) stays on the ground."""
    b = _built(frame, 0.6 * frame.alpha)
    for k in range(800):
        b._step(2.0 * math.sin(0.02 * k), [PointForce(1, 4.0, 8.0, 1e5, 2e5)])
    st = b._state()
    assert st[0, 2] > 0.0  # still rocking counterclockwise (or back near rest)
    for i, sp in enumerate(b.specs):
        pos, R = _link_pose(b, i)
        assert abs(pos[1]) < 1e-12  # no out-of-plane drift
        np.testing.assert_allclose(R[1], [0.0, 1.0, 0.0], atol=1e-12)  # rotation about y only
        x, y, th = st[i, :3]
        np.testing.assert_allclose(pos[[0, 2]], [x, y], atol=1e-9)
        # local +x axis (Bullet x-z) is (cos th, sin th) in rockbench's x-y plane
        np.testing.assert_allclose([R[0, 0], R[2, 0]], [math.cos(th), math.sin(th)], atol=1e-9)
    b._close()
    # a counterclockwise rotation pivots on the bottom-left corner, which stays put
    b = _built(frame, 0.5 * frame.alpha)
    for _ in range(50):
        b._step(0.0, [])
    st = b._state()
    sp = b.specs[0]
    x, y, th = st[0, :3]
    cx = x + math.cos(th) * -sp.half_width - math.sin(th) * -sp.half_height
    cy = y + math.sin(th) * -sp.half_width + math.cos(th) * -sp.half_height
    assert th > 0.0
    assert abs(cx - (sp.x - sp.half_width)) < 2e-4 and abs(cy) < 5e-4
    b._close()


def test_positive_ground_acceleration_uplifts_counterclockwise(block):
    motion = rb.RickerPulse.dimensionless(1.5, 3.0, block.structure, "symmetric", 1)
    r = rb.run(block, motion, engine="pybullet", duration=motion.t_end - motion.t_start)
    ra = rb.run(block, motion, engine="analytic", duration=motion.t_end - motion.t_start)
    up = r.events[r.events["kind"] == "uplift"]
    up_a = ra.events[ra.events["kind"] == "uplift"]
    assert r.ok and len(up) == 1 and len(up_a) == 1
    assert int(up["direction"].iloc[0]) == int(up_a["direction"].iloc[0])
    # and both cross 5 % of alpha at the same time, with the same sign
    first = [h["t"].to_numpy()[np.argmax(np.abs(h["phi"].to_numpy()) > 0.05 * block.alpha)]
             for h in (r.history, ra.history)]
    assert abs(first[0] - first[1]) < 0.01
    i = int(np.searchsorted(ra.history["t"].to_numpy(), first[1])) + 5
    assert np.sign(r.history["phi"].iloc[i]) == np.sign(ra.history["phi"].iloc[i]) == 1.0


# --- friction, masses, forces -------------------------------------------------------------
@pytest.mark.parametrize("mu", [0.3, 0.6])
def test_pair_friction_is_settings_friction(mu):
    """A squat block (no tipping: b/H = 1.4, the widest a scene accepts, tips only beyond
    gx = 1.4 g) sliding under a horizontal 'gravity' gx > mu g accelerates at |gx| - mu g, and
    sticks when |gx| < mu g: the pair's coefficient is settings.friction, although Bullet
    multiplies the two bodies' coefficients."""
    sc = Scene(Block(width=1.4, height=1.0))
    b = _built(sc, friction=mu)
    infos = [pb.getDynamicsInfo(b._bodies[0], 2, physicsClientId=b._cid)[1]]
    infos += [pb.getDynamicsInfo(s, -1, physicsClientId=b._cid)[1] for s in b._static]
    assert infos[0] * infos[1] == pytest.approx(mu, rel=1e-12)
    gx = 1.5 * mu * G
    n = 400
    for _ in range(n):
        b._step(gx, [])
    v = b._state()[0, 3]
    assert v / (n * b.settings.dt) == pytest.approx(gx - mu * G, rel=0.01)
    b._close()
    b = _built(sc, friction=mu)
    for _ in range(n):
        b._step(-0.8 * mu * G, [])
    st = b._state()[0]
    assert abs(st[0] - b.specs[0].x) < 1e-5 and abs(st[3]) < 1e-4
    b._close()


def test_masses_and_inertias_are_the_scenes(frame):
    b = _built(frame)
    for sp, bid in zip(b.specs, b._bodies):
        info = pb.getDynamicsInfo(bid, 2, physicsClientId=b._cid)
        assert info[0] == pytest.approx(sp.mass, rel=1e-12)
        assert info[2][1] == pytest.approx(sp.inertia, rel=1e-12)  # about the plane's normal
        for link in (0, 1):
            m = pb.getDynamicsInfo(bid, link, physicsClientId=b._cid)[0]
            assert 0.0 < m <= 1e-6 * sp.mass * (1 + 1e-12)
    beam = b.specs[1]
    st = frame.structure
    assert beam.inertia == pytest.approx(st.mass_beam * st.beam_gyration_radius ** 2)
    box = beam.mass * ((2 * beam.half_width) ** 2 + (2 * beam.half_height) ** 2) / 12.0
    assert abs(beam.inertia / box - 1.0) > 0.05  # the scene's value, not the box's, is used
    b._close()


def test_free_flight_has_no_hidden_damping_or_motors(block):
    """A block thrown in the air keeps vx and omega and falls with g exactly: Bullet's default
    multibody damping (0.04) and the joints' velocity motors are switched off."""
    b = _built(block)
    bid = b._bodies[0]
    v0 = (1.5, 2.0, 3.0)  # vx [m/s], vy [m/s], omega [rad/s]
    for j, (q, v) in enumerate(zip((0.0, 10.0, 0.0), v0)):
        pb.resetJointState(bid, j, targetValue=q, targetVelocity=v, physicsClientId=b._cid)
    n = 300
    for _ in range(n):
        b._step(0.0, [])
    st = b._state()[0]
    t = n * b.settings.dt
    assert st[3] == pytest.approx(v0[0], rel=1e-9)
    assert st[4] == pytest.approx(v0[1] - G * t, rel=1e-9)
    assert st[5] == pytest.approx(v0[2], rel=1e-9)
    b._close()


def test_world_frame_point_forces_give_the_wrench_about_the_centre_of_mass(block):
    """In flight (no contact), forces at world points give exactly the linear acceleration
    sum F / m and the angular acceleration sum (r x F) / I about the centre of mass: a pure
    couple, and an off-centre oblique force on a body turned by 0.3 rad."""
    cases = [
        lambda x, y: [PointForce(0, x, y + 1.0, -1e5, 0.0), PointForce(0, x, y - 1.0, 1e5, 0.0)],
        lambda x, y: [PointForce(0, x + 0.3, y + 2.0, 2e5, -1e5)],
    ]
    for make in cases:
        b = _built(block)
        bid, sp, dt = b._bodies[0], b.specs[0], b.settings.dt
        pb.resetJointState(bid, 1, targetValue=20.0, targetVelocity=0.0, physicsClientId=b._cid)
        pb.resetJointState(bid, 2, targetValue=0.3, targetVelocity=0.0, physicsClientId=b._cid)
        s0 = b._state()[0]
        fs = make(s0[0], s0[1])
        b._step(0.0, fs)
        s1 = b._state()[0]
        fx, fy = sum(f.fx for f in fs), sum(f.fy for f in fs)
        m = sum((f.px - s0[0]) * f.fy - (f.py - s0[1]) * f.fx for f in fs)
        assert (s1[3] - s0[3]) / dt == pytest.approx(fx / sp.mass, rel=1e-5, abs=1e-9)
        assert (s1[4] - s0[4]) / dt == pytest.approx(fy / sp.mass - G, rel=1e-5)
        assert (s1[5] - s0[5]) / dt == pytest.approx(m / sp.inertia, rel=1e-9)
        b._close()


def test_point_force_moment_about_the_pivot(block):
    """A horizontal force F at the top centre of the block (world frame) tips it clockwise about
    the bottom-right corner with angular acceleration (2 H F - m g b) / I_O."""
    b = _built(block)
    sp = b.specs[0]
    m, hb, hh = sp.mass, sp.half_width, sp.half_height
    i_o = sp.inertia + m * (hb ** 2 + hh ** 2)
    F = 2.0 * m * G * hb / (2.0 * hh)
    n = 100
    for _ in range(n):
        st = b._state()[0]
        top = (st[0] - math.sin(st[2]) * hh, st[1] + math.cos(st[2]) * hh)
        b._step(0.0, [PointForce(0, top[0], top[1], F, 0.0)])
    w = b._state()[0, 5]
    assert w / (n * b.settings.dt) == pytest.approx(-(2 * hh * F - m * G * hb) / i_o, rel=0.02)
    b._close()


def test_device_scene_runs(rb_scene="paper-asymmetric-hybrid"):
    """Tendon and damper forces come from the shared machinery and are applied every step: a
    hybrid frame under a pulse stays bounded and its tendon forces are reported."""
    sc = rb.load_scene(rb_scene)
    motion = rb.RickerPulse.dimensionless(6.0, 4.0, sc.structure, "symmetric", 1)
    r = rb.run(sc, motion, engine="pybullet", duration=motion.t_end - motion.t_start)
    assert r.ok, r.summary.reason
    assert r.summary.uplifted and r.history["tendon_force_left"].max() > 0.0
    # with the default "distributed" dampers nothing slides (the "couple" dampers slid metres)
    assert r.summary.max_sliding < 2e-3 and r.summary.max_penetration < 2e-3


# --- settings --------------------------------------------------------------------------------
@pytest.mark.parametrize("name,value", [
    ("solver_iterations", 0), ("solver_iterations", 2.5), ("contact_erp", 0.0),
    ("contact_erp", 1.5), ("contact_stiffness", -1.0), ("contact_stiffness", 1e9),
    ("contact_breaking_threshold", 0.0), ("contact_breaking_threshold", 0.1),
    ("friction_anchor", "yes"), ("solver", "pgs"), ("solver", "dantzig"), ("damper", "spring"), ("virtual_mass_ratio", 0.0),
    ("virtual_mass_ratio", 0.01), ("friction", 20.0), ("dt", 0.0), ("friction", -1.0),
])
def test_bad_settings_raise_parameter_error(name, value):
    with pytest.raises(ParameterError) as e:
        PybulletSettings(**{name: value})
    assert e.value.name in (name, "contact_damping")


def test_unknown_setting_is_rejected(block):
    with pytest.raises(ParameterError):
        rb.run(block, engine="pybullet", phi0=0.1, duration=0.1,
               settings=PybulletSettings(), iterations=10)

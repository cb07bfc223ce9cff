"""The pymunk backend: its settings, the world it builds, how it represents the tendons, and
the damper trap (the cross-engine accuracy bars are in test_cross_engine.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.dynamics import Dynamics
from rockbench.engines.bodies import body_specs, foundation_spec, initial_poses
from rockbench.engines.devices import DeviceGeometry
from rockbench.errors import ParameterError

pymunk = pytest.importorskip("pymunk")

from rockbench.engines.pymunk import PymunkBackend, PymunkSettings  # noqa: E402


def test_available_reports_versions():
    ok, version = PymunkBackend.available()
    assert ok and version.startswith(f"pymunk {pymunk.version}") and "Chipmunk" in version


@pytest.mark.parametrize("bad", [dict(iterations=0), dict(iterations=2.5),
                                 dict(collision_slop=-1e-4), dict(collision_slop=0.05),
                                 dict(collision_bias=1.0), dict(collision_bias=-0.1),
                                 dict(damper="dashpot"), dict(friction=0.0), dict(dt=0.02),
                                 dict(output_dt=1e-4)])
def test_bad_settings_raise(bad):
    with pytest.raises(ParameterError) as e:
        PymunkSettings(**bad)
    assert e.value.name == next(iter(bad))


def test_unknown_setting_raises():
    with pytest.raises(ParameterError):
        PymunkBackend(rb.load_scene("housner-block"), slop=1e-3)


def _built(scene, phi0=0.0, **settings):
    b = PymunkBackend(scene, **settings)
    b.specs = body_specs(scene)
    b.foundation = foundation_spec(scene)
    b.poses0 = initial_poses(scene, phi0)
    b._build()
    return b


@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric"])
def test_world_has_the_scene_bodies(name):
    scene = rb.load_scene(name)
    b = _built(scene, phi0=0.03, friction=2.5)
    specs = body_specs(scene)
    assert len(b._bodies) == len(specs)
    for body, sp, pose in zip(b._bodies, specs, b.poses0):
        assert body.mass == pytest.approx(sp.mass, rel=1e-12)
        assert body.moment == pytest.approx(sp.inertia, rel=1e-12)   # beam: m rho^2, not a box
        assert tuple(body.position) == pytest.approx(tuple(pose[:2]), abs=1e-12)
        assert body.angle == pytest.approx(pose[2], abs=1e-15)
    assert b._state()[:, :3] == pytest.approx(b.poses0, abs=1e-12)
    shapes = list(b._space.shapes)
    assert all(s.elasticity == 0.0 for s in shapes)
    # pymunk multiplies the coefficients of a pair: every pair gets the setting's value
    mu = {s.friction for s in shapes}
    assert len(mu) == 1 and mu.pop() ** 2 == pytest.approx(2.5, rel=1e-12)
    n_static = sum(1 for s in shapes if s.body.body_type == pymunk.Body.STATIC)
    assert n_static == (2 if scene.is_frame and scene.structure.step > 0 else 1)
    if scene.is_frame:
        beam = b._bodies[1]
        box = specs[1].mass * (specs[1].half_width ** 2 + specs[1].half_height ** 2) / 3
        assert beam.moment != pytest.approx(box, rel=1e-3)
    assert b._space.iterations == PymunkSettings().iterations
    assert b._space.collision_slop == PymunkSettings().collision_slop


def test_rest_is_at_rest():
    """The frame at rest with its foundation stays at rest (no drift, no creep)."""
    scene = rb.load_scene("paper-asymmetric")
    pulse = rb.RickerPulse.dimensionless(0.5, 4.0, scene.structure)   # below uplift
    r = rb.run(scene, pulse, engine="pymunk", duration=2.0)
    assert r.ok and not r.summary.uplifted and r.summary.n_impacts == 0
    assert r.summary.max_abs_phi < 1e-5
    assert r.summary.max_sliding < 1e-5 and r.summary.max_penetration < 1e-4


# -----------------------------------------------------------------------------------------
def _straight_spring_elongations(scene, phi):
    """Elongations [m] of one straight pymunk DampedSpring per column, from the foundation
    anchor (rest centre of the column's base) to the beam anchor (rest centre of its top),
    for the bodies at the mechanism's pose at phi."""
    specs = body_specs(scene)
    poses = initial_poses(scene, phi)
    space = pymunk.Space()
    beam = pymunk.Body(specs[1].mass, specs[1].inertia)
    beam.position = tuple(poses[1, :2])
    beam.angle = float(poses[1, 2])
    out = []
    for idx in (0, 2):
        sp = specs[idx]
        F = (sp.x, sp.y - sp.half_height)
        T0 = (sp.x, sp.y + sp.half_height)
        spring = pymunk.DampedSpring(space.static_body, beam, F,
                                     (T0[0] - specs[1].x, T0[1] - specs[1].y),
                                     rest_length=math.dist(F, T0),
                                     stiffness=scene.devices.tendon_stiffness, damping=0.0)
        out.append(math.dist(F, beam.local_to_world(spring.anchor_b)) - spring.rest_length)
    return np.array(out)


@pytest.mark.parametrize("name", ["paper-asymmetric-hybrid", "paper-symmetric-hybrid"])
def test_straight_spring_versus_base_plus_top_opening(name):
    """The engine applies the shared point forces, whose elongation is the scene model's base
    opening + top opening (exact). A single straight pymunk spring from the foundation anchor
    to the beam anchor would agree to first order in phi and be shorter at second order: by
    at most 0.38 % of the elongation (0.25 % for the left column) over |phi| <= alpha, both
    directions (measured); its generalized force k e de/dphi smaller by at most 1.3 %."""
    scene = rb.load_scene(name)
    geo = DeviceGeometry(scene, body_specs(scene))
    a = scene.alpha
    worst = 0.0
    for s in (1, -1):
        dyn = Dynamics(scene.structure, s, scene.devices)
        for x in np.linspace(0.02, 1.0, 25):
            phi = s * x * a
            st = np.zeros((3, 6))
            st[:, :3] = initial_poses(scene, phi)
            model = np.array(geo.elongations(st))
            ds = dyn.device_state(dyn.configuration(phi))
            assert model == pytest.approx([ds.elong_left, ds.elong_right], rel=1e-10)
            straight = _straight_spring_elongations(scene, phi)
            rel = straight / model - 1
            assert np.all(rel <= 1e-12), "the straight spring is never longer"
            assert np.all(rel > -0.0045)
            if x <= 0.05:
                assert np.all(np.abs(rel) < 2e-4)         # second order: vanishes with phi
            worst = min(worst, rel.min())
            # generalized force of the tendons, by central differences of 1/2 k e^2
            h = 1e-6 * a
            e_p = _straight_spring_elongations(scene, phi + h)
            e_m = _straight_spring_elongations(scene, phi - h)
            gen_straight = np.sum(e_p ** 2 - e_m ** 2) / (4 * h)
            gen_model = ds.elong_left * ds.delong_left + ds.elong_right * ds.delong_right
            assert -0.014 < gen_straight / gen_model - 1 <= 1e-5
    assert worst < -0.001      # the difference is real at |phi| = alpha (documented value)


def test_heel_dampers_lift_the_columns():
    """Why dampers are 'distributed' by default: the paper's dampers push the closing heel
    with more than the dead load on the pivot, so applied at the heel they open the pivots
    and the frame slides, which the analytic model (pivots always closed) cannot show."""
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    pulse = rb.RickerPulse.dimensionless(7.0, 3.0, scene.structure, "symmetric", 1)
    kw = dict(duration=-pulse.t_start + 1.0)
    heel = rb.run(scene, pulse, engine="pymunk", damper="heel", **kw)
    dist = rb.run(scene, pulse, engine="pymunk", **kw)
    assert heel.summary.contact_opened or heel.summary.max_sliding > 2e-3 or not heel.ok
    assert dist.ok and not dist.summary.contact_opened
    assert dist.summary.max_sliding < 1e-3 and dist.summary.max_penetration < 1e-3

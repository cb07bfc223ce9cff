"""Drake-specific checks: the model it builds (true masses and inertias, planar joints whose
positions are the poses, the corner spheres, the pair's stiffness and friction), the ground
motion as a generalized force, CENIC's internal steps counted as the cost, one discrete update
per dt, fracture, settings validation, and the backend's answer where Drake is absent.
Accuracy against the analytic model at the defaults is the cross-engine suite's job
(tests/engines/test_cross_engine.py); here a discrete solver and one pulse, and, in the slow
tier, every solver on the cross-engine cases."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import cases
import rockbench as rb
from rockbench.constants import G
from rockbench.engines.bodies import body_specs, foundation_spec, initial_poses
from rockbench.errors import ParameterError
from rockbench.scene.scene import Scene
from rockbench.scene.structure import Block

pytest.importorskip("pydrake")
from rockbench.engines.drake import DrakeBackend, DrakeSettings  # noqa: E402


def _built(scene, phi0=0.0, **settings) -> DrakeBackend:
    """A backend with its world built as ``run`` builds it (for stepping by hand)."""
    b = DrakeBackend(scene, **settings)
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


# --- availability and settings ---------------------------------------------------------------
def test_available_reports_the_version():
    ok, version = DrakeBackend.available()
    assert ok and version.startswith("drake 1.")
    assert rb.engines.get_backend("drake") is DrakeBackend


def test_unavailable_without_pydrake(monkeypatch):
    """Where Drake is not installed the backend says so instead of raising."""
    monkeypatch.setitem(sys.modules, "pydrake", None)
    ok, why = DrakeBackend._probe()
    assert not ok and "pydrake does not import" in why


@pytest.mark.parametrize("bad", [dict(solver="tamsi"), dict(contact_model="hydro"),
                                 dict(accuracy=0.0), dict(accuracy=0.5), dict(stiffness=1e3),
                                 dict(dissipation=-1.0), dict(relaxation_time=2.0),
                                 dict(corner_radius=0.1), dict(hydroelastic_modulus=1.0),
                                 dict(damper="dashpot"), dict(dt=0.02), dict(output_dt=1e-4),
                                 dict(friction=0.0), dict(accuracy=float("nan"))])
def test_bad_settings_raise(bad):
    name = next(iter(bad))
    with pytest.raises(ParameterError, match=name):
        DrakeSettings(**bad)


# --- the model ---------------------------------------------------------------------------------
def test_masses_inertias_and_planar_poses_are_the_scenes(frame):
    phi0 = 0.4 * frame.alpha
    b = _built(frame, phi0)
    try:
        plant, ctx = b._plant, b._ctx
        for body, sp in zip(b._bodies, b.specs):
            assert body.get_mass(ctx) == pytest.approx(sp.mass, rel=1e-12)
            izz = body.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia().get_moments()[2]
            assert izz == pytest.approx(sp.inertia, rel=1e-12)
        s = b._state()
        np.testing.assert_allclose(s[:, :3], b.poses0, rtol=0, atol=1e-15)
        assert (s[:, 3:] == 0.0).all()
        # the body's world pose is the joint's (x, y, theta): planar, theta counterclockwise
        for body, pose in zip(b._bodies, b.poses0):
            X = plant.EvalBodyPoseInWorld(ctx, body)
            np.testing.assert_allclose(X.translation(), [pose[0], pose[1], 0.0], atol=1e-12)
            R = X.rotation().matrix()
            assert math.atan2(R[1, 0], R[0, 0]) == pytest.approx(pose[2], abs=1e-12)
    finally:
        b._close()


def test_corner_spheres_are_the_pivots(frame, block):
    """Point contact: spheres at the base corners (and the columns' top corners of a frame),
    the beam a box; nothing else of the bodies collides."""
    from pydrake.geometry import Role
    for scene, expect in ((block, {"block": 2}), (frame, {"left": 4, "beam": 1, "right": 4})):
        b = _built(scene)
        try:
            sg_inspector = b._plant.EvalSceneGraphInspector(b._ctx)
            for body in b._bodies:
                ids = b._plant.GetCollisionGeometriesForBody(body)
                assert len(ids) == expect[body.name()]
                for gid in ids:
                    shape = sg_inspector.GetShape(gid)
                    kind = type(shape).__name__
                    assert kind == ("Box" if body.name() == "beam" else "Sphere")
                    assert sg_inspector.GetProximityProperties(gid) is not None
                    assert sg_inspector.GetProperties(gid, Role.kProximity) is not None
        finally:
            b._close()


def test_static_sink_is_the_pair_stiffness(block):
    """A block at rest on its two corner spheres sinks m g / (2 k): ``stiffness`` is the
    contact pair's, although Drake combines the two geometries' stiffnesses in series."""
    k = 1e8
    for solver in ("similar", "cenic"):
        b = _built(block, solver=solver, stiffness=k)
        try:
            y0 = b._state()[0, 1]
            for _ in range(500):
                b._step(0.0, [])
            s = b._state()
        finally:
            b._close()
        sink = y0 - s[0, 1]
        expect = b.specs[0].mass * G / (2 * k)
        assert sink == pytest.approx(expect, rel=0.01), solver
        assert abs(s[0, 2]) < 1e-9 and abs(s[0, 0]) < 1e-9


def test_pair_friction_is_the_settings_friction():
    """Under a constant horizontal ground acceleration of 0.5 g a squat block (b/h = 1.4: it
    rocks only above 1.4 g) slides if mu < 0.5, with the acceleration (0.5 - mu) g, and sticks if mu > 0.5:
    Drake combines the two geometries' coefficients, each pair gets ``friction``."""
    wide = Scene(name="wide", structure=Block(width=1.4, height=1.0))
    for mu, slides in ((0.4, True), (0.6, False)):
        b = _built(wide, friction=mu)
        try:
            for _ in range(300):
                b._step(-0.5 * G, [])
            vx = b._state()[0, 3]
        finally:
            b._close()
        if slides:
            # sliding: the friction force is mu m g, the block accelerates at (0.5 - mu) g
            assert vx == pytest.approx(-(0.5 - mu) * G * 0.3, rel=0.01)
        else:   # CENIC's regularized friction creeps at 0.15 mm/s here ("similar": 5.6 mm/s)
            assert abs(vx) < 1e-3


def test_ground_motion_is_the_inertia_force(block):
    """gravity_x enters as the force m gravity_x on the body's x dof: a body in free flight
    (above the ground, no contact) gains vx = gravity_x t exactly as under gravity."""
    b = _built(block, solver="similar")
    try:
        # lift it clear of the ground, at rest
        q = b._plant.GetPositions(b._ctx)
        q[1] += 1.0
        b._plant.SetPositions(b._ctx, q)
        for _ in range(100):
            b._step(2.0, [])
        s = b._state()
    finally:
        b._close()
    assert s[0, 3] == pytest.approx(2.0 * 0.1, rel=1e-9)
    assert s[0, 4] == pytest.approx(-G * 0.1, rel=1e-9)
    assert abs(s[0, 5]) < 1e-12


def test_one_discrete_update_per_step(block):
    """The discrete plant advances by exactly one update per ``_step`` (the Simulator's
    boundary times never skip or double an update)."""
    b = _built(block, 0.3 * block.alpha, solver="sap", dt=7e-4)
    try:
        for _ in range(2000):
            b._step(0.0, [])
        assert b._sim.get_num_unrestricted_updates() + b._sim.get_num_discrete_updates() == 2000
    finally:
        b._close()


def test_cenic_counts_its_internal_steps_and_tightens_with_accuracy(block):
    """With CENIC, ``steps`` counts the integrator's steps (the cost), at least one per dt, and
    a tighter accuracy takes more of them."""
    steps = {}
    for acc in (1e-2, 1e-7):
        r = rb.run(block, None, engine="drake", phi0=0.5 * block.alpha, duration=2.0,
                   dt=1e-2, output_dt=1e-2, accuracy=acc)
        assert r.ok, r.summary.reason
        steps[acc] = r.cost.steps
    assert steps[1e-2] >= 200
    assert steps[1e-7] > 2 * steps[1e-2]


def test_the_contact_penetration_is_seen_by_the_shared_probe(block):
    """The corner spheres' rolling must not hide the contact's penetration from the shared
    contact probe: with 1 mm spheres a rocking corner lifted by r (1 - cos phi), more than the
    0.1 um it sank, and a run forced to diverge (max_penetration 1e-12 m, check_backend's
    check) said ok; with the default 10 um it is reported."""
    r = rb.run(block, None, engine="drake", phi0=0.5 * block.alpha, duration=0.5,
               max_penetration=1e-12)
    assert r.status == "diverged" and "penetration" in r.summary.reason
    assert 1e-8 < r.summary.max_penetration < 1e-6     # m g / k = 1.2e-7 m on one corner


# --- accuracy (short runs; the cross-engine suite holds the defaults to every bar) ---------------
def _eta_error(r, scene):
    from rockbench.analytic.reference import reference_of
    ref = reference_of(scene)
    imp = r.impacts()
    assert set(imp.direction) == {1, -1} and imp.eta.notna().all()
    return max(abs(e / ref.eta[int(d)] - 1) for e, d in zip(imp.eta, imp.direction))


@pytest.mark.parametrize("solver", ["cenic", "similar"])
def test_block_free_rocking_eta_within_half_a_percent(block, solver):
    r = rb.run(block, None, engine="drake", phi0=0.5 * block.alpha, duration=3.0, solver=solver)
    assert r.ok, r.summary.reason
    assert _eta_error(r, block) < 0.005


def test_hybrid_frame_pulse_peak_within_3_percent():
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    pulse = rb.RickerPulse.dimensionless(7.0, 3.0, scene.structure, "antisymmetric", 1)
    ref = rb.run(scene, pulse, duration=4.0)
    r = rb.run(scene, pulse, engine="drake", duration=4.0)
    assert r.ok, r.summary.reason
    assert not r.summary.overturned
    peak, peak_ref = r.summary.max_abs_phi, ref.summary.max_abs_phi
    assert abs(peak / peak_ref - 1) < 0.03
    assert r.summary.max_sliding < 2e-3 and r.summary.max_penetration < 2e-3


def test_fracture_at_the_analytic_time_then_no_device_force():
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    pulse = rb.RickerPulse.dimensionless(7.998, 2.0, scene.structure, "symmetric", 1)
    duration = 0.3 - pulse.t_start
    ref = rb.run(scene, pulse, duration=duration)
    r = rb.run(scene, pulse, engine="drake", duration=duration)
    assert r.ok, r.summary.reason
    assert ref.summary.fractured and r.summary.fractured
    assert r.summary.t_fracture == pytest.approx(ref.summary.t_fracture, abs=1.5e-3)
    h = r.history
    assert h.tendon_force_left[h.devices_intact].max() > 0.0
    assert (h[["tendon_force_left", "tendon_force_right", "damper_force_left",
               "damper_force_right"]][~h.devices_intact] == 0.0).all().all()


# --- slow: every solver on the cross-engine cases ----------------------------------------------
@pytest.mark.slow
def test_check_backend_passes():
    from rockbench.testing import check_backend
    assert check_backend("drake").ok


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["similar", "sap", "lagged"])
def test_discrete_solvers_on_the_surviving_pulses(solver):
    """The fixed-step solvers at dt = 1e-3 meet the cross-engine bars on the surviving pulses
    (peaks within 3 %, contacts within 2 mm); CENIC, the default, is the cross-engine suite's."""
    for case in cases.SURVIVE_CASES:
        scene = case.load()
        kw = case.kwargs(scene)
        ref = rb.run(scene, **kw)
        r = rb.run(scene, engine="drake", solver=solver, **kw)
        assert r.ok, (case.id, r.summary.reason)
        err = r.summary.max_abs_phi / ref.summary.max_abs_phi - 1
        assert abs(err) < 0.03, (case.id, err)
        assert r.summary.max_sliding < 2e-3, (case.id, r.summary.max_sliding)


# --- work-precision: CENIC's knob is the accuracy ------------------------------------------------
def test_work_precision_sweeps_cenic_accuracy_beside_a_fixed_step_curve():
    """rockbench.studies.tradeoff sweeps Drake's own knob (DrakeBackend.precision_sweeps): CENIC's
    accuracy at the default dt, and a fixed-step solver over the sweep's time steps; the
    table's curve / knob columns keep them apart, and the figure draws them as two curves."""
    import pandas as pd

    from rockbench.report.tradeoff_figures import plot_work_precision
    from rockbench.studies.tradeoff_tables import curve_of as _curve
    from rockbench.studies.tradeoff import settings_grid

    grid = settings_grid(["drake", "pymunk"], dts=[1e-3, 5e-4])
    drake = [dict(s.overrides) for s in grid if s.engine == "drake"]
    assert [d["accuracy"] for d in drake if "accuracy" in d] == [1e-2, 1e-3, 1e-4, 1e-5, 1e-6,
                                                                 1e-7]
    assert [(d["dt"], d["solver"]) for d in drake if "solver" in d] == [(1e-3, "similar"),
                                                                       (5e-4, "similar")]
    assert [dict(s.overrides) for s in grid if s.engine == "pymunk"] == [{"dt": 1e-3},
                                                                         {"dt": 5e-4}]
    cenic = next(s for s in grid if s.engine == "drake")
    assert dict(cenic.refined().overrides)["accuracy"] == pytest.approx(1e-2 / 4)
    rows = [dict(engine=s.engine, setting=s.label, dt=s.dt, cpu_per_sim_s=0.1 * (i + 1),
                 worst_error=0.05 / (i + 1), **_curve(s.engine, s.label))
            for i, s in enumerate(grid)]
    t = pd.DataFrame(rows)
    assert set(t["curve"]) == {"drake", "drake solver=similar", "pymunk"}
    assert list(t.loc[t["curve"] == "drake", "knob"].unique()) == ["accuracy"]
    fig = plot_work_precision(t, errors=("worst_error",))
    labels = [ln.get_label() for ln in fig.axes[0].get_lines()]
    assert {"drake", "drake solver=similar", "pymunk"} <= set(labels)


def test_a_beam_flush_with_the_columns_rocks():
    """beam_width = span + column_width (the smallest the scene allows) puts the columns' top
    corners at the beam's very edge, where Drake resolved the contact poorly (0.13 m of
    penetration, diverged): the beam's contact box overhangs by a margin."""
    import rockbench as rb

    sc = rb.Scene(rb.Frame(column_width=1.0, column_height_left=4.0, column_height_right=2.4,
                           span=6.0, beam_width=7.0, beam_height=0.8), name="flush-beam")
    r = rb.run(sc, None, engine="drake", phi0=0.5 * sc.alpha, duration=2.0)
    assert r.ok, r.summary.reason
    assert r.summary.max_penetration < 1e-3

"""Every engine builds the scene's friction and moves its ground vertically.

* **Friction.** A scene's ``[contact] friction`` is the coefficient every base contact pair gets
  (the engines combine two bodies' coefficients differently: products, harmonic means, explicit
  pairs), ``beam_friction`` the beam on its columns; an engine ``friction`` setting on top of
  it is refused. With a scene friction, sliding is the physics modelled: the run is not marked
  for it and ``Summary.max_sliding`` reports it.
* **Newmark's sliding block** (``rockbench.analytic.sliding``, exact) is the reference for a squat
  block whose friction is below its slenderness (b/h = 1 here, mu = 0.2 .. 0.8): it slides and
  does not rock. Each engine's permanent slip and peak slip are within 5 % of it, under a Ricker
  pulse (fast) and under two records (slow). Well-conditioned measures only: the peak slip
  always; the final slip where it is not the small difference of long excursions back and
  forth (El Centro's final 4.5 mm is the net of a 252 mm slip path: peak only).
* **Vertical ground motion** enters every engine as the foundation's vertical inertial force:
  a block under vertical motion alone stays at rest; a ground that falls faster than g throws
  the block into free flight whose height above the ground is the double integral of
  -(g + a_v); and the slip under horizontal + vertical motion is Newmark's with the normal
  force m (g + a_v).

The engines' settings for sliding (:data:`SLIDING`) are measured (``docs/engines/README.md``):
MuJoCo's default contact impedance 0.99 regularizes friction enough that a block on mu = 0.8
(b/h = 1) tips and slips 23 % short of Newmark; at 0.999 it is within 0.4 %.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.sliding import sliding_response
from rockbench.constants import G
from rockbench.engines import get_backend
from rockbench.engines.base import resolve_friction, run_window
from rockbench.engines.bodies import body_specs, foundation_spec, initial_poses
from rockbench.engines.contacts import body_frictions
from rockbench.engines.loop import step_run
from rockbench.scene.contact import Contact
from rockbench.scene.motion import Record, RickerPulse, WithVertical
from rockbench.testing import engine_params, needs_engine

ENGINES = engine_params()
RECORDS = __import__("pathlib").Path(__file__).resolve().parents[3] / "shared" / "records"
needs_records = pytest.mark.skipif(not RECORDS.is_dir(), reason=f"no records at {RECORDS}")

#: Engine settings for sliding runs (module docstring); every other setting is the default.
SLIDING = {"mujoco": {"impedance": 0.999}}



def _still(t0: float, t1: float) -> Record:
    """No horizontal ground motion from t0 to t1 [s]."""
    return Record([t0, t1], [0.0, 0.0], name="still")


def _squat(mu: float) -> rb.Scene:
    """b/h = 1 (alpha = 45 deg): it slides and never rocks for mu < 1."""
    return rb.Scene(rb.Block(width=1.0, height=1.0), contact=Contact(friction=mu))


def _stepped(scene, motion, engine: str, duration=None, **settings):
    """The engine's body states on the output grid (the run's Stepped): the block's x and y
    relative to its rest pose are its slip and lift relative to the (moving) ground."""
    b = get_backend(engine)(scene, **settings)
    t0, t1 = run_window(scene, motion, duration, 0.0, settings=b.settings)
    b.specs, b.foundation = body_specs(scene), foundation_spec(scene)
    b.poses0 = initial_poses(scene, 0.0)
    st = step_run(b, motion, t0, t1, 0.0)
    assert st.status == "ok", st.reason
    return st, b.specs


def _slip(scene, motion, engine, duration=None):
    st, specs = _stepped(scene, motion, engine, duration, **SLIDING.get(engine, {}))
    return st.grid[:len(st.states)], st.states[:, 0, 0] - specs[0].x


def _pulse_run(mu, motion, engine):
    """(scene, Newmark's sliding block under ``motion`` and its own vertical part, the run)."""
    scene = _squat(mu)
    ref = sliding_response(motion, mu).summary
    duration = motion.t_end - motion.t_start + 0.5
    r = rb.run(scene, motion, engine=engine, duration=duration, **SLIDING.get(engine, {}))
    return scene, ref, r


# --- friction: the scene's, for every pair --------------------------------------------------
def test_scene_friction_replaces_the_engine_default_and_a_setting_on_top_is_refused():
    from rockbench.engines.pymunk import PymunkSettings

    plain, rough = rb.load_scene("housner-block"), _squat(0.3)
    cfg = PymunkSettings()
    assert resolve_friction(plain, cfg) is cfg                       # no friction given
    assert resolve_friction(rough, cfg).friction == 0.3
    assert resolve_friction(rough, PymunkSettings(friction=0.3)).friction == 0.3
    with pytest.raises(rb.ParameterError, match="friction is the scene's"):
        resolve_friction(rough, cfg, {"friction": 0.3})
    with pytest.raises(rb.ParameterError, match=r"friction.*scene's \[contact\] friction"):
        resolve_friction(rough, PymunkSettings(friction=0.7))
    for name in ("pymunk", "mujoco", "pybullet", "opensees", "drake"):
        with pytest.raises(rb.ParameterError) as e:
            get_backend(name)(rough, friction=0.9)
        assert e.value.name == "friction"
        assert get_backend(name)(rough).settings.friction == 0.3
        assert get_backend(name)(plain).settings.friction == get_backend(name).Settings().friction


@pytest.mark.parametrize("base, beam", [(0.3, 0.3), (0.2, 0.9), (0.9, 0.2), (1e-3, 10.0),
                                        (10.0, 0.05)])
def test_body_coefficients_give_every_pair_exactly_its_friction(base, beam):
    g, c, b = body_frictions(base, beam, "product")
    assert g * c == pytest.approx(base, rel=1e-14) and c * b == pytest.approx(beam, rel=1e-14)
    g, c, b = body_frictions(base, beam, "harmonic")
    assert min(g, c, b) > 0
    assert 2 * g * c / (g + c) == pytest.approx(base, rel=1e-13)
    assert 2 * c * b / (c + b) == pytest.approx(beam, rel=1e-13)
    if base == beam:
        assert body_frictions(base, beam, "harmonic") == (base, base, base)
        assert body_frictions(base, beam, "product") == (math.sqrt(base),) * 3


FRAME = rb.load_scene("paper-asymmetric").replace(contact=Contact(friction=0.4,
                                                                  beam_friction=0.7))


@needs_engine("pymunk")
def test_pymunk_pairs_get_the_scene_friction():
    b = get_backend("pymunk")(FRAME)
    b.build()
    space = b._space
    ground = [s for s in space.shapes if s.body is space.static_body]
    cols = [s for s in space.shapes if s.body in (b._bodies[0], b._bodies[2])]
    beam = [s for s in space.shapes if s.body is b._bodies[1]]
    assert {round(g.friction * c.friction, 12) for g in ground for c in cols} == {0.4}
    assert {round(c.friction * s.friction, 12) for c in cols for s in beam} == {0.7}


@needs_engine("pybullet")
def test_pybullet_pairs_get_the_scene_friction():
    b = get_backend("pybullet")(FRAME)
    b.build()
    try:
        pb, cid = b._pb, b._cid
        mu = lambda bid, link: pb.getDynamicsInfo(bid, link, physicsClientId=cid)[1]  # noqa
        ground = {mu(s, -1) for s in b._static}
        left, beam, right = (mu(bid, 2) for bid in b._bodies)
        assert {round(g * c, 12) for g in ground for c in (left, right)} == {0.4}
        assert {round(beam * c, 12) for c in (left, right)} == {0.7}
        assert b._anchor is False        # no friction anchor dragging a slid base back
    finally:
        b._close()


@needs_engine("mujoco")
def test_mujoco_pairs_get_the_scene_friction():
    b = get_backend("mujoco")(FRAME)
    m = b.compile()
    import mujoco

    name = lambda i: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, i)  # noqa: E731
    got = {frozenset((name(m.pair_geom1[k]), name(m.pair_geom2[k]))):
           tuple(float(x) for x in m.pair_friction[k][:2]) for k in range(m.npair)}
    assert got == {frozenset(("left", "ground")): (0.4, 0.4),
                   frozenset(("right", "step")): (0.4, 0.4),
                   frozenset(("left", "beam")): (0.7, 0.7),
                   frozenset(("right", "beam")): (0.7, 0.7)}


@needs_engine("drake")
def test_drake_pairs_get_the_scene_friction():
    b = get_backend("drake")(FRAME)
    b.build()
    insp = b._diagram.GetSubsystemByName("scene_graph").model_inspector()
    plant = b._plant
    mu = {}
    for body in [plant.world_body()] + b._bodies:
        for gid in plant.GetCollisionGeometriesForBody(body):
            props = insp.GetProximityProperties(gid)
            mu[insp.GetName(gid)] = props.GetProperty("material",
                                                      "coulomb_friction").static_friction()
    pair = lambda a, c: 2 * a * c / (a + c)  # noqa: E731 - Drake's combination
    ground = [v for k, v in mu.items() if k.startswith("foundation")]
    bases = [v for k, v in mu.items() if "_base_" in k]
    tops = [v for k, v in mu.items() if "_top_" in k]
    assert len(ground) == 2 and len(bases) == len(tops) == 4
    assert {round(pair(g, c), 12) for g in ground for c in bases} == {0.4}
    assert {round(pair(mu["beam_box"], c), 12) for c in tops} == {0.7}


# --- sliding is physics with a scene friction -----------------------------------------------
@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_without_a_scene_friction_is_still_a_divergence(engine):
    """The same squat block and pulse with the friction as an engine setting (no scene
    friction): sliding beyond max_sliding marks the run, as before. (OpenSees needs its
    sliding tolerance to slide at all: at its rocking default, 1e-8 m, the block sticks.)"""
    from rockbench.engines.opensees import SLIDING_TOLERANCE

    scene = rb.Scene(rb.Block(width=1.0, height=1.0))
    pulse = RickerPulse(1.0 * G, 0.5)
    settings = {**SLIDING, "opensees": {"tolerance": SLIDING_TOLERANCE}}.get(engine, {})
    r = rb.run(scene, pulse, engine=engine, duration=3.5, friction=0.5, **settings)
    assert r.summary.status == "diverged" and "max_sliding" in r.summary.reason


@pytest.mark.parametrize("mu", [0.2, 0.5, 0.8])
@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_block_under_a_pulse_matches_newmark(engine, mu):
    """Ricker pulse of 2 mu g: the block slides 23 mm (mu 0.2) to 92 mm (mu 0.8), more than
    max_sliding at mu >= 0.5; the run is ok, and both the peak slip (Summary.max_sliding) and
    the permanent slip (the history's last slip) are within 5 % of Newmark."""
    pulse = RickerPulse(2.0 * mu * G, 0.5)
    scene, ref, r = _pulse_run(mu, pulse, engine)
    assert r.summary.status == "ok", r.summary.reason
    assert ref.max_abs_displacement > 0.02 and ref.slip_episodes == 1
    assert r.summary.max_sliding == pytest.approx(ref.max_abs_displacement, rel=0.05)
    assert r.history["sliding"].iloc[-1] == pytest.approx(abs(ref.final_displacement), rel=0.05)
    assert r.summary.max_abs_phi < r.settings["uplift_tol"] * scene.alpha * 10   # no rocking


def _record(name: str, t0: float, t1: float, scale: float) -> Record:
    from rockbench.scene.records import load_at2

    rec = load_at2(RECORDS / name)
    t = np.asarray(rec.time)
    keep = (t >= t0) & (t <= t1)
    return Record(t[keep], scale * np.asarray(rec.acceleration(t[keep])), name=name)


@pytest.mark.slow
@needs_records
@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_block_under_records_matches_newmark(engine):
    """Chi-Chi TCU052-N (25-40 s: its near-fault pulse), mu = 0.2: out 212 mm and back to a
    38 mm permanent slip (peak and final checked); El Centro 1940 x 2, mu = 0.2: 33 slip
    episodes, peak 37 mm (the final 4.5 mm is the net of a 252 mm path: not checked)."""
    mu = 0.2
    for rec, final in ((_record("ChiChi1999_TCU052-N.AT2", 25.0, 40.0, 1.0), True),
                       (_record("IV1940_ElCentro_180.AT2", 0.0, 15.0, 2.0), False)):
        ref = sliding_response(rec, mu).summary
        _, u = _slip(_squat(mu), rec, engine)
        assert np.abs(u).max() == pytest.approx(ref.max_abs_displacement, rel=0.05), rec.name
        if final:
            assert ref.slip_path < 12 * abs(ref.final_displacement)     # conditioned
            assert u[-1] == pytest.approx(ref.final_displacement, rel=0.05), rec.name


# --- vertical ground motion ------------------------------------------------------------------
@pytest.mark.parametrize("friction", [None, 0.5])
@pytest.mark.parametrize("engine", ENGINES)
def test_vertical_motion_alone_leaves_a_block_at_rest(engine, friction):
    """A Ricker pulse of 0.6 g up and down (g + a_v stays > 0): no rotation, no slip, every
    engine; with or without a scene friction."""
    scene = rb.Scene(rb.Block(width=1.0, height=2.0), contact=Contact(friction=friction))
    v = RickerPulse(0.6 * G, 0.3)
    motion = WithVertical(_still(v.t_start, v.t_end), v)
    r = rb.run(scene, motion, engine=engine, duration=v.t_end - v.t_start + 1.0)
    assert r.summary.status == "ok", r.summary.reason
    assert r.summary.max_abs_phi < r.settings["uplift_tol"] * scene.alpha
    assert not r.summary.uplifted and r.summary.max_sliding < 1e-5


def _free_flight(av_times, av_values, t):
    """Height [m] above the ground of a body resting on it when the ground accelerates up at
    a_v (piecewise linear through the given points), at times ``t``: 0 until g + a_v < 0,
    then y'' = -(g + a_v) while y > 0 (fine quadrature)."""
    tt = np.linspace(t[0], t[-1], 400001)
    acc = -(G + np.interp(tt, av_times, av_values, left=0.0, right=0.0))
    y = np.zeros_like(tt)
    v = 0.0
    for k in range(1, tt.size):
        h = tt[k] - tt[k - 1]
        a = 0.5 * (acc[k] + acc[k - 1])
        if y[k - 1] <= 0.0 and v <= 0.0 and a <= 0.0:
            v, y[k] = 0.0, 0.0          # resting on the ground
            continue
        y[k] = y[k - 1] + v * h + 0.5 * a * h * h
        v += a * h
        if y[k] < 0.0:                  # landed
            y[k], v = 0.0, 0.0
    return np.interp(t, tt, y)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_ground_falling_faster_than_g_throws_the_block(engine):
    """The ground accelerates down at 2 g for 40 ms: the block leaves it when a_v < -g and its
    height above the ground follows the double integral of -(g + a_v) (peak 15.5 mm at
    0.083 s): the engine moves its ground vertically, with the right sign and size."""
    times = [0.0, 0.005, 0.045, 0.05]
    values = [0.0, -2.0 * G, -2.0 * G, 0.0]
    v = Record(times, values, name="drop")
    motion = WithVertical(_still(0.0, 0.05), v)
    scene = rb.Scene(rb.Block(width=1.0, height=2.0))
    st, specs = _stepped(scene, motion, engine, duration=0.3)
    t = st.grid[:len(st.states)]
    y = st.states[:, 0, 1] - specs[0].y
    ref = _free_flight(times, values, t)
    k = int(np.argmax(ref))
    assert ref[k] > 0.01
    assert y.max() == pytest.approx(ref[k], rel=0.05)
    assert abs(t[int(np.argmax(y))] - t[k]) < 0.005
    flying = ref > 0.2 * ref[k]
    assert np.abs(y[flying] - ref[flying]).max() < 0.05 * ref[k]


@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_under_horizontal_and_vertical_motion_matches_newmark(engine):
    """Horizontal Ricker pulse 2 mu g with a vertical one of half its amplitude, in phase
    (mu = 0.3): the normal force m (g + a_v) sets the friction; the engine's slip is within 5 %
    of Newmark's with the vertical motion, which differs from Newmark's without it by more."""
    mu = 0.3
    h = RickerPulse(2.0 * mu * G, 0.5)
    v = RickerPulse(1.0 * mu * G, 0.5)
    _, ref, r = _pulse_run(mu, WithVertical(h, v), engine)
    flat = sliding_response(h, mu).summary
    assert abs(flat.max_abs_displacement / ref.max_abs_displacement - 1) > 0.15   # it matters
    assert r.summary.status == "ok", r.summary.reason
    assert r.summary.max_sliding == pytest.approx(ref.max_abs_displacement, rel=0.05)
    assert r.history["sliding"].iloc[-1] == pytest.approx(abs(ref.final_displacement), rel=0.05)


@needs_engine("mujoco")
def test_mujoco_batched_path_moves_the_ground_vertically_as_the_plain_one():
    from rockbench.engines.mujoco_batch import run_batch

    scene = _squat(0.3)
    h, v = RickerPulse(0.6 * G, 0.5), RickerPulse(0.3 * G, 0.5)
    motion = WithVertical(h, v)
    (b,) = run_batch(scene, [motion], duration=3.5, nthread=1, **SLIDING["mujoco"])
    p = rb.run(scene, motion, engine="mujoco", duration=3.5, **SLIDING["mujoco"])
    flat = rb.run(scene, h, engine="mujoco", duration=3.5, **SLIDING["mujoco"])
    assert b.summary.max_sliding == pytest.approx(p.summary.max_sliding, rel=1e-6)
    assert abs(flat.summary.max_sliding / p.summary.max_sliding - 1) > 0.1


def test_a_backend_without_vertical_motion_refuses_it_in_one_line():
    from rockbench.engines.base import check_vertical

    class Flat:
        name, vertical_motion = "flat", False

    v = RickerPulse(0.3 * G, 0.5)
    with pytest.raises(rb.ParameterError, match="flat cannot move its ground vertically"):
        check_vertical(Flat, WithVertical(_still(v.t_start, v.t_end), v))
    check_vertical(Flat, v)                                    # horizontal only: fine
    for name in ("pymunk", "mujoco", "pybullet", "opensees", "drake"):
        assert get_backend(name).vertical_motion


def test_the_engines_page_states_each_default_friction():
    """docs/engines/README.md's table of the friction each engine uses when the scene gives
    none equals the engines' Settings."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "engines" /
            "README.md").read_text(encoding="utf-8")
    labels = {"pymunk": "pymunk", "mujoco": "MuJoCo", "pybullet": "PyBullet",
              "opensees": "OpenSees", "drake": "Drake"}
    for name, label in labels.items():
        assert f"| {label} | {get_backend(name).Settings().friction!r} |" in page, name

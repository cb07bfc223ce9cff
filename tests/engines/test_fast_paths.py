"""Fast paths against the plain paths they replace (MuJoCo's ``rollout_test.py`` habit):

* ``ContactProbe.measure_many`` (vectorized over samples) against a per-sample loop of
  ``ContactProbe.measure``;
* the analytic backend's ``history="minimal"`` against ``history="full"`` on the columns both
  fill.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockbench as rb
from rockbench.testing import needs_engine
from rockbench.engines.bodies import body_specs
from rockbench.engines.contacts import ContactProbe

MINIMAL_COLUMNS = ["t", "phi", "phidot", "ground_acc", "mode", "devices_intact"]


@needs_engine("pymunk")
@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric"])
def test_measure_many_equals_a_per_sample_loop(name):
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1)
    r = rb.run(scene, pulse, engine="pymunk", duration=pulse.t_end - pulse.t_start)
    h = r.history
    specs = body_specs(scene)
    n = len(h)
    # body states rebuilt from a real engine run: perturb the rest poses by the history so
    # that corners penetrate, slide and open
    rng = np.random.default_rng(3)
    states = np.zeros((n, len(specs), 6))
    for i, sp in enumerate(specs):
        states[:, i, 0] = sp.x + rng.normal(0, 2e-3, n)
        states[:, i, 1] = sp.y + rng.normal(0, 2e-3, n)
        states[:, i, 2] = h["phi"].to_numpy() * (1.0 + 0.1 * i)
    modes = h["mode"].to_numpy()
    probe = ContactProbe(scene, specs)
    pen, sl, op = probe.measure_many(states, modes)
    loop = [probe.measure(states[k], int(modes[k])) for k in range(n)]
    assert np.array_equal(pen, [x[0] for x in loop])
    assert np.array_equal(sl, [x[1] for x in loop])
    assert np.array_equal(op, [x[2] for x in loop])
    assert pen.max() > 0 and sl.max() > 0 and op.any()     # the check is not vacuous


@pytest.mark.parametrize("name, A, W, shape, sign", [
    ("paper-asymmetric", 3.0, 4.0, "antisymmetric", -1),
    ("paper-asymmetric-hybrid-eps1", 9.0, 3.0, "symmetric", 1),
    ("paper-asymmetric-hybrid-eps1", 10.0, 3.0, "symmetric", 1),    # fractures, overturns
    ("housner-block", 2.5, 3.0, "symmetric", 1),
])
def test_minimal_history_equals_full_history_on_shared_columns(name, A, W, shape, sign):
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(A, W, scene.structure, shape, sign)
    full = rb.run(scene, pulse, history="full")
    mini = rb.run(scene, pulse, history="minimal")
    for c in MINIMAL_COLUMNS:
        assert np.array_equal(full.history[c].to_numpy(), mini.history[c].to_numpy()), c
    assert full.summary.to_dict() == mini.summary.to_dict()
    assert full.history["phi"].abs().max() > 0.1 * scene.alpha


# --- pymunk and MuJoCo: the compiled stepping loop against the Python loop ----------------
_LOOP_CASES = [
    ("housner-block", dict(A=3.0, W=4.0, shape="symmetric", sign=1)),
    ("paper-asymmetric", dict(A=2.0, W=3.0, shape="symmetric", sign=1)),
    ("paper-asymmetric", dict(A=5.0, W=3.0, shape="antisymmetric", sign=-1)),   # overturns
    ("paper-asymmetric", None),                                                  # free rocking
    ("paper-asymmetric-hybrid", dict(A=4.0, W=3.0, shape="symmetric", sign=1)),
    ("paper-asymmetric-hybrid-eps1", dict(A=3.0, W=2.0, shape="symmetric", sign=-1)),
]


@pytest.mark.parametrize("engine", ["pymunk", "mujoco"])
@pytest.mark.parametrize("name, pulse", _LOOP_CASES)
def test_compiled_loop_equals_the_python_loop(engine, name, pulse):
    """Bit for bit without devices; with devices to 1e-8 (rad, m, N relative): the tendon
    lengths come from the C library's hypot, one ulp from CPython's in 0.5 % of calls
    (rockbench.engines.device_kernel)."""
    from rockbench.engines import chipmunk
    from rockbench.engines import mujoco as mj

    if engine not in rb.available_backends():
        pytest.skip(f"{engine} is not installed")
    ok, why = chipmunk.available() if engine == "pymunk" else mj.compiled_available()
    assert ok, why                       # the platforms CI runs on are all enabled
    scene = rb.load_scene(name)
    if pulse is None:
        motion, kw = None, dict(phi0=0.5 * scene.alpha, duration=6.0)
    else:
        motion = rb.RickerPulse.dimensionless(pulse["A"], pulse["W"], scene.structure,
                                              pulse["shape"], pulse["sign"])
        kw = {}
    plain = rb.run(scene, motion, engine=engine, loop="python", **kw)
    fast = rb.run(scene, motion, engine=engine, **kw)
    assert fast.cost.steps == plain.cost.steps
    for col in ("status", "overturned", "fractured", "n_impacts", "exceeded_critical"):
        assert getattr(fast.summary, col) == getattr(plain.summary, col), col
    a, b = plain.history.to_numpy(float), fast.history.to_numpy(float)
    assert a.shape == b.shape
    if not scene.has_devices:
        assert np.array_equal(a, b, equal_nan=True)
        assert plain.events.equals(fast.events)
    else:
        scale = np.maximum(np.nanmax(np.abs(a), axis=0), 1e-12)
        assert np.nanmax(np.abs(a - b) / scale) < 1e-8


@pytest.mark.parametrize("engine, settings", [
    ("pymunk", dict(damper="couple")), ("pymunk", dict(damper="heel")),
    ("mujoco", dict(devices="forces")), ("mujoco", dict(damper="heel")),
    ("mujoco", dict(devices="forces", damper="heel"))])
def test_compiled_loop_equals_the_python_loop_for_every_device_model(engine, settings):
    """The damper models and MuJoCo's shared-force devices, including runs that fracture and
    then diverge (the heel damper lifts the columns: docs/engines/pymunk.md)."""
    if engine not in rb.available_backends():
        pytest.skip(f"{engine} is not installed")
    scene = rb.load_scene("paper-asymmetric-hybrid-eps1")
    motion = rb.RickerPulse.dimensionless(4.0, 3.0, scene.structure, "antisymmetric", -1)
    plain = rb.run(scene, motion, engine=engine, loop="python", **settings)
    fast = rb.run(scene, motion, engine=engine, **settings)
    assert (fast.cost.steps, fast.summary.status, fast.summary.fractured,
            fast.summary.overturned) == (plain.cost.steps, plain.summary.status,
                                         plain.summary.fractured, plain.summary.overturned)
    a, b = plain.history.to_numpy(float), fast.history.to_numpy(float)
    assert a.shape == b.shape
    scale = np.maximum(np.nanmax(np.abs(a), axis=0), 1e-12)
    assert np.nanmax(np.abs(a - b) / scale) < 1e-8


@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric"])
def test_compiled_probe_equals_the_numpy_probe_bit_for_bit(name):
    """``measure_many`` (compiled, what every engine run probes each sample with) against
    ``measure_numpy``: the same arrays bit for bit, on poses that penetrate, slide, open, in
    every mode, and with non-finite states (NaN propagates as in numpy)."""
    scene = rb.load_scene(name)
    specs = body_specs(scene)
    probe = ContactProbe(scene, specs)
    rng = np.random.default_rng(11)
    n = 3000
    states = np.zeros((n, len(specs), 6))
    for i, sp in enumerate(specs):
        states[:, i, 0] = sp.x + rng.normal(0, 2e-3, n)
        states[:, i, 1] = sp.y + rng.normal(0, 2e-3, n)
        states[:, i, 2] = rng.normal(0, 0.05, n)
    states[7, 0, 2] = np.nan
    states[9, -1, 1] = np.inf
    modes = rng.integers(-1, 2, n)
    fast, ref = probe.measure_many(states, modes), probe.measure_numpy(states, modes)
    for a, b in zip(fast, ref):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    assert fast[2].any() and (fast[0] > 0).any() and (fast[1] > 0).any()

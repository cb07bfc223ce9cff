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
from rockbench.engines.bodies import body_specs
from rockbench.engines.contacts import ContactProbe

MINIMAL_COLUMNS = ["t", "phi", "phidot", "ground_acc", "mode", "devices_intact"]


@pytest.mark.parametrize("name", ["housner-block", "paper-asymmetric"])
def test_measure_many_equals_a_per_sample_loop(name):
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1)
    if "pymunk" not in rb.available_backends():
        pytest.skip("pymunk is not installed")
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

"""The analytic model's validity against what the engines do (docs/sliding.md, section 4).

* **Sliding onset.** The analytic run's ``sliding_onset`` (the first time the base needs more
  friction than the scene gives) is where every engine starts to slide: its slip history's
  onset (:func:`rockbench.measure.slip_onset`, a cubic start fitted back to zero) lies within
  one output step plus the engine's own time step of it (an engine resolves an event to its
  step), on blocks the paper never names: squat and stocky, friction 0.2 to 0.8.
* **Vertical ground motion, inside the model.** Where the model holds (a slender block, scene
  friction 0.6, no sliding onset, contact kept), every engine's peak rotation under a pulse
  with a vertical part (ratio 0, 0.35, 0.7: the model's g -> g + a_v) is within 3 % of the
  analytic model's.
"""

from __future__ import annotations

import numpy as np
import pytest

import rockbench as rb
from rockbench.constants import G
from rockbench.measure import slip_onset
from rockbench.scene.contact import Contact
from rockbench.testing import engine_params

ENGINES = engine_params()

#: MuJoCo's contact impedance for sliding runs (tests/engines/test_contact_physics.py).
SLIDING = {"mujoco": {"impedance": 0.999}}


def test_slip_onset_recovers_a_cubic_start_and_ignores_creep():
    t = np.linspace(0.0, 0.1, 101)
    t0 = 0.0423
    slip = 50.0 * np.clip(t - t0, 0.0, None) ** 3 + 2e-6 * t      # creep below lo
    assert slip_onset(t, slip) == pytest.approx(t0, abs=2e-4)
    assert np.isnan(slip_onset(t, np.zeros_like(t)))
    with pytest.raises(rb.ParameterError, match="lo"):
        slip_onset(t, slip, lo=1e-3, hi=1e-4)


@pytest.mark.parametrize("mu, width", [(0.2, 0.5), (0.5, 1.0), (0.8, 1.2)])
@pytest.mark.parametrize("engine", ENGINES)
def test_engines_start_sliding_where_the_model_says_its_base_slides(engine, mu, width):
    scene = rb.Scene(rb.Block(width=width, height=1.0), contact=Contact(friction=mu))
    pulse = rb.RickerPulse(2.0 * mu * G, 0.5)
    ref = rb.run(scene, pulse).summary
    assert ref.sliding_contact == "base" and ref.validity.startswith("outside")
    r = rb.run(scene, pulse, engine=engine, **SLIDING.get(engine, {}))
    assert r.summary.status == "ok", r.summary.reason
    t = r.history["t"].to_numpy()
    out = float(np.median(np.diff(t)))
    step = float(r.settings.get("dt") or out)
    t_engine = slip_onset(t, r.history["sliding"].to_numpy())
    assert abs(t_engine - ref.sliding_onset) <= out + step, (t_engine, ref.sliding_onset)


@pytest.mark.parametrize("ratio", [0.0, 0.35, 0.7])
@pytest.mark.parametrize("engine", ENGINES)
def test_engines_match_the_vertical_motion_model_where_it_holds(engine, ratio):
    scene = rb.Scene(rb.Block(width=0.5, height=2.5), contact=Contact(friction=0.6))
    pulse = rb.RickerPulse.dimensionless(A=2.0, W=4.0, structure=scene.structure,
                                         vertical_ratio=ratio)
    duration = pulse.t_end - pulse.t_start + 2.0
    ref = rb.run(scene, pulse, duration=duration).summary
    assert ref.validity == "inside" and not ref.overturned
    r = rb.run(scene, pulse, engine=engine, duration=duration).summary
    assert r.status == "ok", r.reason
    assert r.max_abs_phi == pytest.approx(ref.max_abs_phi, rel=0.03)

"""The vectorized mechanism and device state (used to build analytic histories) against the
scalar kinematics they replace, on the paper's frames, both directions, over the whole range."""

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic.reference import reference_of


@pytest.mark.parametrize("name", ["paper-asymmetric-hybrid", "paper-symmetric-hybrid"])
@pytest.mark.parametrize("s", [1, -1])
def test_vectorized_equals_scalar(name, s):
    scene = rb.load_scene(name)
    dyn = reference_of(scene).dyn[s]
    phi = s * np.linspace(0.0, 0.97 * scene.fall_angles[s], 301)
    th_b, th_r, dth_b, dth_r = dyn.mechanism.angles_many(phi)
    el, er, dcl, dcr = dyn.device_state_many(phi)
    for i in range(0, phi.size, 7):
        cfg = dyn.configuration(float(phi[i]))
        ds = dyn.device_state(cfg)
        assert th_b[i] == pytest.approx(cfg.bodies[1].theta, abs=1e-13)
        assert th_r[i] == pytest.approx(cfg.bodies[2].theta, abs=1e-13)
        assert dth_b[i] == pytest.approx(cfg.bodies[1].dtheta, abs=1e-11)
        assert dth_r[i] == pytest.approx(cfg.bodies[2].dtheta, abs=1e-11)
        assert (el[i], er[i]) == pytest.approx((ds.elong_left, ds.elong_right), abs=1e-13)
        assert (dcl[i], dcr[i]) == pytest.approx((ds.dchord_left, ds.dchord_right), abs=1e-12)

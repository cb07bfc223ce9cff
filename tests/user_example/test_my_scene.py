"""A user's own scene checked across every available engine (shown in docs/testing.md)."""
import rockbench as rb
from rockbench.testing import assert_agree

scene = rb.Scene(rb.Block(width=1.0, height=4.0), name="my-block")
pulse = rb.RickerPulse.dimensionless(A=2.0, W=3.0, structure=scene.structure)


def test_engine_agrees_with_theory(rockbench_backend, rockbench_reference):
    reference = rockbench_reference(scene, pulse, duration=5.0)
    result = rb.run(scene, pulse, engine=rockbench_backend, duration=5.0)
    assert_agree(result, reference, eta_rtol=0.01)  # forced rocking: 1 %

"""Contacts that slide while a structure falls do not turn an overturn into a 'diverged' run.

Past its critical angle a frame is falling: engines let the falling bodies slide a few
centimetres before the fall angle is reached. That is not a numerical failure, and the verdict
(overturned) is what the comparison needs. Before the fix, every engine reported these runs as
'diverged' (sliding > max_sliding) and no overturning verdict was recorded.
"""

import pytest

import rockbench as rb


@pytest.mark.parametrize("engine", [e for e in rb.available_backends() if e != "analytic"])
def test_overturn_with_sliding_while_falling_is_an_overturn(engine):
    scene = rb.load_scene("paper-symmetric")
    pulse = rb.RickerPulse.dimensionless(4.0, 4.0, scene.structure, "symmetric", 1)
    assert rb.run(scene, pulse).summary.overturned
    r = rb.run(scene, pulse, engine=engine, max_sliding=0.02)
    assert r.summary.status == "ok", r.summary.reason
    assert r.summary.overturned
    assert r.summary.max_sliding > 0.02          # it did slide while falling, and says so

"""Runs that finish without an engine failure but cannot be read as rocking are not "ok"
(issue 13; rockbench.engines.loop.finish)."""

import rockbench as rb

BLOCK = rb.load_scene("housner-block")


def _pulse(scene, A=2.5, W=3.0):
    return rb.RickerPulse.dimensionless(A, W, scene.structure, "symmetric", 1)


def test_unmeasurable_impacts_make_a_run_invalid(monkeypatch):
    """A run whose impacts' eta cannot be measured is not ok (before the check such a run said
    ok with every eta NaN). Forced here by an estimator that measures nothing."""
    import rockbench.engines.loop as loop

    p = _pulse(BLOCK)
    good = rb.run(BLOCK, p, engine="pymunk", duration=6.0)
    assert good.ok and good.summary.n_impacts >= 2
    real = loop.measure_impacts

    def blind(*args, **kwargs):
        return [dict(r, eta=float("nan")) for r in real(*args, **kwargs)]

    monkeypatch.setattr(loop, "measure_impacts", blind)
    coarse = rb.run(BLOCK, p, engine="pymunk", duration=6.0)
    assert coarse.status == "invalid"
    assert "eta" in coarse.summary.reason


def test_a_10_ms_output_grid_still_measures_eta_under_a_pulse():
    """output_dt = 10 ms under a pulse: the windowed fits had too few samples and every eta was
    NaN (issue 13); the equation-of-motion estimator (rockbench.measure) measures them, within
    0.1 % of the 1 ms measurement."""
    p = _pulse(BLOCK)
    fine = rb.run(BLOCK, p, engine="pymunk", duration=6.0)
    coarse = rb.run(BLOCK, p, engine="pymunk", duration=6.0, output_dt=1e-2)
    assert coarse.ok and len(coarse.summary.eta_measured) == len(fine.summary.eta_measured)
    for a, b in zip(coarse.summary.eta_measured, fine.summary.eta_measured):
        assert abs(a / b - 1) < 1e-3


def test_free_rocking_at_10_ms_output_is_still_measured_and_ok():
    """Free rocking measures eta from peak energies, which a 10 ms grid resolves."""
    r = rb.run(BLOCK, None, engine="pymunk", phi0=0.5 * BLOCK.alpha, duration=3.0,
               output_dt=1e-2)
    assert r.ok


def test_a_sliding_collapse_is_flagged_against_the_reference():
    """MuJoCo under A = 50 (paper-asymmetric, fall angle 4 alpha) overturns with the reference
    but its columns slide over 0.1 m while falling: the engine run may say ok (slip while
    falling is allowed, tests/engines/test_falling.py), the stress row must not."""
    from rockbench.stress import _point, run_point

    row = run_point(("mujoco", _point("A", 50.0)))
    assert row["class"] in ("off", "diverged", "invalid")
    if row["status"] == "ok":
        assert "sliding" in row["flags"]

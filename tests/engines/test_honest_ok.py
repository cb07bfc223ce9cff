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
    from rockbench.studies.robustness import _point, run_point

    row = run_point(("mujoco", _point("A", 50.0)))
    assert row["class"] in ("off", "diverged", "invalid")
    if row["status"] == "ok":
        assert "sliding" in row["flags"]


# --- issue 22 section 3: runs that do not move, and runs that stop, say so ----------------------
def _frozen_pymunk(monkeypatch):
    """pymunk whose step does nothing: a world whose bodies never respond (what a density of
    1e-16 did to OpenSees and PyBullet: frozen at their release angle, status ok)."""
    from rockbench.engines.pymunk import PymunkBackend

    monkeypatch.setattr(PymunkBackend, "_step", lambda self, gx, forces: None)


def test_a_frozen_world_in_free_rocking_is_not_ok(monkeypatch):
    phi0 = 0.5 * BLOCK.alpha
    assert rb.run(BLOCK, None, engine="pymunk", phi0=phi0, duration=1.0, loop="python").ok
    _frozen_pymunk(monkeypatch)
    r = rb.run(BLOCK, None, engine="pymunk", phi0=phi0, duration=1.0, loop="python")
    assert r.status == "invalid"
    assert "did not move" in r.summary.reason and "frozen" in r.summary.reason
    assert r.summary.max_abs_phi == phi0                 # it stayed at its release angle


def test_a_frozen_world_under_a_pulse_above_uplift_is_not_ok(monkeypatch):
    _frozen_pymunk(monkeypatch)
    r = rb.run(BLOCK, _pulse(BLOCK, A=2.5), engine="pymunk", duration=4.0, loop="python")
    assert r.status == "invalid" and "analytic model rocks it" in r.summary.reason


def test_a_pulse_below_uplift_does_not_count_as_frozen(monkeypatch):
    """Below the uplift threshold nothing has to move: a still structure is the right answer."""
    _frozen_pymunk(monkeypatch)
    assert rb.run(BLOCK, _pulse(BLOCK, A=0.6), engine="pymunk", duration=4.0,
                  loop="python").ok


def test_a_structure_that_barely_moves_at_its_critical_angle_is_not_frozen():
    """Released at its critical angle the block has no acceleration to speak of: no verdict
    of 'frozen' however little it moves (the reference does not move either)."""
    from rockbench.analytic.reference import reference_of

    crit = reference_of(BLOCK).critical[(1, True)]
    r = rb.run(BLOCK, None, engine="pymunk", phi0=crit, duration=0.3)
    assert r.status != "invalid", r.summary.reason


def test_release_beyond_the_critical_angle_falls_cleanly():
    """From 2 alpha a block falls; its mechanical energy relative to rest starts at ~0 there
    and the check divided by max(E0, 1e-300): the fall was "diverged, energy grew by 1e305 %".
    Now the check's scale is |E0| + the potential at alpha / 20, and it skips samples past the
    critical angle (as the contact checks do): the run overturns, ok."""
    for s in (1, -1):
        r = rb.run(BLOCK, None, engine="pymunk", phi0=s * 2.0 * BLOCK.alpha, duration=4.0)
        assert r.ok, r.summary.reason
        assert r.summary.overturned and r.summary.t_overturn > 0.3

"""The analytic event loop never stalls, and its verdicts hold at the edges (issues 17 and 18).

* grazing uplift: a pulse whose peak is exactly lambda g (A = 1 on the symmetric frames, where
  lambda = tan alpha) is not an uplift (rules.UPLIFT_RTOL); 1e-9 either side of it gives no
  uplift / a tiny one;
* impact chatter: two successive small post-impact velocities close in time settle the
  structure (rules.CHATTER_*), with peaks and verdicts unchanged;
* progress: an event loop that cannot advance returns a Result marked ``invalid`` with the
  reason, in well under a second (rules.PROGRESS_*);
* exceeded critical: set when a segment starts at or beyond the critical angle of its
  potential (after a fracture, or from the initial rotation);
* fall angle: 0.98 x min(pi/2, geometric limit), below the lying-flat pose, for every scene.

SI units, radians; times are process CPU seconds.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest

import rockbench as rb
from rockbench.analytic import rules
from rockbench.analytic.reference import Reference
from rockbench.analytic.solver import AnalyticSettings, simulate
from rockbench.constants import G
from rockbench.errors import SceneError
from rockbench.scene.mechanism import geometric_limit, mechanism
from rockbench.scene.motion import RickerPulse

SYMMETRIC = ("paper-symmetric", "paper-symmetric-hybrid")
MINIMAL = AnalyticSettings(history="minimal")


def _frame_scenes() -> list[str]:
    """The built-in frame scenes (names in ``builtin_scenes()`` that load as a frame)."""
    out = []
    for name in rb.builtin_scenes():
        try:
            sc = rb.load_scene(name)
        except SceneError:          # a data file in scenarios/ that is not a scene
            continue
        if sc.is_frame:
            out.append(name)
    return out


def timed(fn, *args, **kwargs):
    c0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - c0


# --- grazing uplift ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", SYMMETRIC)
@pytest.mark.parametrize("shape", ["symmetric", "antisymmetric"])
@pytest.mark.parametrize("sign", [1, -1])
def test_peak_exactly_at_the_threshold_is_no_uplift(name, shape, sign):
    """lambda = tan alpha on the symmetric frames: A = 1 puts the peak on the threshold (within
    rounding). Before the fix each of these cells spun for minutes and raised RuntimeError."""
    sc = rb.load_scene(name)
    ref = Reference(sc)
    assert ref.lam[1] == pytest.approx(math.tan(sc.alpha), rel=1e-14)
    for W in range(1, 9):
        pulse = RickerPulse.dimensionless(1.0, float(W), sc.structure, shape, sign)
        r, cpu = timed(simulate, sc, pulse, settings=MINIMAL, reference=ref)
        s = r.summary
        assert s.status == "ok", s.reason
        assert cpu < 1.0, f"W={W}: {cpu:.2f} s"
        assert not s.uplifted and s.n_impacts == 0 and s.max_abs_phi == 0.0
        assert (r.history["mode"] == 0).all()


@pytest.mark.parametrize("name", SYMMETRIC)
@pytest.mark.parametrize("sign", [1, -1])
def test_either_side_of_the_threshold(name, sign):
    """A = 1 - 1e-9: no uplift; A = 1 + 1e-9: an uplift, of a tiny excursion that ends at
    rest; both in well under a second."""
    sc = rb.load_scene(name)
    ref = Reference(sc)
    below, cpu_b = timed(simulate, sc, RickerPulse.dimensionless(1 - 1e-9, 2.0, sc.structure,
                                                                 "symmetric", sign),
                         settings=MINIMAL, reference=ref)
    pulse = RickerPulse.dimensionless(1 + 1e-9, 2.0, sc.structure, "symmetric", sign)
    above, cpu_a = timed(simulate, sc, pulse, settings=MINIMAL, reference=ref)
    assert below.summary.status == above.summary.status == "ok"
    assert cpu_b < 1.0 and cpu_a < 1.0
    assert not below.summary.uplifted and below.summary.max_abs_phi == 0.0
    s = above.summary
    assert s.uplifted and not s.overturned
    assert 0.0 < s.max_abs_phi < 1e-12 * sc.alpha
    ups = above.events[above.events["kind"] == "uplift"]
    assert list(ups["direction"]) == [sign]
    # uplift where the excess over lambda g (1 + UPLIFT_RTOL) is strictly positive
    a_up = pulse.acceleration(float(ups["t"].iloc[0]))
    assert sign * a_up > sign * ref.lam[sign] * G * (1.0 + rules.UPLIFT_RTOL)
    assert a_up == pytest.approx(ref.lam[sign] * G, rel=1e-11)
    assert above.events["kind"].iloc[-1] == "rest"


@pytest.mark.parametrize("sign", [1, -1])
def test_uplift_needs_the_relative_margin(sign):
    """A peak of lambda g (1 + UPLIFT_RTOL / 2) does not uplift; lambda g (1 + 1e-10) does."""
    sc = rb.load_scene("paper-asymmetric")
    ref = Reference(sc)
    lam = abs(ref.lam[sign])
    for factor, should in ((1.0 + 0.5 * rules.UPLIFT_RTOL, False), (1.0 + 1e-10, True)):
        r = simulate(sc, RickerPulse(lam * G * factor, 2.0, "symmetric", sign), settings=MINIMAL,
                     reference=ref)
        assert r.summary.status == "ok"
        assert r.summary.uplifted is should


# --- chatter -------------------------------------------------------------------------------------
def _chatter_case():
    """El Centro-like chatter without a data file: the asymmetric frame under a pulse just above
    its threshold (A = 1.15, W = 6) returns to its base with small velocities and chatters."""
    sc = rb.load_scene("paper-asymmetric")
    return sc, RickerPulse.dimensionless(1.15, 6.0, sc.structure, "symmetric", 1)


def test_chatter_settles_with_unchanged_peak_and_verdicts(monkeypatch):
    sc, pulse = _chatter_case()
    ref = Reference(sc)
    with_rule = simulate(sc, pulse, settings=MINIMAL, reference=ref)
    v_chat = rules.CHATTER_VELOCITY_RATIO * ref.p * ref.alpha
    monkeypatch.setattr(rules, "CHATTER_VELOCITY_RATIO", 0.0)      # the rule disabled
    without = simulate(sc, pulse, settings=MINIMAL, reference=ref)
    a, b = with_rule.summary, without.summary
    assert a.status == b.status == "ok"
    # the rule acted: fewer impacts, and the impact that settled it is small and close
    assert b.n_impacts >= a.n_impacts + 10
    imp = with_rule.impacts()
    settled = imp[imp["direction"] == 0]
    assert len(settled) >= 1
    for _, ev in settled.iterrows():
        assert abs(ev["phidot_after"]) <= v_chat
        assert abs(ev["phidot_after"]) > AnalyticSettings().rest_ratio * ref.p * ref.alpha
    # peaks and verdicts unchanged
    assert abs(a.max_abs_phi - b.max_abs_phi) <= 1e-6 * ref.alpha
    for k in ("overturned", "exceeded_critical", "uplifted", "fractured"):
        assert getattr(a, k) == getattr(b, k)


def test_free_rocking_chatter_settles_before_the_rest_threshold(monkeypatch):
    """Free rocking from 2e-6 alpha: its first post-impact velocity is ~2e-3 p alpha; the
    chatter rule settles it once two successive ones are <= CHATTER_VELOCITY_RATIO (3e-4)
    p alpha, the rest rule alone only at 1e-4 p alpha, some 25 impacts later (44 and 70
    impacts). The peak is the initial rotation either way."""
    sc = rb.load_scene("paper-symmetric")
    ref = Reference(sc)
    phi0 = 2e-6 * sc.alpha
    r = simulate(sc, None, phi0=phi0, duration=2.0, settings=MINIMAL, reference=ref)
    v_chat = rules.CHATTER_VELOCITY_RATIO * ref.p * ref.alpha
    monkeypatch.setattr(rules, "CHATTER_VELOCITY_RATIO", 0.0)
    r0 = simulate(sc, None, phi0=phi0, duration=2.0, settings=MINIMAL, reference=ref)
    assert r.summary.max_abs_phi == r0.summary.max_abs_phi == pytest.approx(phi0, rel=1e-12)
    assert r0.summary.n_impacts >= r.summary.n_impacts + 20
    after = r.impacts()["phidot_after"].abs().to_numpy()
    assert after[-1] <= v_chat and after[-2] <= v_chat


# --- progress guarantee --------------------------------------------------------------------------
class _Held(RickerPulse):
    """A ground acceleration held at twice the uplift threshold: the structure at rest uplifts
    at once, whenever it is asked."""

    def __init__(self, level: float):
        self._level = level
        super().__init__(level, 1.0)

    def acceleration(self, t):
        if isinstance(t, (float, int)):
            return self._level
        return np.full(np.shape(t), self._level)


def test_a_stalled_event_loop_returns_an_invalid_result(monkeypatch):
    """A spinning loop, forced: the ground always uplifts the structure at rest, and a
    monkeypatched equation of motion pulls it straight back (phi'' = -1 rad/s^2 at phi = 0), so
    every uplift ends in an impact an instant later, at rest, and uplifts again, without end.
    The guard ends it with status invalid, in well under a second, never raising."""
    sc = rb.load_scene("paper-asymmetric")
    ref = Reference(sc)
    monkeypatch.setattr(ref.dyn[1], "acceleration", lambda *args: -1.0)
    motion = _Held(2.0 * ref.lam[1] * G)
    r, cpu = timed(simulate, sc, motion, duration=5.0, settings=MINIMAL, reference=ref)
    assert r.summary.status == "invalid" and not r.ok
    assert "no progress" in r.summary.reason
    assert cpu < 1.0
    # the history stops where the loop stalled
    t_stop = r.history["t"].iloc[-1]
    assert t_stop < motion.t_start + 5.0
    assert r.cost.sim_time == pytest.approx(t_stop - motion.t_start)


def test_progress_guard_with_an_artificially_strict_window(monkeypatch):
    monkeypatch.setattr(rules, "PROGRESS_WINDOW", 2)
    monkeypatch.setattr(rules, "PROGRESS_MIN_ADVANCE", 1e9)
    sc = rb.load_scene("paper-asymmetric")
    r = rb.run(sc, RickerPulse.dimensionless(3.0, 4.0, sc.structure))
    assert r.summary.status == "invalid" and "no progress" in r.summary.reason


def test_iteration_backstop(monkeypatch):
    monkeypatch.setattr(rules, "MAX_EVENT_ITERATIONS", 3)
    sc = rb.load_scene("paper-asymmetric")
    r = simulate(sc, RickerPulse.dimensionless(3.0, 4.0, sc.structure), settings=MINIMAL)
    assert r.summary.status == "invalid" and "iterations" in r.summary.reason
    assert r.summary.n_impacts <= 3


class _Bad(RickerPulse):
    """A pulse that turns into NaN once the structure rocks: the integrator fails."""

    def acceleration(self, t):
        a = super().acceleration(t)
        return a * math.nan if isinstance(t, float) and t > -0.5 * self.period else a


def test_an_integrator_failure_is_an_invalid_result():
    sc = rb.load_scene("paper-asymmetric")
    good = RickerPulse.dimensionless(3.0, 4.0, sc.structure)
    bad = _Bad(good.amplitude, good.period)
    r, cpu = timed(simulate, sc, bad, settings=MINIMAL)
    assert r.summary.status == "invalid" and r.summary.reason
    assert cpu < 1.0


# --- exceeded critical at the start of a segment (issue 18) --------------------------------------
def test_fracture_beyond_the_post_fracture_critical_angle_exceeds_it():
    """`rockbench run paper-symmetric-hybrid --set fracture_strain=0.02 --set density=25000
    --pulse antisymmetric --amplitude 4 --frequency 2`: fracture at 0.170 rad, beyond the
    post-fracture critical angle 0.142 rad. Before the fix: 'exceeded critical: no'."""
    sc = rb.load_scene("paper-symmetric-hybrid", {"fracture_strain": 0.02, "density": 25000})
    ref = Reference(sc)
    r = simulate(sc, RickerPulse.dimensionless(4.0, 2.0, sc.structure, "antisymmetric", 1),
                 reference=ref)
    s = r.summary
    assert s.status == "ok" and s.fractured and not s.overturned
    ev = r.events
    frac = ev[ev["kind"] == "fracture"].iloc[0]
    d = int(frac["direction"])
    assert d * frac["phi"] >= ref.critical[(d, False)]
    assert s.exceeded_critical
    crit = ev[(ev["kind"] == "critical") & (ev["t"] == frac["t"])]
    assert len(crit) == 1 and crit["phi"].iloc[0] == frac["phi"]


def test_starting_beyond_the_critical_angle_exceeds_it():
    """Free rocking released beyond phi_cr with a velocity back towards rest: it never crosses
    phi_cr upwards, yet it started beyond it."""
    sc = rb.load_scene("paper-symmetric")
    ref = Reference(sc)
    crit = ref.critical[(1, True)]
    r = simulate(sc, None, phi0=1.02 * crit, phidot0=-0.05, duration=3.0, reference=ref)
    assert not r.summary.overturned
    assert r.summary.exceeded_critical
    below = simulate(sc, None, phi0=0.98 * crit, phidot0=-0.05, duration=3.0, reference=ref)
    assert not below.summary.exceeded_critical


# --- the fall angle (issue 18) -------------------------------------------------------------------
@pytest.mark.parametrize("name", list(rb.builtin_scenes()))
def test_fall_angle_is_clearly_below_lying_flat(name):
    try:
        sc = rb.load_scene(name)
    except SceneError:
        pytest.skip(f"{name} is not a scene")
    for s in (1, -1):
        lim = geometric_limit(mechanism(sc.structure, s))
        assert sc.fall_angles[s] == 0.98 * min(math.pi / 2, lim)
        assert sc.fall_angles[s] <= 0.98 * math.pi / 2 < math.pi / 2


def test_block_overturns_at_its_fall_angle_before_lying_flat():
    """`rockbench run housner-block --pulse symmetric --amplitude 3 --frequency 1`: the analytic
    run stops at 0.98 pi/2, not at the lying-flat pose pi/2."""
    sc = rb.load_scene("housner-block")
    ref = Reference(sc)
    r = simulate(sc, RickerPulse.dimensionless(3.0, 1.0, sc.structure, "symmetric", 1),
                 reference=ref)
    s = r.summary
    assert s.overturned and s.exceeded_critical
    assert s.max_abs_phi == pytest.approx(0.98 * math.pi / 2, rel=1e-9)
    assert s.max_abs_phi < math.pi / 2


# --- done when (issue 17): a whole map finishes ok -----------------------------------------------
@pytest.mark.slow
def test_every_map_cell_of_every_builtin_frame_is_ok():
    """A, W in 1..8 (step 1), both shapes, both signs, on every built-in frame scene: every
    cell finishes with status ok (no RuntimeError, no invalid run)."""
    bad = []
    for name in _frame_scenes():
        sc = rb.load_scene(name)
        ref = Reference(sc)
        for A, W, shape, sign in itertools.product(range(1, 9), range(1, 9),
                                                   ("symmetric", "antisymmetric"), (1, -1)):
            pulse = RickerPulse.dimensionless(float(A), float(W), sc.structure, shape, sign)
            r, cpu = timed(simulate, sc, pulse, settings=MINIMAL, reference=ref)
            if r.summary.status != "ok" or cpu > 5.0:
                bad.append((name, A, W, shape, sign, r.summary.status, r.summary.reason, cpu))
    assert not bad, bad

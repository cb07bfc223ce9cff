"""The event rules of the analytic SDOF model, stated once and shared by every analytic path
(the ``solve_ivp`` reference in :mod:`rockbench.analytic.solver` and the compiled path).

Every constant is dimensionless; the scales are those of the taller column: alpha [rad] and
p [rad/s], so a velocity ratio c means |phi'| = c p alpha [rad/s] and an interval ratio c means
c / p [s]. The solver reads these module attributes when a run starts (a test may monkeypatch
them; a compiled copy must use the same values).

Uplift
    A structure at rest uplifts in direction +1 when the ground acceleration *exceeds* the
    threshold, u_g'' > lambda_ccw g (1 + UPLIFT_RTOL), and in direction -1 when
    u_g'' < lambda_cw g (1 + UPLIFT_RTOL) (lambda_cw < 0). A motion that only touches the
    threshold (a grazing, tangent touch, e.g. a pulse whose peak is exactly lambda g) does not
    uplift: the excess must be positive beyond the relative margin UPLIFT_RTOL. The same strict
    comparison is used on the motion's knots (u_g'' is monotonic between knots) and at the root:
    the uplift time is the first time at which u_g'' - lambda g (1 + UPLIFT_RTOL) is strictly
    positive (the root of that difference between the last knot below and the first knot above,
    found by Brent's method, then stepped just past so that the excess is > 0). Rocking then
    starts with phi'' > 0 in the uplift direction, so the uplift cannot re-trigger.

Rest after an impact
    A post-impact |phi'| <= ``rest_ratio`` p alpha (``AnalyticSettings.rest_ratio``, default
    :data:`REST_RATIO`), or an eta <= 0, ends rocking: the structure is at rest (and may uplift
    again at once if the ground motion still exceeds the threshold).

Chatter (Zeno behaviour)
    Returning to its base with a small velocity, a rocking structure makes a sequence of ever
    smaller and ever closer impacts (velocities shrink by eta each time, intervals with them,
    infinitely many in finite time). The structure *settles* (is at rest, exactly as after the
    rest rule) at impact k when all three hold:

    * |phi'+_k| <= CHATTER_VELOCITY_RATIO p alpha (the velocity after this impact),
    * |phi'+_(k-1)| <= CHATTER_VELOCITY_RATIO p alpha (the velocity after the previous impact of
      the same rocking episode: no rest or uplift in between),
    * t_k - t_(k-1) <= CHATTER_INTERVAL / p (the two impacts are close).

    Why all three: a small velocity alone is the rest rule; a short interval alone also happens
    after a strong impact into a direction the ground is driving (no chatter). A neglected
    excursion after a post-impact velocity c p alpha reaches about c^2 alpha / 2 in free rocking
    (phi'' ~ -p^2 alpha near rest), i.e. 4.5e-8 alpha for c = 3e-4.

Progress guarantee
    The event loop counts its iterations (one uplift search, or one integrated segment ending at
    an event or at t_end). If PROGRESS_WINDOW consecutive iterations advance time by less than
    PROGRESS_MIN_ADVANCE / p in total, or the run needs more than MAX_EVENT_ITERATIONS
    iterations, the run stops there and returns a Result with ``summary.status == "invalid"``
    and the reason (never an exception). The same holds for a failure of the integrator or of
    the uplift root search.
"""

from __future__ import annotations

__all__ = ["UPLIFT_RTOL", "REST_RATIO", "CHATTER_VELOCITY_RATIO", "CHATTER_INTERVAL",
           "PROGRESS_WINDOW", "PROGRESS_MIN_ADVANCE", "MAX_EVENT_ITERATIONS"]

#: Relative margin by which the ground acceleration must exceed lambda g to uplift [-].
UPLIFT_RTOL = 1e-12

#: Default rest threshold: post-impact |phi'| <= REST_RATIO p alpha ends rocking [-].
REST_RATIO = 1e-4

#: Chatter: velocity ratio [-]; two successive post-impact |phi'| <= CHATTER_VELOCITY_RATIO
#: p alpha [rad/s] (with CHATTER_INTERVAL) settle the structure. 0 disables the chatter rule.
CHATTER_VELOCITY_RATIO = 3e-4

#: Chatter: interval ratio [-]; the two impacts at most CHATTER_INTERVAL / p [s] apart.
CHATTER_INTERVAL = 1e-1

#: Progress: number of consecutive event-loop iterations over which time must advance [-].
PROGRESS_WINDOW = 50

#: Progress: least advance [-] of time, in units of 1/p, over PROGRESS_WINDOW iterations.
PROGRESS_MIN_ADVANCE = 1e-6

#: Progress: most event-loop iterations in one run [-] (a backstop behind PROGRESS_WINDOW).
MAX_EVENT_ITERATIONS = 100_000

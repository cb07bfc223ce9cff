"""The event rules of the analytic SDOF model, stated once and shared by every analytic path
(the ``solve_ivp`` reference in :mod:`rockbench.analytic.solver` and the compiled path).

Uplift
    A structure at rest uplifts in direction +1 when the ground acceleration *exceeds* the
    threshold, u_g'' > lambda_ccw g (1 + UPLIFT_RTOL), and in direction -1 when
    u_g'' < lambda_cw g (1 + UPLIFT_RTOL) (lambda_cw < 0). A motion that only touches the
    threshold (a grazing, tangent touch, e.g. a pulse whose peak is exactly lambda g) does not
    uplift: the excess must be positive beyond the relative margin UPLIFT_RTOL.

Rest after an impact
    A post-impact |phi'| <= ``rest_ratio`` p alpha (``AnalyticSettings.rest_ratio``, default
    :data:`REST_RATIO`) ends rocking: the structure is at rest (and may uplift again at once if
    the ground motion still exceeds the threshold).
"""

from __future__ import annotations

__all__ = ["UPLIFT_RTOL", "REST_RATIO"]

#: Relative margin by which the ground acceleration must exceed lambda g to uplift [-].
UPLIFT_RTOL = 1e-12

#: Default rest threshold: post-impact |phi'| <= REST_RATIO p alpha ends rocking [-].
REST_RATIO = 1e-4

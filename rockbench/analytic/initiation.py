"""Which mode a rigid block at rest starts in: rest, slide, rock, slide-rock or free flight.

Shenton, H. W. (1996) "Criteria for initiation of slide, rock, and slide-rock rigid-body
modes", J. Eng. Mech. 122(7): 690-693. The paper's abstract states the results this module
reproduces: a slide-rock mode can start from rest; it starts when the friction coefficient is
*greater* than the width-to-height ratio b/h but less than a critical value that grows with
the ground acceleration; so, for a given acceleration, raising the friction moves the
initial mode from slide to slide-rock and finally to rock. The inequalities below are derived
here from the rigid-body equations at the first instant (the paper's text was not available to
check them against its equations; ``docs/sliding.md``), and they are checked in the tests by
an independent enumeration of the contact states.

Setting (planar, Coulomb friction mu, static = kinetic)
-------------------------------------------------------
A rectangular block of half-width b, half-height h (slenderness b/h = tan alpha), mass m,
I_G = m (b^2 + h^2) / 3, at rest on a rigid foundation accelerating horizontally by a_g and
vertically by a_v (up positive). In the foundation's frame the block is loaded by the
effective gravity g_e = g + a_v (down) and the inertial force -m a_g (horizontal). At rest
everything is linear in (a_g, g_e), so the mode depends only on

    A = |a_g| / g_e   [-]     (g_e > 0; g_e <= 0 lifts the block: "free-flight").

With x = A and beta = b/h, the four candidate modes and their consistency conditions (the
pivot is the corner the block rotates about, on the side *opposite* to the ground's
acceleration):

* **rest**: the horizontal reaction m a_g and the vertical m g_e need |A| <= mu (friction)
  and |A| <= beta (the trailing corner's normal force >= 0);
* **slide** (both corners on the ground, slipping): in the frame of the sliding block the
  load is the friction mu m g_e at the base and m g_e, whatever A; the lifting corner's
  normal force is m g_e (b - mu h) / (2 b) >= 0 iff mu <= beta. Slip needs A > mu;
* **rock** (pivot sticks, the other corner lifts): theta'' = 3 g_e (A h - b) / (4 (b^2 + h^2))
  > 0 iff A > beta, and the pivot's reaction H = m (a_g - h theta''), V = m (g_e + b theta'')
  must satisfy |H| <= mu V, i.e. mu >= mu_r(A) with

      mu_r(A) = (A (4 beta^2 + 1) + 3 beta) / (beta^2 + 4 + 3 A beta)         (*)

  (:func:`rocking_friction_demand`; mu_r(beta) = beta, it grows with A, since
  d mu_r / dA = 4 (beta^2 + 1)^2 / (beta^2 + 4 + 3 A beta)^2 > 0, and tends to
  mu_inf = (4 beta^2 + 1) / (3 beta) as A -> infinity, :func:`rock_friction_limit`);
* **slide-rock** (the pivot slips, the other corner lifts): solving the simultaneous
  equations with the pivot's friction at its limit mu V,

      theta'' = 3 g_e (mu h - b) / (4 b^2 + h^2 - 3 mu b h),

  independent of A: positive iff beta < mu < mu_inf. The pivot slips against the friction
  (its tangential acceleration -a_g + mu (g_e + b theta'') + h theta'' < 0 for a_g > 0) iff
  mu < mu_r(A), the same boundary (*) seen from the other side.

So the partition of the (mu, A) plane, for A = |a_g| / g_e (strict "exceeds" at a threshold,
with the relative margin :data:`rockbench.analytic.rules.UPLIFT_RTOL` of the rocking model):

    A <= mu and A <= beta                  rest
    mu < beta and A > mu                   slide
    mu >= beta, A > beta, mu >= mu_r(A)    rock
    mu >= beta, A > beta, mu <  mu_r(A)    slide-rock

The rock/slide-rock boundary (*) lies between beta and mu_inf, so friction above
mu_inf always gives rock and friction below beta never rocks. The classical assumption
(rock whenever mu > b/h) is the limit A -> beta of (*). On a boundary the mode named is the
one the inequalities give (a boundary is a limit, not a mode).

Vertical acceleration enters only through g_e: each threshold in units of g is multiplied by
(1 + a_v / g), :func:`sliding_threshold`, :func:`rocking_threshold`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError, check_finite, check_positive
from . import rules

__all__ = ["MODES", "ModeMap", "sliding_threshold", "rocking_threshold",
           "rocking_friction_demand", "rock_friction_limit", "initiation_mode", "mode_map"]

#: The modes, in the order of their integer codes in :class:`ModeMap`.
MODES = ("rest", "slide", "rock", "slide-rock", "free-flight")


def _effective(a_v_over_g) -> np.ndarray:
    """g_e / g = 1 + a_v / g [-]."""
    return 1.0 + np.asarray(a_v_over_g, dtype=float)


def sliding_threshold(mu: float, a_v_over_g: float = 0.0) -> float:
    """|a_g| / g [-] above which a block at rest slides: mu (1 + a_v / g) (Coulomb)."""
    mu = check_positive("mu", mu)
    return mu * float(_effective(check_finite("a_v_over_g", a_v_over_g)))


def rocking_threshold(b_over_h: float, a_v_over_g: float = 0.0) -> float:
    """|a_g| / g [-] above which a block at rest would uplift: (b/h) (1 + a_v / g) (Housner's
    tan alpha, with g replaced by g + a_v)."""
    beta = check_positive("b_over_h", b_over_h)
    return beta * float(_effective(check_finite("a_v_over_g", a_v_over_g)))


def _demand(beta, A):
    """Eq. (*) of the module docstring, vectorized: the friction needed at a rocking pivot at
    the first instant, A = |a_g| / g_e [-]."""
    return (A * (4.0 * beta**2 + 1.0) + 3.0 * beta) / (beta**2 + 4.0 + 3.0 * A * beta)


def rocking_friction_demand(b_over_h: float, a_g_over_g: float, a_v_over_g: float = 0.0) -> float:
    """mu_r [-]: the friction coefficient a block needs, at the first instant of rocking from
    rest, for its pivot not to slip (the rock / slide-rock boundary, Eq. (*) of the module
    docstring), with A = |a_g| / (g + a_v). Meaningful for A >= b/h (rocking); equals b/h at
    A = b/h and grows with A to :func:`rock_friction_limit`."""
    beta = check_positive("b_over_h", b_over_h)
    ge = float(_effective(check_finite("a_v_over_g", a_v_over_g)))
    if ge <= 0.0:
        raise ParameterError("a_v_over_g", a_v_over_g, "> -1", "g + a_v <= 0: no contact")
    A = abs(check_finite("a_g_over_g", a_g_over_g)) / ge
    return float(_demand(beta, A))


def rock_friction_limit(b_over_h: float) -> float:
    """mu_inf = (4 (b/h)^2 + 1) / (3 b/h) [-]: above it a block that uplifts always rocks
    without slipping, whatever the acceleration (the limit of :func:`rocking_friction_demand`
    as |a_g| -> infinity; also where the slide-rock solution's denominator changes sign)."""
    beta = check_positive("b_over_h", b_over_h)
    return (4.0 * beta * beta + 1.0) / (3.0 * beta)


def _codes(beta, mu, a, av) -> np.ndarray:
    """Mode codes (index in :data:`MODES`) over broadcast arrays of b/h, mu, a_g/g, a_v/g."""
    beta, mu, a, ge = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (beta, mu, a,
                                                                             _effective(av))))
    margin = 1.0 + rules.UPLIFT_RTOL
    flight = ge <= 0.0
    A = np.abs(a) / np.where(flight, 1.0, ge)
    slides = A > mu * margin
    rocks = A > beta * margin
    code = np.zeros(A.shape, dtype=int)
    code = np.where((mu < beta) & slides, 1, code)
    rocking = (mu >= beta) & rocks
    code = np.where(rocking & (mu >= _demand(beta, A)), 2, code)
    code = np.where(rocking & (mu < _demand(beta, A)), 3, code)
    return np.where(flight, 4, code)


def initiation_mode(b_over_h: float, mu: float, a_g_over_g: float,
                    a_v_over_g: float = 0.0) -> str:
    """The mode a rigid block at rest starts in (Shenton 1996; the criteria in the module
    docstring): one of :data:`MODES`.

    Parameters
    ----------
    b_over_h : float
        Slenderness b/h = tan alpha [-] (half-width over half-height), > 0.
    mu : float
        Coulomb friction coefficient [-], > 0.
    a_g_over_g : float
        Horizontal ground acceleration / g [-] (either sign; the mode is symmetric).
    a_v_over_g : float
        Vertical ground acceleration / g [-], up positive; <= -1 gives "free-flight".
    """
    beta = check_positive("b_over_h", b_over_h)
    mu = check_positive("mu", mu)
    a = check_finite("a_g_over_g", a_g_over_g)
    av = check_finite("a_v_over_g", a_v_over_g)
    return MODES[int(_codes(beta, mu, a, av))]


@dataclass(frozen=True)
class ModeMap:
    """Initiation modes over a grid: ``codes[i, j]`` (index in :data:`MODES`) for ``mu[i]``
    and ``a_g_over_g[j]``, at slenderness ``b_over_h`` and vertical ``a_v_over_g``."""

    b_over_h: float
    a_v_over_g: float
    mu: np.ndarray
    a_g_over_g: np.ndarray
    codes: np.ndarray

    @property
    def modes(self) -> np.ndarray:
        """The mode names, same shape as ``codes``."""
        return np.asarray(MODES, dtype=object)[self.codes]

    def fraction(self, mode: str) -> float:
        """Share of the grid's cells in ``mode`` [-]."""
        if mode not in MODES:
            raise ParameterError("mode", mode, f"one of {', '.join(MODES)}")
        return float(np.mean(self.codes == MODES.index(mode)))


def mode_map(b_over_h: float, mu, a_g_over_g, a_v_over_g: float = 0.0) -> ModeMap:
    """:func:`initiation_mode` over the grid ``mu`` x ``a_g_over_g`` (1-D arrays of positive
    friction coefficients and of accelerations in g), for figures of the (mu, a_g / g) plane."""
    beta = check_positive("b_over_h", b_over_h)
    av = check_finite("a_v_over_g", a_v_over_g)
    mus = np.atleast_1d(np.asarray(mu, dtype=float))
    acc = np.atleast_1d(np.asarray(a_g_over_g, dtype=float))
    if mus.ndim != 1 or not np.all(np.isfinite(mus)) or not np.all(mus > 0.0):
        raise ParameterError("mu", mu, "a 1-D array of finite values > 0")
    if acc.ndim != 1 or not np.all(np.isfinite(acc)):
        raise ParameterError("a_g_over_g", a_g_over_g, "a 1-D array of finite values")
    codes = _codes(beta, mus[:, None], acc[None, :], av)
    for arr in (mus, acc, codes):
        arr.setflags(write=False)
    return ModeMap(beta, av, mus, acc, codes)

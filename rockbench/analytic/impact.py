"""Impacts: the coefficient of restitution of a rocking mechanism (paper, Eqs. 22-28, 36).

At an impact the structure passes through its rest configuration (phi = 0) and switches from
the mechanism ``pre`` (the direction it rocked in) to the mechanism ``post``. Impulses act only
at the new pivots (foundation-column contacts A', D' and column-beam contacts B', C'); they are
perfectly plastic (the new pivots stick) and the old pivots separate, as in the paper.

Writing every body's velocity (centre of mass and rotation) as a column of the mechanism's
Jacobian times phi', ``v_i = j_i^pre phi'^-`` before and ``v_i = j_i^post phi'^+`` after, the
impulse-momentum equations of the three bodies are ``M (j^post phi'^+ - j^pre phi'^-) =
W Lambda``. Every impulse does zero virtual work on the post-impact mechanism (it acts at a pivot
of that mechanism, or in equal and opposite pairs at a joint that moves as one), so projecting
on ``j^post`` eliminates all eight impulses:

    eta = phi'^+ / phi'^- = (j^post . M j^pre) / (j^post . M j^post)

This is the closed form of the solution of Eqs. 23-27 (checked in the tests against Eq. 28 for
the symmetric frame, Housner's 1 - 1.5 sin^2 alpha for the block, and the paper's Eq. 36).
"""

from __future__ import annotations

from .dynamics import Dynamics

__all__ = ["restitution", "eta"]


def _jacobian(dyn: Dynamics) -> list[tuple[float, float, float, float, float]]:
    cfg = dyn.configuration(0.0)
    return [(m, Ic, bk.dx, bk.dy, bk.dtheta) for m, Ic, bk in zip(dyn._m, dyn._I, cfg.bodies)]


def restitution(structure, pre: int, post: int) -> float:
    """phi'^+ / phi'^- [-] of an impact from mechanism ``pre`` into mechanism ``post``
    (directions +1 or -1). For ``pre == post`` (no change of pivots) it is 1."""
    jpre = _jacobian(Dynamics(structure, pre))
    jpost = _jacobian(Dynamics(structure, post))
    num = den = 0.0
    for (m, Ic, ax, ay, at), (_, _, bx, by, bt) in zip(jpre, jpost):
        num += m * (ax * bx + ay * by) + Ic * at * bt
        den += m * (bx * bx + by * by) + Ic * bt * bt
    return num / den


def eta(structure, direction: int) -> float:
    """Coefficient of restitution of the impact after which ``structure`` rocks in
    ``direction`` (+1: ``eta_ccw``, the impact that ends clockwise rocking; -1: ``eta_cw``)."""
    return restitution(structure, -direction, direction)

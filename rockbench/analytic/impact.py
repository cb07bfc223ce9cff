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

from ..scene.scene import restitution

__all__ = ["restitution", "eta"]

# restitution(structure, pre, post) is the formula above; it lives with the scene, which
# refuses a structure whose eta is negative (it cannot rock), so that both use one copy.


def eta(structure, direction: int) -> float:
    """Coefficient of restitution of the impact after which ``structure`` rocks in
    ``direction`` (+1: ``eta_ccw``, the impact that ends clockwise rocking; -1: ``eta_cw``)."""
    return restitution(structure, -direction, direction)

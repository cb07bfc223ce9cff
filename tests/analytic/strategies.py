"""Hypothesis strategies and geometry helpers shared by the analytic tests."""

import math

from hypothesis import strategies as st

from rockbench.scene.mechanism import geometric_limit, mechanism
from rockbench.scene.structure import Frame

#: Random frames (asymmetric or symmetric, slender or squat) for which the three-block mechanism
#: holds (a column keeps rotating the rocking way relative to the beam) at least up to
#: |phi| = alpha; rockbench.Scene refuses other frames.
frames = st.builds(
    lambda w, hl, ratio, gap, over, bh, rho, mr: Frame(
        column_width=w, column_height_left=hl, column_height_right=ratio * hl,
        span=w + gap, beam_width=w + gap + w + over, beam_height=bh,
        beam_gyration_radius=rho, mass_ratio=mr),
    w=st.floats(0.2, 2.0), hl=st.floats(2.0, 12.0), ratio=st.floats(0.4, 1.0),
    gap=st.floats(0.5, 14.0), over=st.floats(0.0, 4.0), bh=st.floats(0.3, 3.0),
    rho=st.floats(0.3, 6.0), mr=st.floats(0.05, 20.0)).filter(
    lambda f: min(geometric_limit(mechanism(f, s)) for s in (1, -1)) >= f.alpha)


def material_point(body, rest_body, point) -> tuple[float, float]:
    """Current position [m] of the material point of ``body`` that is at ``point`` at rest."""
    rx, ry = point[0] - rest_body.x, point[1] - rest_body.y
    c, s = math.cos(body.theta), math.sin(body.theta)
    return body.x + c * rx - s * ry, body.y + s * rx + c * ry


def dist(p, q) -> float:
    return math.hypot(p[0] - q[0], p[1] - q[1])

"""Hypothesis strategies shared by the analytic tests."""

from hypothesis import strategies as st

from rockbench.analytic.kinematics import geometric_limit, mechanism
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

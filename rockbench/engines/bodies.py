"""What every engine builds, from the scene alone: the rigid bodies, the foundation, and the
bodies' poses on the exact mechanism at an initial rotation.

Sizes in m, masses in kg, inertias in kg m^2, angles in rad (``docs/conventions.md``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..scene.scene import Scene
from ..scene.mechanism import mechanism
from ..scene.structure import Block, Frame

__all__ = ["BodySpec", "FoundationSpec", "body_specs", "foundation_spec", "initial_poses"]


class BodySpec(NamedTuple):
    """A rigid box body. Sizes in m, mass kg, inertia kg m^2 (planar, about the centre of
    mass; 3-D engines may use it for the axis normal to the plane and box values for the others),
    depth m (out of plane), rest centre of mass (x, y) in m."""

    name: str
    mass: float
    inertia: float
    half_width: float
    half_height: float
    depth: float
    x: float
    y: float


class FoundationSpec(NamedTuple):
    """Static geometry: the ground surface y = 0 (extending over ``x_min``..``x_max``), and an
    optional step (a box ``step_x0``..``step_x1`` by 0..``step_height``) under the right column.
    The step is three column widths wide, centred under the right column, so that the column's
    pivots are on the step's flat top, never on its edges."""

    x_min: float
    x_max: float
    step_x0: float | None
    step_x1: float | None
    step_height: float


def body_specs(scene: Scene) -> list[BodySpec]:
    """The bodies the scene needs, in the order engines must report them: [block] or
    [left column, beam, right column]."""
    st = scene.structure
    if isinstance(st, Block):
        return [BodySpec("block", st.mass, st.inertia_cm, st.b, st.H, st.depth, 0.0, st.H)]
    f: Frame = st
    gl, gb, gr = f.com_left, f.com_beam, f.com_right
    return [
        BodySpec("left", f.mass_left, f.inertia_left, f.b, f.H, f.depth, *gl),
        BodySpec("beam", f.mass_beam, f.inertia_beam, 0.5 * f.beam_width, f.h, f.depth, *gb),
        BodySpec("right", f.mass_right, f.inertia_right, f.b, f.H1, f.depth, *gr),
    ]


def foundation_spec(scene: Scene) -> FoundationSpec:
    st = scene.structure
    if isinstance(st, Block):
        ext = 10.0 * max(st.width, st.height)
        return FoundationSpec(-ext, ext, None, None, 0.0)
    ext = 10.0 * max(st.beam_width, st.column_height_left)
    if st.step > 0.0:
        return FoundationSpec(-ext, st.L + ext, st.L - 3 * st.b, st.L + 3 * st.b, st.step)
    return FoundationSpec(-ext, st.L + ext, None, None, 0.0)


def initial_poses(scene: Scene, phi0: float) -> np.ndarray:
    """Poses (n_bodies, 3): x, y [m], theta [rad] of each body for a rotation phi0 [rad] of the
    left column, the other bodies placed by the mechanism's exact kinematics."""
    specs = body_specs(scene)
    if phi0 == 0.0:
        return np.array([[b.x, b.y, 0.0] for b in specs])
    cfg = mechanism(scene.structure, 1 if phi0 > 0 else -1).configuration(phi0)
    return np.array([[bk.x, bk.y, bk.theta] for bk in cfg.bodies])

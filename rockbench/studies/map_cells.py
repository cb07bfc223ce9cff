"""What a map cell is beyond its run: whether its pulse lies outside the analytic model
(:func:`cell_outside`, the one rule of :mod:`rockbench.validity`), the vertical ratio of a
map, when a reversed pulse's answer is the mirror image of the pulse's (:func:`reversed_mirrors`,
the one rule every study and the campaign use) and the mirror twin of such a cell
(:func:`mirror_twins`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..sweep.map_store import cell_key

__all__ = ["check_vertical_ratio", "cell_outside", "mark_outside", "mirror_twins",
           "with_mirrored", "reversed_mirrors"]


def reversed_mirrors(scene: Any, vertical: float = 0.0) -> bool:
    """True when ``scene``'s response to a reversed (sign -1) motion is the mirror image
    (phi -> -phi) of its response to the motion, so that one sign answers for both: a
    mirror-symmetric structure (:attr:`rockbench.scene.Scene.mirror_symmetric`; a scene
    name or path is loaded) under horizontal motion only (a vertical part ``vertical`` r > 0,
    in phase with the signed pulse, does not turn with its sign)."""
    from ..scene import Scene, load_scene

    sc = scene if isinstance(scene, Scene) else load_scene(scene)
    return bool(sc.mirror_symmetric) and not float(vertical or 0.0)


def check_vertical_ratio(vertical: Any, name: str = "vertical") -> float:
    """A map's vertical ratio r [-] (a_v = r u_g'') as a float in [0, 3], the limit
    ``vertical_ratio`` of every pulse (:mod:`rockbench.limits`, as ``rockbench run
    --vertical``); ParameterError naming ``name`` otherwise."""
    from ..limits import check_in_limit

    if isinstance(vertical, (bool, np.bool_)) or vertical is None:
        raise ParameterError(name, vertical, "a number in [0, 3]")
    return check_in_limit("vertical_ratio", name, vertical)


def cell_outside(scene, shape: str, sign: int, A: float, vertical: float = 0.0) -> bool:
    """Whether the pulse of a map cell (``shape``, ``sign``, A, any W, vertical ratio
    ``vertical``) lies outside the analytic model by the one rule,
    :func:`rockbench.validity.motion_validity` with the scene's friction: its ground falls
    faster than gravity at some time (g + a_v <= 0), or |a_g| > mu (g + a_v) at some time (a
    base at rest slides; without vertical motion PGA > mu g). The test does not depend on W: a
    pulse of another W has the same accelerations on a stretched clock (it is evaluated at
    W = 1)."""
    from ..scene.motion import RickerPulse
    from ..validity import motion_validity

    pulse = RickerPulse.dimensionless(A, 1.0, scene.structure, shape, int(sign),
                                      vertical_ratio=vertical)
    return not motion_validity(scene, pulse).inside


def mark_outside(df: pd.DataFrame, scene, vertical: float = 0.0) -> pd.DataFrame:
    """``df`` (a map) with the column ``outside`` (:func:`cell_outside`, computed once per
    pulse, sign and A) and ``attrs`` ``vertical_ratio`` and ``outside`` (how many cells)."""
    df = df.copy()
    keys = pd.DataFrame({"p": df["pulse"].astype(str).to_numpy(dtype=object),
                         "s": df["sign"].to_numpy().astype(np.int64),
                         "a": df["amplitude"].to_numpy(dtype=float)})
    codes, uniq = pd.factorize(pd.MultiIndex.from_frame(keys))
    known = np.array([cell_outside(scene, str(p), int(s), float(a), vertical)
                      for p, s, a in uniq], dtype=bool)
    flags = known[codes] if len(codes) else np.zeros(0, dtype=bool)
    df["outside"] = flags
    df.attrs.update(vertical_ratio=float(vertical), outside=int(flags.sum()))
    return df


def mirror_twins(cells: Sequence[tuple]) -> tuple[list[tuple], dict[str, tuple]]:
    """``cells`` (shape, sign, A, W) of a mirror-symmetric structure
    (:attr:`rockbench.scene.Scene.mirror_symmetric`) split into those to run and their twins:
    a sign -1 cell whose sign +1 cell is also asked for is not run but mirrored from it
    (:func:`with_mirrored`). Returns (cells to run, key of the +1 cell -> its -1 twin)."""
    asked = {cell_key(*c) for c in cells}
    run, twins = [], {}
    for c in cells:
        shape, sign, A, W = c
        up = cell_key(shape, 1, A, W)
        if sign == -1 and up in asked:
            twins[up] = c
        else:
            run.append(c)
    return run, twins


def with_mirrored(df: pd.DataFrame, twins: dict[str, tuple]) -> pd.DataFrame:
    """``df`` (map rows) and, for each of its sign +1 rows that has a twin in ``twins``
    (:func:`mirror_twins`), the twin's row: the same response mirrored (phi -> -phi: verdict,
    peak |phi|, impacts, fracture, status equal), sign -1, no CPU time of its own."""
    keys = [cell_key(p, s, a, w) for p, s, a, w in zip(df["pulse"], df["sign"],
                                                       df["amplitude"], df["frequency"])]
    hit = np.array([k in twins for k in keys], dtype=bool)
    if not hit.any():
        return df
    mirrored = df.loc[hit].copy()
    mirrored["sign"] = -1
    if "cpu_s" in mirrored:
        mirrored["cpu_s"] = 0.0
    return pd.concat([df, mirrored], ignore_index=True)

"""Intensity measures of a ground-motion record: what a fragility curve is drawn against
(``docs/fragility.md``). Pure functions of a :class:`rockbench.scene.motion.Record` as loaded
(scale 1); a scaled record's measure is the scale times this one.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError

__all__ = ["MEASURES", "intensity"]

#: Intensity measures: key -> (name, unit, definition).
MEASURES: dict[str, tuple[str, str, str]] = {
    "pga": ("PGA", "m/s^2", "peak ground acceleration max |a_g| of the scaled record"),
    "pgv": ("PGV", "m/s", "peak ground velocity max |v_g| of the scaled record, v_g the "
                          "trapezoidal integral of a_g from v_g = 0 at the first sample, "
                          "no baseline correction"),
}


def intensity(record, measure: str = "pga") -> float:
    """The intensity measure ``measure`` (:data:`MEASURES`) of a
    :class:`rockbench.scene.motion.Record` as loaded (scale 1): PGA [m/s^2] or PGV [m/s]."""
    if measure not in MEASURES:
        raise ParameterError("intensity", measure, f"one of {', '.join(MEASURES)}")
    a = np.asarray(record.samples, dtype=float)
    if measure == "pga":
        return float(np.max(np.abs(a)))
    t = np.asarray(record.time, dtype=float)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(t))])
    return float(np.max(np.abs(v)))

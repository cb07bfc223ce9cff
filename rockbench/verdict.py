"""THE overturning verdict of every backend, said once: when a structure is past its critical
angle (:func:`past_critical`), when its fall is under way at the end of a run
(:func:`fall_under_way`) and how such a fall is finished (:func:`finish_fall`).

The rule (``docs/conventions.md``): a structure still past the critical angle of its direction
and device state when the ground motion is over falls. Beyond the critical angle, with no
input, the potential only falls: nothing brings it back. So that every backend gives one
verdict,

* the analytic reference, whose run ended after the ground motion with its fall under way, is
  run :data:`~rockbench.constants.FALL_EXTENSION` seconds longer: the backend
  (:mod:`rockbench.engines.analytic`) and a map's cells on the compiled path
  (:mod:`rockbench.studies.maps`; a map on the ``solve_ivp`` path runs the backend, which
  finishes its falls itself);
* an engine run that stopped past its critical angle (a divergence at its last sample) is
  finished by the analytic model from its last state, for what is left of the ground motion
  and ``FALL_EXTENSION`` seconds more (:mod:`rockbench.engines.verdicts`);
* an engine run that ends after the ground motion past its critical angle for good has
  collapsed (:func:`rockbench.engines.verdicts._collapse`: it reads :func:`past_critical`).

The analytic model's own event "critical" (the root of s phi - phi_cr inside its integrators,
:mod:`rockbench.analytic.solver` and the compiled kernels) is the model detecting the crossing
in its own terms; everything that judges a run's samples or its end reads this module.

Units: radians, seconds.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Mapping, Sequence, TypeVar

import numpy as np

from .constants import FALL_EXTENSION

__all__ = ["FALL_EXTENSION", "past_critical", "fall_under_way", "finish_fall"]

#: The critical angles of a scene: (direction +1 / -1, devices intact) -> angle [rad] > 0, inf
#: where the potential has no maximum before the fall angle
#: (:attr:`rockbench.analytic.reference.Reference.critical`).
Critical = Mapping[tuple[int, bool], float]

R = TypeVar("R")


def past_critical(phi: Any, intact: Any, critical: Critical) -> Any:
    """Whether the rotation ``phi`` [rad] with the devices ``intact`` is past the critical angle
    of its direction and device state: s phi > ``critical[(s, intact)]`` with s the sign of
    phi (an infinite critical angle is never passed). ``phi`` and ``intact`` are numbers or
    arrays (broadcast against each other): a bool for numbers, a boolean mask for arrays."""
    ph = np.asarray(phi, dtype=float)
    on = np.asarray(intact, dtype=bool)
    out = np.zeros(np.broadcast(ph, on).shape, dtype=bool)
    finite = [c for c in critical.values() if math.isfinite(c)]
    # the common case: |phi| at or below every critical angle (one reduction, no mask)
    if finite and ph.size and float(np.abs(ph).max()) > min(finite):
        for s in (1, -1):
            for flag in (True, False):
                c = critical[(s, flag)]
                if math.isfinite(c):
                    out |= (s * ph > c) & (on == flag)
    return bool(out) if out.ndim == 0 else out


def fall_under_way(status: Any, overturned: Any, phi: Any, intact: Any, critical: Critical, *,
                   motion_over: Any = True) -> Any:
    """Whether a run ended with its fall under way: status "ok", not overturned, the ground
    motion over (``motion_over``: the run's end at or after the motion's end; free rocking has
    no motion) and its last state (``phi`` [rad], devices ``intact``) past the critical angle
    (:func:`past_critical`). Numbers give a bool; arrays (a map's cells) a mask."""
    out = ((np.asarray(status) == "ok") & ~np.asarray(overturned, dtype=bool)
           & np.asarray(motion_over, dtype=bool) & past_critical(phi, intact, critical))
    return bool(out) if np.ndim(out) == 0 else out


def finish_fall(runs: Sequence[R], under_way: Sequence[bool],
                run_longer: Callable[[list[int], float], Sequence[R]],
                fell: Callable[[R], bool]) -> tuple[list[R], dict[int, R]]:
    """THE policy for a fall under way at the end of a run, for one run or many (a map's cells):
    every run ``i`` with ``under_way[i]`` (:func:`fall_under_way`; an engine's stopped run: its
    last sample :func:`past_critical`) is run :data:`~rockbench.constants.FALL_EXTENSION`
    seconds longer - ``run_longer(indices, extension)`` returns those runs ``extension``
    seconds longer, from their start or continued from their last state. A longer run that fell
    (``fell(run)``) replaces its run: the fall is finished. One that did not leaves the run as
    it was (its verdict stands: survived).

    Returns (the runs, {index: the longer run} of every run run longer, whose cost is part of
    the verdict's)."""
    out = list(runs)
    which = [i for i, u in enumerate(under_way) if u]
    if not which:
        return out, {}
    longer = dict(zip(which, run_longer(which, FALL_EXTENSION)))
    for i, r in longer.items():
        if fell(r):
            out[i] = r
    return out, longer

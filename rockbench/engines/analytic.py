"""The analytic SDOF reference as a backend (see :mod:`rockbench.analytic.solver`)."""

from __future__ import annotations

import math
from typing import ClassVar

import scipy

from ..analytic.reference import reference_of
from ..analytic.solver import AnalyticSettings, simulate
from .._jit import CpuClock
from ..constants import FALL_EXTENSION
from ..result import Result
from .base import Backend, run_window

__all__ = ["AnalyticBackend"]


class AnalyticBackend(Backend):
    """Event-driven integration of the paper's equation of motion (the reference)."""

    name: ClassVar[str] = "analytic"
    package: ClassVar[str] = "scipy"
    Settings: ClassVar[type] = AnalyticSettings

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        return True, f"scipy {scipy.__version__}"

    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0) -> Result:
        """Integrate from ``phi0`` [rad] for ``duration`` [s] (default: the motion + 10 s).

        A run that ends after the ground motion past its critical angle, not yet fallen, is
        integrated :data:`~rockbench.constants.FALL_EXTENSION` seconds longer: if it falls, the
        longer run is returned (its history ends at the fall, after ``duration``), so that the
        reference and the engines' collapse rule give one verdict (``docs/conventions.md``)."""
        t0, t_end = run_window(self.scene, motion, duration, phi0, settings=self.settings)
        with CpuClock() as clock:
            if _compiled_path(self.settings.method, motion):   # the numba path (maps, records)
                from ..analytic.compiled import simulate_compiled as integrate
            else:                                              # the solve_ivp reference
                integrate = simulate
            ref = reference_of(self.scene)
            result = integrate(self.scene, motion, duration=t_end - t0, phi0=phi0,
                               settings=self.settings, reference=ref)
            if _fall_under_way(result, ref, motion, t_end):
                # the run ended after the ground motion past the critical angle: the fall is
                # finished (one verdict rule for every backend, docs/conventions.md)
                longer = integrate(self.scene, motion, duration=t_end - t0 + FALL_EXTENSION,
                                   phi0=phi0, settings=self.settings, reference=ref)
                if longer.summary.overturned:
                    result = longer
        result.cost.cpu_s, result.cost.compile_cpu_s = clock.cpu_s, clock.compile_s
        return result


def _fall_under_way(result: Result, ref, motion, t_end: float) -> bool:
    """Whether an ok run that did not overturn ended at or after the end of the ground motion
    (``t_end`` [s]; free rocking has none) with |phi| past the critical angle of its direction
    and device state: nothing can bring it back, it is falling."""
    s = result.summary
    if s.status != "ok" or s.overturned or not s.exceeded_critical or result.history.empty:
        return False
    if motion is not None and t_end < float(motion.t_end):
        return False                   # the ground may still bring it back: undecided
    last = result.history.iloc[-1]
    phi = float(last["phi"])
    side = 1 if phi > 0 else -1
    crit = ref.critical[(side, bool(last["devices_intact"]))]
    return math.isfinite(crit) and side * phi > crit


def _compiled_path(method: str, motion) -> bool:
    """Whether a run takes the compiled path: ``method`` "compiled", or "auto" (the default)
    for a record when numba imports (a record costs ~60 x more on solve_ivp; both paths agree
    on every well-conditioned quantity, docs/reproducibility.md). Pulses and free rocking stay
    on solve_ivp under "auto"."""
    if method != "auto":
        return method == "compiled"
    from ..scene.motion import Record
    if not isinstance(motion, Record):
        return False
    from ..analytic.kernels import NUMBA_AVAILABLE
    return NUMBA_AVAILABLE

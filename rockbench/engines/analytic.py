"""The analytic SDOF reference as a backend (see :mod:`rockbench.analytic.solver`)."""

from __future__ import annotations

import time
from typing import ClassVar

import scipy

from ..analytic.reference import reference_of
from ..analytic.solver import AnalyticSettings, simulate
from ..result import Result
from .base import Backend, run_window

__all__ = ["AnalyticBackend"]


class AnalyticBackend(Backend):
    """Event-driven integration of the paper's equation of motion (the reference)."""

    name: ClassVar[str] = "analytic"
    package: ClassVar[str] = "scipy"
    Settings: ClassVar[type] = AnalyticSettings

    @classmethod
    def available(cls) -> tuple[bool, str]:
        return True, f"scipy {scipy.__version__}"

    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0) -> Result:
        t0, t_end = run_window(self.scene, motion, duration, phi0, settings=self.settings)
        cpu = time.process_time()
        if _compiled_path(self.settings.method, motion):   # the numba path (maps, records)
            from ..analytic.compiled import simulate_compiled as integrate
        else:                                              # the solve_ivp reference
            integrate = simulate
        result = integrate(self.scene, motion, duration=t_end - t0, phi0=phi0,
                           settings=self.settings, reference=reference_of(self.scene))
        result.cost.cpu_s = time.process_time() - cpu
        return result


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

"""The analytic SDOF reference as a backend (see :mod:`rockbench.analytic.solver`)."""

from __future__ import annotations

from typing import ClassVar

import scipy

from ..analytic.reference import reference_of
from ..analytic.solver import AnalyticSettings, simulate
from .._jit import CpuClock
from ..errors import ParameterError
from ..result import Result
from ..verdict import fall_under_way, finish_fall
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

    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0,
            keep: str = "all") -> Result:
        """Integrate from ``phi0`` [rad] for ``duration`` [s] (default:
        :func:`rockbench.run_length.run_length`, the motion + 10 s). ``keep``: "all" only (the
        reference keeps its whole Result: every metric is measured against its history).

        A run that ends after the ground motion with its fall under way (past its critical
        angle, not yet fallen) is finished by :func:`rockbench.verdict.finish_fall`: run
        :data:`~rockbench.constants.FALL_EXTENSION` seconds longer, the longer run is returned
        if it falls (its history ends at the fall, after ``duration``), so that the reference
        and the engines' collapse rule give one verdict (``docs/conventions.md``)."""
        if keep != "all":
            raise ParameterError("keep", keep, "'all' for the analytic reference (its whole "
                                               "Result)")
        t0, t_end = run_window(self.scene, motion, duration, phi0, settings=self.settings)
        with CpuClock() as clock:
            if _compiled_path(self.settings.method, motion):   # the numba path (maps, records)
                from ..analytic.compiled import simulate_compiled as integrate
            else:                                              # the solve_ivp reference
                integrate = simulate
            ref = reference_of(self.scene)
            result = integrate(self.scene, motion, duration=t_end - t0, phi0=phi0,
                               settings=self.settings, reference=ref)
            # a fall under way at the end is finished (rockbench.verdict: one rule for every
            # backend, docs/conventions.md)
            (result,), _ = finish_fall(
                [result], [_fall_under_way(result, ref, motion, t_end)],
                lambda _, extension: [integrate(self.scene, motion,
                                                duration=t_end - t0 + extension, phi0=phi0,
                                                settings=self.settings, reference=ref)],
                fell=lambda r: r.summary.overturned)
        result.cost.cpu_s, result.cost.compile_cpu_s = clock.cpu_s, clock.compile_s
        return result


def _fall_under_way(result: Result, ref, motion, t_end: float) -> bool:
    """:func:`rockbench.verdict.fall_under_way` of a run that ends at ``t_end`` [s], read on
    its last history sample."""
    if result.history.empty:
        return False
    s, last = result.summary, result.history.iloc[-1]
    return fall_under_way(s.status, s.overturned, float(last["phi"]),
                          bool(last["devices_intact"]), ref.critical,
                          motion_over=motion is None or t_end >= float(motion.t_end))


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

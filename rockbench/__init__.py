"""rockbench: how far can a general physics engine be trusted for rocking structures, and at
what cost?

The public API (everything else is internal):

>>> import rockbench as rb
>>> scene = rb.load_scene("paper-asymmetric")
>>> pulse = rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure)
>>> result = rb.run(scene, pulse)                      # analytic reference
>>> result.summary.max_abs_phi_over_alpha               # doctest: +SKIP

Conventions (``docs/conventions.md``): SI units and radians; phi is the rotation of the left
(taller) column from rest, positive counterclockwise; dimensionless axes a_g / (g tan alpha) and
omega_g / p with alpha and p of the taller column.
"""

from __future__ import annotations

from typing import Any

from .engines import available_backends, backend_names, engine_info, get_backend
from .errors import ParameterError, RecordError, RockbenchError, SceneError
from .result import Result
from .scene import (Block, Devices, Frame, GroundMotion, Record, RickerPulse, Scene,
                    builtin_scenes, load_record, load_scene, make_pulse)

__version__ = "0.1.0"

__all__ = ["Block", "Frame", "Devices", "Scene", "GroundMotion", "RickerPulse", "Record",
           "Result", "load_scene", "load_record", "builtin_scenes", "make_pulse", "run", "info",
           "get_backend", "backend_names", "available_backends", "engine_info",
           "RockbenchError", "ParameterError", "SceneError", "RecordError", "__version__"]


def run(scene: Scene, motion: GroundMotion | None = None, *, engine: str = "analytic",
        duration: float | None = None, phi0: float = 0.0, settings: Any = None,
        **setting_overrides: Any) -> Result:
    """Simulate ``scene`` under ``motion`` with one backend.

    Parameters
    ----------
    scene : Scene
    motion : GroundMotion or None
        A Ricker pulse or a record; None for free rocking from ``phi0``.
    engine : str
        A registered backend name (``rockbench.backend_names()``).
    duration : float, optional
        Simulated time [s] from the motion's start (default: motion length + 10 s).
    phi0 : float
        Initial rotation [rad] (free rocking).
    settings : the backend's Settings, optional; ``setting_overrides`` replace single fields
        (e.g. ``dt=2e-4``).
    """
    backend = get_backend(engine)(scene, settings, **setting_overrides)
    return backend.run(motion, duration=duration, phi0=phi0)


def info(scene: Scene) -> dict[str, Any]:
    """The analytic constants of ``scene``: alpha [rad], p [rad/s], eta and lambda of both
    directions, critical, fall and fracture angles [rad], masses [kg] (keys as in
    ``rockbench info --json``)."""
    from .analytic.reference import Reference

    return Reference(scene).constants()

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

from .engines import available_backends, backend_names, engine_info, get_backend
from .errors import ParameterError, RecordError, RockbenchError, SceneError
from .result import Result
from .runner import info, run
from .scene import (Block, Devices, Frame, GroundMotion, Record, RickerPulse, Scene,
                    builtin_scenes, load_record, load_scene, make_pulse)

__version__ = "0.1.0"

__all__ = ["Block", "Frame", "Devices", "Scene", "GroundMotion", "RickerPulse", "Record",
           "Result", "load_scene", "load_record", "builtin_scenes", "make_pulse", "run", "info",
           "get_backend", "backend_names", "available_backends", "engine_info",
           "RockbenchError", "ParameterError", "SceneError", "RecordError", "__version__"]

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

Names are imported on first use (PEP 562 ``__getattr__``): ``import rockbench`` and the command
line's ``--help`` load neither pandas, scipy, numba nor any engine; ``rb.run`` loads what a run
needs the first time it is touched.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .errors import ParameterError, RecordError, RockbenchError, SceneError

__version__ = "0.1.0"

#: Public name -> the module (relative to this package) that defines it, imported on first use.
_LAZY: dict[str, str] = {
    **dict.fromkeys(("Block", "Frame", "Devices", "Contact", "Scene", "GroundMotion",
                     "RickerPulse", "Record", "WithVertical", "load_scene", "save_scene",
                     "load_record", "builtin_scenes", "make_pulse"),
                    ".scene"),
    "Result": ".result",
    **dict.fromkeys(("run", "info"), ".runner"),
    **dict.fromkeys(("compare", "Comparison"), ".comparison"),
    **dict.fromkeys(("get_backend", "backend_names", "available_backends", "engine_info"),
                    ".engines"),
    **dict.fromkeys(("plot_history", "plot_map", "plot_work_precision"), ".plotting"),
}

__all__ = ["Block", "Frame", "Devices", "Contact", "Scene", "GroundMotion", "RickerPulse", "Record",
           "WithVertical", "Result", "load_scene", "save_scene", "load_record", "builtin_scenes",
           "make_pulse", "run", "info",
           "compare", "Comparison", "get_backend", "backend_names", "available_backends", "engine_info",
           "RockbenchError", "ParameterError", "SceneError", "RecordError", "plot_history",
           "plot_map", "plot_work_precision", "__version__"]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use (then it is an ordinary attribute)."""
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(where, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # what static tools see (the same names, imported eagerly)
    from .engines import available_backends, backend_names, engine_info, get_backend
    from .plotting import plot_history, plot_map, plot_work_precision
    from .comparison import Comparison, compare
    from .result import Result
    from .runner import info, run
    from .scene import (Block, Contact, Devices, Frame, GroundMotion, Record, RickerPulse,
                        Scene, WithVertical, builtin_scenes, load_record, load_scene,
                        make_pulse, save_scene)

"""Backend registry: name -> "module:Class". Adding an engine is one file and one line here.

Modules are imported lazily, so a missing engine package only affects its own backend.
"""

from __future__ import annotations

import importlib
from typing import Any

from ..errors import BackendUnavailable, ParameterError

#: The registered backends. The analytic reference comes first.
REGISTRY: dict[str, str] = {
    "analytic": "rockbench.engines.analytic:AnalyticBackend",
    "pymunk": "rockbench.engines.pymunk:PymunkBackend",
    "mujoco": "rockbench.engines.mujoco:MujocoBackend",
    "pybullet": "rockbench.engines.pybullet:PybulletBackend",
    "opensees": "rockbench.engines.opensees:OpenseesBackend",
}

__all__ = ["REGISTRY", "get_backend", "backend_names", "available_backends", "engine_info"]


def backend_names() -> list[str]:
    return list(REGISTRY)


def get_backend(name: str):
    """The backend class registered as ``name`` (raises ParameterError for unknown names,
    BackendUnavailable when its module cannot be imported)."""
    if name not in REGISTRY:
        raise ParameterError("engine", name, f"one of {', '.join(REGISTRY)}")
    mod, cls = REGISTRY[name].split(":")
    try:
        module = importlib.import_module(mod)
    except ImportError as e:
        raise BackendUnavailable(f"backend {name!r} cannot be imported: {e}") from None
    return getattr(module, cls)


def engine_info() -> list[dict[str, Any]]:
    """One row per registered backend: name, whether it imports, engine version or reason."""
    rows = []
    for name in REGISTRY:
        try:
            ok, info = get_backend(name).available()
        except BackendUnavailable as e:
            ok, info = False, str(e)
        rows.append({"name": name, "available": ok, "version" if ok else "reason": info})
    return rows


def available_backends() -> list[str]:
    """Names of the backends that can run on this machine."""
    return [r["name"] for r in engine_info() if r["available"]]

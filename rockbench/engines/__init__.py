"""Backend registry: name -> "module:Class". Adding an engine is one file and one line here.

Modules are imported lazily, so a missing engine package only affects its own backend, and an
engine is imported only when it is used: :func:`get_backend` imports the adapter module (which
imports no engine), the adapter's ``available()`` or a run imports the engine. What must not
import every engine - a store's fingerprint, a map's inputs - asks :func:`engine_versions`
(installed package versions, read from the package metadata) or ``engine_info([name])``.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from typing import Any

from ..errors import BackendUnavailable, ParameterError

#: The registered backends. The analytic reference comes first.
REGISTRY: dict[str, str] = {
    "analytic": "rockbench.engines.analytic:AnalyticBackend",
    "pymunk": "rockbench.engines.pymunk:PymunkBackend",
    "mujoco": "rockbench.engines.mujoco:MujocoBackend",
    "pybullet": "rockbench.engines.pybullet:PybulletBackend",
    "opensees": "rockbench.engines.opensees:OpenseesBackend",
    "drake": "rockbench.engines.drake:DrakeBackend",
}

__all__ = ["REGISTRY", "get_backend", "backend_names", "available_backends", "engine_info",
           "engine_versions"]


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


def engine_info(names: Iterable[str] | None = None) -> list[dict[str, Any]]:
    """One row per backend of ``names`` (default: every registered one, which imports every
    engine): name, whether it imports, engine version or reason."""
    rows = []
    for name in REGISTRY if names is None else names:
        try:
            ok, info = get_backend(name).available()
        except BackendUnavailable as e:
            ok, info = False, str(e)
        rows.append({"name": name, "available": ok, "version" if ok else "reason": info})
    return rows


def engine_versions() -> dict[str, str | None]:
    """Backend name -> ``"<distribution> <version>"`` of its installed engine package (None
    when not installed), from the package metadata: no engine is imported."""
    from importlib import metadata

    out: dict[str, str | None] = {}
    for name in REGISTRY:
        try:
            dist = getattr(get_backend(name), "package", name)
        except BackendUnavailable:
            dist = name
        try:
            out[name] = f"{dist} {metadata.version(dist)}"
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def available_backends() -> list[str]:
    """Names of the backends that can run on this machine (imports every engine)."""
    return [r["name"] for r in engine_info() if r["available"]]

"""Backend registry: name -> "module:Class". Adding an engine is one adapter file (the contract:
:mod:`rockbench.engines.base`) and either one line in :data:`REGISTRY` (an engine of this
package) or, from outside the package, an entry point of the group :data:`ENTRY_POINT_GROUP`
in the adapter's own distribution::

    [project.entry-points."rockbench.engines"]
    myengine = "my_package.adapter:MyBackend"

Every caller (run, compare, map, tradeoff, advise, stress, fragility, the report) asks this
registry, so a registered engine reaches all of them with no other edit.

Modules are imported lazily, so a missing engine package only affects its own backend, and an
engine is imported only when it is used: :func:`get_backend` imports the adapter module (which
imports no engine), the adapter's ``available()`` or a run imports the engine. What must not
import every engine - a store's fingerprint, a map's inputs - asks :func:`engine_versions`
(installed package versions, read from the package metadata) or ``engine_info([name])``.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Iterable
from typing import Any

from ..errors import BackendUnavailable, ParameterError
from ..registry import ENTRY_POINT_GROUP, REGISTRY, discover_engines

__all__ = ["REGISTRY", "ENTRY_POINT_GROUP", "discover_engines", "REQUIRE_ENV", "get_backend",
           "backend_names", "available_backends", "engine_info", "engine_versions", "engine_states", "required_engines",
           "check_required", "unavailable_lines", "ENGINE_STATES"]

#: Environment variable naming engines that must be available (comma-separated names, or
#: "all"): where one of them is not, :func:`available_backends` and :func:`check_required`
#: raise instead of leaving it out (CI sets it, so a missing engine turns CI red).
REQUIRE_ENV = "ROCKBENCH_REQUIRE_ENGINES"


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


def _status(name: str) -> tuple[bool, str, str]:
    """(available, version or reason, remedy) of a registered backend; the probe runs once
    per process (:meth:`rockbench.engines.base.Backend.available`)."""
    try:
        cls = get_backend(name)
    except BackendUnavailable as e:
        return False, str(e), f"pip install 'rockbench[{name}]'"
    ok, info = cls.available()
    return ok, info, "" if ok else cls.remedy(info)


def engine_info(names: Iterable[str] | None = None) -> list[dict[str, Any]]:
    """One row per backend of ``names`` (default: every registered one, which imports every
    engine): name, whether it imports, and its engine version or the reason and the remedy.
    Each engine's answer is decided once per process."""
    rows = []
    for name in REGISTRY if names is None else names:
        ok, info, remedy = _status(name)
        row: dict[str, Any] = {"name": name, "available": ok}
        if ok:
            row["version"] = info
        else:
            row.update(reason=info, remedy=remedy)
        rows.append(row)
    return rows


def engine_versions() -> dict[str, str | None]:
    """Backend name -> ``"<distribution> <version>"`` of its installed engine package (None
    when not installed), from the package metadata: no engine is imported."""
    from importlib import metadata

    out: dict[str, str | None] = {}
    for name in REGISTRY:
        try:
            dist = get_backend(name).package or name
        except BackendUnavailable:
            dist = name
        try:
            out[name] = f"{dist} {metadata.version(dist)}"
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def required_engines() -> list[str]:
    """The engines :data:`REQUIRE_ENV` names (empty when it is unset): "all" is every
    registered backend. An unknown name is an error naming the variable."""
    text = os.environ.get(REQUIRE_ENV, "").strip()
    if not text:
        return []
    if text.lower() == "all":
        return list(REGISTRY)
    names = [n.strip() for n in text.split(",") if n.strip()]
    for n in names:
        if n not in REGISTRY:
            raise ParameterError(REQUIRE_ENV, text,
                                 f"'all' or comma-separated names among {', '.join(REGISTRY)}")
    return names


def unavailable_lines(names: Iterable[str] | None = None) -> list[str]:
    """One line per backend of ``names`` (default: every registered one) that cannot run
    here: its name, why, and the remedy."""
    return [f"{r['name']}: {r['reason']}; remedy: {r['remedy']}"
            for r in engine_info(names) if not r["available"]]


def check_required() -> None:
    """Raise :class:`~rockbench.errors.BackendUnavailable` naming every engine that
    :data:`REQUIRE_ENV` requires and that cannot run here (with why and the remedy)."""
    req = required_engines()
    lines = unavailable_lines(req) if req else []
    if lines:
        raise BackendUnavailable(f"{REQUIRE_ENV} requires engines that cannot run here: "
                                 + " | ".join(lines))


def available_backends() -> list[str]:
    """Names of the backends that can run on this machine (imports every engine; decided once
    per process). Raises when an engine that :data:`REQUIRE_ENV` requires is missing."""
    check_required()
    return [r["name"] for r in engine_info() if r["available"]]


#: The state of a registered engine in a run or report (:func:`engine_states`).
ENGINE_STATES = {
    "ran": "selected and available: it ran",
    "not installed": "its engine does not import here (the reason and the remedy say why)",
    "left out": "available, but not selected (--engine)",
}


def engine_states(selected: Iterable[str] | None = None) -> list[dict[str, Any]]:
    """Every registered backend with its state for a run of ``selected`` (None: every
    available one): ``name``, ``state`` (a key of :data:`ENGINE_STATES`), ``detail`` (the
    version; or why it is not installed and the remedy; or the option that left it out)."""
    chosen = None if selected is None else set(selected)
    out = []
    for r in engine_info():
        if not r["available"]:
            out.append({"name": r["name"], "state": "not installed",
                        "detail": f"{r['reason']}; remedy: {r['remedy']}"})
        elif chosen is not None and r["name"] not in chosen:
            out.append({"name": r["name"], "state": "left out",
                        "detail": "not selected (--engine)"})
        else:
            out.append({"name": r["name"], "state": "ran", "detail": r["version"]})
    return out

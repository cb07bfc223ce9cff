"""A scene: the structure, its devices and run-independent options, validated once.

Scenes are data: TOML files (built-in ones in ``rockbench/scenarios/``) of the form::

    kind = "scene"              # optional: what the file is
    name = "paper-asymmetric-hybrid-eps1"
    version = 1
    description = "..."
    [structure]                 # required, with its type
    type = "frame"              # or "block"
    column_height_right = 5.6   # any Frame / Block parameter; omitted ones take their defaults
    [devices]                   # optional, frames only
    tendon_stiffness = 23.5e6
    fracture_strain = 0.01      # omit for no fracture

Any parameter can be overridden with ``key=value`` strings (``span=9``, ``structure.span=9``,
``devices.fracture_strain=none``, ``fall_angle=1.2``).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields, replace
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

from ..errors import ParameterError, SceneError, check_range
from .devices import Devices
from .structure import Block, Frame

__all__ = ["Scene", "load_scene", "builtin_scenes", "apply_overrides"]

_STRUCTURES = {"block": Block, "frame": Frame}


@dataclass(frozen=True)
class Scene:
    """A structure, its (optional) devices, and options shared by every backend.

    Parameters
    ----------
    structure : Block or Frame
    devices : Devices or None
        Tendons and dampers (frames only). None for a free-standing structure.
    name, description : str
    fall_angle : float or None
        |phi| [rad] at which a run reports ``overturned`` (and may stop). None: for each rocking
        direction min(pi/2, 0.98 x the mechanism's geometric limit).
    """

    structure: Block | Frame
    devices: Devices | None = None
    name: str = "custom"
    description: str = ""
    fall_angle: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.structure, (Block, Frame)):
            raise ParameterError("structure", type(self.structure).__name__, "a Block or a Frame")
        if self.devices is not None and not isinstance(self.structure, Frame):
            raise ParameterError("devices", "given", "absent for a block",
                                 "tendons and dampers are defined for the frame only")
        if self.devices is not None and not isinstance(self.devices, Devices):
            raise ParameterError("devices", type(self.devices).__name__, "a Devices or None")
        if self.fall_angle is not None:
            object.__setattr__(self, "fall_angle", check_range(
                "fall_angle", self.fall_angle, 0.0, math.pi, lo_open=True))
        if isinstance(self.structure, Frame):
            from .mechanism import geometric_limit, mechanism
            lims = {s: geometric_limit(mechanism(self.structure, s)) for s in (1, -1)}
            if min(lims.values()) < self.structure.alpha:
                raise ParameterError(
                    "structure", "this frame geometry",
                    "a frame whose three-block rocking mechanism holds up to |phi| >= alpha = "
                    f"{self.structure.alpha:.4g} rad",
                    f"it ends at {lims[1]:.4g} rad counterclockwise, {lims[-1]:.4g} rad "
                    "clockwise: a column would rotate against the beam, which would then bear "
                    "on the column's other top corner (a squat frame with very unequal columns)")

    # --- derived, shared by all backends --------------------------------------------------
    @property
    def alpha(self) -> float:
        """Slenderness of the taller column [rad]."""
        return self.structure.alpha

    @property
    def p(self) -> float:
        """Frequency parameter of the taller column [rad/s]."""
        return self.structure.p

    @property
    def is_frame(self) -> bool:
        return isinstance(self.structure, Frame)

    @property
    def has_devices(self) -> bool:
        d = self.devices
        return d is not None and (d.has_tendons or d.has_dampers)

    @cached_property
    def fall_angles(self) -> dict[int, float]:
        """Fall angle [rad] for each rocking direction (+1, -1): ``fall_angle`` if given, else
        0.98 x min(pi/2, the mechanism's geometric limit) for every structure and backend.

        The limit is pi/2 for a block lying flat on its side (its geometric limit is pi) and
        the toggle of the four-bar linkage for a frame; the 2 % margin keeps the fall angle
        clearly below the pose a body can only pass by penetrating the ground, so an engine's
        overturn is detected before the body lands (docs/conventions.md).
        """
        if self.fall_angle is not None:
            return {1: self.fall_angle, -1: self.fall_angle}
        from .mechanism import geometric_limit, mechanism
        return {s: 0.98 * min(math.pi / 2, geometric_limit(mechanism(self.structure, s)))
                for s in (1, -1)}

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name, "description": self.description,
                             "structure": self.structure.to_dict()}
        if self.devices is not None:
            d["devices"] = self.devices.to_dict()
        if self.fall_angle is not None:
            d["fall_angle"] = self.fall_angle
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "<dict>") -> "Scene":
        """Build a validated scene from the TOML structure described in the module docstring.

        A scene states what it is: the ``[structure]`` table and its ``type`` ("frame" or
        "block") are required; ``[devices]`` is optional. Unknown or missing tables and keys,
        and tables that are not tables, raise :class:`SceneError` naming them and ``source``.
        """
        if not isinstance(data, Mapping):
            raise SceneError(f"{source}: a scene is a table of keys (name, description, "
                             f"[structure], [devices], fall_angle), not {type(data).__name__}")
        allowed = {"kind", "name", "version", "description", "structure", "devices",
                   "fall_angle"}
        if data.get("kind", "scene") != "scene":
            raise SceneError(f"{source}: kind = {data['kind']!r}: not a scene file (a scene "
                             "file has kind = \"scene\" or no kind)")
        unknown = set(data) - allowed
        if unknown:
            raise SceneError(f"{source}: unknown top-level key(s) {sorted(unknown)}; "
                             f"allowed: {sorted(allowed)}")
        for key in ("name", "description"):
            if key in data and not isinstance(data[key], str):
                raise SceneError(f"{source}: {key} must be a string, got {data[key]!r}")
        if "version" in data and (isinstance(data["version"], bool)
                                  or not isinstance(data["version"], int)):
            raise SceneError(f"{source}: version must be an integer, got {data['version']!r}")
        devices = None
        if data.get("devices") is not None:
            if not isinstance(data["devices"], Mapping):
                raise SceneError(f"{source}: [devices] must be a table of device parameters, "
                                 f"got {data['devices']!r}")
            dv = dict(data["devices"])
            _check_keys(f"{source} [devices]", dv, Devices)
            devices = Devices(**dv)
        kinds = " or ".join(repr(k) for k in sorted(_STRUCTURES, reverse=True))
        if "structure" not in data:
            raise SceneError(f"{source}: no [structure] table; a scene states what it is: "
                             f"[structure] with type = {kinds} and its parameters")
        if not isinstance(data["structure"], Mapping):
            raise SceneError(f"{source}: [structure] must be a table with type = {kinds}, "
                             f"got {data['structure']!r}")
        st = dict(data["structure"])
        if "type" not in st:
            raise SceneError(f"{source} [structure]: no type; give type = {kinds}")
        kind = st.pop("type")
        if not isinstance(kind, str) or kind not in _STRUCTURES:
            raise ParameterError("structure.type", kind, f"one of {sorted(_STRUCTURES)}")
        cls_ = _STRUCTURES[kind]
        _check_keys(f"{source} [structure]", st, cls_)
        structure = cls_(**st)
        return cls(structure=structure, devices=devices, name=str(data.get("name", "custom")),
                   description=str(data.get("description", "")),
                   fall_angle=data.get("fall_angle"))

    def replace(self, **changes: Any) -> "Scene":
        return replace(self, **changes)


def _check_keys(where: str, d: Mapping[str, Any], cls_) -> None:
    """Refuse unknown keys, and values that are not numbers (a string, boolean, array, table
    or date where a number [SI] belongs), naming the key."""
    names = {f.name for f in fields(cls_)}
    bad = set(d) - names
    if bad:
        raise SceneError(f"{where}: unknown parameter(s) {sorted(bad)}; known: {sorted(names)}")
    for key, value in d.items():
        if value is not None and (isinstance(value, bool)
                                  or not isinstance(value, (int, float))):
            raise SceneError(f"{where}: {key} = {value!r} is a {type(value).__name__}, "
                             "not a number")


def _scenario_dir():
    return resources.files("rockbench") / "scenarios"


def builtin_scenes() -> dict[str, str]:
    """Names of the built-in scenes mapped to their one-line descriptions (TOML files of
    ``rockbench/scenarios`` whose ``kind`` is "scene" or absent: ``cases.toml`` is not one)."""
    out = {}
    for f in sorted(_scenario_dir().iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            data = tomllib.loads(f.read_text())
            if data.get("kind", "scene") == "scene":
                out[f.name[:-5]] = data.get("description", "")
    return out


def _parse_value(raw: str) -> Any:
    low = raw.strip().lower()
    if low in ("none", "null", ""):
        return None
    if low in ("block", "frame"):
        return low
    try:
        return float(raw)
    except ValueError:
        raise SceneError(f"cannot parse value {raw!r}: expected a number or 'none'") from None


def apply_overrides(data: dict[str, Any], overrides: Mapping[str, Any] | None) -> dict[str, Any]:
    """Return a copy of scene ``data`` with ``key=value`` overrides applied.

    Keys may be dotted (``devices.damping``) or bare (``damping``), in which case the table is
    found from the parameter name. Values may be strings (parsed) or numbers.
    """
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    if not overrides:
        return out
    frame_keys = {f.name for f in fields(Frame)} | {f.name for f in fields(Block)} | {"type"}
    dev_keys = {f.name for f in fields(Devices)}
    if not isinstance(overrides, Mapping):
        raise ParameterError("overrides", overrides, "a dict of key=value scene overrides")
    for key, raw in overrides.items():
        if not isinstance(key, str):
            raise SceneError(f"scene override key {key!r} is not a string")
        value = _parse_value(raw) if isinstance(raw, str) else raw
        if "." in key:
            table, name = key.split(".", 1)
        elif key in ("fall_angle", "name", "description"):
            table, name = "", key
        elif key in dev_keys:
            table, name = "devices", key
        elif key in frame_keys:
            table, name = "structure", key
        elif key == "devices":
            table, name = "", key
        else:
            raise SceneError(f"unknown scene parameter {key!r}; known: "
                             f"{sorted(frame_keys | dev_keys | {'fall_angle', 'devices'})}")
        if table == "":
            if key == "devices" and value is None:
                out["devices"] = None
            else:
                out[name] = value
        elif table in ("structure", "devices"):
            tbl = out.get(table) or {}
            if not isinstance(tbl, dict):
                raise SceneError(f"[{table}] is {tbl!r}, not a table: cannot apply override "
                                 f"{key!r}")
            if value is None and name != "fracture_strain":
                tbl.pop(name, None)
            else:
                tbl[name] = value
            out[table] = tbl
        else:
            raise SceneError(f"unknown scene table {table!r} in override {key!r}")
    return out


def load_scene(name_or_path: str | Path, overrides: Mapping[str, Any] | None = None) -> Scene:
    """Load a built-in scene by name, or a TOML file by path, and apply ``overrides``."""
    if not isinstance(name_or_path, (str, Path)):
        raise ParameterError("scene", name_or_path, "a built-in scene name or a path to a "
                             ".toml file")
    p = Path(name_or_path)
    try:
        is_path = p.suffix == ".toml" or p.exists()
        is_file = is_path and p.is_file()
    except (OSError, ValueError) as e:
        raise SceneError(f"scene {str(name_or_path)[:80]!r} is neither a built-in scene name nor "
                         f"a readable file: {e}") from None
    if is_path:
        if not is_file:
            raise SceneError(f"scene file {str(p)!r} does not exist")
        try:
            text, source = p.read_text(encoding="utf-8"), str(p)
        except (OSError, UnicodeDecodeError) as e:
            raise SceneError(f"cannot read scene file {str(p)!r}: "
                             f"{getattr(e, 'strerror', None) or e}") from None
    else:
        f = _scenario_dir() / f"{name_or_path}.toml"
        if not f.is_file():
            raise SceneError(f"unknown scene {str(name_or_path)!r}; built-in scenes: "
                             f"{', '.join(builtin_scenes())} (or give a path to a .toml file)")
        text, source = f.read_text(), f"{name_or_path}"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{source}: not valid TOML: {e}") from None
    data = apply_overrides(data, overrides)
    return Scene.from_dict(data, source=source)

"""A scene: the structure, its devices and run-independent options, validated once.

Scenes are data: TOML files (built-in ones in ``rockbench/scenarios/``) of the form::

    kind = "scene"              # optional: what the file is
    name = "paper-asymmetric-hybrid-eps1"
    version = 1
    description = "..."
    [structure]                 # required, with its type
    type = "frame"              # or "block"
    column_width = 1.0          # every required field of the type; docs/scenes.md
    ...
    [devices]                   # optional, frames only: all four fields
    tendon_stiffness = 23.5e6
    tendon_length = 8.5
    fracture_strain = 0.01      # or "none"
    damping = 25.3e6
    [contact]                   # optional: Coulomb friction (rockbench.scene.contact)
    friction = 0.4              # base contacts; left out: each engine's default, no sliding
    beam_friction = 0.6         # frames only: the beam on its columns (default: friction)

Every field, its unit, range and default: ``docs/scenes.md`` (generated from
:mod:`rockbench.scene.schema`). A required field left out is refused (one line naming it);
``preset = "paper"`` takes the fields left out from the paper's frame on purpose.

Any parameter can be overridden with ``key=value`` strings (``span=9``, ``structure.span=9``,
``devices.fracture_strain=none``, ``fall_angle=1.2``, ``contact.friction=0.3``).
:func:`load_scene` is the one resolver of a scene argument: a built-in name, a path, or a :class:`Scene` (returned as it is, or with the
overrides applied). :meth:`Scene.to_toml` and :func:`save_scene` write a scene back.
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from dataclasses import dataclass, fields, replace
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

from ..errors import ParameterError, SceneError, check_range
from ..limits import LIMITS, check_in_limit, override_hint
from ..values import parse_value
from .contact import Contact
from .devices import Devices
from .schema import fields_of, required
from .structure import Block, Frame

__all__ = ["Scene", "load_scene", "save_scene", "builtin_scenes", "apply_overrides",
           "restitution"]

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
    contact : Contact
        The contacts' Coulomb friction (:class:`~rockbench.scene.contact.Contact`); the default
        gives none (each engine's own, the rocking model's non-sliding pivots).
    """

    structure: Block | Frame
    devices: Devices | None = None
    name: str = "custom"
    description: str = ""
    fall_angle: float | None = None
    contact: Contact = Contact()

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
        if not isinstance(self.contact, Contact):
            raise ParameterError("contact", type(self.contact).__name__,
                                 "a rockbench.scene.contact.Contact")
        if self.contact.beam_friction is not None and not isinstance(self.structure, Frame):
            raise ParameterError("contact.beam_friction", self.contact.beam_friction,
                                 "absent for a block",
                                 "beam_friction is the beam on its columns' top corners, "
                                 "frames only")
        _check_ranges(self.structure, self.devices)
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
        _check_rocks(self.structure)

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
    def mirror_symmetric(self) -> bool:
        """True when the structure is its own mirror image: a block, or a frame with equal
        columns (its devices, defined per column alike, then mirror too). Its response to a
        reversed horizontal ground motion is then the mirror image (phi -> -phi) of its
        response to the motion: the same overturning verdict, peak |phi|, impacts and
        fracture (the analytic maps use it: docs/maps.md)."""
        st = self.structure
        return isinstance(st, Block) or (isinstance(st, Frame) and st.symmetric)

    @property
    def friction(self) -> float | None:
        """The Coulomb friction coefficient [-] of the base contacts the scene gives
        (``contact.friction``), or None: not given (each engine's default)."""
        return self.contact.friction

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
        if self.contact.given:
            d["contact"] = self.contact.to_dict()
        return d

    def to_toml(self) -> str:
        """The scene as a scene file (TOML): every field it holds, written out; optional
        fields at their default are left out. ``load_scene`` of the file gives back an equal
        scene (:func:`save_scene`)."""
        lines = ['kind = "scene"', f"name = {_toml_str(self.name)}",
                 f"description = {_toml_str(self.description)}"]
        if self.fall_angle is not None:
            lines.append(f"fall_angle = {_toml_num(self.fall_angle)}")
        lines += ["", "[structure]", f'type = "{self.structure.kind}"']
        st = self.structure.to_dict()
        lines += [f"{f.name} = {_toml_num(st[f.name])}" for f in fields_of(self.structure.kind)
                  if f.name in st]
        if self.devices is not None:
            dv = self.devices.to_dict()
            lines += ["", "[devices]"]
            lines += [f"{f.name} = " + ('"none"' if dv[f.name] is None else _toml_num(dv[f.name]))
                      for f in fields_of("devices")]
        if self.contact.given:
            ct = self.contact.to_dict()
            lines += ["", "[contact]"]
            lines += [f"{f.name} = {_toml_num(ct[f.name])}" for f in fields_of("contact")
                      if f.name in ct]
        return "\n".join(lines) + "\n"

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str = "<dict>") -> "Scene":
        """Build a validated scene from the TOML structure described in the module docstring.

        A scene states what it is: the ``[structure]`` table and its ``type`` ("frame" or
        "block") are required; ``[devices]`` is optional. Unknown or missing tables and keys,
        and tables that are not tables, raise :class:`SceneError` naming them and ``source``.
        """
        if not isinstance(data, Mapping):
            raise SceneError(f"{source}: a scene is a table of keys (name, description, "
                             f"[structure], [devices], [contact], fall_angle), not "
                             f"{type(data).__name__}")
        allowed = {"kind", "name", "version", "description", "structure", "devices",
                   "fall_angle", "preset", "contact"}
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
        preset = data.get("preset")
        if preset is not None and (not isinstance(preset, str) or preset not in _PRESETS):
            raise SceneError(f"{source}: preset = {preset!r}: the presets are "
                             f"{', '.join(repr(p) for p in _PRESETS)} (or leave preset out)")
        devices = None
        st_table = data.get("structure")
        if data.get("devices") is not None:
            if not isinstance(data["devices"], Mapping):
                raise SceneError(f"{source}: [devices] must be a table of device parameters, "
                                 f"got {data['devices']!r}")
            dv = dict(data["devices"])
            _check_keys(f"{source} [devices]", dv, Devices)
            if isinstance(st_table, Mapping) and st_table.get("type") == "block":
                raise ParameterError("devices", "given", "absent for a block",
                                     f"{source}: tendons and dampers are defined for the frame "
                                     "only")
            if preset is not None:
                dv = {**_preset(preset, "devices"), **dv}
            if isinstance(dv.get("fracture_strain"), str):
                if dv["fracture_strain"].strip().lower() != "none":
                    raise SceneError(f"{source} [devices]: fracture_strain = "
                                     f"{dv['fracture_strain']!r}: a number in (0, 1), or "
                                     '"none" for tendons that never fracture')
                dv["fracture_strain"] = None
            _check_required(f"{source} [devices]", dv, "devices")
            _check_values("devices", dv)
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
        if preset is not None:
            if kind != "frame":
                raise SceneError(f"{source}: preset = {preset!r} is the paper's frame; a "
                                 f"{kind} takes no preset (give its fields)")
            base = _preset(preset, "structure")
            if "beam_mass" in st or "mass_ratio" in st:   # the beam's mass is given one way
                base = {k: v for k, v in base.items() if k not in ("beam_mass", "mass_ratio")}
            st = {**base, **st}
        st = {k: v for k, v in st.items() if v is not None}
        _check_required(f"{source} [structure]", st, kind)
        _check_values(kind, st)       # ranges first: no arithmetic on a 1e-200 m column
        structure = cls_(**st)
        contact = Contact()
        if data.get("contact") is not None:
            if not isinstance(data["contact"], Mapping):
                raise SceneError(f"{source}: [contact] must be a table (friction, "
                                 f"beam_friction), got {data['contact']!r}")
            ct = {k: v for k, v in data["contact"].items() if v is not None}
            _check_keys(f"{source} [contact]", ct, Contact)
            contact = Contact(**ct)
        return cls(structure=structure, devices=devices, name=str(data.get("name", "custom")),
                   description=str(data.get("description", "")),
                   fall_angle=data.get("fall_angle"), contact=contact)

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
        if key == "fracture_strain" and isinstance(value, str):
            continue   # "none": checked by the caller
        if value is not None and (isinstance(value, bool)
                                  or not isinstance(value, (int, float))):
            raise SceneError(f"{where}: {key} = {value!r} is a {type(value).__name__}, "
                             "not a number")


def _check_required(where: str, d: Mapping[str, Any], table: str) -> None:
    """Refuse a table that leaves out a required field, in one line naming it (and any other
    missing one) with its meaning, unit and range."""
    missing = [n for n in required(table) if d.get(n, ...) is ...]
    if not missing:
        return
    f = next(f for f in fields_of(table) if f.name == missing[0])
    also = f" (also missing: {', '.join(missing[1:])})" if missing[1:] else ""
    if table == "devices":
        need = f"a [devices] table gives all of {', '.join(required(table))}"
    else:
        need = f"a {table} needs {', '.join(required(table))}"
    hint = "" if table == "block" else ', or preset = "paper" for the paper\'s values'
    raise SceneError(f"{where}: missing {f.name}: {f.meaning} [{f.unit}], {f.range_text()}"
                     f"{also}; {need} (docs/scenes.md){hint}")


#: preset name -> the built-in scene files its structure and devices come from
_PRESETS = {"paper": ("paper-asymmetric", "paper-asymmetric-hybrid")}


def _preset(name: str, table: str) -> dict[str, Any]:
    """The ``[structure]`` (without its type) or ``[devices]`` table of preset ``name``, read
    from the built-in scene file that states it."""
    scene = _PRESETS[name][0 if table == "structure" else 1]
    data = tomllib.loads((_scenario_dir() / f"{scene}.toml").read_text())
    out = dict(data[table])
    out.pop("type", None)
    return out


def _check_ranges(structure: Block | Frame, devices: Devices | None) -> None:
    """Every field within its physical range (:data:`rockbench.limits.LIMITS`, per
    :mod:`rockbench.scene.schema`), checked before any arithmetic on the fields."""
    for obj, table in ((structure, structure.kind), (devices, "devices")):
        if obj is not None:
            _check_values(table, {f.name: getattr(obj, f.name) for f in fields_of(table)})
    if isinstance(structure, Frame) and structure.beam_mass is not None:
        lo, hi = LIMITS["mass_ratio"].current()
        m = structure.mass_left
        ratio = structure.beam_mass / m
        if not lo <= ratio <= hi:
            raise ParameterError("beam_mass", structure.beam_mass,
                                 f"in [{lo * m:.4g}, {hi * m:.4g}] kg",
                                 f"{lo:g} to {hi:g} x the left column's {m:.4g} kg: "
                                 f"{override_hint('mass_ratio')}")


def _check_values(table: str, values: Mapping[str, Any]) -> None:
    """Each value of ``values`` (fields of ``table``) within its limit, in the schema's order."""
    for f in fields_of(table):
        value = values.get(f.name)
        if f.limit is not None and value is not None:
            check_in_limit(f.limit, f.name, value)


def restitution(structure: Block | Frame, pre: int, post: int) -> float:
    """phi'^+ / phi'^- [-] of an impact from mechanism ``pre`` into mechanism ``post``
    (directions +1 or -1): the projection of the impulse-momentum equations on the
    post-impact mechanism, eta = (j^post . M j^pre) / (j^post . M j^post), with j the bodies'
    velocity Jacobians at rest and M their masses and inertias (paper, Eqs. 22-28, 36; the
    derivation is in :mod:`rockbench.analytic.impact`, which uses this function). For
    ``pre == post`` (no change of pivots) it is 1."""
    from .mechanism import mechanism

    if isinstance(structure, Block):
        mass = ((structure.mass, structure.inertia_cm),)
    else:
        mass = ((structure.mass_left, structure.inertia_left),
                (structure.mass_beam, structure.inertia_beam),
                (structure.mass_right, structure.inertia_right))
    jpre = mechanism(structure, pre).configuration(0.0).bodies
    jpost = mechanism(structure, post).configuration(0.0).bodies
    num = den = 0.0
    for (m, Ic), a, b in zip(mass, jpre, jpost):
        num += m * (a.dx * b.dx + a.dy * b.dy) + Ic * a.dtheta * b.dtheta
        den += m * (b.dx * b.dx + b.dy * b.dy) + Ic * b.dtheta * b.dtheta
    return num / den


def _eta_min(structure: Block | Frame) -> float:
    """The smaller coefficient of restitution of the two impacts (rocking on clockwise, and
    counterclockwise) [-]."""
    return min(restitution(structure, -s, s) for s in (1, -1))


def _check_rocks(structure: Block | Frame) -> None:
    """Refuse a structure whose impact law gives eta < 0: it stops dead at its first impact
    (it cannot rock), which is outside the model. The error names the width: for a block
    width <= sqrt(2) height (eta = 1 - 1.5 sin^2 alpha >= 0, alpha <= 54.7 deg); for a frame
    the widest columns for which this frame's eta (which depends on the beam too) is >= 0."""
    eta = _eta_min(structure)
    if eta >= 0.0:
        return
    alpha = math.degrees(structure.alpha)
    if isinstance(structure, Block):
        name, value, limit = "width", structure.width, math.sqrt(2.0) * structure.height
        what = f"<= sqrt(2) x height = {limit:.6g} m"
    else:
        name, value = "column_width", structure.column_width
        lo, hi = 1e-3 * value, value
        if _eta_min(replace(structure, column_width=lo)) < 0.0:
            what = "narrower (no width of these columns rocks with this beam)"
        else:
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if _eta_min(replace(structure, column_width=mid)) >= 0.0:
                    lo = mid
                else:
                    hi = mid
            what = f"<= {lo:.6g} m for this frame's other fields"
    raise ParameterError(name, value, what,
                         f"alpha = {alpha:.4g} deg gives a coefficient of restitution eta = "
                         f"{eta:.3g} < 0: the structure cannot rock, it stops at its first "
                         "impact (outside the model; docs/scenes.md)")


def _toml_num(x: float) -> str:
    """A float as TOML: ``repr`` (shortest round-trip form), with a decimal point."""
    text = repr(float(x))
    return text if any(c in text for c in ".en") else text + ".0"


def _toml_str(text: str) -> str:
    """A TOML basic string: JSON's escapes, which TOML shares, plus DEL."""
    return json.dumps(str(text), ensure_ascii=False).replace("\x7f", "\\u007f")


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
    """A scene override's value (:func:`rockbench.values.parse_value`): a number, none (the
    field's default) or a structure type."""
    try:
        return parse_value(raw, 0.0, nullable=True, words=("block", "frame"))
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
    beam = {"mass_ratio": "beam_mass", "beam_mass": "mass_ratio"}  # one replaces the other
    dev_keys = {f.name for f in fields(Devices)}
    contact_keys = {f.name for f in fields(Contact)}
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
        elif key in contact_keys:
            table, name = "contact", key
        elif key in ("devices", "contact"):
            table, name = "", key
        else:
            known = frame_keys | dev_keys | contact_keys | {"fall_angle", "devices", "contact"}
            raise SceneError(f"unknown scene parameter {key!r}; known: {sorted(known)}")
        if table == "":
            if key in ("devices", "contact") and value is None:
                out[key] = None
            else:
                out[name] = value
        elif table in ("structure", "devices", "contact"):
            tbl = out.get(table) or {}
            if not isinstance(tbl, dict):
                raise SceneError(f"[{table}] is {tbl!r}, not a table: cannot apply override "
                                 f"{key!r}")
            if value is None and name != "fracture_strain":
                tbl.pop(name, None)
            else:
                tbl[name] = value
                if table == "structure" and name in beam:
                    tbl.pop(beam[name], None)
            out[table] = tbl
        else:
            raise SceneError(f"unknown scene table {table!r} in override {key!r}")
    return out


def load_scene(name_or_path: "str | os.PathLike | Scene",
               overrides: Mapping[str, Any] | None = None) -> Scene:
    """The one resolver of a scene argument: a built-in scene by name, a TOML file by path, or
    a :class:`Scene` (returned as it is when there are no ``overrides``), with ``overrides``
    (``key=value``, see :func:`apply_overrides`) applied."""
    if isinstance(name_or_path, Scene):
        if not overrides:
            return name_or_path
        data = apply_overrides(name_or_path.to_dict(), overrides)
        return Scene.from_dict(data, source=f"scene {name_or_path.name!r}")
    if isinstance(name_or_path, os.PathLike) and not isinstance(name_or_path, Path):
        name_or_path = Path(os.fspath(name_or_path))
    if not isinstance(name_or_path, (str, Path)):
        raise ParameterError("scene", name_or_path, "a built-in scene name, a path to a "
                             ".toml file or a rockbench.Scene")
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


def save_scene(scene: Scene, path: str | os.PathLike) -> Path:
    """Write ``scene`` as a scene file (:meth:`Scene.to_toml`) at ``path`` (a ``.toml`` file;
    written to a temporary name beside it, then renamed) and return the path.
    ``load_scene(path) == scene``."""
    if not isinstance(scene, Scene):
        raise ParameterError("scene", type(scene).__name__, "a rockbench.Scene")
    try:
        p = Path(path)
    except TypeError:
        raise ParameterError("path", path, "a path to a .toml file") from None
    if p.suffix != ".toml":
        raise ParameterError("path", str(p), "a path ending in .toml",
                             "load_scene reads a path as a file by that suffix")
    text = scene.to_toml()
    tmp = p.with_name(f".{p.name}.tmp-{os.getpid()}")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, p)
    except OSError as e:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        raise SceneError(f"cannot write scene file {str(p)!r}: "
                         f"{getattr(e, 'strerror', None) or e}") from None
    return p

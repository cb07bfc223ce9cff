"""The command line's inputs: options -> scene, ground motion and backend settings, validated,
every error naming the option (a :class:`rockbench.errors.ParameterError`, printed by
:mod:`rockbench.cli` as one line). Options and commands are in :mod:`rockbench.cli`.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

from .errors import ParameterError, RecordError, RockbenchError

__all__ = ["MissingOption", "scene_overrides", "load_scene_from", "setting_value",
           "backend_overrides", "motion_from", "compare_settings"]


class MissingOption(ParameterError):
    """A required option is missing (a :class:`ParameterError` with a plainer message)."""

    def __init__(self, name: str, valid: str, detail: str = ""):
        self.name, self.value, self.valid = name, None, valid
        RockbenchError.__init__(self, f"{name} is required{' ' + detail if detail else ''}: "
                                f"{valid}")


def scene_overrides(pairs: list[tuple[str, str]]) -> dict[str, Any]:
    """``--set`` pairs as load_scene overrides; a value that is not a number, ``none`` or a
    structure type is rejected here, naming its key."""
    out: dict[str, Any] = {}
    for key, raw in pairs:
        try:
            out[key] = float(raw)
        except ValueError:
            if raw.lower() not in ("none", "null", "block", "frame"):
                raise ParameterError(f"--set {key}", raw, "a number or 'none'") from None
            out[key] = raw
    return out


def load_scene_from(args: argparse.Namespace):
    from .scene import load_scene

    return load_scene(args.scene, scene_overrides(args.overrides))


def setting_value(cls: type, name: str, raw: str) -> Any:
    """Parse ``raw`` as the type of the Settings field ``name`` (from its default value)."""
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if name not in fields:
        raise ParameterError(f"--setting {name}", raw,
                             f"a field of {cls.__qualname__}: {', '.join(fields)}")
    f = fields[name]
    default = f.default if f.default is not dataclasses.MISSING else None
    low = raw.lower()
    try:
        if isinstance(default, bool):
            if low in ("true", "yes", "1", "on"):
                return True
            if low in ("false", "no", "0", "off"):
                return False
            raise ValueError
        if isinstance(default, int):
            return int(raw)
        if isinstance(default, float):
            return float(raw)
        if isinstance(default, str):
            return raw
        if low in ("none", "null"):
            return None
        try:
            return float(raw)
        except ValueError:
            return raw
    except ValueError:
        kind = type(default).__name__
        raise ParameterError(f"--setting {name}", raw, f"a value of type {kind}") from None


def backend_overrides(engine: str, args: argparse.Namespace) -> dict[str, Any]:
    """Settings overrides for ``engine`` from --dt and --setting (validated by its Settings)."""
    from .engines import get_backend

    cls = get_backend(engine).Settings
    names = {f.name for f in dataclasses.fields(cls)}
    out: dict[str, Any] = {}
    for name, raw in args.settings:
        out[name] = setting_value(cls, name, raw)
    if args.dt is not None:
        if "dt" not in names:
            raise ParameterError("--dt", args.dt, f"omitted for the {engine} backend",
                                 f"{engine} has no time step; its settings are "
                                 f"{', '.join(sorted(names))}")
        if "dt" in out:
            raise ParameterError("--dt", args.dt, "omitted when --setting dt=... is given")
        out["dt"] = args.dt
    if "dt" in out and "output_dt" in names and "output_dt" not in out:
        # keep the default output grid unless the step is coarser than it
        default_out = next(f.default for f in dataclasses.fields(cls) if f.name == "output_dt")
        if isinstance(out["dt"], (int, float)) and out["dt"] > default_out:
            out["output_dt"] = out["dt"]
    cls(**out)  # validate now: errors name the field
    return out


def motion_from(args: argparse.Namespace, scene) -> tuple[Any, float]:
    """(ground motion or None, phi0 [rad]) from the motion options."""
    pulse_opts = {"--sign": args.sign, "--amplitude": args.amplitude,
                  "--frequency": args.frequency}
    record_opts = {"--record-dt": args.record_dt, "--record-units": args.record_units,
                   "--scale": args.scale}
    if args.pulse is None:
        for opt, v in pulse_opts.items():
            if v is not None:
                raise ParameterError(opt, v, "given only with --pulse")
    if args.record is None:
        for opt, v in record_opts.items():
            if v is not None:
                raise ParameterError(opt, v, "given only with --record")

    if args.pulse is not None:
        from .scene import RickerPulse

        for opt, what in (("--amplitude", "A = a_g / (g tan alpha) > 0"),
                          ("--frequency", "W = omega_g / p > 0")):
            if pulse_opts[opt] is None:
                raise MissingOption(opt, what, "with --pulse")
        pulse = RickerPulse.dimensionless(args.amplitude, args.frequency, scene.structure,
                                          args.pulse, 1 if args.sign is None else args.sign)
        return pulse, 0.0

    if args.record is not None:
        from .scene import load_record

        path = Path(args.record)
        if not path.is_file():
            raise RecordError(f"--record: file {str(path)!r} does not exist")
        if path.suffix.lower() != ".at2":
            if args.record_dt is None:
                raise MissingOption("--record-dt", "the time step [s] > 0",
                                    f"for the headerless record file {path.name}")
            if args.record_units is None:
                raise MissingOption("--record-units", "one of g, m/s2, cm/s2",
                                    f"for the headerless record file {path.name}")
        return load_record(path, dt=args.record_dt, units=args.record_units,
                           scale=1.0 if args.scale is None else args.scale), 0.0

    if args.phi0 is not None:
        # the fall angle of the direction phi0 points to (they differ for an asymmetric frame)
        sign = 1 if args.phi0 > 0 else -1
        fall = scene.fall_angles[sign]
        limit = fall / scene.alpha
        if abs(args.phi0) >= limit:
            way = "counterclockwise" if sign == 1 else "clockwise"
            raise ParameterError("--phi0", args.phi0,
                                 f"0 < |phi0| < {limit:.4g} for {way} rocking (multiples of "
                                 f"alpha; {way} fall angle {fall:.4g} rad)")
        return None, args.phi0 * scene.alpha

    raise MissingOption("a ground motion", "--pulse, --record, or --phi0 for free rocking",
                        "(nothing would move)")


def compare_settings(engines: list[str] | None, args: argparse.Namespace) -> dict | None:
    """Per-backend settings overrides {backend: {field: value}} for compare.

    ``--setting name=value`` goes to every compared backend whose Settings has the field,
    ``--setting backend.name=value`` to that backend only; ``--dt`` to every engine with a time
    step (the analytic reference has none). A setting no compared backend has is an error.
    """
    if not args.settings and args.dt is None:
        return None
    from .engines import REGISTRY, get_backend
    from .runner import REFERENCE, resolve_engines

    names = list(dict.fromkeys([REFERENCE, *resolve_engines(engines, name="--engines")]))
    targeted: list[tuple[str, str, str]] = []   # (backend or "", field, raw)
    for key, raw in args.settings:
        head, dot, tail = key.partition(".")
        if dot and head in REGISTRY:
            if head not in names:
                raise ParameterError(f"--setting {key}", raw,
                                     f"for a compared backend: {', '.join(names)}")
            targeted.append((head, tail, raw))
        else:
            targeted.append(("", key, raw))
    out: dict[str, dict[str, Any]] = {}
    used: set[int] = set()
    dt_used = False
    for engine in names:
        fields = {f.name for f in dataclasses.fields(get_backend(engine).Settings)}
        mine = []
        for i, (target, name, raw) in enumerate(targeted):
            if target == engine or (target == "" and name in fields):
                mine.append((name, raw))
                used.add(i)
        dt = args.dt if "dt" in fields else None
        dt_used |= dt is not None
        over = backend_overrides(engine, argparse.Namespace(settings=mine, dt=dt))
        if over:
            out[engine] = over
    for i, (target, name, raw) in enumerate(targeted):
        if i not in used:
            raise ParameterError(f"--setting {name}", raw,
                                 f"a settings field of one of {', '.join(names)}")
    if args.dt is not None and not dt_used:
        raise ParameterError("--dt", args.dt, "omitted: none of the compared backends has a "
                             "time step")
    return out

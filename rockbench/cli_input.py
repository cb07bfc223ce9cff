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
           "parse_settings", "engine_settings", "backend_overrides", "motion_from",
           "engine_names"]


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


def setting_value(cls: type, name: str, raw: str, shown: str | None = None) -> Any:
    """Parse ``raw`` as the type of the Settings field ``name`` (from its default value);
    errors name ``shown`` (default ``--setting NAME``)."""
    shown = shown or f"--setting {name}"
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if name not in fields:
        raise ParameterError(shown, raw, f"a field of {cls.__qualname__}: {', '.join(fields)}")
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
        raise ParameterError(shown, raw, f"a value of type {kind}") from None


def _settings_class(engine: str):
    from .engines import get_backend

    return get_backend(engine).Settings


def parse_settings(texts: list[str], engines: list[str], *, option: str = "--setting",
                   also: tuple[str, ...] = ()) -> list[tuple[str, str, str]]:
    """The one ``--setting`` grammar: each text is ``ENGINE.KEY=VALUE`` (or a bare
    ``KEY=VALUE`` when exactly one engine is selected: ``engines`` has one name) ->
    ``[(engine, key, raw value), ...]``. ``ENGINE`` must be one of ``engines`` or ``also`` (e.g.
    the analytic reference of ``compare``), ``KEY`` a field of its Settings; errors are
    :class:`ParameterError` lines showing the right form."""
    from .engines import REGISTRY

    selectable = list(dict.fromkeys([*engines, *also]))
    out = []
    for text in texts:
        key, sep, raw = text.partition("=")
        key, raw = key.strip(), raw.strip()
        if not sep or not key:
            raise ParameterError(option, text, "ENGINE.KEY=VALUE (e.g. pymunk.iterations=20)")
        head, dot, field = key.partition(".")
        if dot and head in REGISTRY:
            engine = head
            if engine not in selectable:
                raise ParameterError(option, text, f"a setting of a selected engine: "
                                     f"{', '.join(selectable)}")
        elif dot:
            raise ParameterError(option, text, f"ENGINE.KEY=VALUE with ENGINE one of "
                                 f"{', '.join(REGISTRY)}")
        elif len(engines) == 1:
            engine, field = engines[0], key
        else:
            example = f"{engines[0]}.{key}={raw}" if engines else f"ENGINE.{key}={raw}"
            raise ParameterError(option, text, f"ENGINE.KEY=VALUE naming one of the selected "
                                 f"engines ({', '.join(selectable) or 'none'}), e.g. {option} "
                                 f"{example}")
        out.append((engine, field, raw))
    return out


def engine_settings(texts: list[str], engines: list[str], *, dt: float | None = None,
                    also: tuple[str, ...] = (), option: str = "--setting"
                    ) -> dict[str, dict[str, Any]]:
    """Validated Settings overrides {engine: {field: value}} from ``--setting`` texts (the
    grammar of :func:`parse_settings`) and ``--dt`` (every selected engine with a time step;
    an error if none has one). Each engine's Settings is built once here, so a bad key or value
    is refused before anything runs."""
    selectable = list(dict.fromkeys([*engines, *also]))
    out: dict[str, dict[str, Any]] = {}
    for engine, field, raw in parse_settings(texts, engines, option=option, also=also):
        cls = _settings_class(engine)
        over = out.setdefault(engine, {})
        if field in over:
            raise ParameterError(f"{option} {engine}.{field}", raw, "given once")
        over[field] = setting_value(cls, field, raw, f"{option} {engine}.{field}")
    if dt is not None:
        with_dt = [e for e in engines
                   if "dt" in {f.name for f in dataclasses.fields(_settings_class(e))}]
        if not with_dt:
            names = ", ".join(selectable)
            raise ParameterError("--dt", dt, "omitted: the analytic model has no time step"
                                 if names == "analytic" else
                                 f"omitted: none of {names} has a time step")
        for e in with_dt:
            if "dt" in out.get(e, {}):
                raise ParameterError("--dt", dt, f"omitted when --setting {e}.dt is given")
            out.setdefault(e, {})["dt"] = dt
    for engine, over in out.items():
        _settings_class(engine)(**over)  # validate now: the error names the field
    return out


def backend_overrides(engine: str, args: argparse.Namespace) -> dict[str, Any]:
    """Settings overrides of the one backend ``engine`` from ``args.settings`` (--setting)
    and ``args.dt`` (--dt), validated (:func:`engine_settings`)."""
    return engine_settings(list(args.settings), [engine], dt=args.dt).get(engine, {})


def motion_from(args: argparse.Namespace, scene) -> tuple[Any, float]:
    """(ground motion or None, phi0 [rad]) from the motion options: ``--pulse``, ``--record``
    (a headerless file takes --record-dt and --record-units, or its line of the ``records.csv``
    beside it, as :func:`rockbench.load_record` does), ``--phi0`` [rad] or ``--phi0-alpha``
    [multiples of alpha]."""
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
        duration = getattr(args, "duration", None)
        if duration is not None and pulse.t_start + float(duration) <= 0.0:
            # the run starts 3 T_g before the pulse centre (t = 0): a shorter run ends before
            # the pulse's main lobe and would report a structure that never moved
            raise ParameterError("--duration", duration,
                                 f"> {-pulse.t_start:.4g} s: the run starts at t = "
                                 f"{pulse.t_start:.4g} s (3 T_g before the pulse centre) and "
                                 "would end before the pulse's main lobe")
        return pulse, 0.0

    if args.record is not None:
        from .scene import load_record

        path = Path(args.record)
        if not path.is_file():
            raise RecordError(f"--record: file {str(path)!r} does not exist")
        listed = None
        if path.suffix.lower() != ".at2" and (args.record_dt is None or args.record_units is None):
            from .scene.records import listed_metadata

            listed = listed_metadata(path)      # dt and units from the records.csv beside it
        if path.suffix.lower() != ".at2" and listed is None:
            if args.record_dt is None:
                raise MissingOption("--record-dt", "the time step [s] > 0",
                                    f"for the headerless record file {path.name}")
            if args.record_units is None:
                raise MissingOption("--record-units", "an acceleration unit (g, m/s2, cm/s2)",
                                    f"for the headerless record file {path.name} (or list it "
                                    "in a records.csv beside it)")
        return load_record(path, dt=args.record_dt, units=args.record_units,
                           scale=1.0 if args.scale is None else args.scale), 0.0

    phi0, option = args.phi0, "--phi0"
    if args.phi0_alpha is not None:
        phi0, option = args.phi0_alpha * scene.alpha, "--phi0-alpha"
    if phi0 is not None:
        # the fall angle of the direction phi0 points to (they differ for an asymmetric frame)
        sign = 1 if phi0 > 0 else -1
        fall = scene.fall_angles[sign]
        if abs(phi0) >= fall:
            way = "counterclockwise" if sign == 1 else "clockwise"
            given = args.phi0 if option == "--phi0" else args.phi0_alpha
            rng = (f"0 < |phi0| < {fall:.4g} rad" if option == "--phi0" else
                   f"0 < |phi0| < {fall / scene.alpha:.4g} (multiples of alpha = "
                   f"{scene.alpha:.4g} rad)")
            raise ParameterError(option, given, f"{rng} for {way} rocking (the {way} fall "
                                 f"angle is {fall:.4g} rad = {fall / scene.alpha:.4g} alpha)")
        return None, float(phi0)

    raise MissingOption("a ground motion", "--pulse, --record, or --phi0 / --phi0-alpha for "
                        "free rocking",
                        "(nothing would move)")


def engine_names(args: argparse.Namespace, option: str = "--engine") -> list[str] | None:
    """The engines of a repeatable ``--engine`` (each value a name or a comma-separated list;
    ``--engines`` is the same option), validated, in order, without duplicates; None when none
    was given (the command's default)."""
    given = getattr(args, "engine", None)
    if not given:
        return None
    from .runner import resolve_engines

    names = [n.strip() for v in given for n in v.split(",") if n.strip()]
    if not names:
        raise ParameterError(option, ",".join(given), "backend names")
    return resolve_engines(names, name=option)

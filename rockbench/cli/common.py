"""What every command of the command line shares, in one place: the argument types, the scene,
motion and run options, the one grammar of ``--engine`` (repeatable), ``--setting
ENGINE.KEY=VALUE`` and ``--quiet``; what the options mean once parsed (scene, ground motion and
backend settings, validated, every error naming the option: a
:class:`rockbench.errors.ParameterError`, printed by :func:`rockbench.cli.main.main` as one
line); and the output helpers (JSON, folders, atomic CSV writes). Commands live in
:mod:`rockbench.cli.main` and one module per group (:mod:`.choosing`, :mod:`.maps`,
:mod:`.fragility`).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

from ..errors import ParameterError, RecordError, RockbenchError, RockbenchWarning

__all__ = ["CommandLineError", "Parser", "add_setting_option", "add_engine_option",
           "add_quiet_option", "add_scene_options", "add_motion_options", "add_run_options",
           "add_vertical_option", "vertical_ratio", "arg_number", "arg_positive",
           "arg_nonzero", "arg_count", "arg_sign", "arg_key_value",
           "arg_names", "MissingOption", "scene_overrides", "load_scene_from",
           "engine_settings", "backend_overrides", "motion_from",
           "engine_names", "print_json", "output_folder", "write_atomic", "pandas_display"]


# ==========================================================================================
# Options
# ==========================================================================================

class CommandLineError(Exception):
    """An argument the parser rejects (printed as one line, exit code 2)."""


class Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors raise instead of printing the usage and exiting, so that
    :func:`main` prints exactly one line."""

    def error(self, message: str):  # type: ignore[override]
        raise CommandLineError(message)


def arg_number(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return x


def arg_positive(text: str) -> float:
    x = arg_number(text)
    if x <= 0.0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return x


def arg_nonzero(text: str) -> float:
    x = arg_number(text)
    if x == 0.0:
        raise argparse.ArgumentTypeError(f"must be non-zero, got {text!r}")
    return x


def arg_count(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}")
    return n


def arg_sign(text: str) -> int:
    try:
        s = int(text)
    except ValueError:
        s = 0
    if s not in (1, -1):
        raise argparse.ArgumentTypeError(f"must be 1 or -1, got {text!r}")
    return s


def arg_key_value(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    return key.strip(), value.strip()


def arg_names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected a comma-separated list of names, got {text!r}")
    return names


def add_scene_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE",
                   help="a built-in scene name (rockbench scenes) or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=arg_key_value,
                   action="append", default=[],
                   help="override a scene parameter (e.g. span=9, devices.fracture_strain=none)")


def add_motion_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("ground motion (one of --pulse, --record, --phi0)")
    x = g.add_mutually_exclusive_group()
    x.add_argument("--pulse", choices=("symmetric", "antisymmetric"),
                   help="Ricker pulse shape (paper Eq. 29 / Eq. 30)")
    x.add_argument("--record", metavar="FILE",
                   help="accelerogram: a PEER .AT2 file, a headerless column file, or the "
                        "name of a bundled record (e.g. IV1940_ElCentro_180; docs/records.md)")
    x.add_argument("--phi0", type=arg_nonzero, metavar="RAD",
                   help="free rocking from phi0 = RAD radians (!= 0, + counterclockwise), "
                        "as rockbench.run(phi0=...)")
    x.add_argument("--phi0-alpha", type=arg_nonzero, metavar="X",
                   help="free rocking from phi0 = X alpha (X != 0, + counterclockwise)")
    g.add_argument("--sign", type=arg_sign, default=None, metavar="{1,-1}",
                   help="pulse sign (default 1: the pulse as printed in the paper)")
    g.add_argument("--amplitude", type=arg_positive, metavar="A",
                   help="pulse amplitude A = a_g / (g tan alpha) > 0")
    g.add_argument("--frequency", type=arg_positive, metavar="W",
                   help="pulse frequency W = omega_g / p > 0")
    g.add_argument("--vertical", type=float, metavar="RATIO",
                   help="vertical part of the pulse: a_v = RATIO x u_g'' [-] (same shape, sign "
                        "and period, in phase; a_v in m/s^2, positive up), 0 to 3 (default 0: "
                        "horizontal only)")
    g.add_argument("--record-dt", type=arg_positive, metavar="S",
                   help="time step [s] of a headerless record file")
    g.add_argument("--record-units", metavar="UNITS",
                   help="units of a headerless record file: g, m/s2, cm/s2 (a records.csv "
                        "beside the file gives them, and its dt, when it lists the file)")
    g.add_argument("--record-vertical", metavar="FILE",
                   help="vertical channel of --record (acceleration positive up, in its file's "
                        "units, converted to m/s^2): a PEER .AT2 file or a headerless file (with "
                        "--record-dt and --record-units, or its records.csv line); sampled at "
                        "the horizontal record's times")
    g.add_argument("--scale", type=arg_nonzero, metavar="F",
                   help="multiply the record by F (default 1; a vertical channel too)")


def add_run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=arg_positive, metavar="S",
                   help="simulated time [s] from the motion's start (default: motion + 10 s)")
    p.add_argument("--dt", type=arg_positive, metavar="S",
                   help="engine time step [s] (engines only: the analytic model has none)")
    add_setting_option(p)


def add_setting_option(p: argparse.ArgumentParser, what: str = "set") -> None:
    """``--setting ENGINE.KEY=VALUE`` (repeatable): the one settings grammar of every command
    (:mod:`rockbench.engines.setting_text`)."""
    p.add_argument("--setting", dest="settings", metavar="ENGINE.KEY=VALUE", action="append",
                   default=[], help=f"{what} a field of an engine's Settings, e.g. "
                   "pymunk.iterations=20 (bare KEY=VALUE when one engine is selected); "
                   "repeatable")


def add_engine_option(p: argparse.ArgumentParser, default: str) -> None:
    """``--engine NAME`` (repeatable; a comma-separated list works too; ``--engines`` is the
    same option): the engines of a command that runs several."""
    p.add_argument("--engine", "--engines", dest="engine", metavar="NAME", action="append",
                   help=f"an engine (rockbench engines); repeat for several, e.g. --engine "
                        f"pymunk --engine mujoco (default: {default})")


def add_vertical_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--vertical RATIO`` of a command whose ground motions are generated (``what``: which,
    e.g. "every pulse and record of the evidence"): a_v = RATIO x the horizontal acceleration,
    in phase; read back with :func:`vertical_ratio`."""
    p.add_argument("--vertical", type=arg_number, default=0.0, metavar="RATIO",
                   help=f"{what} also moves the ground vertically: a_v = RATIO x its "
                        "horizontal acceleration (same shape and sign, in phase; positive "
                        "up), 0 to 3 (default 0: horizontal only)")


def vertical_ratio(args: argparse.Namespace) -> float:
    """The ``--vertical`` of a command as r in [0, 3] (ParameterError naming ``--vertical``
    otherwise)."""
    from ..studies.map_cells import check_vertical_ratio

    return check_vertical_ratio(getattr(args, "vertical", 0.0), "--vertical")


def add_quiet_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress on stderr (errors still print)")


# ==========================================================================================
# Inputs
# ==========================================================================================

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
    from ..scene import load_scene

    return load_scene(args.scene, scene_overrides(args.overrides))


def _settings_class(engine: str):
    from ..engines import get_backend

    return get_backend(engine).Settings


def engine_settings(texts: list[str], engines: list[str], *, dt: float | None = None,
                    also: tuple[str, ...] = (), option: str = "--setting"
                    ) -> dict[str, dict[str, Any]]:
    """Validated Settings overrides {engine: {field: value}} from ``--setting`` texts (the
    grammar of :mod:`rockbench.engines.setting_text`) and ``--dt`` (every selected engine with a time step;
    an error if none has one). Each engine's Settings is built once here, so a bad key or value
    is refused before anything runs."""
    selectable = list(dict.fromkeys([*engines, *also]))
    out: dict[str, dict[str, Any]] = {}
    from ..engines.setting_text import parse_settings, setting_value

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


def _bundled_record_path(text: str) -> Path:
    """The file of the bundled record named ``text`` (its file stem, case-insensitive, as
    :func:`rockbench.scene.records.load_bundled` takes it), for a ``--record`` that is not a file; a
    RecordError naming the option, the value and the bundled names otherwise."""
    from ..scene.records import bundled_records

    records = bundled_records()
    key = str(text).strip().lower()
    for r in records:
        if r["name"].lower() in (key, key.removesuffix(".at2")):
            return Path(r["path"])
    raise RecordError(f"--record: {str(text)!r} is neither a file nor a bundled record "
                      f"(one of {', '.join(r['name'] for r in records)})")


def motion_from(args: argparse.Namespace, scene) -> tuple[Any, float]:
    """(ground motion or None, phi0 [rad]) from the motion options: ``--pulse``, ``--record``
    (a headerless file takes --record-dt and --record-units, or its line of the ``records.csv``
    beside it, as :func:`rockbench.load_record` does), ``--phi0`` [rad] or ``--phi0-alpha``
    [multiples of alpha]."""
    pulse_opts = {"--sign": args.sign, "--amplitude": args.amplitude,
                  "--frequency": args.frequency, "--vertical": getattr(args, "vertical", None)}
    record_opts = {"--record-dt": args.record_dt, "--record-units": args.record_units,
                   "--scale": args.scale,
                   "--record-vertical": getattr(args, "record_vertical", None)}
    if args.pulse is None:
        for opt, v in pulse_opts.items():
            if v is not None:
                raise ParameterError(opt, v, "given only with --pulse")
    if args.record is None:
        for opt, v in record_opts.items():
            if v is not None:
                raise ParameterError(opt, v, "given only with --record")

    if args.pulse is not None:
        from ..scene import RickerPulse

        for opt, what in (("--amplitude", "A = a_g / (g tan alpha) > 0"),
                          ("--frequency", "W = omega_g / p > 0")):
            if pulse_opts[opt] is None:
                raise MissingOption(opt, what, "with --pulse")
        try:
            pulse = RickerPulse.dimensionless(args.amplitude, args.frequency, scene.structure,
                                              args.pulse, 1 if args.sign is None else args.sign,
                                              vertical_ratio=args.vertical or 0.0)
        except ParameterError as exc:
            if exc.name != "vertical_ratio":
                raise
            raise ParameterError("--vertical", args.vertical, exc.valid) from None
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
        from ..scene import load_record

        path = Path(args.record)
        if not path.is_file():
            path = _bundled_record_path(args.record)
        listed = None
        if path.suffix.lower() != ".at2" and (args.record_dt is None or args.record_units is None):
            from ..scene.records import listed_metadata

            listed = listed_metadata(path)      # dt and units from the records.csv beside it
        if path.suffix.lower() != ".at2" and listed is None:
            if args.record_dt is None:
                raise MissingOption("--record-dt", "the time step [s] > 0",
                                    f"for the headerless record file {path.name}")
            if args.record_units is None:
                raise MissingOption("--record-units", "an acceleration unit (g, m/s2, cm/s2)",
                                    f"for the headerless record file {path.name} (or list it "
                                    "in a records.csv beside it)")
        vpath = None
        if args.record_vertical is not None:
            vpath = Path(args.record_vertical)
            if not vpath.is_file():
                vpath = _bundled_record_path(args.record_vertical)
        try:
            return load_record(path, dt=args.record_dt, units=args.record_units,
                               scale=1.0 if args.scale is None else args.scale,
                               vertical=vpath, vertical_dt=args.record_dt,
                               vertical_units=args.record_units), 0.0
        except ParameterError as exc:
            if not exc.name.startswith("record-vertical"):
                raise
            raise ParameterError("--record-vertical" if exc.name == "record-vertical"
                                 else "--" + exc.name.replace("record-vertical-", "record-"),
                                 exc.value, exc.valid, f"for --record-vertical {vpath.name}"
                                 ) from None

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
    from ..runner import resolve_engines

    names = [n.strip() for v in given for n in v.split(",") if n.strip()]
    if not names:
        raise ParameterError(option, ",".join(given), "backend names")
    return resolve_engines(names, name=option)


@contextlib.contextmanager
def one_line_warnings():
    """A context in which a warning (a damaged store file skipped, workers capped) prints as
    one line ``rockbench: warning: ...`` on stderr, without the source line."""
    import warnings

    old = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"rockbench: warning: {' '.join(str(message).split())}", file=sys.stderr)

    warnings.showwarning = show
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", RockbenchWarning)   # two damaged files: two lines
            warnings.showwarning = show
            yield
    finally:
        warnings.showwarning = old


def absent_engine_lines(args: argparse.Namespace) -> list[str]:
    """One line per engine a command's selection (``--engine``, or every registered engine)
    could not use here: its name, why, and the remedy."""
    from ..engines import unavailable_lines

    try:
        chosen = engine_names(args)
    except RockbenchError:
        return []
    return [f"not run: {line}" for line in unavailable_lines(chosen)]


# ==========================================================================================
# Output
# ==========================================================================================
def print_json(data: Any) -> None:
    from ..result import jsonable

    print(json.dumps(jsonable(data), indent=2, allow_nan=False))


def output_folder(path: Path, option: str) -> None:
    """Create the folder of output ``path`` (given with ``option``) now, before any run, and
    check it can be written: a one-line error naming the option otherwise."""
    folder = path.parent
    try:
        if path.is_dir():
            raise RockbenchError(f"cannot write {option} {path}: it is a folder")
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise RockbenchError(f"cannot write {option} {path}: {e.strerror or e}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise RockbenchError(f"cannot write {option} {path}: folder {folder} is not writable")


def write_atomic(files: dict[Path, Any], option: str) -> None:
    """Write each DataFrame of ``files`` {path: frame} as CSV to a temporary name beside it,
    then rename them all into place: either every file is complete or none is changed (and no
    temporary file is left). Failures are one-line errors naming ``option``."""
    tmps: dict[Path, Path] = {}
    try:
        for path, frame in files.items():
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            tmps[path] = tmp
            frame.to_csv(tmp, index=False)
        for path, tmp in tmps.items():
            os.replace(tmp, path)
    except OSError as e:
        raise RockbenchError(f"cannot write {option} {next(iter(files))}: "
                             f"{e.strerror or e}") from None
    finally:
        for tmp in tmps.values():
            try:
                tmp.unlink()
            except OSError:
                pass


def pandas_display():
    import pandas as pd

    return pd.option_context("display.width", 200, "display.max_columns", 50)

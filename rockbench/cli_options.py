"""The command line's common options, in one place: argument types, the scene, motion and run
options, and the one grammar of ``--engine`` (repeatable), ``--setting ENGINE.KEY=VALUE`` and
``--quiet`` that every command (:mod:`rockbench.cli`, ``cli_*.py``) adds with these functions.
What the options mean once parsed: :mod:`rockbench.cli_input`."""

from __future__ import annotations

import argparse
import math

__all__ = ["CommandLineError", "add_setting_option", "add_engine_option", "add_quiet_option"]


class CommandLineError(Exception):
    """An argument the parser rejects (printed as one line, exit code 2)."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors raise instead of printing the usage and exiting, so that
    :func:`main` prints exactly one line."""

    def error(self, message: str):  # type: ignore[override]
        raise CommandLineError(message)


def _number(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return x


def _positive(text: str) -> float:
    x = _number(text)
    if x <= 0.0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return x


def _nonzero(text: str) -> float:
    x = _number(text)
    if x == 0.0:
        raise argparse.ArgumentTypeError(f"must be non-zero, got {text!r}")
    return x


def _count(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}")
    return n


def _sign(text: str) -> int:
    try:
        s = int(text)
    except ValueError:
        s = 0
    if s not in (1, -1):
        raise argparse.ArgumentTypeError(f"must be 1 or -1, got {text!r}")
    return s


def _key_value(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    return key.strip(), value.strip()


def _names(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected a comma-separated list of names, got {text!r}")
    return names


def _add_scene_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", metavar="SCENE",
                   help="a built-in scene name (rockbench scenes) or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=_key_value,
                   action="append", default=[],
                   help="override a scene parameter (e.g. span=9, devices.fracture_strain=none)")


def _add_motion_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("ground motion (one of --pulse, --record, --phi0)")
    x = g.add_mutually_exclusive_group()
    x.add_argument("--pulse", choices=("symmetric", "antisymmetric"),
                   help="Ricker pulse shape (paper Eq. 29 / Eq. 30)")
    x.add_argument("--record", metavar="FILE",
                   help="accelerogram: a PEER .AT2 file or a headerless column file")
    x.add_argument("--phi0", type=_nonzero, metavar="RAD",
                   help="free rocking from phi0 = RAD radians (!= 0, + counterclockwise), "
                        "as rockbench.run(phi0=...)")
    x.add_argument("--phi0-alpha", type=_nonzero, metavar="X",
                   help="free rocking from phi0 = X alpha (X != 0, + counterclockwise)")
    g.add_argument("--sign", type=_sign, default=None, metavar="{1,-1}",
                   help="pulse sign (default 1: the pulse as printed in the paper)")
    g.add_argument("--amplitude", type=_positive, metavar="A",
                   help="pulse amplitude A = a_g / (g tan alpha) > 0")
    g.add_argument("--frequency", type=_positive, metavar="W",
                   help="pulse frequency W = omega_g / p > 0")
    g.add_argument("--record-dt", type=_positive, metavar="S",
                   help="time step [s] of a headerless record file")
    g.add_argument("--record-units", metavar="UNITS",
                   help="units of a headerless record file: g, m/s2, cm/s2 (a records.csv "
                        "beside the file gives them, and its dt, when it lists the file)")
    g.add_argument("--scale", type=_nonzero, metavar="F",
                   help="multiply the record by F (default 1)")


def _add_run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--duration", type=_positive, metavar="S",
                   help="simulated time [s] from the motion's start (default: motion + 10 s)")
    p.add_argument("--dt", type=_positive, metavar="S",
                   help="engine time step [s] (engines only: the analytic model has none)")
    add_setting_option(p)


def add_setting_option(p: argparse.ArgumentParser, what: str = "set") -> None:
    """``--setting ENGINE.KEY=VALUE`` (repeatable): the one settings grammar of every command
    (:func:`rockbench.cli_input.parse_settings`)."""
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


def add_quiet_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress on stderr (errors still print)")

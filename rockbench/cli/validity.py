"""The ``rockbench validity-map`` command (``docs/maps.md``, "Where the analytic model
holds"): arguments and output only; the work is :mod:`rockbench.studies.validity_map`."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from .common import (add_engine_option, add_quiet_option, arg_count, arg_key_value, arg_number,
                     engine_names, load_scene_from, output_folder, print_json,
                     write_atomic)
from ..errors import ParameterError

__all__ = ["register", "add_validity_command", "cmd_validity_map"]

#: Largest --grid (cells per axis).
MAX_GRID = 100


def register(sub, commands: dict) -> None:
    """Add the ``validity-map`` sub-command to ``sub`` and its handler to ``commands``."""
    add_validity_command(sub)
    commands["validity-map"] = cmd_validity_map


def add_validity_command(sub) -> None:
    p = sub.add_parser("validity-map", help="where the analytic model holds over (A, W) with the "
                       "scene's friction, and whether the engines agree where it does not")
    p.add_argument("scene", metavar="SCENE",
                   help="a built-in scene name (rockbench scenes) or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=arg_key_value,
                   action="append", default=[],
                   help="override a scene parameter (e.g. contact.friction=0.3)")
    p.add_argument("--shape", choices=("symmetric", "antisymmetric"), default="symmetric",
                   help="Ricker pulse shape (default symmetric)")
    p.add_argument("--sign", type=int, choices=(1, -1), default=1,
                   help="pulse sign (default 1: the pulse as printed in the paper)")
    p.add_argument("--vertical", type=arg_number, default=0.0, metavar="RATIO",
                   help="peak vertical over peak horizontal ground acceleration, in phase, "
                        "0 to 3 (default 0: none)")
    add_engine_option(p, "the fast engines installed; they run only outside the model")
    p.add_argument("--grid", type=arg_count, default=8, metavar="N",
                   help=f"N x N cells, 1 <= N <= {MAX_GRID} (default 8): A from 0.5 to "
                        "max(8, 1.5 mu / tan alpha), W from 1 to 10")
    p.add_argument("--tolerance", type=arg_number, default=0.10, metavar="X",
                   help="relative spread within which engines agree (default 0.10)")
    p.add_argument("--tail", type=arg_number, default=None, metavar="S",
                   help="seconds of free rocking after the pulse window 6 T_g (default: the "
                        "motion + 10 s)")
    p.add_argument("--store", metavar="DIR",
                   help="resumable store (a folder; default OUT/store with --out, else none)")
    p.add_argument("--workers", type=arg_count, metavar="N", help="local worker processes")
    p.add_argument("--out", metavar="DIR",
                   help="write DIR/validity_map.csv and DIR/validity_map.png")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    add_quiet_option(p)


def _figure(fig, path: Path) -> None:
    """Save ``fig`` to ``path`` through a temporary name (never half-written)."""
    import os

    from ..errors import RockbenchError

    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, path)
    except OSError as e:
        raise RockbenchError(f"cannot write --out {path}: {e.strerror or e}") from None
    finally:
        tmp.unlink(missing_ok=True)


def cmd_validity_map(args: argparse.Namespace) -> int:
    from ..progress import enabled
    from ..studies.validity_map import default_axes, engines_to_run, validity_map
    from ..sweep.store import default_store
    from ..report.validity_figures import plot_validity_map, validity_sentences
    from ..validity import friction_of

    if not 0.0 <= args.vertical <= 3.0:
        raise ParameterError("--vertical", args.vertical, "a number in [0, 3]")
    if args.grid > MAX_GRID:
        raise ParameterError("--grid", args.grid, f"an integer in [1, {MAX_GRID}]")
    if not (math.isfinite(args.tolerance) and args.tolerance > 0):
        raise ParameterError("--tolerance", args.tolerance, "a number > 0 (e.g. 0.10)")
    if args.tail is not None and args.tail < 0:
        raise ParameterError("--tail", args.tail, "a number of seconds >= 0")
    out = Path(args.out) if args.out else None
    if out is not None:
        output_folder(out / "validity_map.csv", "--out")
    store = args.store or (default_store(out) if out is not None else None)
    scene = load_scene_from(args)
    engines = engine_names(args)
    if engines is not None and "analytic" in engines:
        raise ParameterError("--engine", ",".join(engines), "engines other than the analytic "
                             "reference (it always runs)")
    ran = engines_to_run(engines)
    A, W = default_axes(scene, args.grid)
    frame = validity_map(scene, shape=args.shape, sign=args.sign, A=A, W=W,
                         vertical_ratio=args.vertical, engines=engines,
                         tolerance=args.tolerance, tail=args.tail, store=store,
                         workers=args.workers, progress=enabled() and not args.json)
    if out is not None:
        write_atomic({out / "validity_map.csv": frame}, "--out")
        _figure(plot_validity_map(frame, title=f"{scene.name}: validity map",
                                  a_mu=friction_of(scene) / math.tan(scene.alpha)),
                out / "validity_map.png")
    if args.json:
        print_json(frame.to_dict("records"))
        return 0

    for s in validity_sentences(frame, friction=friction_of(scene), tolerance=args.tolerance,
                                engines=ran, friction_given=scene.friction is not None):
        print(s)
    counts = frame["region"].value_counts()
    print("cells per region: " + ", ".join(f"{r} {int(counts.get(r, 0))}"
                                           for r in ("model", "agree", "disagree", "diverged")))
    if out is not None:
        print(f"wrote {out / 'validity_map.csv'} and {out / 'validity_map.png'}")
    return 0

"""The ``rockbench map`` command (issue 11, ``docs/maps.md``): arguments and output only;
the work is :mod:`rockbench.maps`."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .cli_input import backend_overrides
from .errors import ParameterError

__all__ = ["add_map_command", "cmd_map"]


def print_json(data) -> None:
    from .cli import _print_json
    _print_json(data)


def add_map_command(sub, _key_value, _count) -> None:
    """map (issue 11; docs/maps.md)."""
    p = sub.add_parser("map", help="overturning map of a scene over (A, W) under Ricker pulses, "
                       "or --compare two stored maps")
    p.add_argument("scene", metavar="SCENE", nargs="?",
                   help="a built-in scene name or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=_key_value,
                   action="append", default=[], help="override a scene parameter")
    p.add_argument("--engine", default="analytic", metavar="NAME", help="backend (default "
                   "analytic, through its compiled path)")
    p.add_argument("--grid", default="100x100", metavar="NAxNW",
                   help="points along A and W (default 100x100)")
    p.add_argument("--amplitude", default="0.5:8", metavar="LO:HI",
                   help="A = a_g / (g tan alpha), inclusive range (default 0.5:8)")
    p.add_argument("--frequency", default="0.5:10", metavar="LO:HI",
                   help="W = omega_g / p, inclusive range (default 0.5:10)")
    p.add_argument("--pulses", default="all", metavar="P",
                   help="all, or a comma-separated subset of symmetric+, symmetric-, "
                        "antisymmetric+, antisymmetric-")
    p.add_argument("--setting", dest="settings", metavar="NAME=VALUE", type=_key_value,
                   action="append", default=[], help="a backend setting (analytic: "
                   "method=compiled|solve_ivp)")
    p.add_argument("--store", metavar="FILE.parquet",
                   help="resumable Parquet store (a folder; default maps/SCENE_ENGINE.parquet)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=_count, metavar="N", help="local worker processes")
    g.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    p.add_argument("--compare", nargs=2, metavar=("A.parquet", "B.parquet"),
                   help="overlay two stored maps: agreement, kappa, boundary shift; "
                        "writes B's overlay figure next to B")
    p.add_argument("--json", action="store_true", help="print JSON")


def cmd_map(args: argparse.Namespace) -> int:
    from .maps import describe_shift, load_map, map_agreement, run_map

    if args.compare:
        a, b = (load_map(x) for x in args.compare)
        ag = map_agreement(a, b)
        out = {k: v for k, v in ag.items() if k != "shift"}
        out["boundary"] = ag["shift"].to_dict(orient="records")
        out["in_words"] = describe_shift(ag["shift"], Path(args.compare[1]).stem)
        if args.json:
            print_json(out)
            return 0
        print(f"{args.compare[1]} against {args.compare[0]}: {ag['n']} cells, "
              f"{100 * ag['fraction']:.2f} % agree, Cohen's kappa {ag['kappa']:.3f}")
        print(out["in_words"])
        return 0
    if not args.scene:
        raise ParameterError("SCENE", None, "a scene name or .toml path (or --compare A B)")
    from .cli_input import scene_overrides as _overrides

    scene_overrides = _overrides(args.overrides) if args.overrides else None
    settings = dict(args.settings)
    method = settings.pop("method", None)
    if args.engine != "analytic" and settings:
        settings = backend_overrides(args.engine, argparse.Namespace(
            settings=list(settings.items()), dt=None))
    store = args.store or str(Path("maps") / f"{Path(args.scene).stem}_{args.engine}.parquet")
    df = run_map(args.scene, args.engine, grid=args.grid, amplitude=args.amplitude,
                 frequency=args.frequency, pulses=args.pulses, overrides=scene_overrides,
                 settings=settings, method=method, store=store, workers=args.workers,
                 scheduler=args.scheduler, progress=sys.stderr.isatty() and not args.json)
    summary = {"scene": args.scene, "engine": args.engine, "cells": len(df),
               "reused": int(df.attrs.get("reused", 0)), "store": store,
               "overturned": int(df["overturned"].fillna(False).astype(bool).sum()),
               "not_ok": int((df["status"] != "ok").sum()), "method": df.attrs.get("method")}
    if args.json:
        print_json(summary)
        return 0
    print(f"{args.scene}, {args.engine}: {summary['cells']} cells ({summary['reused']} reused "
          f"from {store}), {summary['overturned']} overturn, {summary['not_ok']} not ok")
    return 0

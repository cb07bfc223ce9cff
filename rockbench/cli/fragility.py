"""The ``rockbench fragility`` command (``docs/fragility.md``): arguments and output
only; the work is :mod:`rockbench.studies.fragility`.

    rockbench fragility SCENE --records DIR|FILE|NAME ... [--engine E ...] [--scales LO:HI:N]
                        [--intensity pga|pgv] [--boot N] [--seed S] [--setting ENGINE.KEY=VALUE ...]
                        [--dt S] [--set KEY=VALUE ...] [--json] [--store DIR]
                        [--workers N | --scheduler ADDR] [-q]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from .common import (add_engine_option, add_quiet_option, add_setting_option, arg_count,
                     arg_key_value, print_json)

__all__ = ["register", "add_fragility_command", "cmd_fragility"]


def register(sub, commands: dict) -> None:
    """Add the ``fragility`` sub-command to ``sub`` and its handler to ``commands`` (the one
    line :mod:`rockbench.cli.main` spends on it)."""
    add_fragility_command(sub)
    commands["fragility"] = cmd_fragility


def add_fragility_command(sub) -> None:
    p = sub.add_parser("fragility", help="overturning fragility of a scene over an ensemble of "
                       "records, every engine against the analytic model")
    p.add_argument("scene", metavar="SCENE",
                   help="a built-in scene name (rockbench scenes) or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=arg_key_value,
                   action="append", default=[], help="override a scene parameter")
    p.add_argument("--records", nargs="+", action="extend", required=True,
                   metavar="DIR|FILE|NAME",
                   help="record folders, record files, or a bundled ensemble name "
                        "(bundled, or a folder shipped under rockbench/records)")

    add_engine_option(p, "every available backend; the analytic model always runs")
    p.add_argument("--scales", default="0.25:2:8", metavar="LO:HI:N",
                   help="ladder of scale factors of every record, N evenly spaced from LO to "
                        "HI inclusive (default 0.25:2:8)")
    p.add_argument("--intensity", choices=("pga", "pgv"), default="pga",
                   help="intensity measure: pga [m/s^2] (default) or pgv [m/s]")
    p.add_argument("--boot", type=arg_count, default=1000, metavar="N",
                   help="bootstrap resamples of the records (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    add_setting_option(p)
    p.add_argument("--dt", type=float, default=None, metavar="S",
                   help="engine time step [s] (engines only)")
    p.add_argument("--store", metavar="DIR",
                   help="resumable store (default fragility/SCENE); a rerun runs only "
                        "missing cases")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=arg_count, metavar="N", help="local worker processes")
    g.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    p.add_argument("--json", action="store_true", help="print JSON")
    add_quiet_option(p)


def summary(frag) -> dict[str, Any]:
    """The JSON the command prints: per backend ``median``, ``dispersion``, their intervals,
    and (engines) the test's ``statistic`` and ``p_value`` and the verdict."""
    a = frag.analysis
    keep = ("median", "median_ci", "dispersion", "dispersion_ci", "runs", "not_ok",
            "overturned", "records", "note", "n_valid_resamples", "cpu_s", "statistic",
            "p_value", "median_difference", "median_difference_ci", "indistinguishable",
            "verdict", "tests")
    return {"scene": frag.scene, "intensity": a["intensity"], "reference": a["reference"],
            "records": len(frag.records), "scales": frag.scales,
            "engine_scales": frag.info.get("engine_scales"), "level": a["level"],
            "n_boot": a["n_boot"], "seed": a["seed"], "store": frag.store,
            "backends": {b: {k: v[k] for k in keep if k in v}
                         for b, v in a["backends"].items()}}


def _interval(ci) -> str:
    lo, hi = ci
    return "-" if not (math.isfinite(lo) and math.isfinite(hi)) else f"[{lo:.3g}, {hi:.3g}]"


def cmd_fragility(args: argparse.Namespace) -> int:
    from .common import engine_names, engine_settings, load_scene_from, scene_overrides
    from ..studies.fragility import run_fragility
    from ..runner import REFERENCE, resolve_engines

    from ..studies.fragility_stats import check_bootstrap

    load_scene_from(args)                      # a bad scene or --set fails now
    check_bootstrap(args.boot, args.seed, names=("--boot", "--seed"))
    engines = engine_names(args)
    selected = [e for e in (engines or resolve_engines(None)) if e != REFERENCE]
    settings = engine_settings(list(args.settings), selected, dt=args.dt, also=(REFERENCE,))
    store = args.store or str(Path("fragility") / Path(args.scene).stem)
    frag = run_fragility(args.scene, args.records, engines=engines, scales=args.scales,
                         measure=args.intensity, settings=settings,
                         overrides=scene_overrides(args.overrides) or None, store=store,
                         workers=args.workers, scheduler=args.scheduler,
                         progress=not (args.quiet or args.json), n_boot=args.boot,
                         seed=args.seed)
    out = summary(frag)
    if args.json:
        print_json(out)
        return 0
    im = out["intensity"]
    from ..scene.scene import load_scene

    name = load_scene(args.scene).name               # the scene's own name, not its file
    print(f"{name}: {out['records']} records x 2 polarities x {len(frag.scales)} scales "
          f"({frag.scales[0]:g} to {frag.scales[-1]:g}); intensity {im['name']} [{im['unit']}]; "
          f"95 % intervals from {out['n_boot']} bootstrap resamples of the records")
    for b, v in out["backends"].items():
        print(f"  {b:10s} median {v['median']:.4g} {im['unit']} {_interval(v['median_ci'])}, "
              f"dispersion {v['dispersion']:.3g} {_interval(v['dispersion_ci'])}, "
              f"{v['overturned']} of {v['runs'] - v['not_ok']} runs overturned"
              + (f", {v['not_ok']} not ok" if v["not_ok"] else "")
              + (f" ({v['note']}; intensities in {im['unit']})" if v["note"] else ""))
    for b, v in out["backends"].items():
        if "verdict" in v:
            print(v["verdict"])
    print(f"store: {frag.store}")
    return 0

"""The commands for choosing a modelling approach (``docs/choosing.md``): ``rockbench tradeoff``,
``rockbench advise`` and ``rockbench stress`` - their arguments (:func:`add_choosing_commands`,
called by :func:`rockbench.cli.main.build_parser`) and their commands (``cmd_*``, dispatched by
:data:`rockbench.cli.main.COMMANDS`). Errors follow :mod:`rockbench.cli.main`: one line, exit code 2.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..constants import BUDGETS, DT_LADDER
from ..errors import ParameterError

from .common import add_vertical_option, engine_names, load_scene_from, vertical_ratio

__all__ = ["add_choosing_commands", "cmd_tradeoff", "cmd_advise", "cmd_stress"]


def _dts(text: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected time steps like 4e-3,2e-3, got {text!r}"
                                         ) from None
    if not vals or not all(v > 0 and math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"expected positive time steps [s], got {text!r}")
    return vals


def add_choosing_commands(sub) -> None:
    """tradeoff, advise and stress (docs/choosing.md)."""
    from .common import (add_scene_options, arg_count, arg_names, arg_positive, add_engine_option,
                      add_quiet_option)

    p = sub.add_parser("tradeoff", help="work-precision of every engine and setting on a scene "
                       "(error against the analytic model vs CPU cost)")
    add_scene_options(p)
    add_engine_option(p, "every available one")
    p.add_argument("--dt", type=_dts, metavar="S,S,...",
                   help=f"time steps [s] (default {','.join(f'{d:g}' for d in DT_LADDER)})")
    p.add_argument("--setting", dest="settings", metavar="ENGINE.KEY=VALUE[,...]",
                   action="append", default=[],
                   help="an extra setting swept at every dt, e.g. pymunk.iterations=60 (one "
                        "engine's fields, comma-separated, make one setting; bare KEY=VALUE "
                        "when one engine is selected); repeatable")
    p.add_argument("--repeat", type=arg_count, default=3, metavar="N",
                   help="runs of each case; cost = median CPU time (default 3)")
    p.add_argument("--quick", action="store_true", help="the reduced validation set")
    p.add_argument("--workers", type=arg_count, metavar="N", help="parallel worker processes")
    p.add_argument("--store", metavar="PATH", help="result store folder (reused on a rerun)")
    p.add_argument("--out", metavar="DIR",
                   help="write tradeoff.csv, tradeoff_runs.csv and work_precision.png")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    add_quiet_option(p)

    p = sub.add_parser("advise", help="the cheapest confirmed engine and setting within "
                                      "each tolerance")
    add_scene_options(p)
    p.add_argument("--tolerance", type=_tolerances, metavar="X[,Y...]",
                   help="relative bounds on the worst validation error (0.02 = 2 %%), "
                        "comma-separated (default: 0.1,0.05,0.02,0.005)")
    add_engine_option(p, "every registered engine")
    p.add_argument("--quick", action="store_true",
                   help="the quick evidence (a subset of the default): a first answer, with "
                        "its own held-out error")
    p.add_argument("--full", action="store_true",
                   help="the full evidence and the search of the contact parameters (slow)")
    add_vertical_option(p, "every pulse and record of the evidence")
    p.add_argument("--budget", type=arg_positive, metavar="CPU_S",
                   help="the most CPU seconds the search may spend (default: "
                        f"{BUDGETS['quick']:g} quick, {BUDGETS['default']:g} default, none "
                        "--full); beyond it the answer says what to run next")
    p.add_argument("--store", metavar="PATH",
                   help="result store folder, reused on a rerun (default advice/SCENE)")
    p.add_argument("--workers", type=arg_count, metavar="N", help="parallel worker processes")
    p.add_argument("--json", action="store_true", help="print the advice as JSON")
    add_quiet_option(p)

    p = sub.add_parser("stress", help="every engine at the extremes, one axis at a time")
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help="the base structure (built-in name or .toml file; default: the "
                        "paper's asymmetric frame, its device axes from the hybrid one)")
    add_engine_option(p, "every available one")
    p.add_argument("--full", action="store_true", help="the whole ranges (slow)")
    p.add_argument("--axes", type=arg_names, metavar="A,B,...", help="only these axes")
    p.add_argument("--workers", type=arg_count, metavar="N", help="parallel worker processes")
    p.add_argument("--out", metavar="DIR",
                   help="write stress.csv and one stability map per engine (PNG)")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    add_quiet_option(p)


def _swept_settings(texts: list[str], engines: list[str]) -> list:
    """tradeoff's ``--setting`` values, each one extra setting swept at every dt: one engine's
    ``ENGINE.KEY=VALUE`` fields, comma-separated, in the one grammar
    (:func:`rockbench.engines.setting_text.parse_overrides`); typed and validated here (a bad
    key or value exits 2 before anything runs) -> one ``Overrides`` each
    (:func:`rockbench.studies.tradeoff.settings_grid`)."""
    from ..engines.setting_text import parse_overrides

    return [parse_overrides(text, engines, option="--setting") for text in texts]


def _executor(args: argparse.Namespace) -> dict[str, Any]:
    """--workers N: a pool of N processes; 1: in this process (no pool to start)."""
    if args.workers == 1:
        return {"executor": "serial"}
    return {"workers": args.workers} if args.workers else {}


def _png(fig, path: Path) -> None:
    fig.savefig(path, dpi=110)


def cmd_tradeoff(args: argparse.Namespace) -> int:
    from .common import output_folder, pandas_display, print_json, write_atomic
    from ..report.tradeoff_figures import plot_work_precision
    from ..runner import resolve_engines
    from ..studies.tradeoff import tradeoff

    scene = load_scene_from(args)
    engines = engine_names(args)
    extra = _swept_settings(args.settings, [e for e in engines or resolve_engines(None)
                                            if e != "analytic"])
    if args.out:
        output_folder(Path(args.out) / "tradeoff.csv", "--out")
    t = tradeoff(scene, engines, dts=args.dt, settings=extra, repeat=args.repeat,
                 quick=args.quick, store=args.store, progress=not args.quiet,
                 **_executor(args))
    if args.out:
        out = Path(args.out)
        write_atomic({out / "tradeoff.csv": t.table,
                       out / "tradeoff_runs.csv": t.runs.drop(columns=["_cpu"])}, "--out")
        _png(plot_work_precision(t.table, title=f"{scene.name}: work-precision"),
             Path(args.out) / "work_precision.png")
    if args.json:
        print_json(t.to_json())
        return 0
    cols = ["engine", "setting", "worst_error", "verdict", "peak_error_worst",
            "peak_error_median", "nrmse_worst", "eta_error_worst", "verdicts_agree",
            "self_peak_error_worst", "cpu_per_sim_s", "real_time_factor"]
    with pandas_display():
        print(t.table[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    print("units: errors relative [-]; cpu_per_sim_s: process CPU s per simulated s "
          "(median of repeats); real_time_factor: simulated s per CPU s")
    if t.unavailable:
        print("unavailable: " + "; ".join(f"{k}: {v}" for k, v in t.unavailable.items()))
    if args.out:
        print(f"tables and figure: {args.out}")
    return 0


def _tolerances(text: str) -> list[float]:
    """``--tolerance X[,Y...]``: relative errors in (0, 1)."""
    out = []
    for part in text.split(","):
        try:
            v = float(part)
        except ValueError:
            v = math.nan
        if not 0.0 < v < 1.0:
            raise argparse.ArgumentTypeError(f"must be relative errors in (0, 1) such as 0.02 "
                                             f"(2 %) or 0.1,0.02, got {text!r}")
        out.append(v)
    return out


def cmd_advise(args: argparse.Namespace) -> int:
    from ..studies.advise import advise
    from .common import print_json

    scene = load_scene_from(args)
    full = bool(getattr(args, "full", False))   # --full: the full evidence, contact search
    if args.quick and full:
        raise ParameterError("--quick", True, "not together with --full")
    store = args.store or str(Path("advice") / Path(args.scene).stem)
    vertical = vertical_ratio(args)
    a = advise(scene, args.tolerance, engine_names(args), store, quick=args.quick,
               full=full, progress=not args.quiet, vertical=vertical,
               budget_cpu_s=args.budget if args.budget is not None else "auto",
               **_executor(args))
    if args.json:
        print_json(a.to_json())
    else:
        print(a.text())
    return 0


def cmd_stress(args: argparse.Namespace) -> int:
    from .common import output_folder, pandas_display, print_json, write_atomic
    from ..report.tradeoff_figures import plot_stability_map
    from ..scene.scene import load_scene
    from ..studies.robustness import AXES, axis_label, base_values, breaking_points, stress

    engines = engine_names(args)
    if args.out:
        output_folder(Path(args.out) / "stress.csv", "--out")
    scene = getattr(args, "scene", None)
    # a bad scene fails before anything runs; the base is named by its own name
    base = load_scene(scene if scene is not None else "paper-asymmetric").name
    s = stress(engines, full=args.full, axes=args.axes, progress=not args.quiet,
               scene=scene, **_executor(args))
    if args.out:
        write_atomic({Path(args.out) / "stress.csv": s.table}, "--out")
        labels = {a: axis_label(a) for a in [*AXES, "paper", "base"]}
        for eng in dict.fromkeys(s.table["engine"]):
            _png(plot_stability_map(s.table, eng, base=base, labels=labels,
                                    base_values=base_values(scene)),
                 Path(args.out) / f"stability_{eng}.png")
    if args.json:
        print_json(s.to_json())
        return 0
    cols = ["engine", "axis", "value", "class", "error", "status", "flags", "reason"]
    with pandas_display():
        print(_left_text(s.table[cols], ("flags", "reason")).to_string(
            index=False, float_format=lambda v: f"{v:.3g}"))
        print("axes and units: " + "; ".join(axis_label(a) for a in dict.fromkeys(
            s.table["axis"])) + " (error: relative to the analytic model, -)")
        for label, why in s.skipped.items():
            print(f"not run: {label}: its structure is refused by the model ({why})")
        print(f"\nfirst break away from {base}" + (" (the paper's frame)" if scene is None
              else "") + ", per engine and axis:")
        b = breaking_points(s.table, scene)
        print(_left_text(b, ("reason",)).to_string(index=False) if len(b) else
              "none: every point within 5 % or outside the analytic model")
    return 0


def _left_text(df, columns):
    """``df`` with the text ``columns`` left-aligned when printed (pandas right-aligns them,
    which pushes a long reason far to the right of its row)."""
    out = df.copy()
    for c in columns:
        if c in out and len(out):
            w = int(out[c].astype(str).str.len().max())
            out[c] = out[c].astype(str).str.ljust(w)
    return out

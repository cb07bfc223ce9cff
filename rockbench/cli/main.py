"""The ``rockbench`` command line (``rockbench ...`` or ``python -m rockbench ...``).

Commands (``docs/cli.md`` shows each with real output)::

    rockbench scenes    [--json]
    rockbench info      SCENE [--set key=value ...] [--json]
    rockbench run       SCENE [--engine NAME] MOTION [--duration S] [--dt S] [--set key=value ...]
                        [--setting [ENGINE.]KEY=VALUE ...] [--out DIR] [--csv FILE.csv] [--json]
    rockbench engines   [--json]
    rockbench compare   SCENE [--engine NAME ...] MOTION [--duration S] [--dt S] [--set ...]
                        [--setting ENGINE.KEY=VALUE ...] [--report DIR] [--csv FILE.csv] [--json]
    rockbench report    [--out DIR] [--records DIR] [--engine NAME ...] [--quick] [--full]
                        [--workers N] [--dask ADDRESS] [--store PATH]
    rockbench tradeoff  SCENE [--engine NAME ...] [--dt 4e-3,2e-3,...]
                        [--setting ENGINE.KEY=VALUE[,KEY=VALUE] ...] [--repeat N] [--quick]
                        [--workers N] [--store PATH] [--out DIR] [--json]
    rockbench advise    SCENE --tolerance 0.02 [--engine NAME ...] [--quick] [--store PATH]
                        [--workers N] [--json]
    rockbench stress    [--engine NAME ...] [--full] [--axes a,b,...] [--workers N] [--out DIR]
                        [--json]
    rockbench map       SCENE [--engine NAME] [--grid NAxNW] ... | --compare A B
    rockbench fragility SCENE --records ... [--engine NAME ...] ...
    rockbench validity-map SCENE [--shape S] [--sign 1|-1] [--vertical RATIO] [--engine NAME ...]
                        [--grid N] [--out DIR] [--json]

One grammar everywhere: ``--engine NAME`` (repeatable where a command runs several;
``--engines`` is the same option), ``--setting ENGINE.KEY=VALUE`` (bare ``KEY=VALUE`` only when
one engine is selected; parsed and validated once, in :mod:`rockbench.cli.common`), ``--out``
always a folder, ``--phi0`` in radians as ``rockbench.run`` (``--phi0-alpha`` in multiples of
alpha), ``--quiet`` for no progress (:mod:`rockbench.progress`).

MOTION is one of
``--pulse symmetric|antisymmetric [--sign 1|-1] --amplitude A --frequency W`` (A = a_g /
(g tan alpha), W = omega_g / p, alpha and p of the taller column), ``--record FILE
[--record-dt S --record-units UNITS] [--scale F]`` (or the ``records.csv`` beside FILE), or
``--phi0 RAD`` / ``--phi0-alpha X`` (free rocking). Units: SI and radians; times in s.

Errors: any bad input (a :class:`rockbench.errors.RockbenchError` or an argument the parser
rejects) prints one line ``rockbench: error: ...`` on stderr and returns 2, without a traceback;
so does an output (``--out``, ``--csv``, ``--report``) that cannot be written, checked before the
run. Outputs are written to a temporary name and renamed, never half-written. Any other
exception is a bug and keeps its traceback. ``docs/errors.md`` lists the limits and the inputs
tried.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .common import (CommandLineError, Parser, absent_engine_lines, add_engine_option,
                     one_line_warnings, add_motion_options, add_quiet_option, add_run_options,
                     add_vertical_option, vertical_ratio, add_scene_options, arg_count,
                     backend_overrides, engine_names, engine_settings, load_scene_from,
                     motion_from, output_folder, pandas_display, print_json, write_atomic)
from ..constants import G
from ..errors import ParameterError, RockbenchError

__all__ = ["build_parser", "main"]

PROG = "rockbench"

#: Commands that run several engines (by default every registered one): each ends by naming
#: the engines of its selection that could not run here, why, and the remedy.
ENGINE_COMMANDS = ("report", "compare", "tradeoff", "advise", "stress", "fragility",
                   "validity-map")

#: Summary rows of ``rockbench compare`` (the full table goes to --csv / --json).
COMPARE_COLUMNS = ("backend", "status", "max_abs_phi_over_alpha", "peak_rel_error", "nrmse",
                   "n_impacts", "eta_max_rel_error", "overturned", "verdict_agrees",
                   "max_penetration", "max_sliding", "wall_s", "real_time_factor")


# ==============================================================================================
# Parser
# ==============================================================================================
def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rockbench`` command."""
    from .. import __version__

    parser = Parser(prog=PROG, description="Analytic rocking-frame reference vs physics "
                     "engines. Units: SI and radians.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("scenes", help="list the built-in scenes")
    p.add_argument("--json", action="store_true", help="print JSON")

    p = sub.add_parser("info", help="analytic constants of a scene (alpha, p, lambda, eta, ...)")
    add_scene_options(p)
    p.add_argument("--json", action="store_true", help="print JSON")

    p = sub.add_parser("run", help="simulate a scene with one backend")
    add_scene_options(p)
    p.add_argument("--engine", default=None, metavar="NAME", action="append",
                   help="backend (rockbench engines; default analytic)")
    add_motion_options(p)
    add_run_options(p)
    p.add_argument("--out", metavar="DIR",
                   help="write DIR/history.csv and DIR/events.csv")
    p.add_argument("--csv", metavar="FILE.csv",
                   help="write the history to FILE.csv (and the events to <stem>_events.csv)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_quiet_option(p)

    p = sub.add_parser("engines", help="registered backends and installed engine versions")
    p.add_argument("--json", action="store_true", help="print JSON")

    p = sub.add_parser("compare", help="run several backends and compare them with the "
                       "analytic reference")
    add_scene_options(p)
    add_engine_option(p, "every available one")
    add_motion_options(p)
    add_run_options(p)
    p.add_argument("--report", metavar="DIR", help="write an HTML report of the case to DIR")
    p.add_argument("--csv", metavar="FILE.csv", help="write the metrics table as CSV")
    p.add_argument("--json", action="store_true", help="print the tables as JSON")
    add_quiet_option(p)

    p = sub.add_parser("report", help="run a campaign (the paper's, or one about your scenes) "
                                      "and write the HTML report")
    p.add_argument("scenes", nargs="*", metavar="SCENE",
                   help="the structures to report on (built-in names or .toml files; the first "
                        "is the one the decision is about); none: the paper's frames")
    p.add_argument("--plan", metavar="FILE",
                   help="a campaign plan file (kind = \"campaign-plan\", docs/report.md)")
    p.add_argument("--out", default="reports", metavar="DIR", help="output folder (reports)")
    p.add_argument("--records", metavar="DIR", help="records folder (default: bundled ones)")
    add_engine_option(p, "every available one")
    p.add_argument("--quick", action="store_true",
                   help="a small campaign that still decides: the quick evidence, the "
                        "analytic map only, no stability sweep or fragility")
    p.add_argument("--workers", type=arg_count, metavar="N", help="parallel worker processes")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run the cases on a dask.distributed scheduler at ADDRESS")
    p.add_argument("--store", metavar="PATH",
                   help="result store (Parquet or CSV); finished cases are skipped on a rerun")
    p.add_argument("--full", action="store_true",
                   help="the long campaign: measure every engine's map at the plan's full grid "
                        "(the paper's: 100x100x4, adaptively; OUT/engine-maps) where it is "
                        "missing or no longer reproduces, the slower engines' fragility runs "
                        "at the default report's cells (OUT/fragility-engines), the next "
                        "larger evidence, every engine's whole fragility ladder and the full "
                        "stability sweep (reuses the store)")
    add_vertical_option(p, "every pulse and record of the campaign (the stability sweep "
                           "stays horizontal)")
    add_quiet_option(p)
    from .choosing import add_choosing_commands

    add_choosing_commands(sub)
    from .maps import add_map_command
    add_map_command(sub)
    from .fragility import register as add_fragility  # rockbench fragility
    add_fragility(sub, COMMANDS)
    from .validity import register as add_validity  # rockbench validity-map
    add_validity(sub, COMMANDS)
    return parser


# ==============================================================================================
# Shared helpers
# ==============================================================================================
def _fmt(v: Any, digits: int = 6) -> str:
    if v is None:
        return "none"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.{digits}g}"
    return str(v)


def _table(rows: list[list[str]], header: list[str]) -> str:
    """A plain left-aligned text table."""
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(str(c).ljust(w) for c, w in zip(header, widths)).rstrip(),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    return "\n".join(lines)


def _describemotion_from(motion, phi0: float, alpha: float) -> str:
    """The motion's one long label (:func:`rockbench.result.motion_label`), with the initial
    rotation of free rocking and the size of a record."""
    from ..result import motion_label

    if motion is None:
        return f"free rocking from phi0 = {phi0 / alpha:.4g} alpha = {phi0:.6g} rad"
    d = motion.describe()
    text = motion_label(d, long=True)
    if d.get("kind") == "record":
        text += (f": {d['npts']} samples, dt = {d['dt_s']:g} s, PGA = {d['pga_m_s2']:.4g} m/s^2 "
                 f"({d['pga_m_s2'] / G:.3g} g)")
    return text


def _events_path(out: Path) -> Path:
    return out.with_name(f"{out.stem}_events.csv")


# ==============================================================================================
# Commands
# ==============================================================================================
def cmd_scenes(args: argparse.Namespace) -> int:
    from ..scene import builtin_scenes, load_scene

    rows = [{"name": name, "type": load_scene(name).structure.kind, "description": desc}
            for name, desc in builtin_scenes().items()]
    if args.json:
        print_json(rows)
    else:
        print(_table([[r["name"], r["type"], r["description"]] for r in rows],
                     ["name", "type", "description"]))
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    from .. import runner
    from ..analytic.reference import CONSTANTS

    scene = load_scene_from(args)
    consts = runner.info(scene)
    if args.json:
        print_json(consts)
        return 0
    alpha = consts["alpha"]
    print(f"scene: {consts.get('scene', scene.name)} ({consts.get('type', scene.structure.kind)})"
          f"{' with devices' if scene.has_devices else ''}")
    rows = []
    for key, value in consts.items():
        if key in ("scene", "type"):
            continue
        unit, meaning = CONSTANTS.get(key, ("", ""))
        if not hasattr(scene.structure, "column_height_left"):   # a block has no columns
            meaning = meaning.replace(" of the taller column", "")
        if unit == "rad" and key != "alpha" and isinstance(value, float):
            meaning += f" (= {value / alpha:.4g} alpha)"
        if value is None and key.startswith("phi_cr"):
            meaning += " (none: no zero of dV/dphi before the fall angle)"
        elif value is None and key.startswith("phi_fracture"):
            meaning += " (none: the tendons never fracture)"
        rows.append([key, _fmt(value), unit, meaning])
    print(_table(rows, ["quantity", "value", "unit", "meaning"]))
    return 0


def _run_engine(args: argparse.Namespace) -> str:
    """The one engine of ``rockbench run`` (default analytic)."""
    names = engine_names(args) or ["analytic"]
    if len(names) > 1:
        raise ParameterError("--engine", ",".join(names),
                             "one engine (rockbench compare runs several)")
    return names[0]


def _history_files(args: argparse.Namespace) -> list[tuple[str, Path, Path]]:
    """[(option, history path, events path)] of ``run --out DIR`` (DIR/history.csv,
    DIR/events.csv) and ``run --csv FILE.csv`` (FILE.csv, FILE_events.csv), their folders
    created and checked before the run."""
    files = []
    if args.out:
        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise RockbenchError(f"cannot write --out {out}: it is a file (--out is a folder; "
                                 "--csv FILE.csv names a file)")
        files.append(("--out", out / "history.csv", out / "events.csv"))
    if args.csv:
        csv = Path(args.csv)
        if csv.is_dir() or csv.name in ("", ".", ".."):
            raise RockbenchError(f"cannot write --csv {csv}: it is a folder (--out DIR writes "
                                 "DIR/history.csv)")
        files.append(("--csv", csv, _events_path(csv)))
    for option, history, _ in files:
        output_folder(history, option)               # before the run: fail fast
    return files


def cmd_run(args: argparse.Namespace) -> int:
    from .. import runner
    from ..progress import simulated_time

    scene = load_scene_from(args)
    engine = _run_engine(args)
    overrides = backend_overrides(engine, args)
    motion, phi0 = motion_from(args, scene)
    targets = _history_files(args)
    with simulated_time(f"{scene.name}: {engine}", show=not args.quiet):
        result = runner.run(scene, motion, engine=engine, duration=args.duration, phi0=phi0,
                            **overrides)
    files = {}
    for option, history, events in targets:
        write_atomic({history: result.history, events: result.events}, option)
        files = {"history_csv": str(history), "events_csv": str(events)}

    if args.json:
        data = result.to_json()
        data["engine"] = engine
        data["phi0"] = phi0
        data["real_time_factor"] = result.cost.real_time_factor
        data.update(files)
        print_json(data)
        return 0

    s, c, alpha = result.summary, result.cost, scene.alpha
    print(f"{scene.name}, engine {engine}: {_describemotion_from(motion, phi0, alpha)}")
    if s.status != "ok":
        print(f"status             {s.status}: {s.reason}")
    rows = [
        ["max |phi| / alpha", f"{s.max_abs_phi_over_alpha:.4g}",
         f"(max |phi| = {s.max_abs_phi:.4g} rad, alpha = {alpha:.4g} rad)"],
        ["uplifted", _fmt(s.uplifted),
         f"(first at t = {s.t_uplift:.4g} s)" if s.t_uplift is not None else ""],
        ["impacts", str(s.n_impacts), ""],
        ["exceeded critical", _fmt(s.exceeded_critical), ""],
        ["overturned", _fmt(s.overturned),
         f"(at t = {s.t_overturn:.4g} s)" if s.t_overturn is not None else ""],
        ["fractured", _fmt(s.fractured),
         f"(at t = {s.t_fracture:.4g} s)" if s.t_fracture is not None else ""],
        ["status", s.status, ""],
    ]
    if s.validity is not None:
        rows.append(["model validity", s.validity,
                     f"(contact: {s.sliding_contact})" if s.sliding_contact else ""])
    if s.eta_measured:
        etas = ", ".join(f"{e:.4f}" for e in s.eta_measured[:8])
        more = f", ... ({len(s.eta_measured)} in all)" if len(s.eta_measured) > 8 else ""
        rows.append(["eta measured", etas + more, "(-)"])
    if s.max_penetration is not None:
        rows.append(["max penetration", f"{s.max_penetration * 1e3:.3g} mm", ""])
    if s.max_sliding is not None:
        rows.append(["max sliding", f"{s.max_sliding * 1e3:.3g} mm", ""])
    rows.append(["cost", f"{c.wall_s:.3g} s wall",
                 (f"({c.steps} steps, {c.sim_time:.4g} s simulated, real-time factor "
                  f"{c.real_time_factor:.4g})")])
    for name, value, note in rows:
        print(f"{name:<18} {value} {note}".rstrip())
    if files:
        print(f"history: {files['history_csv']} ({len(result.history)} rows), "
              f"events: {files['events_csv']} ({len(result.events)} rows)")
    return 0


def cmd_engines(args: argparse.Namespace) -> int:
    from ..engines import engine_info, engine_versions

    rows = engine_info()
    packages = engine_versions()                 # from the package metadata, no import
    for r in rows:
        r["package"] = packages.get(r["name"])
    if args.json:
        print_json(rows)
        return 0
    print(_table([[r["name"], _fmt(r["available"]), r.get("version") or r.get("reason", ""),
                   r["package"] or "not installed"] for r in rows],
                 ["backend", "imports", "engine version / reason", "package"]))
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    from .. import comparison as compare_mod
    from ..runner import REFERENCE, resolve_engines

    scene = load_scene_from(args)
    engines = engine_names(args)
    motion, phi0 = motion_from(args, scene)
    chosen = [e for e in (engines or resolve_engines(None)) if e != REFERENCE] or [REFERENCE]
    settings = engine_settings(args.settings, chosen, dt=args.dt, also=(REFERENCE,))
    if args.csv:
        output_folder(Path(args.csv), "--csv")
    if args.report:
        output_folder(Path(args.report) / "index.html", "--report")
    comparison = compare_mod.compare(scene, motion, engines=engines, phi0=phi0,
                                     duration=args.duration, settings=settings or None,
                                     progress=not args.quiet)
    table = comparison.table
    report_path = csv_path = None
    if args.csv:
        csv_path = Path(args.csv)
        write_atomic({csv_path: table}, "--csv")
    if args.report:
        from ..report import write_case_report

        try:
            report_path = write_case_report(comparison, args.report)
        except OSError as e:
            raise RockbenchError(f"cannot write --report {args.report}: "
                                 f"{e.strerror or e}") from None
    ref = next((r for r in comparison.results.values() if r.backend == "analytic"), None)
    if args.json:
        data = {"scene": scene.name, "motion": comparison.motion, "phi0": comparison.phi0,
                "table": table.to_dict(orient="records"),
                "eta": comparison.eta.to_dict(orient="records")}
        if ref is not None:     # the analytic model's own validity (docs/metrics.md)
            data.update({k: getattr(ref.summary, k) for k in
                         ("sliding_onset", "sliding_contact", "t_lift_off", "validity")})
        if csv_path:
            data["csv"] = str(csv_path)
        if report_path:
            data["report"] = str(report_path)
        print_json(data)
        return 0
    print(f"{scene.name}: {_describemotion_from(motion, phi0, scene.alpha)}")
    cols = [c for c in COMPARE_COLUMNS if c in table.columns]
    with pandas_display():
        print(table[cols].to_string(index=False, na_rep="n/a",
                                    float_format=lambda v: f"{v:.4g}"))
    print("units: max_abs_phi_over_alpha, peak_rel_error, nrmse, eta_max_rel_error: -; "
          "max_penetration, max_sliding: m; wall_s: s; real_time_factor: simulated s per wall s"
          "; n/a: not measured (e.g. the analytic model has no contact to penetrate or slide)")
    if ref is not None and ref.summary.validity and ref.summary.validity != "inside":
        print(f"analytic model: {ref.summary.validity}")
    for name, res in comparison.results.items():       # a run not ok says why, not only that
        if res.summary.status != "ok":
            print(f"{name}: {res.summary.status}: {res.summary.reason or 'no reason given'}")
    if csv_path:
        print(f"table: {csv_path}")
    if report_path:
        print(f"report: {report_path}")
    return 0


def _print_constants(out: str | Path, scenes=None) -> None:
    """Print the analytic constants of the campaign's scenes (``scenes``: a user's; default
    the paper plan's) and write them to ``out/constants.csv`` (the table ``rockbench info``
    gives for one scene)."""
    import pandas as pd

    from ..analytic.reference import CONSTANTS
    from ..runner import info
    from ..scene import load_scene

    if Path(out).exists() and not Path(out).is_dir():
        raise ParameterError("--out", str(out), "a folder (it is a file)")
    if not scenes:
        from ..campaign.plan import campaign_plan, every_scene

        scenes = every_scene(campaign_plan())          # the paper's frames, every one it runs

    keys = ("alpha", "p", "lambda_ccw", "lambda_cw", "eta_ccw", "eta_cw", "phi_cr_ccw",
            "phi_cr_cw", "phi_fall_ccw", "phi_fall_cw", "phi_fracture_ccw", "phi_fracture_cw")
    cols = {"scene": "", **{k: CONSTANTS[k][0] for k in keys}}
    rows = [info(load_scene(name)) for name in scenes]
    table = pd.DataFrame(rows).reindex(columns=list(cols))
    print("Analytic constants of the campaign's scenes (critical angle: none = no zero of "
          "dV/dphi before the fall angle; fracture: none = no fracture):")
    shown = table.rename(columns={c: f"{c} [{u}]" if u else c for c, u in cols.items()})
    with pandas_display():
        print(shown.to_string(index=False, na_rep="none", float_format=lambda v: f"{v:.5g}"))
    output_folder(Path(out) / "constants.csv", "--out")
    write_atomic({Path(out) / "constants.csv": table}, "--out")


def cmd_report(args: argparse.Namespace) -> int:
    from ..campaign import run as campaign

    if args.records is not None and not Path(args.records).is_dir():
        raise ParameterError("--records", args.records, "an existing folder of record files")
    engines = engine_names(args)
    kwargs: dict[str, Any] = {"full": args.full, "progress": not args.quiet,
                              "engines": engines, "records_dir": args.records,
                              "quick": args.quick, "store": args.store,
                              "scenes": list(args.scenes) or None,
                              "vertical": vertical_ratio(args) if args.vertical else None}
    if args.plan is not None:
        if args.scenes:
            raise ParameterError("--plan", args.plan, "either --plan FILE or scenes, not both")
        if not Path(args.plan).is_file():
            raise ParameterError("--plan", args.plan, "an existing plan file (.toml)")
        kwargs["plan"] = args.plan
    if args.dask is not None:
        kwargs.update(executor="dask", dask_address=args.dask)
    if args.workers is not None:
        kwargs["workers"] = args.workers
    plan_scenes = list(args.scenes)
    if args.plan is not None:
        from ..campaign.plan import plan_file_scenes

        plan_scenes = plan_file_scenes(args.plan)    # the whole plan checked, before any work
    _print_constants(args.out, plan_scenes or None)
    path = campaign.run_campaign(args.out, **kwargs)
    print(f"report: {path}")
    return 0


def _choosing(name: str):
    """``rockbench tradeoff | advise | stress`` (rockbench/cli/choosing.py), imported on use."""
    def command(args: argparse.Namespace) -> int:
        from . import choosing as cli_choosing

        return getattr(cli_choosing, f"cmd_{name}")(args)
    return command


def _map(args: argparse.Namespace) -> int:
    from .maps import cmd_map
    return cmd_map(args)


COMMANDS = {"scenes": cmd_scenes, "info": cmd_info, "run": cmd_run, "engines": cmd_engines,
            "compare": cmd_compare, "report": cmd_report, "tradeoff": _choosing("tradeoff"),
            "advise": _choosing("advise"), "stress": _choosing("stress"), "map": _map}


# ==============================================================================================
def _one_line(message: str) -> str:
    return " ".join(str(message).split())


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); return the exit code:
    0 success, 2 bad input (one line ``rockbench: error: ...`` on stderr), 130 interrupted,
    141 output pipe closed early."""
    parser = build_parser()
    try:
        args = parser.parse_args(None if argv is None else list(argv))
    except CommandLineError as e:
        print(f"{PROG}: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except SystemExit as e:  # --help, --version
        return e.code if isinstance(e.code, int) else 0
    from ..progress import configure

    configure(quiet=bool(getattr(args, "quiet", False)))
    try:
        with one_line_warnings():
            rc = COMMANDS[args.command](args)
        if args.command in ENGINE_COMMANDS:     # every engine it could not use, one line each
            for line in absent_engine_lines(args):
                print(f"{PROG}: {line}", file=sys.stderr)
        return rc
    except RockbenchError as e:
        print(f"{PROG}: error: {_one_line(e)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`, which exited early
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        except (OSError, ValueError):
            pass
        return 141

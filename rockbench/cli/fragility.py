"""The ``rockbench fragility`` command (``docs/fragility.md``): arguments and output
only; the work is :mod:`rockbench.studies.fragility`.

    rockbench fragility SCENE --records DIR|FILE|NAME ... [--engine E ...] [--scales LO:HI:N]
                        [--intensity pga|pgv|pga_norm|pgv_norm|sa] [--boot N] [--seed S]
                        [--setting ENGINE.KEY=VALUE ...] [--dt S] [--set KEY=VALUE ...]
                        [--tail S] [--vertical RATIO] [--no-numerical] [--export DIR] [--json]
                        [--store DIR] [--workers N | --scheduler ADDR] [-q]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..studies.intensity import MEASURES
from .common import (add_engine_option, add_quiet_option, add_setting_option, arg_count,
                     arg_key_value, arg_number, print_json)

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
                   help="record folders, record files, a bundled ensemble name "
                        "(bundled, or a folder shipped under rockbench/records), or the "
                        "synthetic ensemble: synthetic (20 records, seed 0), "
                        "synthetic:seed=S or synthetic:n=N,seed=S (docs/synthetic.md)")

    add_engine_option(p, "every available backend; the analytic model always runs")
    p.add_argument("--scales", default="0.25:2:8", metavar="LO:HI:N",
                   help="ladder of scale factors of every record, N evenly spaced from LO to "
                        "HI inclusive (default 0.25:2:8)")
    p.add_argument("--intensity", choices=tuple(MEASURES), default="pga",
                   help="intensity measure of the curves: pga [m/s^2] (default), pgv [m/s], "
                        "pga_norm = PGA/(g tan alpha) [-], pgv_norm = PGV/(p g tan alpha) [-], "
                        "sa = Sa(2 pi / p) [m/s^2]; the table of every measure's dispersion "
                        "is printed whichever is chosen")
    p.add_argument("--tail", type=float, default=None, metavar="S",
                   help="end each run S seconds after the record's strong motion (95 %% of "
                        "its Arias intensity); default: the whole record + 10 s")
    p.add_argument("--vertical", type=arg_number, default=None, metavar="RATIO",
                   help="every record without a vertical channel of its own (a records.csv "
                        "column vertical names one) also moves the ground vertically: a_v = "
                        "RATIO x its horizontal acceleration, in phase, 0 to 3 (default: only "
                        "the recorded channels)")
    p.add_argument("--no-numerical", dest="numerical", action="store_false",
                   help="do not measure the engines' own error on the scene (beta_num; "
                        "measured by default on the scene's pulses at the settings used)")
    p.add_argument("--export", metavar="DIR",
                   help="write the fitted curves to DIR/fragility.xml (OpenQuake NRML) and "
                        "DIR/fragility.csv (pelicun), docs/fragility-export.md")
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
    """The JSON the command prints: the ensemble, per backend ``median``, ``dispersion``, their
    intervals, ``dispersion_numerical`` and ``dispersion_total``, the most efficient measure,
    and (engines) the test's ``statistic`` and ``p_value`` and the verdict; ``measures``: the
    intensity-measure table; ``numerical``: how each engine's beta_num was measured;
    ``vertical`` (only when the runs carry vertical motion): which
    (:func:`rockbench.studies.fragility.describe_vertical`)."""
    a = frag.analysis
    keep = ("median", "median_ci", "dispersion", "dispersion_ci", "dispersion_numerical",
            "dispersion_total", "im_best", "im_same_best", "runs", "not_ok", "outside_model",
            "overturned", "records", "note", "n_valid_resamples", "cpu_s", "statistic",
            "p_value", "median_difference", "median_difference_ci", "indistinguishable",
            "verdict", "tests")
    out = {"scene": frag.scene, "intensity": a["intensity"], "reference": a["reference"],
            "ensemble": {k: v for k, v in a.get("ensemble", {}).items() if k != "text"},
            "records": len(frag.records), "scales": frag.scales,
            "engine_scales": frag.info.get("engine_scales"), "tail": a.get("tail"),
            "structure": a.get("structure"), "level": a["level"],
            "n_boot": a["n_boot"], "seed": a["seed"], "store": frag.store,
            "backends": {b: {k: v[k] for k in keep if k in v}
                         for b, v in a["backends"].items()},
            "measures": a.get("measures"), "numerical": a.get("numerical", {}),
            "validity": a.get("validity")}
    if a.get("vertical"):                  # absent without vertical motion (keys unchanged)
        out["vertical"] = a["vertical"]
    return out


def _interval(ci) -> str:
    lo, hi = ci
    return "-" if not (math.isfinite(lo) and math.isfinite(hi)) else f"[{lo:.3g}, {hi:.3g}]"


def cmd_fragility(args: argparse.Namespace) -> int:
    from .common import (engine_names, engine_settings, load_scene_from, output_folder,
                         scene_overrides)
    from ..studies.fragility import run_fragility
    from ..runner import REFERENCE, resolve_engines

    from ..studies.fragility_stats import check_bootstrap

    load_scene_from(args)                      # a bad scene or --set fails now
    check_bootstrap(args.boot, args.seed, names=("--boot", "--seed"))
    if args.vertical is not None:
        from ..limits import check_in_limit

        check_in_limit("vertical_ratio", "--vertical", args.vertical)
    engines = engine_names(args)
    selected = [e for e in (engines or resolve_engines(None)) if e != REFERENCE]
    settings = engine_settings(list(args.settings), selected, dt=args.dt, also=(REFERENCE,))
    store = args.store or str(Path("fragility") / Path(args.scene).stem)
    if args.export:
        output_folder(Path(args.export) / "fragility.xml", "--export")
    frag = run_fragility(args.scene, args.records, engines=engines, scales=args.scales,
                         measure=args.intensity, settings=settings,
                         overrides=scene_overrides(args.overrides) or None, store=store,
                         workers=args.workers, scheduler=args.scheduler,
                         progress=not (args.quiet or args.json), n_boot=args.boot,
                         seed=args.seed, tail=args.tail,
                         numerical="measure" if args.numerical else None,
                         vertical=args.vertical)
    out = summary(frag)
    if args.export:
        from ..errors import ParameterError
        from ..studies.fragility_export import write_fragility_exports

        try:
            written = write_fragility_exports(frag.analysis, args.export, runs=frag.runs,
                                              record_ims=frag.records)
            out["export"] = {k: str(v) for k, v in written.items()}
        except ParameterError as e:            # no curve to write: said, not an error
            out["export"] = {"error": f"not written: {e}"}
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
    print(f"ensemble: {frag.analysis['ensemble']['text']}")
    if out.get("vertical"):
        print(out["vertical"]["text"])
    if (out.get("validity") or {}).get("text"):
        print(out["validity"]["text"])
    print("dispersion: record-to-record beta_RR, the engine's own beta_num (its error on the "
          "scene's pulses at this setting), beta_total = sqrt(beta_RR^2 + beta_num^2) [-]")
    for b, v in out["backends"].items():
        print(f"  {b:10s} beta_RR {v['dispersion']:.3g}, beta_num "
              f"{v['dispersion_numerical']:.2g}, beta_total {v['dispersion_total']:.3g}")
    m = out.get("measures")
    if m:
        st = out["structure"]
        print(f"intensity measures (dispersion [-], rank; Sa at T_p = 2 pi / p = "
              f"{st['sa_period']:.3g} s):")
        for b, v in m["backends"].items():
            print(f"  {b:10s} " + ", ".join(
                f"{m['measures'][k]['name']} {f['dispersion']:.3g} ({f['rank']})"
                for k, f in v["fits"].items() if f["rank"] is not None))
        for v in m["backends"].values():
            if "sentence" in v:
                print(v["sentence"])
    if args.export:
        print("export: " + ", ".join(out["export"].values()))
    print(f"store: {frag.store}")
    return 0

"""The ``rockbench map`` command (``docs/maps.md``): arguments and output only;
the work is :mod:`rockbench.studies.maps`."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .common import (add_quiet_option, add_setting_option, arg_count, arg_key_value,
                     arg_number, backend_overrides, print_json)
from ..errors import ParameterError

__all__ = ["add_map_command", "cmd_map"]


def add_map_command(sub) -> None:
    """map (docs/maps.md)."""
    p = sub.add_parser("map", help="overturning map of a scene over (A, W) under Ricker pulses, "
                       "or --compare two stored maps")
    p.add_argument("scene", metavar="SCENE", nargs="?",
                   help="a built-in scene name or a path to a .toml file")
    p.add_argument("--set", dest="overrides", metavar="KEY=VALUE", type=arg_key_value,
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
    p.add_argument("--vertical", type=arg_number, default=0.0, metavar="RATIO",
                   help="every pulse also moves the ground vertically: a_v = RATIO x u_g'' "
                        "(same shape, sign and period, in phase; positive up), 0 to 3 "
                        "(default 0: horizontal only)")

    add_setting_option(p, "set")       # the one grammar; analytic: method=compiled|solve_ivp
    add_quiet_option(p)
    p.add_argument("--store", metavar="FILE.parquet",
                   help="resumable Parquet store (a folder; default maps/SCENE_ENGINE.parquet)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=arg_count, metavar="N", help="local worker processes")
    g.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    p.add_argument("--compare", nargs=2, metavar=("A.parquet", "B.parquet"),
                   help="two stored maps of the same cells: agreement, kappa, boundary shift "
                        "(with --figure: B's verdicts overlaid on A)")
    p.add_argument("--adaptive", action="store_true",
                   help="simulate only where the verdict can change (a coarse pass, then "
                        "refinement where neighbours differ or survival is near critical) and "
                        "infer the other cells (marked in the store)")
    p.add_argument("--figure", metavar="FILE.png",
                   help="draw the map (with --compare: the overlay) to this image file "
                        "(.png, .pdf or .svg)")
    p.add_argument("--json", action="store_true", help="print JSON")


def _figure_path(text: str | None) -> Path | None:
    """The --figure path, checked before any work: a known image suffix, a writable folder."""
    if text is None:
        return None
    from ..errors import RockbenchError

    path = Path(text)
    if path.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise ParameterError("--figure", text, "a file name ending in .png, .pdf or .svg")
    if path.is_dir():
        raise RockbenchError(f"cannot write --figure {path}: it is a folder")
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise RockbenchError(f"cannot write --figure {path}: {e.strerror or e}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise RockbenchError(f"cannot write --figure {path}: folder {folder} is not writable")
    return path


def _save(fig, path: Path) -> None:
    from ..errors import RockbenchError

    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, path)
    except OSError as e:
        raise RockbenchError(f"cannot write --figure {path}: {e.strerror or e}") from None
    finally:
        tmp.unlink(missing_ok=True)


def _with_near_boundary(df, store: Path):
    """``df`` (the first map of --compare) with its cells near the boundary marked
    (:func:`rockbench.studies.maps.mark_near_boundary`) when its store says it is an analytic map
    (its scene, run length and vertical ratio are in ``_inputs.json``); otherwise ``df``
    unchanged."""
    import re

    from ..studies.map_agreement import mark_near_boundary
    from ..scene.scene import Scene
    from ..sweep.map_store import read_inputs

    inputs = read_inputs(store)
    if not isinstance(inputs, dict) or inputs.get("engine") != "analytic" or not len(df):
        return df
    m = re.search(r"\+ ([0-9.eE+-]+) s$", str(inputs.get("duration", "")))
    tail = float(m.group(1)) if m else None
    scene = Scene.from_dict(inputs["scene"], source=f"{store}/_inputs.json")
    return mark_near_boundary(df, scene, tail=None if tail == 10.0 else tail,
                              vertical=float(inputs.get("vertical_ratio", 0.0)))


#: Options of a map run that mean nothing with --compare (a comparison reads two stores).
_RUN_OPTIONS = (("scene", None, "SCENE"), ("grid", "100x100", "--grid"),
                ("amplitude", "0.5:8", "--amplitude"), ("frequency", "0.5:10", "--frequency"),
                ("pulses", "all", "--pulses"), ("vertical", 0.0, "--vertical"),
                ("engine", "analytic", "--engine"),
                ("store", None, "--store"), ("adaptive", False, "--adaptive"),
                ("workers", None, "--workers"), ("scheduler", None, "--scheduler"))


def _compare_alone(args: argparse.Namespace) -> None:
    """ParameterError when an option that runs a map is given with --compare (it would be
    ignored: the comparison reads the two stores as they are)."""
    for attr, default, option in _RUN_OPTIONS:
        if getattr(args, attr, default) != default:
            raise ParameterError(option, getattr(args, attr),
                                 "left out with --compare A B (a comparison reads the two "
                                 "stores as they are; run each map first)")
    if args.overrides or args.settings:
        raise ParameterError("--set" if args.overrides else "--setting",
                             (args.overrides or args.settings)[0],
                             "left out with --compare A B (a comparison reads the two stores)")


def _is_map_store(path: str) -> None:
    """RockbenchError naming ``path`` unless it is a map store folder (``_inputs.json`` or map
    part files: what ``rockbench map --store`` writes)."""
    from ..errors import RockbenchError
    from ..sweep.map_store import part_files

    p = Path(path)
    if not p.is_dir():
        raise ParameterError("--compare", path, "map store folders written by rockbench map "
                             "(NAME.parquet)", "no such folder" if not p.exists()
                             else "a file, not a folder")
    if not (p / "_inputs.json").is_file() and not part_files(p):
        raise RockbenchError(f"--compare: {path} is not a map store (it holds neither "
                             f"_inputs.json nor part-*.parquet files of a map); give the "
                             f"--store folders of two `rockbench map` runs")


def agreement_words(ag: dict) -> str:
    """The words of :func:`rockbench.report.words.agreement_words` for a
    :func:`~rockbench.studies.map_agreement.map_agreement` result."""
    from ..report.words import agreement_words as words

    common = ag.get("common", ag["n"])
    return words({"cells": ag["n"], "differ": ag.get("differ"), "agree_fraction":
                  ag["fraction"], "kappa": ag["kappa"],
                  "not_ok": ag.get("not_ok_first", 0) + ag.get("not_ok_second", 0),
                  "only_first": ag.get("cells_first", common) - common,
                  "only_second": ag.get("cells_second", common) - common},
                 against="the first map")


def _same_structure(first: str, second: str) -> None:
    """RockbenchError unless the two stores' ``_inputs.json`` name the same structure (its
    parameters, the name and description aside): a map of one structure says nothing about
    another's verdicts, even on the same (A, W) cells."""
    from ..errors import RockbenchError
    from ..sweep.map_store import read_inputs

    scenes = []
    for path in (first, second):
        inputs = read_inputs(Path(path))
        scene = inputs.get("scene") if isinstance(inputs, dict) else None
        if isinstance(scene, dict):
            scene = {k: v for k, v in scene.items() if k not in ("name", "description")}
        scenes.append(scene)
    if scenes[0] is not None and scenes[1] is not None and scenes[0] != scenes[1]:
        raise RockbenchError(f"{first} and {second} are maps of different structures (their "
                             "_inputs.json differ): --compare takes two maps of one scene")


def _set_aside_other_code(store: Path, *, quiet: bool) -> None:
    """The default store (``maps/SCENE_ENGINE.parquet``, not one the user named) written by
    other rockbench physics code (its ``code`` fingerprint differs) is renamed to
    ``NAME.parquet.code-OLD`` and the map computed afresh, with one line on stderr: an upgrade
    neither fails nor deletes anything. A store the user named is refused as before."""
    from ..sweep.map_store import read_inputs
    from ..sweep.store import code_fingerprint

    if not (store / "_inputs.json").is_file():
        return
    old = read_inputs(store)
    if isinstance(old, str) or "code" not in old or old["code"] == code_fingerprint():
        return
    aside = store.with_name(f"{store.name}.code-{old['code']}")
    if aside.exists():
        return                                   # leave it to the refusal, which names both
    try:
        store.rename(aside)
    except OSError:
        return
    if not quiet:
        print(f"rockbench: {store} was computed by other rockbench code (code {old['code']}); "
              f"kept as {aside}, computing the map afresh", file=sys.stderr)


def cmd_map(args: argparse.Namespace) -> int:
    from ..errors import RockbenchError
    from ..studies.map_agreement import NEAR_BOUNDARY_MARGIN, describe_shift, map_agreement
    from ..studies.maps import load_map, run_map

    figure = _figure_path(args.figure)
    if args.compare:
        _compare_alone(args)
        for path in args.compare:
            _is_map_store(path)
        _same_structure(*args.compare)
        a, b = (load_map(x) for x in args.compare)
        a = _with_near_boundary(a, Path(args.compare[0]))
        ag = map_agreement(a, b)
        if ag["n"] == 0:
            raise RockbenchError(f"{args.compare[0]} and {args.compare[1]} share "
                                 f"{len(ag['cells'])} cells, but none ran with status ok in "
                                 f"both: nothing to compare")
        out = {k: v for k, v in ag.items() if k not in ("shift", "cells")}
        out["boundary"] = ag["shift"].to_dict(orient="records")
        out["in_words"] = describe_shift(ag["shift"], Path(args.compare[1]).stem)
        if figure is not None:
            from ..report.map_figures import plot_map_overlay

            name = Path(args.compare[1]).stem
            _save(plot_map_overlay(a, b, name=name, title=f"{name} on {Path(args.compare[0]).stem}"
                                   f": {100 * ag['fraction']:.1f} % of {ag['n']} cells agree"),
                  figure)
            out["figure"] = str(figure)
        if args.json:
            print_json(out)
            return 0
        print(f"{args.compare[1]} against {args.compare[0]}: {agreement_words(ag)}")
        if "near_boundary" in ag:
            print(f"{ag['near_boundary']} cells lie within {100 * NEAR_BOUNDARY_MARGIN:g} % in A "
                  f"of the first map's boundary (near the boundary): "
                  f"{ag['disagree_near_boundary']} differing verdicts there, "
                  f"{ag['disagree_away']} away from it")
        print(out["in_words"])
        if figure is not None:
            print(f"figure: {figure}")
        return 0
    if not args.scene:
        raise ParameterError("SCENE", None, "a scene name or .toml path (or --compare A B)")
    from ..engines.setting_text import split_field
    from ..studies.maps import check_vertical_ratio
    from ..sweep.map_store import map_store_path
    from .common import scene_overrides as _overrides

    vertical = check_vertical_ratio(args.vertical, "--vertical")

    scene_overrides = _overrides(args.overrides) if args.overrides else None
    method, texts = None, []
    for text in args.settings:         # the map's own analytic choice: method=compiled|solve_ivp
        engine, key, raw = split_field(text)
        if args.engine == "analytic" and key == "method" and engine in (None, "analytic"):
            method = raw
        else:
            texts.append(text)
    settings = backend_overrides(args.engine, argparse.Namespace(settings=texts, dt=None))
    # the default store of a vertical map is its own (a horizontal one is not refused)
    tags = [f"vertical{vertical:g}"] if vertical else []
    store = args.store or str(map_store_path("maps", Path(args.scene).stem, args.engine, *tags))
    if not args.store:
        _set_aside_other_code(Path(store), quiet=args.quiet)
    df = run_map(args.scene, args.engine, grid=args.grid, amplitude=args.amplitude,
                 frequency=args.frequency, pulses=args.pulses, overrides=scene_overrides,
                 settings=settings, method=method, store=store, workers=args.workers,
                 scheduler=args.scheduler, progress=not args.quiet, adaptive=args.adaptive,
                 vertical=vertical)
    summary = {"scene": args.scene, "engine": args.engine, "vertical_ratio": vertical,
               "cells": len(df), "cells_run": int(df.attrs.get("cells_run", 0)),
               "reused": int(df.attrs.get("reused", 0)), "store": store,
               "overturned": int(df["overturned"].fillna(False).astype(bool).sum()),
               "not_ok": int((df["status"] != "ok").sum()),
               "outside": int(df["outside"].sum()), "method": df.attrs.get("method")}
    if args.adaptive:
        summary["inferred"] = int(df.attrs.get("inferred", 0))
    name = df.attrs.get("scene", args.scene)          # the scene's own name, not its file
    what = f"{name}, {args.engine}" + (f", a_v = {vertical:g} a_g" if vertical else "")
    if figure is not None:
        from ..report.map_figures import plot_map_panels

        _save(plot_map_panels(df, title=what), figure)
        summary["figure"] = str(figure)
    if args.json:
        print_json(summary)
        return 0
    how = (f", {summary['cells_run']} simulated now, {summary['inferred']} inferred"
           if args.adaptive else "")
    print(f"{what}: {summary['cells']} cells ({summary['reused']} reused "
          f"from {store}{how}), {summary['overturned']} overturn, {summary['not_ok']} not ok, "
          f"{summary['outside']} outside the analytic model")
    if figure is not None:
        print(f"figure: {figure}")
    return 0

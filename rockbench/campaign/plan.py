"""Campaign plans: what ``rockbench report`` runs, as data.

* The paper's plan ships as ``rockbench/scenarios/paper-plan.toml`` (``kind = "campaign-plan"``);
  :func:`campaign_plan` reads it (once, on first use).
* ``rockbench report --plan FILE`` runs a user's plan file of the same form
  (:func:`load_plan`): keys left out are derived from its ``scenes`` as below. Every plan,
  the paper's included, is checked completely against the one schema before any work
  (:mod:`rockbench.campaign.plan_schema`, ``docs/plans.md``).
* ``rockbench report SCENE [SCENE ...]`` runs :func:`plan_for_scenes`: the same parts as the
  paper's campaign, with every case chosen from the scenes themselves through the analytic
  model (nothing is taken from the paper's frames):

  - pulse cases at W = 3 and 4 with A the geometric mean of the largest uplift threshold
    (A_up = min|lambda| / tan alpha) and the smallest analytic overturning threshold of the four
    Ricker pulses at that W (over every scene): each scene rocks and survives;
  - fracture cases: per scene with fracturing devices, the smallest A (A = 1 .. 60 by factors
    of 1.25, antisymmetric + pulse, W = 3) at which the analytic model fractures them;
  - analytic maps of every scene at the paper's resolution, engine maps of the first scene (the
    fast engines on 6 x 6 x 4 cells by default, every engine at 12 x 12 x 4 with ``--full``),
    A up to max(8, 1.5 x the threshold at W = 10);
  - work-precision, advice and the stability sweep on the first scene;
  - the bundled records on every scene (at most three), both polarities.

A = a_g / (g tan alpha), W = omega_g / p with alpha and p of each scene's taller column.
"""

from __future__ import annotations

import functools
import math
import os
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Sequence

from ..errors import ParameterError, SceneError

__all__ = ["plan_for_scenes", "load_plan", "scene_refs", "structure_table", "campaign_plan",
           "read_plan", "every_scene"]

_SHAPES = (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1), ("antisymmetric", -1))


def scene_refs(scenes: Sequence[Any], folder: str | os.PathLike) -> list[str]:
    """Scene arguments as strings a worker process can load: built-in names and TOML paths as
    they are (paths made absolute), :class:`~rockbench.scene.scene.Scene` objects saved as
    ``folder/<name>.toml``. Every scene is loaded once here, so a bad one fails now."""
    from ..scene.scene import Scene, load_scene, save_scene

    out: list[str] = []
    for s in scenes:
        if isinstance(s, Scene):
            d = Path(folder)
            d.mkdir(parents=True, exist_ok=True)
            path = d / f"{s.name}.toml"
            save_scene(s, path)
            out.append(str(path.resolve()))
            continue
        if not isinstance(s, (str, os.PathLike)):
            raise ParameterError("scenes", s, "built-in scene names, .toml paths or Scenes")
        load_scene(s)
        text = os.fspath(s)
        out.append(str(Path(text).resolve()) if (text.endswith(".toml") or os.sep in text)
                   else text)
    if len({_label(r) for r in out}) != len(out):
        raise SceneError("two scenes of the report have the same name: give each its own "
                         "`name` (the report and its store tell them apart by it)")
    return out


def _label(ref: str) -> str:
    from .maps import scene_label

    return scene_label(ref)


def _thresholds(scene, W: float) -> float:
    """The smallest analytic overturning A of the four Ricker pulses at ``W``."""
    from ..studies.validation import overturn_threshold

    return min(overturn_threshold(scene, W, shape, sign, rtol=1e-2) for shape, sign in _SHAPES)


def _fracture_case(ref: str, scene) -> tuple | None:
    """(scene, shape, sign, A, W) of the smallest A at which the analytic model fractures the
    scene's devices under an antisymmetric + pulse at W = 3, or None."""
    from ..run_length import run_length
    from ..runner import run
    from ..scene.motion import RickerPulse

    dev = scene.devices
    if dev is None or getattr(dev, "fracture_strain", None) in (None, math.inf):
        return None
    A = 1.0
    while A <= 60.0:
        p = RickerPulse.dimensionless(A, 3.0, scene.structure, "antisymmetric", 1)
        r = run(scene, p, duration=round(run_length(p, 3.0), 3), method="compiled")
        if r.summary.fractured:
            return (ref, "antisymmetric", 1, round(A, 3), 3.0)
        A *= 1.25
    return None


def plan_for_scenes(scenes: Sequence[Any], *, quick: bool = False,
                    folder: str | os.PathLike = ".") -> dict[str, Any]:
    """The campaign plan for ``scenes`` (names, TOML paths or Scenes; the first one is the
    structure the decision is about), derived as the module docstring says. ``quick``: the
    quick form (one pulse, one record, no fracture cases).
    ``folder``: where Scene objects are saved for the worker processes."""
    from ..scene.scene import load_scene
    from ..studies.validation import uplift_threshold

    if not scenes:
        raise ParameterError("scenes", "none", "at least one scene")
    refs = scene_refs(scenes, folder)
    loaded = [load_scene(r) for r in refs]
    first, sc0 = refs[0], loaded[0]
    t3, t4 = ([_thresholds(s, w) for s in loaded] for w in (3.0, 4.0))
    a3, a4, a3_0, a4_0 = min(t3), min(t4), t3[0], t4[0]
    a_up = max(uplift_threshold(s) for s in loaded)
    a10 = _thresholds(sc0, 10.0)
    finite = [x for x in (a3, a4, a3_0, a4_0) if math.isfinite(x)]
    if not finite:
        raise SceneError(f"no Ricker pulse up to A = 30 overturns {sc0.name!r} in the analytic "
                         "model: its maps and pulse cases cannot be chosen from its boundary; "
                         "write a plan file (rockbench report --plan)")
    fin = lambda x: x if math.isfinite(x) else max(finite)  # noqa: E731
    r2 = lambda x: float(f"{x:.3g}")  # noqa: E731
    # a pulse case between uplift and overturning: the geometric mean of the largest uplift
    # threshold and the smallest overturning one (every scene rocks and survives it)
    rock = lambda a_ot: math.sqrt(a_up * fin(a_ot)) if fin(a_ot) > a_up else a_up  # noqa: E731
    paper = campaign_plan(quick)
    hi = max(8.0, math.ceil(1.5 * fin(a10))) if math.isfinite(a10) else 8.0
    frac = [] if quick else [c for c in (_fracture_case(r, s) for r, s in zip(refs, loaded))
                             if c is not None]
    names = [s.name for s in loaded]
    plan = dict(paper)
    plan.update({
        "scenes": tuple(refs),
        "pulse_points": ((r2(rock(a3)), 3.0),) if quick else
        ((r2(rock(a3)), 3.0), (r2(rock(a4)), 4.0)),
        "pulse_shapes": paper["pulse_shapes"] if quick else _SHAPES,
        "fracture_cases": tuple(frac),
        "record_frames": {n: r for n, r in zip(names[:3], refs[:3])},
        "choice_scene": first,
        # the advice on a user's structure is chosen and confirmed on the default evidence
        # (as `rockbench advise`; 28 cases): its report's budget is 15 minutes, not 10
        "choice_evidence": "quick" if quick else "default",
        "stress_scene": first,
        "stress_hybrid_scene": None,
        "description": "; ".join(f"{s.name}: {s.description}" if s.description else s.name
                                 for s in loaded),
        "maps": {"analytic_scenes": tuple(refs[:1] if quick else refs),
                 "analytic_grid": (100, 100), "analytic_amplitude": f"0.5:{hi:g}",
                 "analytic_frequency": "0.5:10", "engine_scenes": (first,),
                 "engine_amplitude": f"1:{hi:g}", "engine_frequency": "1:10",
                 "engine_tail": 3.0, "measured_grid": (12, 12), "full_grid": (100, 100),
                 "fast_grids": {_label(first): (6, 6)}},
        # where the analytic model holds (rockbench.studies.validity_map), on the first
        # scene with its own friction or the validity rule's default
        "validity_map": _validity_spec(first, quick),
    })
    return plan


def _validity_spec(scene: str, quick: bool) -> dict[str, Any]:
    """The validity map of a plan (:mod:`rockbench.studies.validity_map`): on the decision's
    scene, symmetric pulses + on n x n cells (8, 5 with ``--quick``), 3 s of free rocking
    after each pulse window."""
    return {"scene": scene, "grid": 5 if quick else 8, "tail": 3.0}


def _read_plan_file(path: str | os.PathLike) -> dict[str, Any]:
    """A plan file's TOML data (one-line errors naming the file)."""
    try:
        return tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as e:
        raise ParameterError("plan", str(path), "a readable TOML plan file",
                             getattr(e, "strerror", None) or str(e)) from None
    except tomllib.TOMLDecodeError as e:
        raise ParameterError("plan", str(path), "a valid TOML plan file", str(e)) from None


def every_scene(plan: dict[str, Any]) -> list[str]:
    """Every scene a plan runs, in order of first use: the compared scenes, the fracture
    cases', the record frames', the maps' (analytic and engines'), the decision's and the
    stability sweep's (the paper's plan: its seven frames)."""
    m = plan.get("maps", {})
    refs = [*plan["scenes"], *(c[0] for c in plan.get("fracture_cases", ())),
            *plan.get("record_frames", {}).values(), *m.get("analytic_scenes", ()),
            *m.get("engine_scenes", ()), plan.get("choice_scene"), plan.get("stress_scene"),
            plan.get("stress_hybrid_scene")]
    return list(dict.fromkeys(str(r) for r in refs if r))


def plan_file_scenes(path: str | os.PathLike) -> list[str]:
    """The scenes of a plan file (relative ``.toml`` paths made absolute), after checking the
    whole file (:func:`rockbench.campaign.plan_schema.check_plan`)."""
    from .plan_schema import check_plan, resolve_scenes

    p = Path(path)
    return list(resolve_scenes(check_plan(_read_plan_file(p), str(path), folder=p.parent),
                               p.parent)["scenes"])


def load_plan(path: str | os.PathLike, *, quick: bool = False,
              folder: str | os.PathLike = ".") -> dict[str, Any]:
    """A plan file (``kind = "campaign-plan"``; keys as in ``scenarios/paper-plan.toml``, in a
    ``[campaign]`` table or at the top level; ``docs/plans.md``), checked completely before any
    work (:func:`rockbench.campaign.plan_schema.check_plan`). ``scenes`` is required; every
    other key left out is derived from the scenes (:func:`plan_for_scenes`)."""
    from .plan_schema import check_plan, plan_keys, resolve_scenes

    p = Path(path)
    data = _read_plan_file(p)
    c = resolve_scenes(check_plan(data, str(path), folder=p.parent), p.parent)  # all of it,
    base = plan_for_scenes(c["scenes"], quick=quick, folder=folder)           # before any work
    given = {k: v for k, v in c.items() if k != "quick"}
    keys = set(plan_keys("campaign")) | {"maps"}
    merged = {**{k: v for k, v in base.items() if k not in given and k in keys}, **given}
    merged["scenes"] = list(base["scenes"])
    merged.setdefault("maps", {})
    merged["maps"] = {**base["maps"], **dict(merged["maps"])}
    merged["quick"] = c.get("quick", {})
    full, q = read_plan({"campaign": _plain(merged)}, str(path))
    return q if quick else full


def _plain(plan: dict[str, Any]) -> dict[str, Any]:
    """A plan as TOML-like data (tuples as lists), for :func:`rockbench.sweep.cases.read_plan`."""
    def conv(v):
        if isinstance(v, dict):
            return {k: conv(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [conv(x) for x in v]
        return v
    return {k: conv(v) for k, v in plan.items() if v is not None}


def structure_table(refs: Sequence[Any]):
    """The structures a report is about, as its page shows them: one row per field of each
    scene (``scene`` by its name, ``part``: block | frame | devices, ``field``, ``value``,
    ``unit``, ``meaning`` as docs/scenes.md gives them), then the scene's alpha and p."""
    import pandas as pd

    from ..scene.scene import load_scene
    from ..scene.schema import fields_of

    rows = []
    for ref in refs:
        sc = load_scene(ref)
        kind = "frame" if hasattr(sc.structure, "column_height_left") else "block"
        given = sc.structure.to_dict()
        parts = [(kind, f, given[f.name]) for f in fields_of(kind) if f.name in given]
        if sc.devices is not None:
            parts += [("devices", f, getattr(sc.devices, f.name)) for f in fields_of("devices")]
        of = " of the taller column" if kind == "frame" else ""
        parts += [("derived", None, ("alpha", "rad", sc.alpha, f"slenderness{of}, atan(b/H)")),
                  ("derived", None, ("p", "rad/s", sc.p, f"frequency parameter{of}, "
                                     "sqrt(3g/(4R))"))]
        for part, f, v in parts:
            name, unit, v, meaning = (v if f is None else (f.name, f.unit, v, f.meaning))
            rows.append({"scene": sc.name, "part": part, "field": name,
                         "value": "none" if v is None else f"{v:.6g}", "unit": unit or "-",
                         "meaning": meaning})
    return pd.DataFrame(rows, columns=["scene", "part", "field", "value", "unit", "meaning"])


# =========================================================================================
# Reading plans (the paper's and users' files)
# =========================================================================================
def _pairs(rows, kinds=(float, float)) -> tuple[tuple, ...]:
    return tuple(tuple(k(v) for k, v in zip(kinds, r, strict=True)) for r in rows)


def _plans(c: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    full = {"scenes": tuple(c["scenes"]), "pulse_points": _pairs(c["pulse_points"]),
            "pulse_shapes": _pairs(c["pulse_shapes"], (str, int)),
            "pulse_tail": float(c["pulse_tail"]),
            "free_phi0": float(c["free_phi0"]), "free_duration": float(c["free_duration"]),
            "max_records": None, "record_tail": None,
            "record_duration": (float(c["record_duration"]) if "record_duration" in c
                                else None),
            "record_frames": dict(c["record_frames"]),
            "fracture_cases": _pairs(c.get("fracture_cases", ()), (str, str, int, float, float)),
            "choice_scene": str(c.get("choice_scene", c["scenes"][0])),
            "choice_evidence": str(c.get("choice_evidence", "quick")),
            "vertical": float(c.get("vertical", 0.0)),
            "stress_scene": c.get("stress_scene"),
            "stress_hybrid_scene": c.get("stress_hybrid_scene"),
            "maps": _maps_plan(c.get("maps", {}), c),
            "validity_map": _validity_spec(str(c.get("choice_scene", c["scenes"][0])), False),
            "description": str(c.get("description", ""))}
    q = c.get("quick", {})
    quick = dict(full, scenes=tuple(q.get("scenes", full["scenes"][:2])),
                 pulse_points=_pairs(q.get("pulse_points", full["pulse_points"][:1])),
                 pulse_shapes=_pairs(q.get("pulse_shapes", full["pulse_shapes"][:1]),
                                     (str, int)),
                 pulse_tail=float(q.get("pulse_tail", 2.0)),
                 free_duration=float(q.get("free_duration", 3.0)),
                 max_records=int(q.get("max_records", 1)),
                 record_tail=float(q.get("record_tail", 2.0)),
                 record_duration=None,
                 validity_map=_validity_spec(full["choice_scene"], True),
                 record_frames=dict(c["record_frames"]),
                 fracture_cases=_pairs(q.get("fracture_cases", ()),
                                       (str, str, int, float, float)))
    return full, quick


def _maps_plan(m: dict[str, Any], c: dict[str, Any]) -> dict[str, Any]:
    """The maps part of a plan: analytic maps (scenes, grid, A and W ranges) and engine maps
    (scenes, ranges, free-rocking tail [s], measured grid, the fast engines' grid per scene)."""
    scenes = list(c["scenes"])
    return {"analytic_scenes": tuple(m.get("analytic_scenes", scenes)),
            "analytic_grid": tuple(int(v) for v in m.get("analytic_grid", (100, 100))),
            "analytic_amplitude": str(m.get("analytic_amplitude", "0.5:8")),
            "analytic_frequency": str(m.get("analytic_frequency", "0.5:10")),
            "engine_scenes": tuple(m.get("engine_scenes", scenes[:1])),
            "engine_amplitude": str(m.get("engine_amplitude", "1:8")),
            "engine_frequency": str(m.get("engine_frequency", "1:10")),
            "engine_tail": float(m.get("engine_tail", 3.0)),
            "measured_grid": tuple(int(v) for v in m.get("measured_grid", (12, 12))),
            "full_grid": tuple(int(v) for v in m.get("full_grid", (100, 100))),
            "fast_grids": {k: tuple(int(x) for x in v)
                           for k, v in m.get("fast_grids", {scenes[0]: (6, 6)}).items()}}


def read_plan(data: dict[str, Any], source: str = "(data)", *,
              folder: str | os.PathLike | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """(plan, quick plan) of a plan file's data (``kind = "campaign-plan"``; the plan in its
    ``[campaign]`` table or at the top level), checked completely first
    (:func:`rockbench.campaign.plan_schema.check_plan`: one line naming ``source``, the key and
    the valid form). Keys as in ``scenarios/paper-plan.toml`` (``docs/plans.md``)."""
    from .plan_schema import check_plan

    c = check_plan(data, source, folder=folder)
    c.setdefault("description", data.get("description", ""))
    return _plans(c)


@functools.lru_cache(maxsize=1)
def _paper_plans() -> tuple[dict[str, Any], dict[str, Any]]:
    text = (resources.files("rockbench") / "scenarios" / "paper-plan.toml").read_text(
        encoding="utf-8")
    return read_plan(tomllib.loads(text), "rockbench/scenarios/paper-plan.toml")


def campaign_plan(quick: bool = False) -> dict[str, Any]:
    """The paper's plan (a fresh copy; ``scenarios/paper-plan.toml``, read and checked on first
    use): ``scenes``, ``pulse_points`` ((A, W) pairs), ``pulse_shapes`` ((shape, sign) pairs),
    ``pulse_tail`` [s],
    ``free_phi0`` [alpha], ``free_duration`` [s], ``max_records`` (None: all), ``record_tail``
    [s] (None: record + 10 s), ``record_duration`` [s] (cap on a record run's length from its
    start, None: no cap), ``record_frames`` (label -> scene), ``fracture_cases`` ((scene,
    shape, sign, A, W)), the choice and stress scenes and ``maps`` (``docs/plans.md``).

    ``quick``: a few cases (two scenes, one pulse, shorter runs) for tests and a first look.
    """
    p = _paper_plans()[1 if quick else 0]
    return {k: dict(v) if isinstance(v, dict) else v for k, v in p.items()}

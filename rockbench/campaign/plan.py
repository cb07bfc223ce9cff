"""Campaign plans: what ``rockbench report`` runs, as data.

* The paper's plan ships as ``rockbench/scenarios/paper-plan.toml`` (``kind = "campaign-plan"``);
  :func:`rockbench.sweep.cases.campaign_plan` reads it.
* ``rockbench report --plan FILE`` runs a user's plan file of the same form
  (:func:`load_plan`): keys left out are derived from its ``scenes`` as below.
* ``rockbench report SCENE [SCENE ...]`` runs :func:`plan_for_scenes`: the same parts as the
  paper's campaign, with every case chosen from the scenes themselves through the analytic
  model (nothing is taken from the paper's frames):

  - pulse cases at W = 3 and 4 with A the geometric mean of the largest uplift threshold
    (A_up = min|lambda| / tan alpha) and the smallest analytic overturning threshold of the four
    Ricker pulses at that W (over every scene): each scene rocks and survives;
  - the speed sweep's case on the first scene at A = 0.7 x that threshold, W = 4;
  - the summary map of the first scene at A = (0.4, 0.7, 0.9, 1.1, 1.5) x its threshold at W = 3;
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

import math
import os
import tomllib
from pathlib import Path
from typing import Any, Sequence

from ..errors import ParameterError, SceneError

__all__ = ["plan_for_scenes", "load_plan", "scene_refs", "structure_table"]

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
    from ..runner import run
    from ..scene.motion import RickerPulse

    dev = scene.devices
    if dev is None or getattr(dev, "fracture_strain", None) in (None, math.inf):
        return None
    A = 1.0
    while A <= 60.0:
        p = RickerPulse.dimensionless(A, 3.0, scene.structure, "antisymmetric", 1)
        r = run(scene, p, duration=round(6 * p.period + 3.0, 3), method="compiled")
        if r.summary.fractured:
            return (ref, "antisymmetric", 1, round(A, 3), 3.0)
        A *= 1.25
    return None


def plan_for_scenes(scenes: Sequence[Any], *, quick: bool = False,
                    folder: str | os.PathLike = ".") -> dict[str, Any]:
    """The campaign plan for ``scenes`` (names, TOML paths or Scenes; the first one is the
    structure the decision is about), derived as the module docstring says. ``quick``: the
    quick form (one pulse, a 2-point map, two time steps, one record, no fracture cases).
    ``folder``: where Scene objects are saved for the worker processes."""
    from ..scene.scene import load_scene
    from ..sweep.cases import campaign_plan
    from ..studies.validation import uplift_threshold

    if not scenes:
        raise ParameterError("scenes", "none", "at least one scene")
    refs = scene_refs(scenes, folder)
    loaded = [load_scene(r) for r in refs]
    first, sc0 = refs[0], loaded[0]
    a3 = min(_thresholds(s, 3.0) for s in loaded)
    a4 = min(_thresholds(s, 4.0) for s in loaded)
    a_up = max(uplift_threshold(s) for s in loaded)
    a3_0, a4_0 = _thresholds(sc0, 3.0), _thresholds(sc0, 4.0)
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
        "map_scene": first,
        "map_A": tuple(r2(f * fin(a3_0)) for f in ((0.7, 1.5) if quick
                                                  else (0.4, 0.7, 0.9, 1.1, 1.5))),
        "map_W": (3.0,) if quick else (1.5, 2.0, 3.0, 4.0, 6.0),
        "dt_case": {"scene": first, "shape": "symmetric", "sign": 1,
                    "A": r2(0.7 * fin(a4_0)), "W": 4.0},
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
    })
    return plan


def load_plan(path: str | os.PathLike, *, quick: bool = False,
              folder: str | os.PathLike = ".") -> dict[str, Any]:
    """A plan file (``kind = "campaign-plan"``; keys as in ``scenarios/paper-plan.toml``, in a
    ``[campaign]`` table or at the top level). ``scenes`` is required; every other key left
    out is derived from the scenes (:func:`plan_for_scenes`)."""
    from ..sweep.cases import read_plan

    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as e:
        raise ParameterError("plan", str(path), "a readable TOML plan file",
                             getattr(e, "strerror", None) or str(e)) from None
    except tomllib.TOMLDecodeError as e:
        raise ParameterError("plan", str(path), "a valid TOML plan file", str(e)) from None
    if data.get("kind", "campaign-plan") != "campaign-plan":
        raise ParameterError("plan", str(path), 'a file with kind = "campaign-plan"',
                             f"it says kind = {data.get('kind')!r}")
    c = dict(data.get("campaign", data))
    if not c.get("scenes"):
        raise ParameterError("plan", str(path), "a plan with a `scenes` list")
    base = plan_for_scenes([str((p.parent / s).resolve()) if str(s).endswith(".toml") else s
                            for s in c["scenes"]], quick=quick, folder=folder)
    given = {k: v for k, v in c.items() if k not in ("kind", "version", "quick")}
    merged = {**{k: v for k, v in base.items() if k not in given}, **given}
    merged["scenes"] = list(base["scenes"])
    merged.setdefault("maps", {})
    merged["maps"] = {**base["maps"], **dict(merged["maps"])}
    for k in ("dt_case",):
        merged[k] = dict(merged[k])
    merged["quick"] = c.get("quick", {})
    try:
        full, q = read_plan({"campaign": _plain(merged)})
    except (KeyError, TypeError, ValueError) as e:
        raise ParameterError("plan", str(path), "a plan whose keys are as in "
                             "rockbench/scenarios/paper-plan.toml", str(e)) from None
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

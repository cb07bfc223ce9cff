"""The campaign plan's format, key by key: the one table a plan file is validated against,
completely and before any work, and that ``docs/plans.md`` is generated from (:func:`markdown`;
a test checks that the committed page equals its output).

A plan file (``kind = "campaign-plan"``) holds its keys in a ``[campaign]`` table (or at the
top level), the engine and analytic maps in ``[campaign.maps]`` and the ``--quick`` form's
replacements in ``[campaign.quick]``. :func:`check_plan` refuses, in one line naming the file,
the key and the valid form: an unknown key (with the nearest known one), a value of the wrong
kind (a string where a list belongs is not iterated letter by letter), a number that is not
finite or outside its range (the ranges of :data:`rockbench.limits.LIMITS` where one applies:
A, W, map cells), an unknown pulse shape or sign, a grid with too many cells, an axis whose
ends are not increasing. Scene references are checked by loading them
(:func:`rockbench.scene.load_scene`), relative ``.toml`` paths from the plan's folder.

A = a_g / (g tan alpha), W = omega_g / p with alpha and p of each scene's taller column;
durations in s; rotations as multiples of alpha.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ParameterError

__all__ = ["PlanKey", "KEYS", "check_plan", "resolve_scenes", "plan_keys", "markdown"]

#: Engine time steps a plan may ask for [s] (the engines' own range, EngineSettings.dt).
_DT = (1e-6, 1e-2)
#: Longest duration or tail a plan may give [s]: an hour of simulated time per run.
_SECONDS = 3600.0
_SHAPES = ("symmetric", "antisymmetric")


class _Bad(Exception):
    """A value outside its key's form: the message says what the key must be."""


# =========================================================================================
# Value checks (each returns nothing and raises _Bad with the valid form)
# =========================================================================================
def _number(v: Any, lo: float, hi: float, *, lo_open: bool = True, what: str = "a number"
            ) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _Bad(f"{what}, a finite number")
    if (v <= lo if lo_open else v < lo) or v > hi:
        raise _Bad(f"{what} in {'(' if lo_open else '['}{lo:g}, {hi:g}]")
    return float(v)


def _limit(key: str, v: Any, what: str) -> float:
    from ..limits import LIMITS

    lim = LIMITS[key]
    lo, hi = lim.current()
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _Bad(f"{what}, a finite number {lim.describe(lo, hi)}")
    bad_lo = lo is not None and (v <= lo if lim.lo_open else v < lo)
    if bad_lo or (v >= hi if lim.hi_open else v > hi):
        raise _Bad(f"{what} {lim.describe(lo, hi)}")
    return float(v)


def _list(v: Any, what: str, *, empty: bool = False) -> list:
    if isinstance(v, (str, bytes)) or not isinstance(v, (list, tuple)):
        raise _Bad(f"a list of {what} (not {type(v).__name__})")
    if not v and not empty:
        raise _Bad(f"a non-empty list of {what}")
    return list(v)


def seconds(v: Any) -> None:
    _number(v, 0.0, _SECONDS, what="a duration [s]")


def scene_ref(v: Any) -> None:
    if not isinstance(v, str) or not v.strip():
        raise _Bad("a built-in scene name or a .toml path")


def scenes(v: Any) -> None:
    for s in _list(v, "scene names or .toml paths"):
        scene_ref(s)


def optional_scene(v: Any) -> None:
    if v is not None:
        scene_ref(v)


def _pair(r: Any) -> None:
    r = _list(r, "two numbers")
    if len(r) != 2:
        raise _Bad("[A, W] pairs of two numbers")
    _limit("A", r[0], "A")
    _limit("W", r[1], "W")


def pulse_points(v: Any) -> None:
    for r in _list(v, "[A, W] pairs"):
        _pair(r)


def _shape_sign(shape: Any, sign: Any) -> None:
    if shape not in _SHAPES:
        raise _Bad(f"a pulse shape among {', '.join(_SHAPES)} (not {shape!r})")
    if isinstance(sign, bool) or sign not in (1, -1):
        raise _Bad(f"a pulse sign 1 or -1 (not {sign!r})")


def pulse_shapes(v: Any) -> None:
    for r in _list(v, "[shape, sign] pairs"):
        r = _list(r, "[shape, sign]")
        if len(r) != 2:
            raise _Bad('[shape, sign] pairs such as ["symmetric", 1]')
        _shape_sign(*r)


def phi0(v: Any) -> None:
    _number(v, 0.0, 10.0, what="an initial rotation phi0 / alpha [-]")


def vertical(v: Any) -> None:
    _number(v, 0.0, 3.0, lo_open=False,
            what="a vertical ratio a_v / a_g [-] (limit vertical_ratio)")


def fracture_cases(v: Any) -> None:
    for r in _list(v, "[scene, shape, sign, A, W] cases", empty=True):
        r = _list(r, "[scene, shape, sign, A, W]")
        if len(r) != 5:
            raise _Bad('[scene, shape, sign, A, W] cases such as ["my-frame", '
                       '"antisymmetric", 1, 8.0, 2.0]')
        scene_ref(r[0])
        _shape_sign(r[1], r[2])
        _limit("A", r[3], "A")
        _limit("W", r[4], "W")


def record_frames(v: Any) -> None:
    if not isinstance(v, Mapping) or not v:
        raise _Bad('a non-empty table label = scene, e.g. {"free-standing" = "my-frame"}')
    for s in v.values():
        scene_ref(s)


def evidence(v: Any) -> None:
    if v not in ("quick", "default", "full"):
        raise _Bad('"quick", "default" or "full"')


def text(v: Any) -> None:
    if not isinstance(v, str):
        raise _Bad("text")


def count(v: Any) -> None:
    if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 10000:
        raise _Bad("an integer in [1, 10000]")


def grid(v: Any) -> None:
    from ..limits import LIMITS

    r = _list(v, "two integers")
    if len(r) != 2 or any(isinstance(x, bool) or not isinstance(x, int) or x < 1 for x in r):
        raise _Bad("[NA, NW], two integers >= 1")
    _, hi = LIMITS["map_cells"].current()
    if r[0] * r[1] * 4 > hi:
        raise _Bad(f"[NA, NW] with NA x NW x 4 pulses <= {hi:g} cells (limit map_cells; "
                   f"{LIMITS['map_cells'].env} raises it): {r[0]} x {r[1]} x 4 is "
                   f"{r[0] * r[1] * 4:g}")


def _axis(v: Any, key: str) -> None:
    if not isinstance(v, str) or v.count(":") != 1:
        raise _Bad(f'"LO:HI" (a string), the range of {key}')
    lo_t, hi_t = v.split(":")
    try:
        lo, hi = float(lo_t), float(hi_t)
    except ValueError:
        raise _Bad(f'"LO:HI" with two numbers, the range of {key}') from None
    _limit(key, lo, f"its LO ({key})")
    _limit(key, hi, f"its HI ({key})")
    if not lo < hi:
        raise _Bad(f'"LO:HI" with LO < HI (the range of {key}; equal ends would repeat one '
                   f'value along the whole axis)')


def a_axis(v: Any) -> None:
    _axis(v, "A")


def w_axis(v: Any) -> None:
    _axis(v, "W")


def fast_grids(v: Any) -> None:
    if not isinstance(v, Mapping):
        raise _Bad("a table scene = [NA, NW]")
    for g in v.values():
        grid(g)


# =========================================================================================
# The keys
# =========================================================================================
@dataclass(frozen=True)
class PlanKey:
    """One key of a plan file: ``table`` ("campaign", "maps" or "quick"), ``name``, ``unit``,
    ``form`` (the valid form in words), ``default`` (what a missing key becomes, in words),
    ``meaning`` (one line) and ``check`` (raises on a value outside the form)."""

    table: str
    name: str
    unit: str
    form: str
    default: str
    meaning: str
    check: Callable[[Any], None]


_DERIVED = "derived from the scenes (rockbench.campaign.plan.plan_for_scenes)"

#: Every key of a plan file, by table, in the order the docs list them.
KEYS: tuple[PlanKey, ...] = (
    PlanKey("campaign", "scenes", "", "a non-empty list of scene names or .toml paths",
            "required", "the structures the report is about; the first is the one the "
            "decision is about", scenes),
    PlanKey("campaign", "description", "", "text", "the scenes' own descriptions",
            "one line about the plan, the page's subtitle", text),
    PlanKey("campaign", "pulse_points", "-", "a list of [A, W] pairs", _DERIVED,
            "(A, W) of the pulse cases compared across engines", pulse_points),
    PlanKey("campaign", "pulse_shapes", "", '[shape, sign] pairs, shape "symmetric" or '
            '"antisymmetric", sign 1 or -1', "all four", "the Ricker pulses of each point",
            pulse_shapes),
    PlanKey("campaign", "pulse_tail", "s", f"(0, {_SECONDS:g}]", "6",
            "free rocking after each pulse window (6 T_g)", seconds),
    PlanKey("campaign", "free_phi0", "-", "(0, 10]", "0.3",
            "initial rotation phi0 / alpha of the free-rocking cases", phi0),
    PlanKey("campaign", "free_duration", "s", f"(0, {_SECONDS:g}]", "8",
            "length of the free-rocking cases", seconds),
    PlanKey("campaign", "fracture_cases", "", "a list of [scene, shape, sign, A, W]", _DERIVED,
            "hybrid pulse cases where the analytic model fractures the devices", fracture_cases),
    PlanKey("campaign", "record_duration", "s", f"(0, {_SECONDS:g}]", "the record + 10 s",
            "longest run of a record, from its start", seconds),
    PlanKey("campaign", "record_frames", "", "a table label = scene", "the first three scenes",
            "the scenes of the record part (Fig. 9), by label", record_frames),
    PlanKey("campaign", "choice_scene", "", "a scene", "the first scene",
            "the structure the decision is about (work-precision, advice)", scene_ref),
    PlanKey("campaign", "choice_evidence", "", '"quick", "default" or "full"',
            '"default" ("quick" for the paper\'s plan)',
            "the validation set the advice is chosen and confirmed on", evidence),
    PlanKey("campaign", "vertical", "-", "[0, 3]", "0 (horizontal only)",
            "every pulse and record of the campaign (comparisons, maps, "
            "evidence, records, fragility, validity map) also moves the ground vertically: "
            "a_v = vertical x its horizontal acceleration, in phase (a record with a vertical "
            "channel of its own keeps it; the stability sweep stays horizontal)", vertical),
    PlanKey("campaign", "stress_scene", "", "a scene", "the first scene",
            "the base of the stability sweep (rockbench stress)", optional_scene),
    PlanKey("campaign", "stress_hybrid_scene", "", "a scene with devices", "none",
            "where the stability sweep's device axes start", optional_scene),
    # --- [campaign.maps] ------------------------------------------------------------------
    PlanKey("maps", "analytic_scenes", "", "a list of scenes", "every scene",
            "the scenes of the analytic maps (paper Figs. 4-7)", scenes),
    PlanKey("maps", "analytic_grid", "-", "[NA, NW], NA x NW x 4 within the limit map_cells",
            "[100, 100]", "the analytic maps' grid", grid),
    PlanKey("maps", "analytic_amplitude", "-", '"LO:HI", LO < HI', '"0.5:8"',
            "A range of the analytic maps", a_axis),
    PlanKey("maps", "analytic_frequency", "-", '"LO:HI", LO < HI', '"0.5:10"',
            "W range of the analytic maps", w_axis),
    PlanKey("maps", "engine_scenes", "", "a list of scenes", "the first scene",
            "the scenes of the engine maps", scenes),
    PlanKey("maps", "engine_amplitude", "-", '"LO:HI", LO < HI', '"1:8"',
            "A range of the engine maps", a_axis),
    PlanKey("maps", "engine_frequency", "-", '"LO:HI", LO < HI', '"1:10"',
            "W range of the engine maps", w_axis),
    PlanKey("maps", "engine_tail", "s", f"(0, {_SECONDS:g}]", "3",
            "free rocking after the pulse window of an engine map's cell", seconds),
    PlanKey("maps", "measured_grid", "-", "[NA, NW]", "[12, 12]",
            "the grid of every engine's measured map (rockbench report --full)", grid),
    PlanKey("maps", "full_grid", "-", "[NA, NW]", "[100, 100]",
            "the paper's resolution, measured adaptively by --full", grid),
    PlanKey("maps", "fast_grids", "-", "a table scene = [NA, NW]", "the first scene: [6, 6]",
            "the fast engines' default grid per scene", fast_grids),
    # --- [campaign.quick] -----------------------------------------------------------------
    PlanKey("quick", "scenes", "", "a list of scenes", "the first two",
            "--quick: the scenes", scenes),
    PlanKey("quick", "pulse_points", "-", "a list of [A, W] pairs", "the first point",
            "--quick: the pulse cases", pulse_points),
    PlanKey("quick", "pulse_shapes", "", "[shape, sign] pairs", "the first shape",
            "--quick: the pulses", pulse_shapes),
    PlanKey("quick", "pulse_tail", "s", f"(0, {_SECONDS:g}]", "2", "--quick: the pulse tail",
            seconds),
    PlanKey("quick", "free_duration", "s", f"(0, {_SECONDS:g}]", "3",
            "--quick: free rocking", seconds),
    PlanKey("quick", "max_records", "-", "an integer in [1, 10000]", "1",
            "--quick: records used", count),
    PlanKey("quick", "record_tail", "s", f"(0, {_SECONDS:g}]", "2",
            "--quick: free rocking after a record", seconds),
    PlanKey("quick", "fracture_cases", "", "a list of [scene, shape, sign, A, W]", "none",
            "--quick: fracture cases", fracture_cases),
)

_TOP = ("kind", "version", "description", "campaign")
_SUBTABLES = ("maps", "quick")


def plan_keys(table: str = "campaign") -> dict[str, PlanKey]:
    """The keys of one table of a plan file ("campaign", "maps" or "quick"), by name."""
    return {k.name: k for k in KEYS if k.table == table}


_keys = plan_keys


def _unknown(name: str, known: list[str]) -> str:
    near = difflib.get_close_matches(name, known, n=1)
    return ("a key of the plan format (docs/plans.md)"
            + (f"; did you mean {near[0]!r}?" if near else f": {', '.join(sorted(known))}"))


def check_plan(data: Mapping[str, Any], source: str, *,
               folder: str | Path | None = None) -> dict[str, Any]:
    """The campaign table of a plan file's ``data``, checked completely (module docstring);
    :class:`~rockbench.errors.ParameterError` naming ``plan <source>: <key>``, the value and
    the valid form at the first problem. ``folder``: where relative ``.toml`` scene paths are
    (the plan file's folder); every scene reference is loaded once."""
    if not isinstance(data, Mapping):
        raise ParameterError(f"plan {source}", type(data).__name__, "a TOML table")
    for k in data:
        if k not in _TOP and not (k in _keys("campaign") and "campaign" not in data):
            raise ParameterError(f"plan {source}: {k}", data[k],
                                 _unknown(k, list(_TOP) + list(_keys("campaign"))))
    if data.get("kind", "campaign-plan") != "campaign-plan":
        raise ParameterError(f"plan {source}: kind", data.get("kind"), '"campaign-plan"')
    c = data.get("campaign", data)
    if not isinstance(c, Mapping):
        raise ParameterError(f"plan {source}: campaign", type(c).__name__, "a table")
    c = {k: v for k, v in c.items() if k not in ("kind", "version")}
    if not c.get("scenes"):
        raise ParameterError(f"plan {source}: scenes", c.get("scenes"),
                             "a non-empty list of scene names or .toml paths (required)")
    for table, values in [("campaign", c), *[(t, c.get(t)) for t in _SUBTABLES]]:
        if values is None:
            continue
        where = f"plan {source}: " + ("" if table == "campaign" else f"{table}.")
        if not isinstance(values, Mapping):
            raise ParameterError(where.rstrip(". "), values, f"a table [campaign.{table}]")
        keys = _keys(table)
        for name, v in values.items():
            if table == "campaign" and name in _SUBTABLES:
                continue
            if name not in keys:
                raise ParameterError(f"{where}{name}", v, _unknown(name, list(keys)))
            try:
                keys[name].check(v)
            except _Bad as e:
                raise ParameterError(f"{where}{name}", v, str(e)) from None
    _check_scenes(c, source, folder)
    return dict(c)


def _scene_refs(c: Mapping[str, Any]) -> list[tuple[str, str]]:
    """(key, scene reference) of every scene a checked plan names."""
    out = [("scenes", s) for s in c.get("scenes", ())]
    for k in ("choice_scene", "stress_scene", "stress_hybrid_scene"):
        if c.get(k) is not None:
            out.append((k, c[k]))
    out += [("fracture_cases", r[0]) for r in c.get("fracture_cases", ())]
    out += [("record_frames", s) for s in dict(c.get("record_frames", {})).values()]
    m, q = c.get("maps") or {}, c.get("quick") or {}
    out += [("maps.analytic_scenes", s) for s in m.get("analytic_scenes", ())]
    out += [("maps.engine_scenes", s) for s in m.get("engine_scenes", ())]
    out += [("quick.scenes", s) for s in q.get("scenes", ())]
    out += [("quick.fracture_cases", r[0]) for r in q.get("fracture_cases", ())]
    return out


def resolve_scenes(c: Mapping[str, Any], folder: str | Path) -> dict[str, Any]:
    """A checked plan's campaign table with every relative ``.toml`` scene reference made
    absolute from ``folder`` (the plan file's folder)."""
    def fix(ref: Any) -> Any:
        return (str((Path(folder) / ref).resolve()) if isinstance(ref, str)
                and ref.endswith(".toml") else ref)

    out = dict(c)
    for k in ("scenes",):
        if k in out:
            out[k] = [fix(x) for x in out[k]]
    for k in ("choice_scene", "stress_scene", "stress_hybrid_scene"):
        if out.get(k) is not None:
            out[k] = fix(out[k])
    if "fracture_cases" in out:
        out["fracture_cases"] = [[fix(r[0]), *r[1:]] for r in out["fracture_cases"]]
    if "record_frames" in out:
        out["record_frames"] = {k: fix(v) for k, v in dict(out["record_frames"]).items()}
    if out.get("maps"):
        m = dict(out["maps"])
        for k in ("analytic_scenes", "engine_scenes"):
            if k in m:
                m[k] = [fix(x) for x in m[k]]
        out["maps"] = m
    if out.get("quick"):
        q = dict(out["quick"])
        if "scenes" in q:
            q["scenes"] = [fix(x) for x in q["scenes"]]
        if "fracture_cases" in q:
            q["fracture_cases"] = [[fix(r[0]), *r[1:]] for r in q["fracture_cases"]]
        out["quick"] = q
    return out


def _check_scenes(c: Mapping[str, Any], source: str, folder: str | Path | None) -> None:
    from ..errors import RockbenchError
    from ..scene.scene import load_scene

    seen: set[str] = set()
    for key, ref in _scene_refs(c):
        path = (str((Path(folder) / ref).resolve()) if folder is not None
                and str(ref).endswith(".toml") else ref)
        if path in seen:
            continue
        seen.add(path)
        try:
            load_scene(path)
        except RockbenchError as e:
            raise ParameterError(f"plan {source}: {key}", ref,
                                 "a built-in scene name or a .toml scene file that loads",
                                 " ".join(str(e).split())[:300]) from None


# =========================================================================================
# docs/plans.md
# =========================================================================================
_HEAD = """# Plans: what `rockbench report` runs, key by key

A campaign is a **plan**, data not code. `rockbench report` runs the paper's plan
(`rockbench/scenarios/paper-plan.toml`); `rockbench report SCENE ...` derives one from your
scenes; `rockbench report --plan FILE` runs a file of this form (`kind = "campaign-plan"`), the
keys in a `[campaign]` table (or at the top level), the maps in `[campaign.maps]`, the `--quick`
form's replacements in `[campaign.quick]`. Only `scenes` is required: every key left out is
derived from the scenes as [report.md](report.md) ("Plans") says.

A plan is checked completely before any work (`rockbench.campaign.plan_schema.check_plan`): an
unknown key (a typo: the message names the nearest key), a value of the wrong kind, a number
that is not finite or outside its range, an unknown pulse shape, a grid with too many cells,
an axis whose ends are not increasing or a scene that does not load stops the command with one
line naming the file, the key and the valid form (exit 2).

A = a_g / (g tan alpha), W = omega_g / p, with alpha and p of each scene's taller column. This
page is generated from the schema (`python -m rockbench.campaign.plan_schema > docs/plans.md`);
a test checks that it is current.
"""


def markdown() -> str:
    """``docs/plans.md``: every key of every table with its unit, form, default and meaning."""
    from ..limits import LIMITS

    out = [_HEAD]
    titles = {"campaign": "`[campaign]`", "maps": "`[campaign.maps]`",
              "quick": "`[campaign.quick]` (`--quick` only)"}
    for table in ("campaign", "maps", "quick"):
        out.append(f"\n## {titles[table]}\n\n| key | unit | valid | default | meaning |\n"
                   "|---|---|---|---|---|")
        for k in KEYS:
            if k.table == table:
                out.append(f"| `{k.name}` | {k.unit or ''} | {k.form} | {k.default} | "
                           f"{k.meaning} |")
    out.append("\n## Ranges\n\n| quantity | range | environment variable |\n|---|---|---|")
    for key in ("A", "W", "map_cells"):
        lim = LIMITS[key]
        out.append(f"| {key} | {lim.describe(lim.lo, lim.hi)} | `{lim.env}` |")
    out.append(f"| durations and tails | (0, {_SECONDS:g}] s | |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":  # pragma: no cover - regenerates docs/plans.md
    print(markdown(), end="")

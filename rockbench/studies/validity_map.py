"""The analytic model's validity map: over a grid of Ricker pulses (A, W), where the SDOF
rocking model holds, where the engines agree on what happens outside it (slide-rock), and
where nothing agrees.

Each cell is one pulse (``shape``, ``sign``, ``vertical_ratio``) at A = a_g / (g tan alpha)
and W = omega_g / p (alpha and p of the taller column). The analytic model runs first
(:func:`rockbench.run`, its run validity :func:`rockbench.validity.run_validity` with the
scene's friction, :func:`rockbench.validity.friction_of`). Inside the model no engine runs:
the analytic model is the reference there, and the cheapest. Outside it every selected engine
runs at its default settings (or ``settings``), and :func:`classify_cell` decides the region
from their summaries. A scene without its own friction is mapped with
:data:`rockbench.validity.DEFAULT_FRICTION` given to every engine alike (their own defaults
differ, each at least that): the rule and the engines then see the same contact.

Columns of the frame (:data:`VALIDITY_COLUMNS`; ``docs/maps.md``):

* ``A`` [-], ``W`` [-]: the cell;
* ``region``: one of :data:`REGIONS` -
  ``"model"`` the analytic run stays inside the model (validity ``inside``: no contact needs
  more friction than it has, the ground never falls faster than gravity);
  ``"agree"`` outside the model, and every engine ran (status ``ok``) and they agree
  (:func:`classify_cell`: the same verdict overturned or not, and both spreads at most
  ``tolerance``, which a cell where every engine overturns does not need); ``"disagree"``
  outside, every engine ran, and they do not agree;
  ``"diverged"`` outside, and at least one engine's run diverged, was invalid or failed (or
  no engine could run);
* ``reason``: the analytic run's validity sentence (``inside``, or "outside the model from
  t = ... s: why"; a run that does not assess it: the a-priori test from the motion,
  :func:`rockbench.validity.motion_validity`);
* ``sliding_onset_s`` [s]: first time a contact of the analytic model needs more friction
  than it has (NaN: never); ``lift_off_s`` [s]: first time g + a_v <= 0 (NaN: never);
* ``spread_phi`` [-]: (max - min) / max(median, :data:`PHI_FLOOR`) of the engines' peak
  |phi| [rad]; ``spread_sliding`` [-]: the same of their ``max_sliding`` [m] with
  :data:`SLIDING_FLOOR` (NaN inside the model, or when no engine reports it);
* ``engines_run``: the engines run in the cell, comma-separated ("" inside the model);
* ``cheapest``: in an ``"agree"`` cell, the engine with the least process CPU time
  (``cpu_s``) among them ("" otherwise).

Every finished cell is kept in the one store (:mod:`rockbench.sweep.store`: one Parquet row
per cell under ``<store>/<code fingerprint>/validity``, the engines' summaries as JSON), so a
rerun resumes; the region is computed again from the stored summaries, so another
``tolerance`` needs no run. Cells run on the one executor (:mod:`rockbench.sweep.executors`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ..errors import ParameterError

__all__ = ["validity_map", "engines_to_run", "classify_cell", "relative_spread", "default_axes", "REGIONS",
           "VALIDITY_COLUMNS", "default_engines", "PHI_FLOOR", "SLIDING_FLOOR",
           "with_rule_friction"]

#: The regions of a validity map, in the order of the figure's legend.
REGIONS = ("model", "agree", "disagree", "diverged")

def default_engines() -> list[str]:
    """The engines a validity map runs outside the model by default: the installed ones whose
    backend declares itself ``fast`` (:class:`rockbench.engines.base.Backend`), so that an
    8 x 8 map costs seconds, not minutes."""
    from ..engines import available_backends, get_backend
    from ..runner import REFERENCE

    return [e for e in available_backends() if e != REFERENCE and get_backend(e).fast]


#: Floor of the median peak |phi| [rad] in :func:`relative_spread` (a block barely rocking:
#: engines within 1 mrad of each other agree).
PHI_FLOOR = 1e-3

#: Floor of the median sliding [m] in :func:`relative_spread` (engines within 1 mm of each
#: other agree on a base that hardly slides).
SLIDING_FLOOR = 1e-3

#: The columns of a validity map: name -> "unit, meaning".
VALIDITY_COLUMNS: dict[str, str] = {
    "A": "-, a_g / (g tan alpha) of the pulse",
    "W": "-, omega_g / p of the pulse",
    "region": "-, model | agree | disagree | diverged",
    "reason": "-, the analytic run's validity: inside, or outside from when and why",
    "sliding_onset_s": "s, first time a contact of the analytic model needs more friction than "
                       "it has (NaN: never)",
    "lift_off_s": "s, first time the ground falls faster than gravity (NaN: never)",
    "spread_phi": "-, (max - min) / max(median, 1 mrad) of the engines' peak |phi|",
    "spread_sliding": "-, (max - min) / max(median, 1 mm) of the engines' max_sliding",
    "engines_run": "-, the engines run in the cell, comma-separated",
    "cheapest": "-, in an agree cell, the engine with the least CPU time",
}


# ------------------------------------------------------------------------------------------
# The agreement rule (pure)
# ------------------------------------------------------------------------------------------
def relative_spread(values: Sequence[float | None], floor: float) -> float:
    """(max - min) / max(median, ``floor``) [-] of the finite ``values`` (None and NaN left
    out); NaN when none is finite. ``floor`` (same unit as the values, > 0) keeps a spread
    of near-zero values finite: values within ``floor`` of each other have spread <= 1."""
    v = np.array([np.nan if x is None else float(x) for x in values], dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan
    return float((v.max() - v.min()) / max(float(np.median(v)), floor))


def classify_cell(runs: Sequence[Mapping[str, Any]], *, tolerance: float = 0.10,
                  phi_floor: float = PHI_FLOOR, sliding_floor: float = SLIDING_FLOOR
                  ) -> dict[str, Any]:
    """The region of a cell outside the model from its engines' summaries ``runs`` (dicts with
    ``engine``, ``status``, ``overturned``, ``max_abs_phi`` [rad], ``max_sliding`` [m],
    ``cpu_s`` [s]).

    * ``"diverged"`` when ``runs`` is empty, or some run's status is not ``"ok"``, or its peak
      |phi| is not finite;
    * ``"agree"`` when every run has the same ``overturned`` verdict, ``spread_phi`` =
      :func:`relative_spread` of ``max_abs_phi`` (floor ``phi_floor``) <= ``tolerance`` and
      ``spread_sliding`` = that of ``max_sliding`` (floor ``sliding_floor``; runs without one
      left out, NaN when none has one, which does not count against agreement) <=
      ``tolerance``; when every run overturns, the verdict alone (a run's ``max_sliding``
      then includes the fall, the bodies' slip as they topple and land: a measure of the
      debris, not of the engine; the spreads are still reported); one engine alone agrees
      with itself;
    * ``"disagree"`` otherwise.

    Returns ``region``, ``spread_phi`` [-], ``spread_sliding`` [-] (over the runs with status
    ok) and ``cheapest`` (an agree cell's run with the least ``cpu_s``, else "")."""
    ok = [r for r in runs if r.get("status") == "ok"]
    sp = relative_spread([r.get("max_abs_phi") for r in ok], phi_floor)
    ss = relative_spread([r.get("max_sliding") for r in ok], sliding_floor)
    out = {"spread_phi": sp, "spread_sliding": ss, "cheapest": ""}
    finite = all(r.get("max_abs_phi") is not None and math.isfinite(float(r["max_abs_phi"]))
                 for r in ok)
    if not runs or len(ok) < len(runs) or not finite:
        return dict(out, region="diverged")
    verdicts = {bool(r.get("overturned")) for r in ok}
    fell = verdicts == {True}
    if len(verdicts) == 1 and (fell or (sp <= tolerance and not ss > tolerance)):
        cpu = [float(r.get("cpu_s", math.inf)) for r in ok]
        return dict(out, region="agree", cheapest=str(ok[int(np.argmin(cpu))]["engine"]))
    return dict(out, region="disagree")


# ------------------------------------------------------------------------------------------
# One cell (in a worker)
# ------------------------------------------------------------------------------------------
def _nan(x: Any) -> float:
    return math.nan if x is None else float(x)


def _run_cell(item: Mapping[str, Any]) -> dict[str, Any]:
    """Run one cell: the analytic model, then (outside it) every engine; the stored row
    (``case_id``, ``A``, ``W``, ``reason``, ``sliding_onset_s``, ``lift_off_s``, ``runs``:
    the engines' summaries as JSON)."""
    from ..runner import run
    from ..scene.motion import RickerPulse
    from ..scene.scene import Scene
    from ..run_length import pulse_run_length
    from ..validity import motion_validity

    scene = Scene.from_dict(item["scene"], source=f"scene {item['scene'].get('name', '')!r}")
    A, W = float(item["A"]), float(item["W"])
    motion = RickerPulse.dimensionless(A, W, scene.structure, item["shape"], int(item["sign"]),
                                       float(item["vertical_ratio"]))
    dur = pulse_run_length(W, scene.p, item["tail"])
    row = {"case_id": item["case_id"], "A": A, "W": W}
    try:
        s = run(scene, motion, duration=dur, history="minimal").summary
    except Exception as e:  # noqa: BLE001 - a cell that fails is data
        return dict(row, reason=f"not assessed: the analytic run failed ({type(e).__name__}: "
                                f"{e})", sliding_onset_s=math.nan, lift_off_s=math.nan,
                    runs=json.dumps([{"engine": "analytic", "status": "error"}]))
    # the run's own check; a run that did not assess it: the a-priori one, from the motion
    reason = s.validity or motion_validity(scene, motion).reason
    row.update(reason=reason, sliding_onset_s=_nan(s.sliding_onset),
               lift_off_s=_nan(s.t_lift_off))
    runs = []
    if reason.startswith("outside"):
        for e in item["engines"]:
            try:
                r = run(scene, motion, engine=e, duration=dur, keep="summary",
                        **dict(item["settings"].get(e) or {}))
                es = r.summary
                runs.append({"engine": e, "status": es.status, "overturned": bool(es.overturned),
                             "max_abs_phi": _nan(es.max_abs_phi),
                             "max_sliding": None if es.max_sliding is None
                             else float(es.max_sliding),
                             "cpu_s": float(r.cost.cpu_s), "reason": es.reason or ""})
            except Exception as e_:  # noqa: BLE001 - an engine that fails is data
                runs.append({"engine": e, "status": "error",
                             "reason": f"{type(e_).__name__}: {e_}"})
    row["runs"] = json.dumps(runs)
    return row


def _cell_item(item: Mapping[str, Any]) -> dict[str, Any]:
    """What the executor runs: :func:`_run_cell` looked up at call time (a test replaces it)."""
    return _run_cell(item)


# ------------------------------------------------------------------------------------------
# The map
# ------------------------------------------------------------------------------------------
def with_rule_friction(scene: Any) -> Any:
    """``scene`` (a Scene) as its validity map runs it: unchanged with its own friction, else
    with the validity rule's :data:`rockbench.validity.DEFAULT_FRICTION` given to every engine
    alike (their own defaults differ; the rule assumes this one)."""
    import dataclasses

    from ..scene.contact import Contact
    from ..validity import DEFAULT_FRICTION

    if scene.friction is not None:
        return scene
    return dataclasses.replace(scene, contact=Contact(friction=DEFAULT_FRICTION))


def default_axes(scene: Any, n: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A report's grid: ``n`` values of A from 0.5 to max(8, 1.5 A_mu) (A_mu = mu / tan alpha,
    where the PGA reaches mu g; at most 100) and ``n`` of W from 1 to 10."""
    from ..validity import friction_of

    a_mu = friction_of(scene) / math.tan(float(scene.structure.alpha))
    hi = min(100.0, max(8.0, math.ceil(1.5 * a_mu)))
    return np.round(np.linspace(0.5, hi, n), 6), np.round(np.linspace(1.0, 10.0, n), 6)


def _axis(values: Any, name: str) -> np.ndarray:
    from ..limits import check_in_limit

    try:
        v = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
    except (TypeError, ValueError):
        raise ParameterError(name, values, "a non-empty sequence of numbers") from None
    if v.size == 0:
        raise ParameterError(name, "[]", "a non-empty sequence of numbers (at least one cell)")
    for x in v:
        check_in_limit(name, name, x)
    return v


def engines_to_run(engines: Any) -> list[str]:
    """The engines to run outside the model: ``engines`` (names; ParameterError naming
    ``engines`` for an unknown one or the analytic reference) or, with None,
    :func:`default_engines`; engines not installed are left out."""
    from ..engines import available_backends
    from ..runner import REFERENCE, resolve_engines

    if engines is None:
        return default_engines()
    names = resolve_engines(engines)
    if not names or REFERENCE in names:
        raise ParameterError("engines", engines, "one or more engine names other than the "
                                                 f"analytic reference {REFERENCE!r}")
    have = set(available_backends())
    return [e for e in names if e in have]


def _check_settings(settings: Mapping[str, Mapping[str, Any]], names: Sequence[str]) -> None:
    """ParameterError naming ``settings`` for an engine not run or a field its Settings
    dataclass does not have (the values are checked by the engine when it runs)."""
    import dataclasses

    from ..engines import get_backend

    for e, fields in settings.items():
        if e not in names:
            raise ParameterError("settings", e, f"settings of the engines run: {names}")
        known = {f.name for f in dataclasses.fields(get_backend(e).Settings)}
        bad = sorted(set(fields) - known)
        if bad:
            raise ParameterError("settings", f"{e}.{bad[0]}", f"a field of {e}'s settings: "
                                                             f"{', '.join(sorted(known))}")


def validity_map(scene: Any, *, shape: str = "symmetric", sign: int = 1, A: Any = None,
                 W: Any = None, vertical_ratio: float = 0.0, engines: Any = None,
                 settings: Mapping[str, Mapping[str, Any]] | None = None,
                 tolerance: float = 0.10, store: Any = None, workers: int | None = None,
                 tail: float | None = None, progress: bool = False) -> pd.DataFrame:
    """The validity map of ``scene`` (a Scene, a built-in name or a TOML path): one row per
    (A, W) cell, columns :data:`VALIDITY_COLUMNS` (module docstring), A varying fastest.

    ``A`` [-], ``W`` [-]: the grid's axes (default :func:`default_axes`, 8 x 8);
    ``shape`` ("symmetric" | "antisymmetric"), ``sign`` (1 | -1), ``vertical_ratio`` [-] in
    [0, 3]: the pulse; ``engines``: run outside the model (default :func:`default_engines`,
    the fast ones installed); ``settings``: engine name -> setting overrides (default: each
    engine's defaults); ``tolerance`` [-]: of :func:`classify_cell`; ``store``: a folder,
    the cells kept under ``<store>/<fingerprint>/validity`` and reused; ``workers``: local
    processes (1: in this process; default: the cores); ``tail`` [s]: the run's free rocking
    after the pulse window 6 T_g (default: the package's, the motion + 10 s)."""
    from ..limits import check_in_limit
    from ..scene.scene import Scene, load_scene
    from ..sweep import store as S
    from ..sweep.executors import execute

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if shape not in ("symmetric", "antisymmetric"):
        raise ParameterError("shape", shape, "'symmetric' or 'antisymmetric'")
    if sign not in (1, -1):
        raise ParameterError("sign", sign, "1 or -1")
    vr = check_in_limit("vertical_ratio", "vertical_ratio", vertical_ratio)
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise ParameterError("tolerance", tolerance, "a finite number > 0 (e.g. 0.10)")
    if tail is not None and not (math.isfinite(float(tail)) and float(tail) >= 0):
        raise ParameterError("tail", tail, "a finite number of seconds >= 0")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ParameterError("workers", workers, "an integer >= 1")
    scene = with_rule_friction(scene)
    da, dw = default_axes(scene)
    As = _axis(da if A is None else A, "A")
    Ws = _axis(dw if W is None else W, "W")
    names = engines_to_run(engines)
    settings = {k: dict(v or {}) for k, v in (settings or {}).items()}
    _check_settings(settings, names)

    sd = scene.to_dict()
    base = {"scene": sd, "shape": shape, "sign": int(sign), "vertical_ratio": vr,
            "engines": names, "settings": settings, "tail": tail}
    items = []
    for w in Ws:
        for a in As:
            it = dict(base, A=float(a), W=float(w))
            it["case_id"] = S.key({k: v for k, v in it.items()})
            items.append(it)
    done: dict[str, dict] = {}
    directory = S.store_path(store, "validity") if store is not None else None
    if directory is not None:
        S.need_pyarrow()
        done = {r["case_id"]: r for r in S.load_store(directory, damaged="quiet")
                .to_dict("records")}
    todo = [(it["case_id"], it) for it in items if it["case_id"] not in done]

    def on_result(k: str, row: dict) -> None:
        done[k] = row
        if directory is not None and not row.get("crashed"):
            S.write_row(directory, row)

    def crashed(it: Mapping[str, Any], why: str) -> dict:
        return {"case_id": it["case_id"], "A": it["A"], "W": it["W"], "crashed": True,
                "reason": f"not assessed: {why}", "sliding_onset_s": math.nan,
                "lift_off_s": math.nan, "runs": json.dumps([{"engine": "?", "status": "error"}])}

    if todo:
        run = dict(on_result=on_result, crashed=crashed, label=lambda it: f"A={it['A']:g} "
                   f"W={it['W']:g}", executor="serial" if workers == 1 else "process",
                   workers=workers, progress=progress, desc="validity map", unit="cell")
        if directory is not None:
            with S.writer_lock(directory, "validity store"):
                execute(_cell_item, todo, **run)
            S.compact(directory)
        else:
            execute(_cell_item, todo, **run)
    return _frame([done[it["case_id"]] for it in items], tolerance)


def _frame(rows: Sequence[Mapping[str, Any]], tolerance: float) -> pd.DataFrame:
    """The map's frame (:data:`VALIDITY_COLUMNS`) from stored cell rows."""
    out = []
    for r in rows:
        runs = json.loads(r["runs"]) if isinstance(r.get("runs"), str) else []
        reason = str(r["reason"])
        inside = reason == "inside"
        c = (dict(region="model", spread_phi=math.nan, spread_sliding=math.nan, cheapest="")
             if inside else classify_cell(runs, tolerance=tolerance))
        out.append({"A": float(r["A"]), "W": float(r["W"]), "region": c["region"],
                    "reason": reason, "sliding_onset_s": _nan(r.get("sliding_onset_s")),
                    "lift_off_s": _nan(r.get("lift_off_s")), "spread_phi": c["spread_phi"],
                    "spread_sliding": c["spread_sliding"],
                    "engines_run": ",".join(x["engine"] for x in runs
                                            if x.get("engine") not in (None, "?", "analytic")),
                    "cheapest": c["cheapest"]})
    return pd.DataFrame(out, columns=list(VALIDITY_COLUMNS))

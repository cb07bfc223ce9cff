"""``rockbench advise``: which engine, which setting, for a tolerance, at what cost.

:func:`advise` answers from measurements on the user's scene (a built-in name, a scene file or a
:class:`~rockbench.scene.scene.Scene`): for every engine it runs the validation set of
:mod:`rockbench.tradeoff` at time steps from the largest down (:data:`ADVISE_DTS`), and stops
at the first setting whose **worst validation error** (:func:`rockbench.tradeoff.case_error`:
|peak error| of every surviving pulse, eta error of every free-rocking impact, infinite for a run
that is not ok or gets the overturning verdict wrong) is within the tolerance. Because the cost
of a run grows as its step shrinks (every measurement in ``docs/choosing.md``), that first
passing setting is the engine's cheapest; finer steps are not run. Engines are ranked by cost
(process CPU seconds per simulated second, median of the repeats); engines that reach the
tolerance at no step tried are listed with the best error they reached and where; engines that
cannot run here with the reason.

:func:`decide` is the pure part (a tradeoff table and a tolerance in, the advice out), so the
choice can be tested on a controlled table and the report can turn any tradeoff table into
advice (:func:`advice_for_report`).

Runs are reused through the store (``store``: a directory; :mod:`rockbench.sweep.store`, the
project's one store, under ``<store>/<code fingerprint>/tradeoff/``: a run is keyed by the
scene's data, the validation case, the engine, its settings and the repeat count, and by the
fingerprint of the code that decides its physics, so results of other code are never reused).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

import pandas as pd

from .errors import ParameterError

__all__ = ["ADVISE_DTS", "QUICK_DTS", "Advice", "advise", "decide", "advice_for_report"]

#: Time steps [s] tried, largest first.
ADVISE_DTS: tuple[float, ...] = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)
#: Engines whose cheapest passing setting costs at most this factor x the cheapest one's are
#: marked ``tie_with_cheapest``. On the shared 2-core machine of docs/choosing.md the repeats of
#: one sweep agreed within 2 %, but the same setting measured in sweeps 35 minutes apart moved
#: by up to 40 % (pymunk, dt 2e-3: 0.0123 and 0.0088 CPU s per simulated s; CPU time still
#: depends on what shares the core), so a smaller difference is not a ranking.
TIE = 1.25
#: Time steps [s] tried with ``quick``.
QUICK_DTS: tuple[float, ...] = (4e-3, 2e-3, 1e-3)

_EVIDENCE = ["engine", "setting", "dt", "worst_error", "verdict", "peak_error_worst",
             "eta_error_worst", "nrmse_worst", "verdicts_agree", "n_ok", "n_cases",
             "cpu_per_sim_s", "cpu_per_sim_s_min", "cpu_per_sim_s_max", "real_time_factor"]


@dataclass
class Advice:
    """The answer of :func:`advise` (JSON: :meth:`to_json`).

    scene, tolerance [-] (relative: 0.02 = 2 %);
    ranking : one dict per engine considered, the engines that meet the tolerance first
        (cheapest first), then those that cannot (smallest error first), then the unavailable:
        ``engine``, ``meets`` (bool), ``status`` ("meets", "cannot reach", "unavailable"),
        ``setting`` / ``dt`` [s] / ``worst_error`` [-] / ``cpu_per_sim_s`` [s/s] /
        ``real_time_factor`` [-] (the cheapest passing setting; for an engine that cannot reach
        the tolerance: its best setting), ``reason`` (why it cannot, in words),
        ``tie_with_cheapest`` (engines that meet it: cost within :data:`TIE` of the cheapest);
    considered : every engine name considered, in the order given;
    evidence : the tradeoff rows behind the answer (every setting run);
    quick : whether the reduced validation set was used; cases : the validation set;
    machine : where the cost was measured.
    """

    scene: str
    tolerance: float
    ranking: list[dict[str, Any]]
    considered: list[str]
    evidence: pd.DataFrame
    quick: bool = False
    cases: list[dict[str, Any]] = field(default_factory=list)
    machine: dict[str, Any] = field(default_factory=dict)

    @property
    def recommended(self) -> dict[str, Any] | None:
        """The cheapest engine and setting within the tolerance (None if none)."""
        return self.ranking[0] if self.ranking and self.ranking[0]["meets"] else None

    def to_json(self) -> dict[str, Any]:
        from .result import _jsonable

        ev = self.evidence[[c for c in _EVIDENCE if c in self.evidence.columns]]
        return _jsonable({
            "scene": self.scene, "tolerance": self.tolerance, "quick": self.quick,
            "recommended": self.recommended, "ranking": self.ranking,
            "considered": self.considered,
            "error_definition": "worst over the validation set of |peak error| (surviving "
                                "pulses) and eta error (free rocking); inf if a run is not ok "
                                "or its overturning verdict is wrong",
            "cost_definition": "process CPU s per simulated s, median of repeats (whole run: "
                               "build, stepping, Python loop, post-processing)",
            "evidence": [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                          for k, v in r.items()} for r in ev.to_dict("records")],
            "cases": self.cases, "machine": self.machine})

    def text(self) -> str:
        """A short human answer: the recommendation, then every engine's line."""
        lines = [f"Scene {self.scene}, tolerance {100 * self.tolerance:g} % "
                 f"(worst validation error{', quick set' if self.quick else ''}):"]
        rec = self.recommended
        if rec:
            lines.append(f"  use {rec['engine']} at {rec['setting']}: worst error "
                         f"{100 * rec['worst_error']:.3g} %, {rec['cpu_per_sim_s']:.3g} CPU s "
                         f"per simulated s (real-time factor {rec['real_time_factor']:.3g})")
            ties = [r["engine"] for r in self.ranking[1:] if r.get("tie_with_cheapest")]
            if ties:
                lines.append(f"  (as cheap within {100 * (TIE - 1):.0f} %, a tie on this "
                             f"machine: {', '.join(ties)})")
        else:
            lines.append("  no engine reaches this tolerance at the settings tried")
        for i, r in enumerate(self.ranking, 1):
            if r["status"] == "meets":
                lines.append(f"  {i}. {r['engine']}: {r['setting']}, error "
                             f"{100 * r['worst_error']:.3g} %, {r['cpu_per_sim_s']:.3g} CPU s/s, "
                             f"rtf {r['real_time_factor']:.3g}")
            else:
                lines.append(f"  {i}. {r['engine']}: {r['status']}: {r['reason']}")
        return "\n".join(lines)


def _fmt_err(e: float) -> str:
    return "inf (a run not ok or a wrong verdict)" if not math.isfinite(e) else f"{100 * e:.3g} %"


def decide(table: pd.DataFrame, tolerance: float, *, engines: Sequence[str] | None = None,
           unavailable: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """The ranking of :class:`Advice` from a tradeoff table (:data:`rockbench.tradeoff.
    TABLE_COLUMNS`: at least engine, setting, dt, worst_error, cpu_per_sim_s,
    real_time_factor): per engine the cheapest setting (smallest ``cpu_per_sim_s``; ties: the
    larger dt) with ``worst_error <= tolerance``; engines without one get their smallest
    error. ``engines``: the engines considered (default: those in the table), each gets a row;
    ``unavailable``: engine -> why it could not run."""
    tolerance = _check_tolerance(tolerance)
    unavailable = dict(unavailable or {})
    names = list(dict.fromkeys(list(engines) if engines is not None else list(table["engine"])))
    for n in unavailable:
        if n not in names:
            names.append(n)
    meets, cannot, missing = [], [], []
    for n in names:
        g = table[table["engine"] == n]
        if n in unavailable or g.empty:
            missing.append({"engine": n, "meets": False, "status": "unavailable",
                            "setting": None, "dt": None, "worst_error": None,
                            "cpu_per_sim_s": None, "real_time_factor": None,
                            "reason": unavailable.get(n, "not measured")})
            continue
        err = g["worst_error"].astype(float)
        ok = g[err <= tolerance]
        if len(ok):
            best = ok.sort_values(["cpu_per_sim_s", "dt"], ascending=[True, False]).iloc[0]
            meets.append({"engine": n, "meets": True, "status": "meets",
                          "setting": str(best["setting"]), "dt": float(best["dt"]),
                          "worst_error": float(best["worst_error"]),
                          "cpu_per_sim_s": float(best["cpu_per_sim_s"]),
                          "real_time_factor": float(best["real_time_factor"]), "reason": ""})
        else:
            best = g.assign(_e=err).sort_values(["_e", "cpu_per_sim_s"]).iloc[0]
            tried = ", ".join(f"{s}" for s in g["setting"])
            cannot.append({"engine": n, "meets": False, "status": "cannot reach",
                           "setting": str(best["setting"]), "dt": float(best["dt"]),
                           "worst_error": float(best["worst_error"]),
                           "cpu_per_sim_s": float(best["cpu_per_sim_s"]),
                           "real_time_factor": float(best["real_time_factor"]),
                           "reason": f"best worst error {_fmt_err(float(best['worst_error']))} "
                                     f"at {best['setting']} > tolerance "
                                     f"{100 * tolerance:g} % (tried: {tried})"})
    meets.sort(key=lambda r: (r["cpu_per_sim_s"], -r["dt"]))
    for r in meets:   # CPU time moves by a few percent between measurements: call it a tie
        r["tie_with_cheapest"] = r["cpu_per_sim_s"] <= TIE * meets[0]["cpu_per_sim_s"]
    cannot.sort(key=lambda r: (r["worst_error"], r["cpu_per_sim_s"]))
    return meets + cannot + missing


def _check_tolerance(tolerance: Any) -> float:
    try:
        t = float(tolerance)
    except (TypeError, ValueError):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02"
                             ) from None
    if not (0.0 < t < 1.0):
        raise ParameterError("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.02")
    return t


def advise(scene, tolerance: float, engines: Sequence[str] | None = None, store=None, *,
           dts: Iterable[float] | None = None, quick: bool = False, repeat: int | None = None,
           executor: str = "process", workers: int | None = None,
           progress: bool = False) -> Advice:
    """The cheapest setting of every engine within ``tolerance`` on ``scene``.

    Parameters
    ----------
    scene : Scene, built-in name or path to a scene file (:func:`rockbench.load_scene`).
    tolerance : relative bound on the worst validation error (0.02 = 2 %).
    engines : backend names (default: every registered engine but the analytic model; those
        that cannot run here are listed as unavailable).
    store : directory of the store to reuse and fill (None: nothing kept).
    dts : time steps [s] tried, from the largest down (default :data:`ADVISE_DTS`, quick:
        :data:`QUICK_DTS`).
    quick : the reduced validation set (:func:`rockbench.tradeoff.validation_set`) and one
        repeat: for tests and a first look.
    repeat : runs of each case for the cost (default 3; quick: 1).
    """
    from .engines import REGISTRY, get_backend
    from .runner import REFERENCE, resolve_engines
    from .scene.scene import Scene, load_scene
    from .tradeoff import machine_info, tradeoff, validation_set

    tolerance = _check_tolerance(tolerance)
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    names = ([n for n in REGISTRY if n != REFERENCE] if engines is None
             else [n for n in resolve_engines(engines) if n != REFERENCE])
    if not names:
        raise ParameterError("engines", engines, "at least one engine besides the analytic model")
    dts = sorted({float(d) for d in (dts if dts is not None else
                                     (QUICK_DTS if quick else ADVISE_DTS))}, reverse=True)
    repeat = (1 if quick else 3) if repeat is None else repeat
    unavailable: dict[str, str] = {}
    tables = []
    vset = validation_set(scene, quick=quick)
    for n in names:
        try:
            ok, why = get_backend(n).available()
        except Exception as e:  # BackendUnavailable: the module does not import
            ok, why = False, str(e)
        if not ok:
            unavailable[n] = why
            continue
        for d in dts:
            t = tradeoff(scene, [n], dts=[d], repeat=repeat, cases=vset,
                         self_consistency="none", executor=executor, workers=workers,
                         store=store, progress=progress)
            tables.append(t.table)
            if float(t.table["worst_error"].iloc[0]) <= tolerance:
                break
    evidence = (pd.concat(tables, ignore_index=True) if tables
                else pd.DataFrame(columns=_EVIDENCE))
    ranking = decide(evidence, tolerance, engines=names, unavailable=unavailable)
    return Advice(scene=scene.name, tolerance=tolerance, ranking=ranking, considered=names,
                  evidence=evidence, quick=quick, cases=[c.to_dict() for c in vset],
                  machine=machine_info())


def advice_for_report(table: pd.DataFrame, tolerances: Sequence[float] = (0.02, 0.002)
                      ) -> pd.DataFrame:
    """For the report: one row per (tolerance, engine) of :func:`decide` on a tradeoff table
    (columns tolerance [-], rank, engine, status, setting, dt [s], worst_error [-],
    cpu_per_sim_s [s/s], real_time_factor [-], reason): the recommendation is rank 1 of each
    tolerance when its status is "meets"."""
    rows = []
    for tol in tolerances:
        for i, r in enumerate(decide(table, tol), 1):
            rows.append({"tolerance": float(tol), "rank": i, **{k: r[k] for k in (
                "engine", "status", "setting", "dt", "worst_error", "cpu_per_sim_s",
                "real_time_factor", "reason")}})
    return pd.DataFrame(rows)

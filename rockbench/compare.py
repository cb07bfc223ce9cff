"""Metrics of one backend run against the analytic reference, and the comparison of one case.

:func:`compare` runs the analytic reference and every selected backend on one scene and one
ground motion and returns a :class:`Comparison`: the results, a tidy table with one row per
backend (columns :data:`METRIC_COLUMNS`) and a table with one row per impact (columns
:data:`ETA_COLUMNS`). :func:`metrics` and :func:`eta_rows` measure a single result against a
reference result; ``rockbench.testing.assert_agree`` is built on them.

How the metrics are measured (``docs/metrics.md`` lists every column with its unit):

* histories are compared on the reference's output grid: the backend's ``phi`` is interpolated
  linearly onto it (:func:`numpy.interp`) from the later of the two starts to the earlier of the
  two ends (a run that overturns stops there);
* the effective eta of every impact a backend reports is compared with the analytic eta of the
  mechanism it rocks into after the impact (``Reference(scene).eta[direction]``, Eq. 22 of the
  paper generalised to the frame by projection);
* a run that did not finish cleanly (status ``diverged`` or ``invalid``) keeps its row, with its
  reason and its cost, but NaN physics metrics, so that it is never plotted as physics.

This module runs backends only through the registry (:mod:`rockbench.engines`); it never imports
an engine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .errors import BackendUnavailable, ParameterError
from .result import Result
from .scene.scene import Scene

__all__ = ["REFERENCE", "METRIC_COLUMNS", "ETA_COLUMNS", "Comparison", "compare", "metrics",
           "eta_rows"]

#: Name of the reference backend every metric is measured against.
REFERENCE = "analytic"

#: Columns of :attr:`Comparison.table`, in order: column -> "unit, definition".
METRIC_COLUMNS: dict[str, str] = {
    "backend": "-, registered backend name",
    "engine_version": "-, engine package and version that ran",
    "status": "-, ok | diverged | invalid | unavailable (non-ok rows have NaN physics metrics)",
    "reason": "-, why a run is not ok (empty when ok)",
    "max_abs_phi_over_alpha": "-, max |phi| / alpha over the backend's run",
    "peak_rel_error": "-, max|phi| / max|phi_ref| - 1 (NaN when the reference never uplifts)",
    "nrmse": "-, RMS of (phi - phi_ref) / alpha over the common time grid (the reference's "
             "output grid, from the later start to the earlier end)",
    "max_abs_error_over_alpha": "-, max |phi - phi_ref| / alpha over the common time grid",
    "t_uplift_error": "s, t_uplift - t_uplift_ref (NaN unless both uplift)",
    "t_first_impact_error": "s, time of the first impact - that of the reference (NaN unless both "
                            "have one)",
    "n_impacts": "-, number of impacts of the backend's run",
    "n_impacts_ref": "-, number of impacts of the reference run",
    "eta_ccw_ref": "-, analytic eta of an impact after which the structure rocks counterclockwise",
    "eta_cw_ref": "-, analytic eta of an impact after which the structure rocks clockwise",
    "eta_ccw_mean": "-, mean effective eta of the backend's impacts into counterclockwise rocking",
    "eta_ccw_std": "-, standard deviation (ddof = 0) of those etas",
    "eta_cw_mean": "-, mean effective eta of the backend's impacts into clockwise rocking",
    "eta_cw_std": "-, standard deviation (ddof = 0) of those etas",
    "eta_max_rel_error": "-, max over the backend's impacts of |eta / eta_ref - 1|",
    "overturned": "-, the backend's run overturned",
    "overturned_ref": "-, the reference run overturned",
    "verdict_agrees": "-, overturned == overturned_ref",
    "t_overturn_error": "s, t_overturn - t_overturn_ref (NaN unless both overturn)",
    "energy_gained_at_impact": "-, an impact gained kinetic energy: a measured eta >= 1, or "
                               "eta^2 I_after(0) / I_before(0) > 1 (I: the mechanism's inertia "
                               "at phi = 0 for the direction before and after)",
    "max_penetration": "m, largest contact penetration (engines; NaN for the analytic model)",
    "max_sliding": "m, largest tangential slip of a contact point (engines; NaN for analytic)",
    "contact_opened": "-, a contact the analytic model keeps closed opened (engines; <NA> for "
                      "analytic)",
    "wall_s": "s, wall time of the integration or stepping only (model building excluded)",
    "steps": "-, integrator or engine steps",
    "real_time_factor": "-, simulated seconds per wall second",
}

#: Columns of :attr:`Comparison.eta`: one row per (backend, impact).
ETA_COLUMNS: dict[str, str] = {
    "backend": "-, registered backend name",
    "impact": "-, index of the impact in the backend's run (0 = first)",
    "t": "s, time of the impact",
    "direction": "-, +1 rocking counterclockwise after the impact, -1 clockwise",
    "eta": "-, effective coefficient of restitution of the impact (engines: measured from the "
           "motion; analytic: applied)",
    "eta_ref": "-, analytic eta of the same direction (Reference(scene).eta[direction])",
    "rel_error": "-, eta / eta_ref - 1",
}

_BOOL_COLUMNS = ("overturned", "overturned_ref", "verdict_agrees", "energy_gained_at_impact",
                 "contact_opened")
_INT_COLUMNS = ("n_impacts", "n_impacts_ref", "steps")
_STR_COLUMNS = ("backend", "engine_version", "status", "reason")


# =========================================================================================
# The analytic constants of a scene (cached: a Reference is built from the scene once)
# =========================================================================================
def _reference_of(scene: Scene):
    """``rockbench.analytic.reference.Reference`` of ``scene`` (pure physics, cached)."""
    from .analytic.reference import reference_of

    return reference_of(scene)


def _inertia0(scene: Scene, direction: int) -> float:
    """Generalised inertia [kg m^2] of the mechanism rocking in ``direction`` at phi = 0."""
    return float(_reference_of(scene).dyn[direction].terms(0.0).inertia)


# =========================================================================================
# Helpers on results
# =========================================================================================
def _check_result(name: str, r: Any) -> Result:
    if not isinstance(r, Result):
        raise ParameterError(name, type(r).__name__, "a rockbench Result")
    return r


def _first_time(events: pd.DataFrame, kind: str) -> float:
    ev = events[events["kind"] == kind]
    return float(ev["t"].iloc[0]) if len(ev) else math.nan


def _num(x: Any) -> float:
    return math.nan if x is None else float(x)


def _engine_version(result: Result) -> str:
    v = result.settings.get("engine_version") if isinstance(result.settings, dict) else None
    if v:
        return str(v)
    from .engines import get_backend  # registry only: no engine import for the analytic model
    try:
        ok, info = get_backend(result.backend).available()
    except Exception:  # pragma: no cover - unknown or broken backend
        return ""
    return str(info) if ok else ""


def history_error(result: Result, reference: Result) -> tuple[np.ndarray, np.ndarray]:
    """(t [s], (phi - phi_ref) / alpha [-]) on the common time grid: the reference's output
    times from the later of the two starts to the earlier of the two ends, with the result's phi
    interpolated linearly onto them. Empty arrays when the runs do not overlap."""
    h, hr = result.history, reference.history
    if len(h) == 0 or len(hr) == 0:
        return np.zeros(0), np.zeros(0)
    t = h["t"].to_numpy(dtype=float)
    tr = hr["t"].to_numpy(dtype=float)
    lo, hi = max(t[0], tr[0]), min(t[-1], tr[-1])
    tol = 1e-9 * max(1.0, abs(hi))
    m = (tr >= lo - tol) & (tr <= hi + tol)
    grid = tr[m]
    phi = np.interp(grid, t, h["phi"].to_numpy(dtype=float))
    phi_ref = hr["phi"].to_numpy(dtype=float)[m]
    return grid, (phi - phi_ref) / reference.scene.alpha


def _peak(result: Result) -> tuple[float, float]:
    """(max |phi| [rad], time of it [s]) of a result's history."""
    h = result.history
    if len(h) == 0:
        return math.nan, math.nan
    a = np.abs(h["phi"].to_numpy(dtype=float))
    i = int(np.nanargmax(a))
    return float(a[i]), float(h["t"].iloc[i])


# =========================================================================================
# Metrics
# =========================================================================================
def eta_rows(result: Result, reference: Result) -> list[dict[str, Any]]:
    """One row (columns :data:`ETA_COLUMNS`) per impact of ``result``: its effective eta
    against the analytic eta of the direction it rocks into after the impact.

    Impacts are taken in order from ``result.events``; ``eta_ref`` comes from the reference's
    scene (``Reference(scene).eta``), so it applies to every impact whatever its order. A result
    that is not ``ok`` has no rows.
    """
    result = _check_result("result", result)
    reference = _check_result("reference", reference)
    if not result.ok:
        return []
    eta_ref = _reference_of(reference.scene).eta
    rows = []
    for k, ev in enumerate(result.impacts().itertuples(index=False)):
        d = int(ev.direction)
        ref = float(eta_ref[d]) if d in eta_ref else math.nan
        e = _num(ev.eta)
        rows.append({"backend": result.backend, "impact": k, "t": float(ev.t), "direction": d,
                     "eta": e, "eta_ref": ref,
                     "rel_error": e / ref - 1.0 if math.isfinite(e) and ref else math.nan})
    return rows


def _energy_gained(result: Result) -> bool:
    """Any impact with a measured eta >= 1, or whose kinetic energy grows:
    eta^2 I_after(0) / I_before(0) > 1, the structure rocking in -direction before the impact
    and in direction after it (see METRIC_COLUMNS)."""
    for ev in result.impacts().itertuples(index=False):
        e, after = _num(ev.eta), int(ev.direction)
        if not math.isfinite(e):
            continue
        if abs(e) >= 1.0:
            return True
        if after in (1, -1):
            ratio = e * e * _inertia0(result.scene, after) / _inertia0(result.scene, -after)
            if ratio > 1.0 + 1e-12:
                return True
    return False


def _empty_row(backend: str, reference: Result | None) -> dict[str, Any]:
    row: dict[str, Any] = {c: math.nan for c in METRIC_COLUMNS}
    row.update(backend=backend, engine_version="", status="", reason="")
    for c in _BOOL_COLUMNS:
        row[c] = None
    for c in _INT_COLUMNS:
        row[c] = None
    if reference is not None:
        ref = _reference_of(reference.scene)
        row["eta_ccw_ref"], row["eta_cw_ref"] = float(ref.eta[1]), float(ref.eta[-1])
        if reference.ok:
            row["n_impacts_ref"] = int(reference.summary.n_impacts)
            row["overturned_ref"] = bool(reference.summary.overturned)
    return row


def metrics(result: Result, reference: Result) -> dict[str, Any]:
    """One row of :attr:`Comparison.table` (keys :data:`METRIC_COLUMNS`): ``result`` measured
    against ``reference`` (the analytic run of the same scene, motion and initial rotation).

    A result (or reference) that is not ``ok`` gets its status, reason, engine version and cost
    but NaN / missing physics metrics.
    """
    result = _check_result("result", result)
    reference = _check_result("reference", reference)
    row = _empty_row(result.backend, reference)
    row["engine_version"] = _engine_version(result)
    row["status"] = result.status
    row["reason"] = result.summary.reason or ""
    row["wall_s"] = float(result.cost.wall_s)
    row["steps"] = int(result.cost.steps)
    row["real_time_factor"] = float(result.cost.real_time_factor)
    if not result.ok:
        return row
    if not reference.ok:
        row["reason"] = f"reference run is {reference.status}: {reference.summary.reason}"
        return row
    s, sr = result.summary, reference.summary
    row["max_abs_phi_over_alpha"] = float(s.max_abs_phi_over_alpha)
    peak, _ = _peak(result)
    peak_ref, _ = _peak(reference)
    row["peak_rel_error"] = peak / peak_ref - 1.0 if peak_ref > 0 else math.nan
    _, err = history_error(result, reference)
    if err.size:
        row["nrmse"] = float(np.sqrt(np.mean(err * err)))
        row["max_abs_error_over_alpha"] = float(np.max(np.abs(err)))
    row["t_uplift_error"] = _num(s.t_uplift) - _num(sr.t_uplift)
    row["t_first_impact_error"] = (_first_time(result.events, "impact")
                                   - _first_time(reference.events, "impact"))
    row["n_impacts"] = int(s.n_impacts)
    eta = pd.DataFrame(eta_rows(result, reference), columns=list(ETA_COLUMNS))
    for d, tag in ((1, "ccw"), (-1, "cw")):
        e = eta.loc[eta["direction"] == d, "eta"].to_numpy(dtype=float)
        e = e[np.isfinite(e)]
        row[f"eta_{tag}_mean"] = float(np.mean(e)) if e.size else math.nan
        row[f"eta_{tag}_std"] = float(np.std(e)) if e.size else math.nan
    rel = np.abs(eta["rel_error"].to_numpy(dtype=float))
    rel = rel[np.isfinite(rel)]
    row["eta_max_rel_error"] = float(rel.max()) if rel.size else math.nan
    row["overturned"] = bool(s.overturned)
    row["verdict_agrees"] = bool(s.overturned) == bool(sr.overturned)
    row["t_overturn_error"] = (_num(s.t_overturn) - _num(sr.t_overturn)
                               if s.overturned and sr.overturned else math.nan)
    row["energy_gained_at_impact"] = _energy_gained(result)
    row["max_penetration"] = _num(s.max_penetration)
    row["max_sliding"] = _num(s.max_sliding)
    row["contact_opened"] = None if s.contact_opened is None else bool(s.contact_opened)
    return row


def _table(rows: list[dict[str, Any]]) -> pd.DataFrame:
    df = pd.DataFrame(rows, columns=list(METRIC_COLUMNS))
    for c in _STR_COLUMNS:
        df[c] = df[c].fillna("").astype(str)
    for c in _BOOL_COLUMNS:
        df[c] = df[c].astype("boolean")
    for c in _INT_COLUMNS:
        df[c] = pd.array([None if v is None or (isinstance(v, float) and math.isnan(v))
                          else int(v) for v in df[c]], dtype="Int64")
    floats = [c for c in METRIC_COLUMNS if c not in _BOOL_COLUMNS + _INT_COLUMNS + _STR_COLUMNS]
    df[floats] = df[floats].astype("float64")
    return df


def _eta_table(rows: list[dict[str, Any]]) -> pd.DataFrame:
    df = pd.DataFrame(rows, columns=list(ETA_COLUMNS))
    return df.astype({"backend": str, "impact": "int64", "t": "float64", "direction": "int64",
                      "eta": "float64", "eta_ref": "float64", "rel_error": "float64"})


# =========================================================================================
# One case across backends
# =========================================================================================
@dataclass
class Comparison:
    """Every selected backend on one scene and one ground motion, against the reference.

    Attributes
    ----------
    scene : Scene
    motion : dict
        ``motion.describe()``, or ``{"kind": "none"}`` for free rocking.
    phi0 : float
        Initial rotation [rad].
    results : dict[str, Result]
        Backend name -> Result, the reference (``"analytic"``) first. Unavailable backends have
        no entry.
    table : pandas.DataFrame
        One row per backend (reference row included), columns :data:`METRIC_COLUMNS`.
    eta : pandas.DataFrame
        One row per (backend, impact), columns :data:`ETA_COLUMNS`.
    """

    scene: Scene
    motion: dict
    phi0: float
    results: dict[str, Result]
    table: pd.DataFrame
    eta: pd.DataFrame
    duration: float | None = None
    settings: dict[str, Any] = field(default_factory=dict)

    def histories(self) -> pd.DataFrame:
        """Tidy rotation histories: backend, t [s], phi [rad], phidot [rad/s], ground_acc
        [m/s^2], mode [-], one row per backend and output time."""
        cols = ["t", "phi", "phidot", "ground_acc", "mode"]
        frames = [r.history[cols].assign(backend=name)[["backend"] + cols]
                  for name, r in self.results.items() if len(r.history)]
        if not frames:
            return pd.DataFrame(columns=["backend"] + cols)
        return pd.concat(frames, ignore_index=True)

    def _write(self, directory, ext: str, writer) -> list[Path]:
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        out = []
        for name, df in (("metrics", self.table), ("eta", self.eta),
                         ("history", self.histories())):
            p = d / f"{name}.{ext}"
            writer(df, p)
            out.append(p)
        return out

    def to_csv(self, directory) -> list[Path]:
        """Write ``metrics.csv`` (:attr:`table`), ``eta.csv`` (:attr:`eta`) and ``history.csv``
        (:meth:`histories`) into ``directory`` (created); return their paths."""
        return self._write(directory, "csv", lambda df, p: df.to_csv(p, index=False))

    def to_parquet(self, directory) -> list[Path]:
        """As :meth:`to_csv`, in Parquet (needs pyarrow: ``pip install rockbench[parquet]``)."""
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            from .errors import RockbenchError
            raise RockbenchError("writing Parquet needs pyarrow: pip install "
                                 "'rockbench[parquet]'") from None
        return self._write(directory, "parquet", lambda df, p: df.to_parquet(p, index=False))


def _settings_for(settings: Mapping[str, Any] | None, name: str) -> tuple[Any, dict[str, Any]]:
    """(settings object or None, overrides dict) for backend ``name``."""
    if not settings or name not in settings:
        return None, {}
    s = settings[name]
    if s is None:
        return None, {}
    if isinstance(s, Mapping):
        return None, dict(s)
    return s, {}


def compare(scene: Scene, motion=None, *, engines=None, phi0: float = 0.0,
            duration: float | None = None, settings: Mapping[str, Any] | None = None,
            progress: bool = False) -> Comparison:
    """Run the reference and every selected backend on ``scene`` and measure them.

    Parameters
    ----------
    scene : Scene
    motion : GroundMotion or None
        None: free rocking from ``phi0``.
    engines : list of str, optional
        Backend names; None: every available backend. The reference (``"analytic"``) always runs,
        first. A backend whose engine is not installed gets a row with status ``"unavailable"``.
    phi0 : float
        Initial rotation [rad].
    duration : float, optional
        Simulated time [s] (default: the motion's length + 10 s, or 10 s of free rocking).
    settings : dict, optional
        Backend name -> that backend's Settings object, or a dict of setting overrides
        (e.g. ``{"pymunk": {"dt": 2e-4}}``).
    progress : bool
        Show a tqdm progress bar naming the running backend.
    """
    from .engines import available_backends, get_backend

    if not isinstance(scene, Scene):
        raise ParameterError("scene", type(scene).__name__, "a rockbench Scene")
    if engines is None:
        names = available_backends()
    else:
        if isinstance(engines, str):
            engines = [engines]
        names = list(dict.fromkeys(engines))
        for n in names:
            _check_engine_name(n)
    if settings is not None:
        if not isinstance(settings, Mapping):
            raise ParameterError("settings", type(settings).__name__,
                                 "a dict: backend name -> Settings or dict of overrides")
        from .engines import REGISTRY
        for k in settings:
            if k not in REGISTRY:
                raise ParameterError("settings", k,
                                     f"keyed by backend names: {', '.join(REGISTRY)}")
    order = [REFERENCE] + [n for n in names if n != REFERENCE]

    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(order), desc="compare", unit="backend")
    results: dict[str, Result] = {}
    unavailable: dict[str, str] = {}
    try:
        for name in order:
            if bar is not None:
                bar.set_description(f"{scene.name}: {name}")
            obj, over = _settings_for(settings, name)
            try:
                backend = get_backend(name)(scene, obj, **over)
                results[name] = backend.run(motion, duration=duration, phi0=phi0)
            except BackendUnavailable as e:
                if name == REFERENCE:
                    raise
                unavailable[name] = str(e)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()

    reference = results[REFERENCE]
    rows, etas = [], []
    for name in order:
        if name in results:
            rows.append(metrics(results[name], reference))
            etas.extend(eta_rows(results[name], reference))
        else:
            row = _empty_row(name, reference)
            row.update(status="unavailable", reason=unavailable.get(name, ""))
            rows.append(row)
    return Comparison(scene=scene,
                      motion=motion.describe() if motion is not None else {"kind": "none"},
                      phi0=float(phi0), results=results, table=_table(rows),
                      eta=_eta_table(etas), duration=duration,
                      settings={k: results[k].settings for k in results})


def _check_engine_name(name: Any) -> None:
    """Raise ParameterError unless ``name`` is a registered backend name."""
    from .engines import REGISTRY

    if not isinstance(name, str) or name not in REGISTRY:
        raise ParameterError("engines", name, f"registered backend names: {', '.join(REGISTRY)}")

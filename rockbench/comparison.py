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

The module also holds what every layer above measures with: :data:`TOLERANCES` (the one
tolerance table: the report's agreement grades, ``assert_agree``'s defaults, ``check_backend``'s
free-rocking bars and the cross-engine bars), the derived metrics of a table
(:func:`with_derived`) and the overturning map of a sweep (:func:`overturn_map`).

Importing it imports no engine, no scene and no runner: :func:`compare` runs backends through
:func:`rockbench.runner.run_all`, imported when it is called, so that the report layer may import
the column dictionaries, :data:`TOLERANCES` and :func:`with_derived` from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np
import pandas as pd

from .errors import ParameterError
from .result import Result, as_float

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from .scene.scene import Scene

__all__ = ["REFERENCE", "METRIC_COLUMNS", "ETA_COLUMNS", "DERIVED_COLUMNS", "TOLERANCES",
           "TOLERANCE_KEYS", "Comparison", "compare", "metrics", "eta_rows", "history_error",
           "with_derived", "overturn_map", "peak_of"]


def __getattr__(name: str) -> Any:
    # REFERENCE is runner's (the one place that names the reference backend); re-exported here
    # lazily so that importing this module does not import the runner and the engine registry.
    if name == "REFERENCE":
        from .runner import REFERENCE

        return REFERENCE
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# =========================================================================================
# The one tolerance table
# =========================================================================================
#: Every tolerance rockbench measures agreement with, in one place (values in the units of
#: :data:`TOLERANCE_KEYS`). Entries:
#:
#: * ``"assert_agree"`` - the defaults of :func:`rockbench.testing.assert_agree` (free rocking
#:   and moderate pulses at the engines' default time step, 1 ms);
#: * ``"free_rocking"``, ``"surviving_pulse"``, ``"overturning_pulse"`` - the cross-engine bars
#:   (``tests/engines/test_cross_engine.py``), each a set of ``assert_agree`` keyword arguments:
#:   ``assert_agree(result, reference, **TOLERANCES["free_rocking"])``; a tolerance of None skips
#:   that check;
#: * ``"contacts"`` - the cross-engine bar on contact penetration and sliding (engines);
#: * ``"check_backend"`` - the free-rocking checks of :func:`rockbench.testing.check_backend`
#:   (Housner's block from phi0 = +-alpha/2, dt = 1 ms): ``eta_rtol`` against Housner's
#:   1 - 1.5 sin^2(alpha), ``nrmse`` against the analytic history over 1 s;
#: * ``"grades"`` - the report's agreement colours: metric -> (good, fair) limits on the
#:   metric's absolute value, |x| <= good is "good" (green), <= fair "fair" (amber), larger
#:   "poor" (red); units those of the metric (:data:`METRIC_COLUMNS`, :data:`DERIVED_COLUMNS`),
#:   documented in ``docs/report.md``. The "good" limits of peak and eta equal assert_agree's
#:   defaults; nrmse is tightened there (a whole-run history that drifts in phase by a few
#:   percent of a rocking cycle already gives 0.01-0.05, hence the wider "good" here).
#:
#: pymunk, MuJoCo and PyBullet measure the free-rocking eta within 0.1-0.3 % at dt = 1 ms
#: (``docs/testing.md``), hence 0.5 %.
TOLERANCES: dict[str, dict[str, Any]] = {
    "assert_agree": dict(peak_rtol=0.03, eta_rtol=0.005, nrmse=0.005, verdict=True),
    "free_rocking": dict(peak_rtol=None, eta_rtol=0.005, nrmse=0.005, verdict=True),
    "surviving_pulse": dict(peak_rtol=0.03, eta_rtol=None, nrmse=None, verdict=True),
    "overturning_pulse": dict(peak_rtol=None, eta_rtol=None, nrmse=None, verdict=True),
    "contacts": dict(max_penetration=2e-3, max_sliding=2e-3),
    "check_backend": dict(eta_rtol=0.005, nrmse=0.05),
    "grades": {
        "nrmse": (0.01, 0.05),
        "max_abs_error_over_alpha": (0.05, 0.2),
        "peak_rel_error": (0.03, 0.10),
        "eta_mean_rel_error": (0.005, 0.02),
        "eta_max_rel_error": (0.005, 0.02),
        "t_first_impact_error": (0.01, 0.05),
        "max_penetration": (1e-3, 5e-3),
        "max_sliding": (1e-3, 1e-2),
    },
}

#: Unit and meaning of every key of the :data:`TOLERANCES` entries (the ``"grades"`` entry is
#: keyed by metric: see :data:`METRIC_COLUMNS`).
TOLERANCE_KEYS: dict[str, str] = {
    "peak_rtol": "-, bound on |max|phi| / max|phi_ref| - 1| (reference at rest: on "
                 "max|phi| / alpha); None skips the check",
    "eta_rtol": "-, bound on |eta / eta_ref - 1| of every measured impact; None skips",
    "nrmse": "-, bound on the RMS of (phi - phi_ref) / alpha over the common time grid; None "
             "skips",
    "verdict": "-, require the same overturning verdict as the reference",
    "max_penetration": "m, bound on the largest contact penetration of a run (engines)",
    "max_sliding": "m, bound on the largest tangential slip of a contact point (engines)",
}

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
    "fractured": "-, the backend's devices fractured (a tendon reached the fracture strain)",
    "fractured_ref": "-, the reference's devices fractured",
    "fracture_agrees": "-, fractured == fractured_ref",
    "t_fracture_error": "s, t_fracture - t_fracture_ref (NaN unless both fracture)",
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
    "cpu_s": "s, process CPU time of the whole run (building included, numba compiling apart)",
    "cpu_per_sim_s": "s/s, cpu_s per simulated second",
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

#: Columns derived from a metrics table (:func:`with_derived`; not in :data:`METRIC_COLUMNS`).
DERIVED_COLUMNS: dict[str, str] = {
    "eta_mean_rel_error": "-, max over the two directions of |eta_mean / eta_ref - 1| "
                          "(mean effective eta against the analytic eta)",
}

_BOOL_COLUMNS = ("overturned", "overturned_ref", "verdict_agrees", "fractured", "fractured_ref",
                 "fracture_agrees", "energy_gained_at_impact", "contact_opened")
_INT_COLUMNS = ("n_impacts", "n_impacts_ref", "steps")
_STR_COLUMNS = ("backend", "engine_version", "status", "reason")


# =========================================================================================
# The analytic constants of a scene (cached: a Reference is built from the scene once)
# =========================================================================================
def _reference_of(scene: "Scene"):
    """``rockbench.analytic.reference.Reference`` of ``scene`` (pure physics, cached)."""
    from .analytic.reference import reference_of

    return reference_of(scene)


def _inertia0(scene: "Scene", direction: int) -> float:
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


def peak_of(result: Result) -> tuple[float, float]:
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
        e = as_float(ev.eta)
        rows.append({"backend": result.backend, "impact": k, "t": float(ev.t), "direction": d,
                     "eta": e, "eta_ref": ref,
                     "rel_error": e / ref - 1.0 if math.isfinite(e) and ref else math.nan})
    return rows


def _energy_gained(result: Result) -> bool:
    """Any impact with a measured eta >= 1, or whose kinetic energy grows:
    eta^2 I_after(0) / I_before(0) > 1, the structure rocking in -direction before the impact
    and in direction after it (see METRIC_COLUMNS)."""
    for ev in result.impacts().itertuples(index=False):
        e, after = as_float(ev.eta), int(ev.direction)
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
            row["fractured_ref"] = bool(reference.summary.fractured)
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
    cpu, sim = float(result.cost.cpu_s), float(result.cost.sim_time)
    row["cpu_s"] = cpu
    row["cpu_per_sim_s"] = cpu / sim if sim > 0 and cpu == cpu else math.nan
    if not result.ok:
        return row
    if not reference.ok:
        row["reason"] = f"reference run is {reference.status}: {reference.summary.reason}"
        return row
    s, sr = result.summary, reference.summary
    row["max_abs_phi_over_alpha"] = float(s.max_abs_phi_over_alpha)
    peak, _ = peak_of(result)
    peak_ref, _ = peak_of(reference)
    row["peak_rel_error"] = peak / peak_ref - 1.0 if peak_ref > 0 else math.nan
    _, err = history_error(result, reference)
    if err.size:
        row["nrmse"] = float(np.sqrt(np.mean(err * err)))
        row["max_abs_error_over_alpha"] = float(np.max(np.abs(err)))
    row["t_uplift_error"] = as_float(s.t_uplift) - as_float(sr.t_uplift)
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
    row["t_overturn_error"] = (as_float(s.t_overturn) - as_float(sr.t_overturn)
                               if s.overturned and sr.overturned else math.nan)
    row["fractured"] = bool(s.fractured)
    row["fracture_agrees"] = bool(s.fractured) == bool(sr.fractured)
    row["t_fracture_error"] = (as_float(s.t_fracture) - as_float(sr.t_fracture)
                               if s.fractured and sr.fractured else math.nan)
    row["energy_gained_at_impact"] = _energy_gained(result)
    row["max_penetration"] = as_float(s.max_penetration)
    row["max_sliding"] = as_float(s.max_sliding)
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
@dataclass(repr=False)
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
    duration : float or None
        Simulated time [s] asked for (None: the default).
    settings : dict
        Backend name -> the settings its run used.
    constants : dict
        The scene's analytic constants (``rockbench.info(scene)``: keys and units in
        :data:`rockbench.analytic.reference.CONSTANTS`), for the report.
    """

    scene: "Scene"
    motion: dict
    phi0: float
    results: dict[str, Result]
    table: pd.DataFrame
    eta: pd.DataFrame
    duration: float | None = None
    settings: dict[str, Any] = field(default_factory=dict)
    constants: dict[str, Any] = field(default_factory=dict)

    def label(self) -> str:
        """``'scene' (motion)``: what was compared."""
        from .result import motion_label

        m = self.motion if self.motion.get("kind") != "none" else None
        what = motion_label(m) if m else f"free rocking from phi0 = {self.phi0:.4g} rad"
        return f"{getattr(self.scene, 'name', None) or 'scene'!r} ({what})"

    def _lines(self) -> list[str]:
        """One short line per backend: status, peak error, eta error, verdict, cost."""
        def pct(x: Any) -> str:
            v = as_float(x)
            return f"{100 * v:.2f} %" if math.isfinite(v) else "n/a"

        out = []
        for _, r in self.table.iterrows():
            bits = [str(r["status"])]
            if r["backend"] != "analytic":
                bits.append(f"peak {pct(r.get('peak_rel_error'))}")
                bits.append(f"eta {pct(r.get('eta_max_rel_error'))}")
                va = r.get("verdict_agrees")
                if va is not None and va == va:
                    bits.append("same verdict" if bool(va) else "OTHER VERDICT")
            res = self.results.get(r["backend"])
            if res is not None and res.cost.cpu_s == res.cost.cpu_s:
                bits.append(f"{res.cost.cpu_s:.3g} CPU s")
            out.append(f"{r['backend']}: " + ", ".join(bits))
        return out

    def __repr__(self) -> str:
        return (f"<Comparison of {len(self.results)} backends on {self.label()}: "
                + "; ".join(self._lines()) + ">")

    def _repr_html_(self) -> str:
        """The notebook view: what was compared, one line per backend, the metrics table."""
        import html as _html

        cols = [c for c in ("backend", "status", "max_abs_phi_over_alpha", "peak_rel_error",
                            "nrmse", "eta_max_rel_error", "overturned", "verdict_agrees",
                            "max_penetration", "max_sliding") if c in self.table]
        return (f"<div><p><b>{_html.escape(self.label())}</b></p><ul>"
                + "".join(f"<li>{_html.escape(x)}</li>" for x in self._lines()) + "</ul>"
                + self.table[cols].to_html(index=False, float_format=lambda v: f"{v:.4g}")
                + "<p>units: docs/metrics.md; <code>comparison.table</code>, "
                  "<code>.eta</code>, <code>.histories()</code></p></div>")

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


def compare(scene: "Scene", motion=None, *, engines=None, phi0: float = 0.0,
            duration: float | None = None, settings: Mapping[str, Any] | None = None,
            progress: bool = False) -> Comparison:
    """Run the reference and every selected backend on ``scene`` and measure them
    (:func:`rockbench.runner.run_all`, then :func:`metrics` and :func:`eta_rows`).

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
    from .analytic.reference import reference_of
    from .runner import REFERENCE, resolve_engines, run_all

    names = resolve_engines(engines)
    results, unavailable = run_all(scene, motion, engines=names, phi0=phi0, duration=duration,
                                   settings=settings, progress=progress)
    reference = results[REFERENCE]
    rows, etas = [], []
    for name in [REFERENCE] + [n for n in names if n != REFERENCE]:
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
                      settings={k: r.settings for k, r in results.items()},
                      constants=reference_of(scene).constants())


# =========================================================================================
# Derived metrics (tables in, tables out)
# =========================================================================================
def with_derived(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` (columns of :data:`METRIC_COLUMNS`) with :data:`DERIVED_COLUMNS` added."""
    t = table.copy()
    if {"eta_ccw_mean", "eta_ccw_ref", "eta_cw_mean", "eta_cw_ref"} <= set(t.columns):
        a = (t["eta_ccw_mean"].astype(float) / t["eta_ccw_ref"].astype(float) - 1.0).abs()
        b = (t["eta_cw_mean"].astype(float) / t["eta_cw_ref"].astype(float) - 1.0).abs()
        t["eta_mean_rel_error"] = pd.concat([a, b], axis=1).max(axis=1, skipna=True)
    return t


def overturn_map(frame: pd.DataFrame, *, engine: str | None = None, scene: str | None = None,
                 shape: str | None = None, sign: int | None = None,
                 value: str = "overturned") -> pd.DataFrame:
    """Pivot a sweep frame of Ricker cases into a map: index ``A`` (rows, a_g / (g tan alpha)),
    columns ``W`` (omega_g / p), cells ``value`` (default ``overturned`` as 1.0 / 0.0; NaN where
    the case is not ``ok``). Filters select one engine / scene / shape / sign; a map that would
    still hold two cases in one cell raises ParameterError naming the column that differs."""
    if not isinstance(frame, pd.DataFrame) or "motion.A" not in frame or "motion.W" not in frame:
        raise ParameterError("frame", type(frame).__name__,
                             "a run_cases frame of Ricker cases given by A and W")
    if value not in frame:
        raise ParameterError("value", value, "a column of the frame, e.g. overturned, "
                                             "max_abs_phi_over_alpha")
    df = frame[frame["motion.kind"] == "ricker"]
    for col, want in (("engine", engine), ("scene", scene), ("motion.shape", shape),
                      ("motion.sign", sign)):
        if want is not None:
            df = df[df[col] == want]
    if df.empty:
        raise ParameterError("frame", "no matching rows",
                             "rows for the selected engine/scene/shape/sign")
    keys = df[["motion.A", "motion.W"]]
    if keys.duplicated().any():
        varying = [c for c in ("engine", "scene", "motion.shape", "motion.sign", "case_id")
                   if c in df and df[c].nunique() > 1]
        raise ParameterError(varying[0] if varying else "frame", "several values",
                             "one value: select it with the matching argument "
                             "(engine=, scene=, shape=, sign=)")

    def num(v: Any) -> float:
        try:
            return math.nan if v is None else float(v)
        except (TypeError, ValueError):
            return math.nan

    vals = pd.Series([num(v) for v in df[value]], index=df.index)
    vals = vals.where(df["status"] == "ok")
    out = pd.DataFrame({"A": df["motion.A"].astype(float), "W": df["motion.W"].astype(float),
                        "v": vals.astype(float)})
    table = out.pivot(index="A", columns="W", values="v").sort_index().sort_index(axis=1)
    table.columns.name = "W"
    table.index.name = "A"
    return table

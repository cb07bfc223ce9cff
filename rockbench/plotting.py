"""Public plotting helpers: the report's figures for your own runs, maps and sweeps.

Each function returns a :class:`matplotlib.figure.Figure` built without pyplot (so it is safe in
scripts, tests and worker processes); a notebook displays it, ``fig.savefig(path)`` writes it.

* :func:`plot_history` - rotation histories phi / alpha [-] against t [s] of one or more
  :class:`~rockbench.result.Result` of the same case (the analytic reference bold, black), with
  the ground acceleration [m/s^2] and the difference to the reference;
* :func:`plot_map` - an overturning map (the frame of ``rockbench.studies.maps.run_map`` or a map
  store) on W = omega_g / p and A = a_g / (g tan alpha), or an engine's verdicts over the analytic
  map with ``compare=``;
* :func:`plot_work_precision` - error against CPU cost per simulated second, one curve per
  engine (the table of ``rockbench tradeoff``).
"""

from __future__ import annotations

from typing import Any, Mapping

import pandas as pd
from matplotlib.figure import Figure

from .errors import ParameterError

__all__ = ["plot_history", "plot_map", "plot_work_precision"]


def plot_history(*results: Any, detail: bool = True, title: str | None = None) -> Figure:
    """Rotation histories of runs of one case, one line per backend.

    ``results``: :class:`~rockbench.result.Result` objects (``rb.run(...)``), or one mapping
    ``{label: Result}``. alpha [rad] (the taller column's slenderness, which scales the y axis)
    is taken from the first run's scene. With ``detail`` (default) three panels: ground
    acceleration [m/s^2], phi / alpha [-], and (phi - phi_ref) / alpha against the analytic run
    when one is given.
    """
    from .report.figures import plot_histories

    if len(results) == 1 and isinstance(results[0], Mapping):
        runs = dict(results[0])
    else:
        runs = {}
        for r in results:
            if not hasattr(r, "history") or not hasattr(r, "backend"):
                raise ParameterError("results", type(r).__name__,
                                     "rockbench Result objects (rb.run(...)) or one mapping "
                                     "{label: Result}")
            label, k = r.backend, 2
            while label in runs:
                label, k = f"{r.backend} ({k})", k + 1
            runs[label] = r
    if not runs:
        raise ParameterError("results", "nothing", "at least one Result")
    first = next(iter(runs.values()))
    scene = getattr(first, "scene", None)
    if scene is None or not hasattr(scene, "structure"):
        raise ParameterError("results", type(first).__name__, "Results that carry their scene")
    if title is None:
        title = first.label() if hasattr(first, "label") else None
    return plot_histories(runs, alpha=float(scene.structure.alpha), title=title, detail=detail)


_MAP_COLUMNS = ("pulse", "sign", "amplitude", "frequency", "overturned", "max_abs_phi_over_alpha",
                "status")


def _check_map(frame: Any, name: str) -> pd.DataFrame:
    if not isinstance(frame, pd.DataFrame):
        raise ParameterError(name, type(frame).__name__, "a map frame (rockbench.studies.maps.run_map)")
    missing = [c for c in _MAP_COLUMNS if c not in frame.columns]
    if missing:
        raise ParameterError(name, f"a frame without {', '.join(missing)}",
                             f"a map frame with columns {', '.join(_MAP_COLUMNS)}")
    if not len(frame):
        raise ParameterError(name, "an empty frame", "a map with at least one cell")
    return frame


def plot_map(frame: pd.DataFrame, *, compare: pd.DataFrame | None = None,
             title: str | None = None, name: str | None = None) -> Figure:
    """An overturning map: four panels (symmetric / antisymmetric pulse, sign + / -) on W (x)
    and A (y); red overturns, blue shades max |phi| / alpha of a surviving structure, hatched
    cells lie outside the analytic model (its ``outside`` column); the default title names a
    vertical ratio (``attrs["vertical_ratio"]`` of :func:`rockbench.studies.maps.run_map`).

    With ``compare`` (a map of the same cells by another backend) the figure shows that
    backend's verdicts as markers over this map (``frame`` is then the reference, usually the
    analytic map) and rings the cells where they differ. ``name`` labels the compared backend
    (default: its ``backend`` column).
    """
    from .report.map_figures import plot_map_overlay, plot_map_panels

    ratio = float(getattr(frame, "attrs", {}).get("vertical_ratio", 0.0) or 0.0)
    frame = _check_map(frame, "frame")
    if compare is None:               # a map run with a vertical part says so (run_map's attrs)
        return plot_map_panels(frame, title=title or "overturning map" + (
            f", a_v = {ratio:g} a_g" if ratio else ""))
    compare = _check_map(compare, "compare")
    if name is None:
        name = str(compare["backend"].iloc[0]) if "backend" in compare.columns else "compared"
    return plot_map_overlay(frame, compare, name=name,
                            title=title or f"{name} over the reference map")


def plot_work_precision(table: pd.DataFrame, *, tolerance: float | None = None,
                        title: str | None = None) -> Figure:
    """Work-precision diagram of a ``rockbench tradeoff`` table (``rockbench.studies.tradeoff.tradeoff``):
    worst error [-] against process CPU s per simulated s (log-log), one curve per engine through
    its settings, the Pareto front marked, and ``tolerance`` [-] as a horizontal line."""
    from .report.tradeoff_figures import plot_work_precision as _plot

    if not isinstance(table, pd.DataFrame):
        raise ParameterError("table", type(table).__name__,
                             "a work-precision table (rockbench.studies.tradeoff.tradeoff)")
    need = {"engine", "dt", "cpu_per_sim_s", "worst_error"}
    if not need <= set(table.columns):
        raise ParameterError("table", "a frame without " + ", ".join(sorted(need - set(
            table.columns))), "a work-precision table with columns " + ", ".join(sorted(need)))
    if tolerance is not None and not (0 < float(tolerance) < 1):
        raise ParameterError("tolerance", tolerance, "a fraction in (0, 1), e.g. 0.02 for 2 %")
    return _plot(table, tolerance=tolerance, title=title)

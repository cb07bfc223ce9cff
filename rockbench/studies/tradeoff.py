"""Work-precision: how accurate each engine is on a scene, at each setting, and at what cost.

:func:`tradeoff` runs a fixed **validation set** of a scene
(:func:`rockbench.studies.validation.validation_set`, re-exported here) with every selected engine at
every setting (by default the one ladder of time steps,
:data:`rockbench.constants.DT_LADDER`), with
repeats, and measures

* **accuracy against the analytic reference** (:func:`rockbench.comparison.metrics` on every run):
  worst and median |peak error| over the surviving pulses, worst and median nrmse, worst and
  median eta error over the free-rocking runs, overturning-verdict agreement;
* **self-consistency** (Erez, Tassa & Todorov 2015, "Simulation tools for model-based robotics"):
  every setting against the same engine at a step four times smaller (``dt / 4``), on the same
  cases. The difference is the engine's *discretisation* error; what remains of the error against
  the analytic model once that is small is *model* error (the engine converges to something
  else than the rigid-impact model);
* **cost** as process CPU time (:func:`time.process_time`, user + system time of the worker
  process, all threads: the engines run on one thread) of the whole run (building the model,
  stepping, the Python loop and the post-processing into a Result), divided by the simulated
  time: CPU seconds per simulated second, the median of ``repeat`` runs with its min-max spread,
  and the CPU real-time factor (simulated seconds per CPU second, the inverse). CPU time, unlike
  wall time, does not change with the load of a shared machine, so the ranking is stable.

Output: a :class:`Tradeoff` with ``runs`` (one row per engine, setting and case:
:data:`RUN_COLUMNS`) and ``table`` (one row per engine and setting: :data:`TABLE_COLUMNS`);
``rockbench.report.tradeoff_figures.plot_work_precision(t.table)`` draws the work-precision
diagram.

The **worst validation error** (``worst_error``, what ``rockbench advise`` compares with a
tolerance) of a setting is the largest of: |peak error| of every surviving pulse, the eta error
of every free-rocking impact (:func:`rockbench.comparison.metrics`' ``eta_max_rel_error``); it is
infinite when a run is not ``ok`` or gets the overturning verdict wrong. Errors are relative
(0.02 = 2 %).

Runs go through :func:`rockbench.runner.run` and the one executor
(:func:`rockbench.sweep.executors.execute`: serial, process pool or Dask); finished runs are kept
in the one store (:mod:`rockbench.sweep.store`) under ``<store>/<code fingerprint>/tradeoff/``,
keyed by the scene's data, the case, the engine and its settings, and the repeat count.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Mapping, Sequence

from ..errors import ParameterError
from .tradeoff_tables import (DT_LADDER, RUN_COLUMNS, TABLE_COLUMNS, VERDICTS, Tradeoff, runs_frame,
                              add_self_consistency, case_error, classify_error, machine_info,
                              precision_sweeps, summarize)
from .validation import (ValidationCase, _analytic, _scene_from_key,
                         _scene_key, overturn_threshold, validation_set)

if TYPE_CHECKING:
    from ..engines.setting_text import Overrides

__all__ = ["precision_sweeps", "ValidationCase", "validation_set",
           "overturn_threshold", "Setting", "settings_grid", "tradeoff", "Tradeoff", "summarize",
           "classify_error", "RUN_COLUMNS", "TABLE_COLUMNS", "VERDICTS", "case_error"]

#: The clock of the cost: process CPU time (user + system) [s]. A module attribute so that a
#: test can replace it.
cpu_clock = time.process_time

#: Self-consistency partner: each setting is compared with the same engine at dt / this.
REFINEMENT = 4



# =========================================================================================
# Settings
# =========================================================================================
@dataclass(frozen=True)
class Setting:
    """One engine setting: ``engine`` and a tuple of (name, value) setting overrides."""

    engine: str
    overrides: tuple[tuple[str, Any], ...]

    @property
    def dt(self) -> float:
        from ..engines import get_backend

        d = dict(self.overrides)
        if "dt" in d:
            return float(d["dt"])
        return float(getattr(get_backend(self.engine).Settings(), "dt", math.nan))

    @property
    def label(self) -> str:
        """``"dt=0.001"`` or ``"dt=0.001,iterations=50"`` (dt first, then sorted names)."""
        d = dict(self.overrides)
        parts = [f"dt={self.dt:g}"] + [f"{k}={d[k]:g}" if isinstance(d[k], float)
                                       else f"{k}={d[k]}" for k in sorted(d) if k != "dt"]
        return ",".join(parts)

    def refined(self, factor: int = REFINEMENT) -> "Setting":
        """The same setting at dt / factor (or, for a setting of a backend's own precision
        knob, :func:`precision_sweeps`, that knob / factor)."""
        d = dict(self.overrides)
        knob = next((k for k, _, _ in precision_sweeps(self.engine) if k != "dt" and k in d),
                    "dt")
        d[knob] = (self.dt if knob == "dt" else float(d[knob])) / factor
        return Setting(self.engine, tuple(sorted(d.items())))


def settings_grid(engines: Sequence[str], dts: Iterable[float] | None = None,
                  extra: Sequence[Mapping[str, Any] | str | Overrides] | None = None
                  ) -> list[Setting]:
    """Every (engine, setting) of a sweep: each engine at each ``dt`` [s] (default
    :data:`DT_LADDER`), and each ``extra`` override set at each dt, unless it sets dt itself.
    An extra set is text in the one setting grammar (:mod:`rockbench.engines.setting_text`:
    ``"iterations=50"`` for every engine, ``"pymunk.iterations=50,collision_slop=1e-4"`` or
    the older ``"pymunk:iterations=50"`` for one), a mapping (every engine; values as given) or
    an :class:`~rockbench.engines.setting_text.Overrides`; text is typed by each engine's
    Settings. Settings are validated by the engines when they run."""
    from ..engines.setting_text import parse_overrides

    dts = [float(d) for d in (DT_LADDER if dts is None else dts)]
    for d in dts:
        if not (d > 0 and math.isfinite(d)):
            raise ParameterError("dt", d, "> 0 [s]")
    extras = [parse_overrides({})] + [parse_overrides(e, option="setting")
                                      for e in extra or []]
    out: list[Setting] = []
    for eng in engines:
        for over in extras:
            if not over.applies_to(eng):
                continue
            ex = over.for_engine(eng)
            # each of the engine's curves (precision_sweeps: dt for every engine but those
            # whose class declares its own knob); an extra that sets the knob is run as given
            for knob, values, fixed in (precision_sweeps(eng) if not ex else
                                        (("dt", None, {}),)):
                vals = [ex[knob]] if knob in ex else (dts if values is None else values)
                for v in vals:
                    o = {**fixed, **ex, knob: float(v)}
                    if knob == "dt" or "dt" in ex:
                        o["dt"] = float(o.get("dt", v))
                    s = Setting(eng, tuple(sorted(o.items())))
                    if s not in out:
                        out.append(s)
    return out


# =========================================================================================
# One run (what the executor runs; picklable, top level)
# =========================================================================================
@functools.lru_cache(maxsize=64)
def _reference(key: str, case: ValidationCase):
    scene = _scene_from_key(key)
    sc, motion = case.load(scene)
    # records: the compiled analytic path (the default of record comparisons; same answers)
    return _analytic(sc, motion, case.duration, case.phi0, compiled=case.kind == "record"
                     or (case.motion is not None and dict(case.motion).get("kind") == "record"))


@functools.lru_cache(maxsize=64)
def _band(key: str, case: ValidationCase):
    """The analytic model's own sensitivity band of a record case (:mod:`rockbench.studies.sensitivity`)."""
    from .sensitivity import band

    sc, motion = case.load(_scene_from_key(key))
    return band(sc, motion, duration=case.duration, phi0=case.phi0)


#: (engine, setting label) already warmed up in this process, with the warm-up's CPU time [s].
_WARMED: dict[tuple[str, str], float] = {}

#: Simulated time [s] of the warm-up run (free rocking from 0.3 alpha).
WARMUP_DURATION = 0.5


def _warm(setting: "Setting", scene, over: dict[str, Any]) -> float:
    """Run one short case of ``setting`` on ``scene`` before anything is timed, once per process
    (the one-off costs: imports, numba's compile of the stepping loop, the engine's first-run
    allocations). Returns its CPU time [s] the first time, NaN after."""
    from ..runner import run

    k = (setting.engine, setting.label)
    if k in _WARMED:
        return math.nan
    c0 = cpu_clock()
    try:
        run(scene, None, engine=setting.engine, duration=WARMUP_DURATION,
            phi0=0.3 * scene.alpha, **over)
    except Exception:   # the timed run reports the failure
        pass
    _WARMED[k] = cpu_clock() - c0
    return _WARMED[k]


def _build_cpu(setting: "Setting", scene, phi0: float, over: dict[str, Any]) -> float:
    """CPU time [s] of building the engine's model of ``scene`` (a one-off cost per run,
    measured apart: :meth:`EngineBackend.build` then release), or 0 for a backend without one."""
    from ..engines import get_backend

    cls = get_backend(setting.engine)
    if not hasattr(cls, "build"):
        return 0.0
    b = cls(scene, None, **over)
    c0 = cpu_clock()
    try:
        b.build(phi0)
    finally:
        try:
            b._close()
        except Exception:
            pass
    return cpu_clock() - c0


def _run_overrides(setting: Setting) -> dict[str, Any]:
    """The setting's overrides, with ``output_dt`` raised to dt when dt exceeds the engine's
    default output interval (1 ms): histories stay sampled at 1 ms or at every step."""
    from ..engines import get_backend

    over = dict(setting.overrides)
    if "output_dt" not in over:
        od = float(get_backend(setting.engine).Settings().output_dt)
        if setting.dt > od:
            over["output_dt"] = setting.dt
    return over


def _run_item(item: dict[str, Any]) -> dict[str, Any]:
    """Run one (engine, setting, case) ``repeat`` times; return its row (metrics against the
    analytic reference; for a record, its place in the reference's sensitivity band; CPU times:
    the steady-state part of every repeat, the model build and the process's one-off warm-up
    apart) and the thinned history (t, phi) for self-consistency.
    Never raises for a failure of the run: it becomes status "error"."""
    from ..comparison import metrics
    from ..runner import run

    case: ValidationCase = item["case"]
    setting: Setting = item["setting"]
    row: dict[str, Any] = {"engine": setting.engine, "setting": setting.label,
                           "dt": setting.dt, "case": case.name, "kind": case.kind,
                           "part": case.part, "group": case.group,
                           "near_boundary": bool(case.near_boundary)}
    try:
        scene = _scene_from_key(item["scene"])
        sc, motion = case.load(scene)
        ref = _reference(item["scene"], case)
        over = _run_overrides(setting)
        row["warmup_cpu_s"] = _warm(setting, sc, over)
        build = _build_cpu(setting, sc, case.phi0, over)
        cpu: list[float] = []
        result = None
        for _ in range(int(item["repeat"])):
            c0 = cpu_clock()
            result = run(sc, motion, engine=setting.engine, duration=case.duration,
                         phi0=case.phi0, **over)
            # numba's one-off compiling of a specialization the warm-up did not meet is
            # not the setting's cost (Result.cost.compile_cpu_s, rockbench._jit.CpuClock)
            spent = cpu_clock() - c0 - float(result.cost.compile_cpu_s or 0.0)
            cpu.append(max(spent - build, 0.0))
        m = metrics(result, ref)
        row.update({k: m[k] for k in ("status", "reason", "peak_rel_error", "nrmse",
                                      "eta_max_rel_error", "verdict_agrees", "overturned",
                                      "overturned_ref", "energy_gained_at_impact",
                                      "max_sliding", "max_penetration", "contact_opened")})
        if case.kind == "record" and row["status"] == "ok":
            j = _band(item["scene"], case).judge(result)
            row["in_band"], row["band_distance"] = bool(j.inside), float(j.relative)
        row["sim_time"] = float(result.cost.sim_time)
        row["cpu_s"] = [float(c) for c in cpu]
        row["build_cpu_s"] = float(build)
        row["t"] = result.history["t"].to_numpy(dtype=float)
        row["phi"] = result.history["phi"].to_numpy(dtype=float)
        row["alpha"] = float(sc.alpha)
    except Exception as e:  # a failing run is data
        row.update(status="error", reason=f"{type(e).__name__}: {e}", cpu_s=[],
                   sim_time=math.nan)
    return row


def _crashed(item: dict[str, Any], reason: str) -> dict[str, Any]:
    s, c = item["setting"], item["case"]
    return {"engine": s.engine, "setting": s.label, "dt": s.dt, "case": c.name,
            "kind": c.kind, "part": c.part, "group": c.group,
            "near_boundary": bool(c.near_boundary), "status": "error", "reason": reason,
            "cpu_s": [], "sim_time": math.nan}


# =========================================================================================
# The store
# =========================================================================================
def _item_key(item: dict[str, Any]) -> str:
    from ..sweep.store import code_fingerprint, key

    s, c = item["setting"], item["case"]
    return key({"scene": item["scene"], "case": c.physics(), "engine": s.engine,
                "settings": dict(s.overrides), "repeat": int(item["repeat"]),
                "code": code_fingerprint()})


def _store_dir(store) -> Path:
    from ..sweep.store import store_path

    return store_path(store, "tradeoff")


def _load_stored(directory: Path, k: str) -> dict[str, Any] | None:
    from ..sweep.store import load_payload

    return load_payload(directory, k)


# =========================================================================================
# The sweep
# =========================================================================================
def tradeoff(scene, engines: Sequence[str] | None = None, *, dts: Iterable[float] | None = None,
             settings: Sequence[Mapping[str, Any] | str] | None = None, repeat: int = 3,
             quick: bool = False, self_consistency: str = "grid",
             executor: str = "process", workers: int | None = None, store=None,
             progress: bool = False, cases: Sequence[ValidationCase] | None = None,
             exact: Sequence[Mapping[str, Any]] | None = None,
             on_row: Any = None) -> Tradeoff:
    """Measure work-precision on ``scene`` (a Scene, a built-in name or a scene file).

    Parameters
    ----------
    engines : backend names (default: every available engine, the analytic model excluded).
    dts : time steps [s] (default :data:`DT_LADDER`).
    settings : extra override sets (:func:`settings_grid`), e.g. ``["iterations=50"]``.
    repeat : runs of each case (>= 1); the cost is the median over them, with min-max spread.
    quick : the reduced validation set (:func:`validation_set`).
    self_consistency : ``"grid"`` (compare with dt / 4 where that dt is in the sweep),
        ``"run"`` (run the missing dt / 4 settings too, once, not shown as settings) or
        ``"none"``.
    executor, workers : :func:`rockbench.sweep.executors.execute` (``"process"`` by default:
        each worker is one process on one core; CPU time is per process, so parallel runs do
        not inflate each other's cost as long as no core is oversubscribed).
    store : a directory: runs already there (same scene data, case, engine, settings, repeat
        count and code fingerprint) are not run again; new ones are written there.
    cases : a validation set to use instead of :func:`validation_set`.
    exact : override sets run as they are, instead of the grid of ``dts`` x ``settings``
        (each for every engine; without dt an engine runs at its default step).
    on_row : called with each run's row as it finishes here (not for runs the store held).
    """
    from ..runner import REFERENCE, resolve_engines
    from ..scene.scene import load_scene
    from ..sweep.executors import execute

    scene = load_scene(scene)          # a name, a file or a Scene: the one resolver
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ParameterError("repeat", repeat, "an integer >= 1")
    if self_consistency not in ("grid", "run", "none"):
        raise ParameterError("self_consistency", self_consistency, "grid, run or none")
    names = [n for n in resolve_engines(engines) if n != REFERENCE]
    from ..engines import get_backend

    unavailable: dict[str, str] = {}
    usable = []
    for n in names:
        ok, why = get_backend(n).available()
        if ok:
            usable.append(n)
        else:
            unavailable[n] = why
    if exact is not None:
        grid = [Setting(e, tuple(sorted(dict(o).items()))) for e in usable for o in exact]
    else:
        grid = settings_grid(usable, dts, settings)
    shown = set(grid)
    if self_consistency == "run":
        for s in list(grid):
            f = s.refined()
            if f not in shown and f.dt >= 1e-6:
                grid.append(f)
    vset = list(cases) if cases is not None else validation_set(scene, quick=quick)
    key = _scene_key(scene)
    items = []
    for s in grid:
        for c in vset:
            # refinement-only runs need no repeats: their cost is not reported
            items.append({"scene": key, "case": c, "setting": s,
                          "repeat": repeat if s in shown else 1})
    keyed = [(_item_key(it), it) for it in items]
    done: dict[str, dict[str, Any]] = {}
    directory = None
    if store is not None:
        directory = _store_dir(store)
        for k, _ in keyed:
            row = _load_stored(directory, k)
            if row is not None and row.get("status") != "error":
                done[k] = row
    todo = [(k, it) for k, it in keyed if k not in done]

    def on_result(k: str, row: dict[str, Any]) -> None:
        done[k] = row
        if directory is not None and row.get("status") != "error":
            from ..sweep.store import write_payload
            write_payload(directory, k, row)
        if on_row is not None:
            on_row(row)

    # TODO(pymunk/mujoco threads): every engine here steps on one thread.
    execute(_run_item, todo, on_result=on_result, crashed=_crashed,
            label=lambda it: f"{it['setting'].engine} {it['setting'].label} {it['case'].name}",
            is_error=lambda r: r.get("status") not in ("ok",), executor=executor,
            workers=workers, progress=progress, desc="tradeoff", unit="run")
    runs = []
    for k, it in keyed:
        r = dict(done[k])
        c = it["case"]        # its place in this split (the store keys the physics only)
        r.update(part=c.part, group=c.group, near_boundary=bool(c.near_boundary),
                 measure=c.measure, peak_ref=float(c.peak_ref))
        r["_setting"] = it["setting"]
        r["_shown"] = it["setting"] in shown
        runs.append(r)
    add_self_consistency(runs)
    frame = runs_frame([r for r in runs if r["_shown"]])
    table = summarize(frame)
    return Tradeoff(scene=scene.name, cases=vset, runs=frame, table=table,
                    unavailable=unavailable, machine=machine_info())

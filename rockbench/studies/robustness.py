"""``rockbench stress``: every backend at the extremes, one axis at a time from a base scene.

Each :class:`StressPoint` changes one thing of the base scene (by default the paper's asymmetric
frame ``paper-asymmetric``, whose device axes start from ``paper-asymmetric-hybrid``; a user's
scene is its own base, with the device axes only when it has devices) and runs it with
the analytic reference and every selected engine at its default settings (the ``dt`` axis
changes the engines' step). Every point of every engine gives a row (:data:`STRESS_COLUMNS`),
whatever happens: an invalid scene or setting, an exception, a diverged run each become a row
with its reason. The row's ``class`` (:data:`rockbench.studies.tradeoff.VERDICTS`):

* ``within 1%`` / ``within 5%`` / ``off`` (> 5 %): the error against the analytic reference:
  free rocking: the largest eta error of its impacts; a pulse or record the reference survives:
  |peak error| (max |phi - phi_ref| / alpha when the reference hardly uplifts); one it
  overturns: |t_overturn error| / T_g (T_g the pulse period; 1 s for a record), and ``off``
  when the overturning verdicts differ;
* ``off`` also when the run is ``ok`` but fails a check the Result itself could make
  (``flags``): a contact slid more than ``TOLERANCES["contacts"]["max_sliding"]`` (2 mm) before
  the structure fell, energy gained at an impact in free rocking; ``invalid`` when the
  reference has impacts but the run measured no finite eta (e.g. a too coarse ``output_dt``);
* ``diverged`` / ``invalid``: the run's status (or an exception: ``invalid`` with its reason);
* ``outside model``: the point lies outside the analytic model's validity: its motion asks
  the base for more friction than the contact has (:func:`rockbench.validity.motion_validity`,
  the rule every study uses: peak ground acceleration above mu g), or, in most engines that
  ran, the impacts rebound (a contact the model keeps closed opens and the effective eta
  exceeds the analytic one by more than 20 %): stocky frames, where the rigid, sticking impact
  of the model no longer describes the physics. ``model_validity`` says which side of that
  line every point is on, and ``engine_class`` keeps the engine's own class there.

:func:`stress` (fast by default: a handful of points per axis, about a minute for the three
engines on two cores; ``full=True``: the whole ranges), :func:`breaking_points` (per engine and
axis, the first value away from the paper's frame that is not within 5 %), and
``rockbench.report.tradeoff_figures.plot_stability_map`` (one figure per backend).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from .tradeoff import classify_error

__all__ = ["AXES", "StressPoint", "stress_points", "run_point", "stress", "Stress",
           "structure_refusal", "axis_label",
           "breaking_points", "STRESS_COLUMNS", "synthetic_record", "PAPER_VALUES",
           "base_values"]

_BASE = "paper-asymmetric"
_HYBRID = "paper-asymmetric-hybrid"
_REBOUND = 0.2           # effective eta above the analytic one by more than this: rebounding
_PULSE = dict(kind="ricker", shape="symmetric", sign=1)

#: axis -> (meaning and unit, fast values, full values). The base point is the scene the sweep
#: starts from (the paper's asymmetric frame by default); the device axes scale its own tendons
#: and dampers (the paper's hybrid frame by default).
AXES: dict[str, tuple[str, tuple, tuple]] = {
    "alpha": ("slenderness of the taller column [rad] (its width H tan(alpha) at its height H; "
              "free rocking from 0.5 alpha)", (0.05, 0.6), (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6)),
    "mass_ratio": ("beam / column mass ratio [-] (frames; free rocking from 0.5 alpha)",
                   (0.1, 100.0), (0.1, 0.3, 1.0, 3.0, 30.0, 100.0)),
    "H1/H": ("right / left column height [-] (frames; free rocking from 0.5 alpha)", (0.5,),
             (0.5, 0.6, 0.7, 0.9, 1.0)),
    "tendon": ("tendon stiffness / the scene's own [-] (scenes with devices; symmetric pulse "
               "A = 7, W = 3)", (0.0, 1000.0), (0.0, 0.1, 10.0, 100.0, 1000.0)),
    "damper": ("damper constant / the scene's own [-] (scenes with devices; A = 7, W = 3)",
               (0.0, 10.0), (0.0, 0.3, 3.0, 10.0)),
    "dt": ("engine time step [s] (symmetric pulse A = 2.5, W = 3)", (1e-2,),
           (1e-5, 1e-4, 4e-3, 1e-2)),
    "A": ("pulse amplitude a_g / (g tan alpha) [-] (symmetric pulse, W = 3)", (50.0, 200.0),
          (1.5, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0)),
    "W": ("pulse frequency omega_g / p [-] (symmetric pulse, A = 3)", (0.5, 50.0),
          (0.3, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0)),
    "record": ("length of a synthetic accelerogram [s] (PGA 2 g tan alpha)", (20.0,),
               (20.0, 100.0)),
}

def axis_label(axis: str) -> str:
    """The axis with the unit its :data:`AXES` meaning states, e.g. ``"alpha [rad]"``,
    ``"tendon [x own]"`` (the device axes scale the scene's own values); the base scene's own
    points (``paper`` / ``base``) are ``"... [0 free rocking, 1 pulse]"``."""
    import re

    if axis not in AXES:
        return f"{axis} [0 free rocking, 1 pulse]"
    if axis in _DEVICE_AXES:
        return f"{axis} [x own]"
    m = re.search(r"\[([^\]]+)\]", AXES[axis][0])
    return f"{axis} [{m.group(1)}]" if m else axis


#: Axes a scene without tendons and dampers has no use for, and those a block has not.
_DEVICE_AXES = ("tendon", "damper")
_FRAME_AXES = ("mass_ratio", "H1/H")


def base_values(scene=None) -> dict[str, float]:
    """The base point's value on every axis: the scene's alpha [rad], beam / column mass ratio
    and H1/H (frames), 1 on the device axes, dt 1e-3 s, A = 2.5, W = 3 (the base pulse)."""
    from ..scene.scene import load_scene

    sc = load_scene(_BASE if scene is None else scene)
    st = sc.structure
    out = {"alpha": round(float(sc.alpha), 4), "tendon": 1.0, "damper": 1.0, "dt": 1e-3,
           "A": 2.5, "W": 3.0, "record": math.nan}
    if hasattr(st, "column_height_right"):
        out["H1/H"] = round(st.column_height_right / st.column_height_left, 6)
        # the scene's beam / left column mass, however it was given (beam_mass, mass_ratio
        # or the default solid beam): the base of the mass_ratio axis
        out["mass_ratio"] = round(float(st.mass_beam / st.mass_left), 6)
    return out


#: The paper frame's value on every axis (the default base point).
PAPER_VALUES: dict[str, float] = {"alpha": 0.1419, "mass_ratio": 10.0, "H1/H": 0.8,
                                  "tendon": 1.0, "damper": 1.0, "dt": 1e-3, "A": 2.5, "W": 3.0,
                                  "record": math.nan}


@dataclass(frozen=True)
class StressPoint:
    """One point of one axis (plain data). ``scene``: a built-in name, a TOML path or a Scene;
    ``overrides``: scene
    overrides (name, value); ``motion``: a Ricker spec as (key, value) pairs, ``("record",
    length)`` for the synthetic record, or None (free rocking from ``phi0`` x alpha);
    ``settings``: engine setting overrides; ``duration`` [s] (None: chosen from the motion)."""

    axis: str
    value: float
    scene: Any
    overrides: tuple = ()
    motion: tuple | None = None
    phi0: float = 0.0
    settings: tuple = ()
    duration: float | None = None

    @property
    def label(self) -> str:
        return f"{self.axis}={self.value:g}"


def _point(axis: str, v: float, base: Any = _BASE, hybrid: Any = _HYBRID) -> StressPoint:
    """The point ``v`` of ``axis`` from the ``base`` scene (the device axes from ``hybrid``, the
    same structure with devices); the overrides scale the scene's own values."""
    from ..scene.scene import load_scene

    pulse = lambda A, W: tuple(sorted({**_PULSE, "A": A, "W": W}.items()))  # noqa: E731
    if axis in ("alpha", "H1/H"):
        st = load_scene(base).structure
        frame = hasattr(st, "column_height_left")
        H = st.column_height_left if frame else st.height
        if axis == "alpha":
            key = "column_width" if frame else "width"
            return StressPoint(axis, v, base, ((key, round(H * math.tan(v), 6)),), None, 0.5)
        return StressPoint(axis, v, base, (("column_height_right", round(H * v, 6)),), None,
                           0.5)
    if axis == "mass_ratio":
        return StressPoint(axis, v, base, (("mass_ratio", v),), None, 0.5)
    if axis in _DEVICE_AXES:
        dev = load_scene(hybrid).devices
        key, own = (("tendon_stiffness", dev.tendon_stiffness) if axis == "tendon" else
                    ("damping", dev.damping))
        return StressPoint(axis, v, hybrid, ((key, own * v),), pulse(7.0, 3.0))
    if axis == "dt":
        return StressPoint(axis, v, base, (), pulse(2.5, 3.0), 0.0, (("dt", v),))
    if axis == "A":
        return StressPoint(axis, v, base, (), pulse(v, 3.0))
    if axis == "W":
        return StressPoint(axis, v, base, (), pulse(3.0, v))
    if axis == "record":
        return StressPoint(axis, v, base, (), ("record", v), 0.0, (), v + 5.0)
    raise ParameterError("axis", axis, f"one of {', '.join(AXES)}")


def stress_points(full: bool = False, axes: Sequence[str] | None = None, *,
                  scene: Any = None, hybrid: Any = None) -> list[StressPoint]:
    """The points of the fast (default) or ``full`` form, the base scene first (as the ``base``
    axis, or ``paper`` for the paper's frame: free rocking from 0.5 alpha and the A = 2.5,
    W = 3 pulse).

    ``scene``: the base (a name, a TOML path or a Scene; default the paper's asymmetric frame,
    whose device axes start from the paper's hybrid frame). A user's scene is its own base;
    the device axes start from ``hybrid`` (default: the scene itself when it has tendons and
    dampers, else they do not run), the frame axes run only on a frame; asking for an axis the
    scene cannot have is an error."""
    from ..scene.scene import load_scene

    if scene is None or (scene == _BASE and hybrid in (None, _HYBRID)):
        scene, base, hybrid, label = None, _BASE, _HYBRID, "paper"
    else:
        sc = load_scene(scene)
        hybrid = hybrid if hybrid is not None else (scene if sc.has_devices else None)
        base, label = scene, "base"
        frame = hasattr(sc.structure, "column_height_left")
    names = list(AXES) if axes is None else list(axes)
    for a in names:
        if a not in AXES:
            raise ParameterError("axes", a, f"axis names: {', '.join(AXES)}")
    if scene is not None:
        unusable = [a for a in names if (a in _DEVICE_AXES and hybrid is None)
                    or (a in _FRAME_AXES and not frame)]
        if axes is not None and unusable:
            raise ParameterError("axes", ",".join(unusable),
                                 "axes the scene has (tendon, damper: scenes with devices; "
                                 "mass_ratio, H1/H: frames)")
        names = [a for a in names if a not in unusable]
    pts = [StressPoint(label, 0.0, base, (), None, 0.5),
           StressPoint(label, 1.0, base, (), tuple(sorted({**_PULSE, "A": 2.5,
                                                             "W": 3.0}.items())))]
    for a in names:
        for v in AXES[a][2 if full else 1]:
            pts.append(_point(a, float(v), base, hybrid))
    return pts


def synthetic_record(length: float, structure, pga_over_uplift: float = 2.0, seed: int = 13):
    """A deterministic synthetic accelerogram of ``length`` [s] (dt 0.01 s): band-limited noise
    (0.5-5 Hz) under a 2 s rise, flat strong phase to 40 % of the length and exponential decay,
    scaled to a PGA of ``pga_over_uplift`` x g tan(alpha) (alpha of the taller column)."""
    from ..constants import G
    from ..scene.motion import Record

    dt = 0.01
    n = int(round(length / dt)) + 1
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    spec = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, dt)
    spec[(f < 0.5) | (f > 5.0)] = 0.0
    a = np.fft.irfft(spec, n)
    t_strong = 0.4 * length
    env = np.where(t < 2.0, t / 2.0, np.where(t < t_strong, 1.0,
                                              np.exp(-(t - t_strong) / (0.1 * length))))
    a = a * env
    a *= pga_over_uplift * G * math.tan(structure.alpha) / np.max(np.abs(a))
    return Record(t, a, name=f"synthetic-{length:g}s", source="rockbench.studies.robustness")


def _load(pt: StressPoint):
    """(scene, motion, duration) of a point; raises for an invalid scene."""
    from ..scene.motion import motion_from_spec
    from ..scene.scene import load_scene
    from .validation import _free_duration

    scene = load_scene(pt.scene, dict(pt.overrides) or None)
    fall = min(4.0 * scene.alpha, min(scene.fall_angles.values()))
    scene = scene.replace(fall_angle=fall)
    if pt.motion is None:
        phi0 = pt.phi0 * scene.alpha
        return scene, None, min(10.0, _free_duration(scene, phi0)), phi0
    if pt.motion[0] == "record":
        rec = synthetic_record(float(pt.motion[1]), scene.structure)
        return scene, rec, pt.duration, 0.0
    spec = dict(pt.motion)
    if spec.get("A", 0.0) > 100.0:
        # beyond the A limit of rockbench.limits (a guard against input mistakes): the same
        # pulse given by its amplitude a_g = A g tan(alpha) [m/s^2] and period 2 pi / (W p) [s]
        from ..constants import G
        A, W = spec.pop("A"), spec.pop("W")
        spec.update(amplitude=A * G * math.tan(scene.alpha), period=2 * math.pi / (W * scene.p))
    motion = motion_from_spec(spec, scene.structure)
    dur = pt.duration or (max(2.5, 2 * motion.period) + 3 * motion.period)
    return scene, motion, dur, 0.0


# =========================================================================================
# Rows
# =========================================================================================
#: Columns of :attr:`Stress.table`.
STRESS_COLUMNS: dict[str, str] = {
    "engine": "-, backend name",
    "axis": "-, what changes (AXES; 'paper' / 'base': the base scene itself)",
    "value": "-, the axis value (unit in AXES)",
    "status": "-, the run's status (ok | diverged | invalid; invalid also for an exception)",
    "reason": "-, why not ok, or the exception",
    "class": "-, within 1% | within 5% | off | diverged | invalid | outside model",
    "engine_class": "-, the class from this engine's run alone (before the validity check)",
    "error": "-, relative error against the analytic reference (see the module docstring)",
    "flags": "-, checks an ok run fails: sliding, energy gained, eta not measured, a verdict "
             "that differs from the analytic one",
    "model_validity": "-, inside | outside (why) the analytic model's validity at this point",
    "peak_rel_error": "-, max|phi| / max|phi_ref| - 1",
    "eta_ratio_max": "-, largest measured eta / analytic eta over the run's impacts",
    "overturned": "-, the run overturned", "overturned_ref": "-, the reference overturned",
    "t_overturn_error": "s, t_overturn - t_overturn_ref",
    "max_sliding": "m, largest contact slip", "contact_opened": "-, a contact the model keeps "
                                                                "closed opened",
    "ref_status": "-, status of the analytic reference run",
    "cpu_s": "s, process CPU time of the engine run",
    "sim_time": "s, simulated time of the engine run",
}


def _row(engine: str, pt: StressPoint) -> dict[str, Any]:
    row = {c: math.nan for c in STRESS_COLUMNS}
    row.update(engine=engine, axis=pt.axis, value=pt.value, status="invalid", reason="",
               flags="", model_validity="", overturned=None, overturned_ref=None,
               contact_opened=None, ref_status="")
    return row


def run_point(item: tuple[str, StressPoint]) -> dict[str, Any]:
    """Run one engine on one point against the analytic reference; never raises."""
    import time

    from ..comparison import TOLERANCES, metrics
    from ..runner import run

    engine, pt = item
    row = _row(engine, pt)
    try:
        scene, motion, dur, phi0 = _load(pt)
        from ..validity import motion_validity
        row["model_validity"] = motion_validity(scene, motion).reason   # the one rule
        ref = run(scene, motion, engine="analytic", duration=dur, phi0=phi0)
        row["ref_status"] = ref.status
        c0 = time.process_time()
        from .tradeoff import Setting, _run_overrides
        over = _run_overrides(Setting(engine, tuple(pt.settings)))
        res = run(scene, motion, engine=engine, duration=dur, phi0=phi0, **over)
        row["cpu_s"] = time.process_time() - c0
        row["sim_time"] = float(res.cost.sim_time)
    except Exception as e:  # an invalid scene, setting or an engine failure: a row, not a crash
        row.update(status="invalid", reason=f"{type(e).__name__}: {e}", error=math.inf)
        row["engine_class"] = row["class"] = "invalid"
        return row
    m = metrics(res, ref)
    row.update(status=res.status, reason=res.summary.reason or "")
    for k in ("peak_rel_error", "overturned", "overturned_ref", "t_overturn_error",
              "max_sliding", "contact_opened"):
        row[k] = m.get(k)
    from ..analytic.reference import reference_of
    eta_ref = reference_of(scene).eta
    imp = res.impacts()
    ratios = [float(e) / float(eta_ref[int(d)]) for e, d in zip(imp["eta"], imp["direction"])
              if int(d) in eta_ref and np.isfinite(e)]
    row["eta_ratio_max"] = max(ratios) if ratios else math.nan
    if not res.ok:
        row["error"] = math.inf
        row["engine_class"] = row["class"] = classify_error(math.inf, res.status)
        return row
    if not ref.ok:
        row.update(error=math.nan, reason=f"reference {ref.status}: {ref.summary.reason}")
        row["engine_class"] = row["class"] = "invalid"
        return row
    flags = []
    invalid = False
    n_ref_imp = int(ref.summary.n_impacts)
    if n_ref_imp and len(imp) and not ratios:
        flags.append("no finite eta measured (output_dt too coarse?)")
        invalid = True
    slide_bar = TOLERANCES["contacts"]["max_sliding"]
    if math.isfinite(m["max_sliding"]) and m["max_sliding"] > slide_bar:
        flags.append(f"sliding {1e3 * m['max_sliding']:.3g} mm > {1e3 * slide_bar:g} mm")
    if motion is None and bool(m.get("energy_gained_at_impact")):
        flags.append("energy gained at an impact")
    period = float(getattr(motion, "period", 1.0)) if motion is not None else 1.0
    if not bool(m["verdict_agrees"]):                # the error is the verdict, said in words
        flags.append("overturns where the analytic model survives" if bool(m["overturned"])
                     else "survives where the analytic model overturns")
    if bool(m["overturned_ref"]):
        if not bool(m["verdict_agrees"]):
            err = math.inf
        else:
            err = abs(float(m["t_overturn_error"])) / period
    elif motion is None:
        err = float(m["eta_max_rel_error"]) if math.isfinite(m["eta_max_rel_error"]) else (
            math.inf if invalid else 0.0)
    else:
        if not bool(m["verdict_agrees"]):
            err = math.inf
        else:
            err = abs(float(m["peak_rel_error"]))
            if not math.isfinite(err) or ref.summary.max_abs_phi_over_alpha < 0.05:
                err = float(m["max_abs_error_over_alpha"])
    row["error"] = err
    row["flags"] = "; ".join(flags)
    cls = classify_error(err, "ok")
    if invalid:
        cls = "invalid"
    elif flags and cls in ("within 1%", "within 5%"):
        cls = "off"
    row["engine_class"] = row["class"] = cls
    return row


def _crashed(item, reason: str) -> dict[str, Any]:
    engine, pt = item
    row = _row(engine, pt)
    row.update(reason=reason, error=math.inf)
    row["engine_class"] = row["class"] = "invalid"
    return row


def _validity(df: pd.DataFrame) -> pd.DataFrame:
    """Mark the points outside the model's validity: a motion whose peak ground acceleration
    exceeds the base friction (:func:`rockbench.validity.motion_validity`, the one rule), or
    where most engines' impacts rebound."""
    df = df.copy()
    for (axis, value), g in df.groupby(["axis", "value"], sort=False):
        apriori = g["model_validity"].fillna("").astype(str)
        apriori = apriori[apriori.str.startswith("outside")]
        if len(apriori):       # the motion asks the base for more friction than it has
            df.loc[g.index, "model_validity"] = apriori.iloc[0]
            df.loc[g.index, "class"] = "outside model"
            continue
        ok = g[g["status"] == "ok"]
        reb = ok[(ok["contact_opened"].fillna(False).astype(bool))
                 & (ok["eta_ratio_max"].astype(float) > 1 + _REBOUND)]
        if len(ok) and 2 * len(reb) > len(ok):
            why = (f"outside: impacts rebound in {len(reb)} of {len(ok)} engines (effective "
                   f"eta up to {reb['eta_ratio_max'].max():.2f} x the analytic, contacts open)")
            df.loc[g.index, "model_validity"] = why
            df.loc[g.index, "class"] = "outside model"
        else:
            df.loc[g.index, "model_validity"] = "inside"
    return df


def structure_refusal(pt: StressPoint) -> str | None:
    """Why the structure of ``pt`` (its base scene with the point's overrides) is not one the
    model accepts (the ParameterError or SceneError of loading it), or None when it is one.
    Such a point says nothing about an engine: e.g. the alpha axis's 0.6 rad asks a frame for
    columns wider than its span."""
    from ..errors import SceneError
    from ..scene.scene import load_scene

    try:
        load_scene(pt.scene, dict(pt.overrides) or None)
    except (ParameterError, SceneError) as e:
        return f"{type(e).__name__}: {e}"
    return None


@dataclass
class Stress:
    """The stress sweep: ``table`` (one row per engine and point, :data:`STRESS_COLUMNS`),
    ``full`` (which form), ``unavailable`` (engine -> why), ``scene`` (the base scene: None for
    the paper's frame), ``skipped`` (point label -> why its structure is refused: not run,
    :func:`structure_refusal`)."""

    table: pd.DataFrame
    full: bool = False
    unavailable: dict[str, str] = field(default_factory=dict)
    scene: Any = None
    skipped: dict[str, str] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        from ..result import jsonable

        recs = self.table.astype(object).where(self.table.notna(), None).to_dict("records")
        return jsonable({"full": self.full, "unavailable": self.unavailable,
                          "axes": {k: v[0] for k, v in AXES.items()},
                          "base_values": base_values(self.scene), "skipped": self.skipped,
                          "breaking_points": breaking_points(self.table,
                                                            self.scene).to_dict("records"),
                          "rows": recs, "columns": STRESS_COLUMNS})


def stress(engines: Sequence[str] | None = None, *, full: bool = False,
           axes: Sequence[str] | None = None, points: Sequence[StressPoint] | None = None,
           executor: str = "process", workers: int | None = None,
           progress: bool = False, scene: Any = None, hybrid: Any = None) -> Stress:
    """Run every point (:func:`stress_points` from ``scene``, default the paper's frame; or
    ``points``) with every engine (default: the available engines) through the one executor;
    return a :class:`Stress`."""
    from ..engines import get_backend
    from ..runner import REFERENCE, resolve_engines
    from ..sweep.executors import execute

    names = [n for n in resolve_engines(engines) if n != REFERENCE]
    unavailable = {}
    usable = []
    for n in names:
        ok, why = get_backend(n).available()
        (usable.append(n) if ok else unavailable.__setitem__(n, why))
    pts = (list(points) if points is not None
           else stress_points(full, axes, scene=scene, hybrid=hybrid))
    skipped = {}
    for p in pts:
        why = structure_refusal(p)
        if why is not None:
            skipped[p.label] = why
    pts = [p for p in pts if p.label not in skipped]
    items = [(f"{i}", (n, p)) for i, (n, p) in enumerate((n, p) for p in pts for n in usable)]
    rows: dict[str, dict] = {}
    execute(run_point, items, on_result=lambda k, r: rows.__setitem__(k, r), crashed=_crashed,
            label=lambda it: f"{it[0]} {it[1].label}",
            is_error=lambda r: r["class"] in ("diverged", "invalid"), executor=executor,
            workers=workers, progress=progress, desc="stress", unit="run")
    df = pd.DataFrame([rows[k] for k, _ in items], columns=list(STRESS_COLUMNS))
    return Stress(table=_validity(df), full=full, unavailable=unavailable, scene=scene,
                  skipped=skipped)


def breaking_points(table: pd.DataFrame, scene: Any = None) -> pd.DataFrame:
    """Per engine and axis, the first value, going away from the base scene (``scene``; default
    the paper's frame) on either side, whose class is off, diverged or invalid (columns engine,
    axis, side ("below" / "above" the base value), value, unit (the axis's, :func:`axis_label`),
    class, reason); points outside the model's validity are skipped."""
    bad = ("off", "diverged", "invalid")
    values = PAPER_VALUES if scene in (None, _BASE) else base_values(scene)
    out = []
    for (eng, axis), g in table.groupby(["engine", "axis"], sort=False):
        if axis in ("paper", "base"):
            continue
        p = values.get(axis, math.nan)
        g = g.sort_values("value")
        for side, sub in (("below", g[g["value"] < p].iloc[::-1]), ("above", g[g["value"] > p])
                          ) if math.isfinite(p) else (("all", g),):
            for _, r in sub.iterrows():
                if r["class"] in bad:
                    unit = axis_label(axis).partition(" [")[2].rstrip("]")
                    out.append({"engine": eng, "axis": axis, "side": side,
                                "value": float(r["value"]), "unit": unit,
                                "class": r["class"],
                                "reason": r["reason"] or r["flags"] or
                                f"error {r['error']:.3g}"})
                    break
    return pd.DataFrame(out, columns=["engine", "axis", "side", "value", "unit", "class",
                                      "reason"])

"""The one result schema every backend fills.

A :class:`Result` holds

* ``history`` - a pandas frame sampled at a fixed output interval, columns :data:`HISTORY_COLUMNS`
  (engines add :data:`CONTACT_COLUMNS`);
* ``events`` - a pandas frame, one row per event, columns :data:`EVENT_COLUMNS`;
* ``summary`` - a :class:`Summary` (peak, verdicts, counts, status);
* ``cost`` - a :class:`Cost` (wall seconds of the integration or stepping only, steps, calls);
* the scene, the ground motion description and the backend settings used.

Units: SI and radians throughout (see ``docs/conventions.md``). ``phi`` is the rotation of the
left (taller) column from rest, positive counterclockwise.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from typing import Any, Mapping

import numpy as np
import pandas as pd

__all__ = ["Result", "Summary", "Cost", "HISTORY_COLUMNS", "CONTACT_COLUMNS", "EVENT_COLUMNS",
           "SUMMARY_FIELDS", "COST_FIELDS", "EVENT_KINDS", "STATUSES", "output_grid",
           "motion_label", "as_float"]

#: History columns and units, in order.
HISTORY_COLUMNS: dict[str, str] = {
    "t": "s, time",
    "phi": "rad, rotation of the left (taller) column from rest, + counterclockwise",
    "phidot": "rad/s, d(phi)/dt",
    "ground_acc": "m/s^2, horizontal ground acceleration, + to the right",
    "theta_beam": "rad, rotation of the beam from rest (NaN for a block)",
    "theta_right": "rad, rotation of the right column from rest (NaN for a block)",
    "mode": "-, +1 rocking counterclockwise, -1 clockwise, 0 at rest (engines: sign of phi "
            "when uplifted)",
    "devices_intact": "-, True while tendons and dampers are in place",
    "tendon_elong_left": "m, elongation of the left tendon (0 without tendons)",
    "tendon_elong_right": "m, elongation of the right tendon",
    "tendon_force_left": "N, tension in the left tendon",
    "tendon_force_right": "N, tension in the right tendon",
    "damper_force_left": "N, force in the left damper (+ resisting opening)",
    "damper_force_right": "N, force in the right damper",
}

#: Extra history columns that engine backends fill (NaN for the analytic backend).
CONTACT_COLUMNS: dict[str, str] = {
    "penetration": "m, largest penetration at any contact",
    "sliding": "m, largest tangential slip of any contact point since it was established",
}

#: Event columns and units.
EVENT_COLUMNS: dict[str, str] = {
    "t": "s, time of the event",
    "kind": "-, one of EVENT_KINDS",
    "phi": "rad, phi at the event",
    "phidot_before": "rad/s, angular velocity just before",
    "phidot_after": "rad/s, angular velocity just after",
    "eta": "-, coefficient of restitution applied (analytic) or measured (engines); NaN otherwise",
    "direction": "-, +1/-1 rocking direction after the event (0: at rest)",
}

#: Summary fields: unit and meaning (what ``Summary.to_frame()`` and the notebook view show).
SUMMARY_FIELDS: dict[str, str] = {
    "max_abs_phi": "rad, largest |phi| over the run",
    "max_abs_phi_over_alpha": "-, max |phi| / alpha (alpha of the taller column)",
    "overturned": "-, the structure fell (|phi| reached the fall angle, or came to rest beyond "
                  "its critical angle)",
    "t_overturn": "s, time of the fall",
    "exceeded_critical": "-, |phi| exceeded the critical angle of the current potential",
    "uplifted": "-, the structure left its rest position",
    "t_uplift": "s, first uplift",
    "n_impacts": "-, number of impacts",
    "fractured": "-, tendons/dampers fractured",
    "t_fracture": "s, time of the fracture",
    "status": "-, ok | diverged | invalid",
    "reason": "-, why a run is not ok",
    "eta_measured": "-, effective coefficient of restitution per impact (engines)",
    "max_penetration": "m, largest penetration at any contact (engines)",
    "max_sliding": "m, largest tangential slip of a contact point (engines)",
    "contact_opened": "-, a contact the analytic model keeps closed opened (engines)",
    "sliding_onset": "s, first time a contact of the analytic model needs more friction than "
                     "the scene's (|T| / N > mu; None when never; analytic)",
    "sliding_contact": "-, the contact that needs it first: base (the pivots on the ground) or "
                       "beam (the beam on its columns); None when none (analytic)",
    "t_lift_off": "s, first time the ground falls faster than gravity (g + a_v <= 0): the "
                  "structure leaves the ground and the analytic run stops; None when never",
    "validity": "-, inside | outside the model from t = ... s and why (the analytic model's own "
                "check, rockbench.validity.run_validity; None: not assessed)",
}

#: Cost fields: unit and meaning.
COST_FIELDS: dict[str, str] = {
    "cpu_s": "s, process CPU time of the whole run (building included), without the one-off "
             "loading or compiling of numba kernels (compile_cpu_s)",
    "compile_cpu_s": "s, process CPU time of loading or compiling numba kernels during the run "
                     "(the first run of a kind in a process; 0 afterwards)",
    "wall_s": "s, wall time of the integration or stepping only",
    "sim_time": "s, simulated time",
    "steps": "-, integrator or engine steps",
    "rhs_calls": "-, right-hand-side evaluations (analytic)",
    "cpu_real_time_factor": "-, simulated s per CPU s of the whole run",
    "real_time_factor": "-, simulated s per wall s of the stepping",
}

EVENT_KINDS = ("uplift", "impact", "peak", "critical", "fracture", "overturn", "rest")
STATUSES = ("ok", "diverged", "invalid")


def as_float(x: Any) -> float:
    """``x`` as a float; NaN when it is missing (None, NA) or not a number (the one reader of
    optional numbers in result rows and tables)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def jsonable(x: Any) -> Any:
    """``x`` in plain JSON types (the one converter of results, tables and CLI output):
    mappings with string keys, lists, bool, int, float, str, None; non-finite floats, pandas'
    NA and NaT become null, paths and other objects their text."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if x is None or isinstance(x, str):
        return x
    import sys
    pd = sys.modules.get("pandas")                # NA / NaT only exist if pandas is loaded
    if pd is not None and (x is pd.NA or x is pd.NaT):
        return None
    return str(x)


@dataclass
class Summary:
    """Scalar outcome of one run (units in the field comments)."""

    max_abs_phi: float                 # rad, max |phi| over the run
    max_abs_phi_over_alpha: float      # -, max |phi| / alpha (alpha of the taller column)
    overturned: bool                   # |phi| reached the fall angle, or an engine's structure
    #                                    ended the run at rest beyond its critical angle (collapsed)
    t_overturn: float | None           # s
    exceeded_critical: bool            # |phi| exceeded the critical angle of the current potential
    uplifted: bool
    t_uplift: float | None             # s, first uplift
    n_impacts: int
    fractured: bool
    t_fracture: float | None           # s
    status: str = "ok"                 # ok | diverged | invalid
    reason: str | None = None          # why a run is not ok
    eta_measured: list[float] = field(default_factory=list)  # engines: effective eta per impact
    max_penetration: float | None = None  # m (engines)
    max_sliding: float | None = None      # m (engines)
    contact_opened: bool | None = None    # engines: a contact the analytic model keeps closed opened
    sliding_onset: float | None = None    # s (analytic): first friction demand above mu
    sliding_contact: str | None = None    # "base" | "beam" (analytic)
    t_lift_off: float | None = None       # s: g + a_v <= 0 from here (analytic run stops)
    validity: str | None = None           # "inside" | "outside the model from t = ...: why"

    @property
    def t_outside(self) -> float | None:
        """The time [s] from which the run is outside the model (the earlier of
        :attr:`sliding_onset` and :attr:`t_lift_off`), None when it stays inside: comparisons
        with the rocking model hold up to it."""
        ts = [t for t in (self.sliding_onset, self.t_lift_off)
              if t is not None and math.isfinite(t)]
        return min(ts) if ts else None

    def to_dict(self) -> dict[str, Any]:
        return jsonable(asdict(self))

    def to_frame(self) -> pd.DataFrame:
        """The summary as a frame indexed by field, with columns ``value``, ``unit`` and
        ``meaning`` (:data:`SUMMARY_FIELDS`); ``eta_measured`` is shown as its count, mean, min
        and max."""
        rows = []
        for name, text in SUMMARY_FIELDS.items():
            unit, meaning = text.split(", ", 1)
            value = getattr(self, name)
            if name == "eta_measured":
                v = np.asarray(value, dtype=float)
                value = (f"{v.size} impacts, mean {v.mean():.4f} "
                         f"({v.min():.4f} .. {v.max():.4f})" if v.size else "none measured")
            rows.append((name, value, unit, meaning))
        return _field_frame(rows)

    def _repr_html_(self) -> str:
        return _fields_table(self.to_frame())

    def __str__(self) -> str:
        return _short_summary(self)


def _short_summary(s: "Summary") -> str:
    verdict = (f"overturned at t = {s.t_overturn:.3f} s" if s.overturned and s.t_overturn
               is not None else "overturned" if s.overturned else "survived")
    if s.status != "ok" and not s.overturned:
        verdict = "no verdict of its own"    # the reason says what is known (docs/errors.md)
    text = (f"{s.status}, max|phi|/alpha = {s.max_abs_phi_over_alpha:.4g}, {verdict}, "
            f"{s.n_impacts} impacts")
    if s.fractured:
        text += ", fractured" + (f" at t = {s.t_fracture:.3f} s" if s.t_fracture is not None
                                 else "")
    if s.status != "ok" and s.reason:
        text += f" ({s.reason})"
    if s.validity and s.validity.startswith("outside"):
        text += f"; {s.validity}"
    return text


def _field_frame(rows: list[tuple[str, Any, str, str]]) -> pd.DataFrame:
    """(field, value, unit, meaning) rows -> a frame indexed by field; values keep their types."""
    names, values, units, meanings = zip(*rows)
    index = pd.Index(names, name="field")
    return pd.DataFrame({"value": pd.Series(list(values), index=index, dtype=object),
                         "unit": list(units), "meaning": list(meanings)}, index=index)


def _fields_table(frame: pd.DataFrame) -> str:
    """An HTML table of a field/value/unit/meaning frame (the notebook view)."""
    def cell(v: Any) -> str:
        if isinstance(v, (float, np.floating)):
            return "" if not math.isfinite(float(v)) else f"{float(v):.6g}"
        return "" if v is None else str(v)

    import html as _html
    rows = "".join(
        f"<tr><th style='text-align:left'>{_html.escape(str(i))}</th>"
        f"<td style='text-align:right'>{_html.escape(cell(r['value']))}</td>"
        f"<td>{_html.escape(str(r['unit']))}</td>"
        f"<td style='text-align:left'>{_html.escape(str(r['meaning']))}</td></tr>"
        for i, r in frame.iterrows())
    return ("<table><thead><tr><th>field</th><th>value</th><th>unit</th><th>meaning</th>"
            f"</tr></thead><tbody>{rows}</tbody></table>")


@dataclass
class Cost:
    """What a run cost. ``wall_s`` counts the integration or stepping only, not model building;
    ``cpu_s`` the process CPU time of the whole run (building, stepping, measuring), which
    another process's load does not inflate: rankings use it. The one-off loading or compiling
    of numba kernels (a process's first run of a kind) is ``compile_cpu_s``, not in ``cpu_s``
    (:class:`rockbench._jit.CpuClock`)."""

    wall_s: float          # s
    sim_time: float        # s of simulated time
    steps: int             # integrator or engine steps
    rhs_calls: int = 0     # right-hand-side evaluations (analytic)
    cpu_s: float = math.nan  # s, process CPU time of the whole run (building included)
    compile_cpu_s: float = 0.0  # s, one-off loading/compiling of numba kernels, not in cpu_s

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall second [-]."""
        return self.sim_time / self.wall_s if self.wall_s > 0 else math.inf

    @property
    def cpu_real_time_factor(self) -> float:
        """Simulated seconds per CPU second of the whole run [-] (NaN if not measured)."""
        return self.sim_time / self.cpu_s if self.cpu_s > 0 else math.nan

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["real_time_factor"] = self.real_time_factor
        d["cpu_real_time_factor"] = self.cpu_real_time_factor
        return jsonable(d)

    def to_frame(self) -> pd.DataFrame:
        """The cost as a frame indexed by field, with ``value``, ``unit``, ``meaning``
        (:data:`COST_FIELDS`)."""
        d = {**asdict(self), "real_time_factor": self.real_time_factor,
             "cpu_real_time_factor": self.cpu_real_time_factor}
        return _field_frame([(k, d[k], *t.split(", ", 1)) for k, t in COST_FIELDS.items()])

    def _repr_html_(self) -> str:
        return _fields_table(self.to_frame())


@dataclass
class Result:
    """Outcome of one backend run. See the module docstring for the schema."""

    backend: str
    scene: Any
    motion: dict[str, Any]
    history: pd.DataFrame
    events: pd.DataFrame
    summary: Summary
    cost: Cost
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def status(self) -> str:
        return self.summary.status

    @property
    def ok(self) -> bool:
        return self.summary.status == "ok"

    def impacts(self) -> pd.DataFrame:
        """The impact events."""
        return self.events[self.events["kind"] == "impact"].reset_index(drop=True)

    def to_json(self) -> dict[str, Any]:
        """JSON-safe summary + cost + identification (no history)."""
        d = {"backend": self.backend, "scene": getattr(self.scene, "name", None)}
        d.update(self.summary.to_dict())
        d.update(self.cost.to_dict())
        d["motion"] = jsonable(self.motion)
        d["settings"] = jsonable(self.settings)
        return d

    def dumps(self) -> str:
        return json.dumps(self.to_json(), indent=2)

    def label(self) -> str:
        """``backend on 'scene' (motion)``: who ran what."""
        return (f"{self.backend} on {getattr(self.scene, 'name', None) or 'scene'!r} "
                f"({motion_label(self.motion)})")

    def __repr__(self) -> str:
        cpu = self.cost.cpu_s
        cost = f", {cpu:.3g} CPU s" if cpu == cpu else ""
        return f"<Result {self.label()}: {_short_summary(self.summary)}{cost}>"

    def _repr_html_(self) -> str:
        """The notebook view: who ran what, the summary and the cost, with units."""
        import html as _html
        return (f"<div><p><b>{_html.escape(self.label())}</b>: "
                f"{_html.escape(_short_summary(self.summary))}</p>"
                f"<details open><summary>summary</summary>{self.summary._repr_html_()}</details>"
                f"<details><summary>cost</summary>{self.cost._repr_html_()}</details>"
                f"<p>history: {len(self.history)} samples x {self.history.shape[1]} columns "
                f"(<code>result.history</code>); events: {len(self.events)} rows "
                "(<code>result.events</code>)</p></div>")


def empty_events() -> pd.DataFrame:
    """An events frame with the schema's columns and no rows."""
    return pd.DataFrame({c: pd.Series(dtype="float64") for c in EVENT_COLUMNS}).astype(
        {"kind": "object", "direction": "int64"})


def events_frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    """Build an events frame from a list of row dicts (missing fields -> NaN)."""
    if not rows:
        return empty_events()
    df = pd.DataFrame(rows)
    for c in EVENT_COLUMNS:
        if c not in df:
            df[c] = np.nan
    df["direction"] = df["direction"].fillna(0).astype("int64")
    return df[list(EVENT_COLUMNS)]


def output_grid(t0: float, t_end: float, output_dt: float) -> np.ndarray:
    """The output times [s]: t0 + k output_dt up to t_end, and t_end itself when it is not on
    that grid (the analytic backend's grid, so that histories align sample by sample)."""
    n = int(math.floor((t_end - t0) / output_dt + 1e-9)) + 1
    tg = t0 + output_dt * np.arange(n)
    if tg[-1] < t_end - 1e-12:
        tg = np.append(tg, t_end)
    return tg


def _g4(x: Any) -> str:
    try:
        return f"{float(x):.4g}"
    except (TypeError, ValueError):
        return str(x)


def motion_label(motion: Mapping[str, Any] | None, *, long: bool = False) -> str:
    """The one human label of a ground motion, from ``GroundMotion.describe()`` (what a
    :class:`Result` keeps in ``motion``) or from a case's motion spec
    (:func:`rockbench.scene.motion.motion_from_spec`); None or ``{"kind": "none"}`` is free
    rocking.

    Short (default): ``"symm+ A=3 W=4"``, ``"anti- a=2.1 m/s2 T=0.8 s"``, ``"LA21 x-1"``,
    ``"free rocking"``. Long: ``"symmetric Ricker pulse, sign +1, A = 3, W = 4 (a_g = 4.2 m/s^2,
    T_g = 1.09 s)"``, ``"record LA21 (scale -1)"``. A and W are a_g / (g tan alpha) and
    omega_g / p; a_g in m/s^2, T_g in s. A vertical component adds ``" V=0.5"`` (short) or
    ``", vertical part 0.5 x horizontal"`` (long) to a pulse, and its channel's name to a
    record (``"TCU052-N & TCU052-V"``, ``"record TCU052-N with vertical TCU052-V"``); any
    other vertical motion (:class:`~rockbench.scene.motion.WithVertical`, whose description
    nests it under ``vertical``) its own label (``"still & vertical symm+ a=5.9 m/s2 T=0.3 s"``).
    """
    m = dict(motion or {"kind": "none"})
    kind = m.get("kind", "none")
    if kind == "none":
        return "free rocking"
    if isinstance(m.get("vertical"), Mapping):     # a WithVertical: any two motions
        v = motion_label(m.pop("vertical"), long=long)
        return (motion_label(m, long=long)
                + (f", with vertical {v}" if long else f" & vertical {v}"))
    if kind == "ricker":
        shape, sign = str(m.get("shape", "symmetric")), int(m.get("sign", 1))
        amp = m.get("amplitude_m_s2", m.get("amplitude"))
        per = m.get("period_s", m.get("period"))
        vr = as_float(m.get("vertical_ratio", 0.0))
        vr = vr if math.isfinite(vr) and vr > 0.0 else 0.0
        if not long:
            vert = f" V={vr:g}" if vr else ""
            if "A" in m and "W" in m:
                return f"{shape[:4]}{'+' if sign > 0 else '-'} A={m['A']:g} W={m['W']:g}{vert}"
            return (f"{shape[:4]}{'+' if sign > 0 else '-'} a={_g4(amp)} m/s2 T={_g4(per)} s"
                    f"{vert}")
        text = f"{shape} Ricker pulse, sign {sign:+d}"
        if "A" in m and "W" in m:
            text += f", A = {m['A']:g}, W = {m['W']:g}"
        if amp is not None and per is not None:
            text += f" (a_g = {_g4(amp)} m/s^2, T_g = {_g4(per)} s)"
        if vr:
            text += f", vertical part {vr:g} x horizontal"
        return text
    if kind == "record":
        name = m.get("name") or (str(m.get("path", "")).replace("\\", "/").rsplit("/", 1)[-1]
                                 .rsplit(".", 1)[0]) or "record"
        scale = float(m.get("scale", 1.0) or 1.0)
        vname = m.get("vertical_name") or (
            str(m.get("vertical_path", "")).replace("\\", "/").rsplit("/", 1)[-1]
            .rsplit(".", 1)[0])
        if long:
            return (f"record {name}" + (f" with vertical {vname}" if vname else "")
                    + (f" (scale {scale:g})" if scale != 1.0 else ""))
        return name + (f" & {vname}" if vname else "") + (f" x{scale:g}" if scale != 1.0 else "")
    return str(kind)

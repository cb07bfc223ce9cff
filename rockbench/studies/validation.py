"""The evidence of a scene: the runs every setting of every engine is measured on
(``rockbench tradeoff``, ``rockbench advise``; ``docs/choosing.md``), drawn from that scene with
the analytic model, and split into a **choice** part and a **held-out** part.

:func:`validation_set` builds it from :func:`candidate_cases` (the whole catalogue of a scene):

* free rocking from phi0 = +-0.1, +-0.3 and +-0.7 alpha, each to between the peak after the
  third impact and the fourth impact;
* Ricker pulse cells over the scene's A-W plane: W in :data:`W_GRID`, both shapes and both
  signs; per pulse the analytic overturning threshold A_ov (:func:`overturn_threshold`) and the
  uplift threshold A_up = min|lambda| / tan(alpha); cells *away* from the boundary at
  A = A_up + f (A_ov - A_up), f in :data:`AWAY_LEVELS` (0.2: a small uplift), cells *near* the
  boundary at A = :data:`NEAR_LEVELS` x A_ov (within :data:`NEAR_MARGIN` of it, on both sides)
  and overturning cells at :data:`OVER_LEVEL` x A_ov. Cells whose analytic peak stays below
  :data:`MIN_PEAK` alpha are left out (and the next in order taken);
* the bundled records (``rockbench/records``), both polarities, scaled to
  :data:`RECORD_FACTORS` x the scene's uplift PGA (g min|lambda|), 15 s from their start: long
  phases of small uplift, where soft contacts swallow small rockings (a record whose analytic
  peak stays below :data:`MIN_PEAK` alpha is left out).

Every case lies within the analytic model: its pivots never slide. A case outside it by the
one validity rule (:func:`rockbench.validity.motion_validity`: a peak ground acceleration beyond
mu g, where a base slides under the ground's own acceleration whatever it rocks) is never
evidence: it is left out like a case below MIN_PEAK, and the next in order taken. A squat
structure that needs more than mu g to overturn has no overturning cases in its evidence.

Every case is labelled by its own conditioning, whatever its kind:

* **near the boundary** (``near_boundary``): a pulse cell within :data:`NEAR_MARGIN` of the
  analytic overturning threshold, or any pulse or record whose analytic verdict flips within
  its own sensitivity band (:func:`rockbench.studies.sensitivity.band`: eta, pivots and the
  motion perturbed by what no one can claim to know better). Its verdict is reported, never
  counted: it would decide nothing about an engine;
* **the measure** (``measure``) that is well-conditioned for it: free rocking of a structure
  without devices is judged by eta of each impact; free rocking *with* devices by its history
  (the relative RMS of phi against the reference, over the initial amplitude), because the eta
  of a damped impact measures the damper's timing, not the engine; a surviving pulse by its
  peak; a record by the distance of its peak to the model's sensitivity band; an overturning
  case by its verdict.

On a mirror-symmetric structure (a block, or a frame with equal columns) a case and its
sign-flipped twin are the same physics: only the positive sign is kept
(:func:`rockbench.studies.map_cells.reversed_mirrors`, the one rule).

With a vertical ratio r (``validation_set(vertical=r)``, ``advise --vertical``) every pulse
and record of the evidence also moves the ground vertically, a_v = r times its horizontal
acceleration, in phase: the thresholds, the labels and the analytic reference are computed
with it, and both signs are kept (a vertical part turns with the pulse's sign: the reversed
pulse is no mirror image).

Every case has a *group* (free | away:<shape><sign> | near | overturn | record). Within a group
(the away cells of the four pulses together) the cases are put in a seeded, deterministic order
(sha256 of the seed and the case name); a set of size ``quick`` / ``default`` / ``full`` takes,
in that order, the first :data:`GROUP_SIZES` cases of each group (of each pulse, for the away
cells), so quick is a subset of default, which is a subset of full (the same cases, to the
digit); of the cases taken from a group, those at even places form the **choice** part, those
at odd places the **held-out** part (every part has cases of every group of two or more). Units: SI, radians; A = a_g / (g tan alpha),
W = omega_g / p. Everything is cached in memory per scene data.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
from dataclasses import dataclass, replace
from typing import Any

from ..constants import G
from ..errors import ParameterError
from ..run_length import run_length
from ..validity import motion_validity
from .map_agreement import NEAR_BOUNDARY_MARGIN

__all__ = ["ValidationCase", "validation_set", "candidate_cases", "overturn_threshold",
           "uplift_threshold", "SIZES", "GROUP_SIZES", "NEAR_MARGIN", "W_GRID", "SEED",
           "MEASURES"]

#: The measure of a case (``ValidationCase.measure``): what its error is.
MEASURES = {"eta": "largest |eta / eta_ref - 1| over the impacts (free rocking, no devices)",
            "history": "RMS of (phi - phi_ref) / alpha over the run, divided by |phi0| / alpha "
                       "(free rocking with devices)",
            "peak": "|max|phi| / max|phi_ref| - 1| (a surviving pulse)",
            "band": "relative distance of the peak to the analytic sensitivity band, 0 inside "
                    "(a record)",
            "verdict": "the overturning verdict (an overturning case: 0 when it agrees)"}

# The design (the analytic model chooses the cells; see the module docstring)
W_GRID = (1.5, 2.0, 3.0, 4.0, 6.0, 8.0)
_PULSES = (("symmetric", 1), ("symmetric", -1), ("antisymmetric", 1), ("antisymmetric", -1))
AWAY_LEVELS = (0.2, 0.5, 0.85)       # fraction of the way from A_up to A_ov
NEAR_LEVELS = (0.99, 1.01)           # x A_ov (within NEAR_MARGIN)
#: Cells whose A is within this relative distance of the analytic overturning threshold are
#: "near the boundary" (the maps' one margin, :data:`rockbench.studies.maps.NEAR_BOUNDARY_MARGIN`): a
#: verdict that differs from the reference there is reported, not counted as wrong.
NEAR_MARGIN = NEAR_BOUNDARY_MARGIN
OVER_LEVEL = 1.3                     # x A_ov
#: Cases whose analytic peak is below this [alpha] are left out: engines count |phi| below
#: about 1e-3 alpha as no uplift at all, and a relative peak error of a response of a few
#: thousandths of alpha measures the contact's compliance, not the rocking.
MIN_PEAK = 0.05
_FREE_PHI0 = (0.1, 0.3, 0.7)         # x alpha, both directions
RECORD_FACTORS = (1.3, 2.0, 3.0)     # x the uplift PGA g min|lambda|
_RECORD_DURATION = 15.0              # s from the record's start
#: Free rocking [s] after a pulse's strong part (run_length's window "strong": the runs of
#: the validation set are repeated at every time step of every engine, so they end early).
_AWAY_TAIL = 2.5
_OVER_TAIL = 8.0                     # s after it for near and overturning cells (finish a fall)
_FALL = 4.0                          # x alpha: fall angle of every pulse cell
_A_MAX = 30.0                        # no overturning below this A: the pulse is left out
#: Seed of the order of the cases within a group (the split and the subsets follow from it).
SEED = 24
#: Cases per group (per away group: per pulse shape and sign) of each size.
GROUP_SIZES: dict[str, dict[str, int]] = {
    "quick": {"free": 2, "away": 1, "near": 2, "overturn": 2, "record": 2},
    "default": {"free": 4, "away": 3, "near": 4, "overturn": 4, "record": 4},
    "full": {"free": 99, "away": 99, "near": 99, "overturn": 99, "record": 99},
}
SIZES = tuple(GROUP_SIZES)


# =========================================================================================
# The cases
# =========================================================================================
@dataclass(frozen=True)
class ValidationCase:
    """One run of the evidence (plain data: picklable, hashable, JSON-able).

    kind : "free" (free rocking from ``phi0``), "survive" (a Ricker pulse the analytic frame
        survives), "overturn" (one that overturns it) or "record" (a scaled record);
    name : short label, unique within a scene, e.g. ``"free+0.3"``, ``"symm+1 W=3 A=2.112"``;
    motion : a motion spec (:func:`rockbench.scene.motion.motion_from_spec`) or None;
    phi0 : initial rotation [rad]; duration : simulated time [s];
    fall : fall angle [rad] of the run (None: the scene's own);
    peak_ref : analytic max |phi| / alpha [-];
    group : the case's group (module docstring); part : "choice" or "held-out";
    near_boundary : A within :data:`NEAR_MARGIN` of the analytic overturning threshold, or
        the analytic verdict flips within the case's own sensitivity band;
    a_ratio : A / A_ov [-] of a pulse cell (NaN otherwise); rank : place in its group's order;
    measure : the well-conditioned measure of its error (:data:`MEASURES`);
    verdict_agreement : fraction of the sensitivity band's perturbed runs with the unperturbed
        verdict [-] (NaN: not computed, free rocking).
    """

    kind: str
    name: str
    motion: tuple | None
    phi0: float
    duration: float
    fall: float | None = None
    peak_ref: float = math.nan
    group: str = ""
    part: str = "choice"
    near_boundary: bool = False
    a_ratio: float = math.nan
    rank: int = 0
    measure: str = "peak"
    verdict_agreement: float = math.nan

    def motion_spec(self) -> dict[str, Any] | None:
        return None if self.motion is None else dict(self.motion)

    def load(self, scene):
        """(scene with this case's fall angle, GroundMotion or None)."""
        from ..scene.motion import motion_from_spec

        sc = scene if self.fall is None else scene.replace(fall_angle=self.fall)
        return sc, motion_from_spec(self.motion_spec(), sc.structure)

    def physics(self) -> dict[str, Any]:
        """What the run is (its store key): kind, name, motion, phi0, duration, fall - not
        its place in a split."""
        return {"kind": self.kind, "name": self.name, "motion": self.motion_spec(),
                "phi0": self.phi0, "duration": self.duration, "fall": self.fall}

    def to_dict(self) -> dict[str, Any]:
        d = {"kind": self.kind, "name": self.name, "motion": self.motion_spec(),
             "phi0": self.phi0, "duration": self.duration, "fall": self.fall,
             "peak_ref": None if not math.isfinite(self.peak_ref) else self.peak_ref,
             "group": self.group, "part": self.part, "near_boundary": self.near_boundary,
             "a_ratio": None if not math.isfinite(self.a_ratio) else self.a_ratio,
             "measure": self.measure,
             "verdict_agreement": (None if not math.isfinite(self.verdict_agreement)
                                   else self.verdict_agreement)}
        return d


def _scene_key(scene) -> str:
    return json.dumps(scene.to_dict(), sort_keys=True, default=str)


@functools.lru_cache(maxsize=64)
def _scene_from_key(text: str):
    from ..scene.scene import Scene

    return Scene.from_dict(json.loads(text))


def _pulse(scene, A: float, W: float, shape: str, sign: int, vertical: float = 0.0):
    from ..scene.motion import RickerPulse

    return RickerPulse.dimensionless(A, W, scene.structure, shape, sign,
                                     vertical_ratio=vertical)


def _analytic(scene, motion, duration: float, phi0: float = 0.0, *, compiled: bool = False):
    """The analytic reference run (``compiled``: the numba path, same answers, for the cells'
    labels and the records)."""
    from ..runner import run

    if compiled:
        return run(scene, motion, engine="analytic", duration=duration, phi0=phi0,
                   method="compiled")
    return run(scene, motion, engine="analytic", duration=duration, phi0=phi0)


def _fall(scene) -> float:
    return min(_FALL * scene.alpha, min(scene.fall_angles.values()))


@functools.lru_cache(maxsize=512)
def _threshold(key: str, W: float, shape: str, sign: int, rtol: float,
               vertical: float = 0.0) -> float:
    from ..analytic.compiled import run_pulse_grid
    from ..analytic.reference import reference_of
    from ..verdict import fall_under_way, finish_fall

    scene = _scene_from_key(key)
    sc = scene.replace(fall_angle=_fall(scene))
    # the run's length, and whether it ends after the pulse, do not depend on A
    p1 = _pulse(sc, 1.0, W, shape, sign, vertical)
    dur = run_length(p1, _OVER_TAIL, window="strong")
    over = dur >= float(p1.t_end) - float(p1.t_start)

    critical = reference_of(sc).critical

    def overturns(A: float) -> bool:
        # the compiled model's verdict alone (the kernel of every analytic run, without the
        # history, events and friction demand a Result carries: most of a run's cost here,
        # benchmarks/results/evidence_labels.md), a fall under way at the end finished as the
        # analytic backend finishes it (rockbench.verdict)
        def row(extra: float = 0.0):
            return run_pulse_grid(sc, [(shape, sign, A, W)], duration=dur + extra,
                                  vertical_ratio=vertical).iloc[0]

        r = row()
        (r,), _ = finish_fall(
            [r], [fall_under_way(r["status"], r["overturned"], r["phi_end"], r["intact_end"],
                                 critical, motion_over=over)],
            lambda _, extension: [row(extension)], fell=lambda x: bool(x["overturned"]))
        return bool(r["overturned"])

    return bisect_threshold(overturns, rtol)


def bisect_threshold(overturns, rtol: float) -> float:
    """The smallest A [-] for which ``overturns(A)`` holds, by scanning up from A = 1 by
    factors of 1.5 and bisecting the first bracket to a relative width ``rtol`` (inf when
    nothing up to A = 30 overturns)."""
    lo, hi = 1.0, 1.5
    while not overturns(hi):
        lo, hi = hi, hi * 1.5
        if hi > _A_MAX:
            return math.inf
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if overturns(mid):
            hi = mid
        else:
            lo = mid
    return hi


def overturn_threshold(scene, W: float, shape: str = "symmetric", sign: int = 1, *,
                       rtol: float = 1e-3, vertical: float = 0.0) -> float:
    """The smallest A = a_g / (g tan alpha) [-] of a Ricker pulse (``W`` = omega_g / p,
    ``shape``, ``sign``) that overturns ``scene`` in the analytic model (fall angle
    min(4 alpha, the scene's), run to 8 s after the pulse's strong part), found by scanning A up
    from 1 by factors of 1.5 and bisecting the first bracket to a relative width ``rtol`` (inf
    when nothing up to A = 30 overturns it), each verdict by the analytic maps' kernel
    (:func:`rockbench.analytic.compiled.run_pulse_grid`). ``vertical``: r, the pulse's vertical part
    a_v = r u_g'' (in phase). Cached in memory per scene data."""
    return _threshold(_scene_key(scene), float(W), str(shape), int(sign), float(rtol),
                      float(vertical))


def uplift_threshold(scene) -> float:
    """A_up = min|lambda| / tan(alpha) [-]: the smallest A of a ground acceleration that uplifts
    the structure in either direction (lambda: the uplift thresholds of the reference)."""
    from ..analytic.reference import reference_of

    lam = reference_of(scene).lam
    return min(abs(float(v)) for v in lam.values()) / math.tan(scene.alpha)


def _free_duration(scene, phi0: float) -> float:
    """End of a free-rocking run [s]: between the peak after the third impact and the fourth
    impact of the analytic run, so that every impact is bracketed by complete excursions."""
    r = _analytic(scene, None, 20.0, phi0, compiled=True)
    t = r.impacts()["t"].to_numpy(dtype=float)
    if t.size >= 4:
        return float(t[2] + 0.75 * (t[3] - t[2]))
    if t.size >= 2:
        return float(t[-1] + 0.75 * (t[-1] - t[-2]))
    return 10.0


def _order(seed: int, name: str) -> str:
    return hashlib.sha256(f"{seed}|{name}".encode()).hexdigest()


# ----------------------------------------------------------------------------------------
# candidates: every case of a scene, unlabelled (no analytic run yet but the thresholds)
# ----------------------------------------------------------------------------------------
def _short(shape: str, sign: int) -> str:
    return f"{'symm' if shape == 'symmetric' else 'anti'}{'+' if sign > 0 else '-'}"


@functools.lru_cache(maxsize=16)
def _candidates(key: str, vertical: float = 0.0) -> tuple[tuple[str, dict[str, Any]], ...]:
    """(group, description) of every candidate case of the scene, in a fixed order (one sign
    only for a mirror-symmetric structure without vertical motion: a pulse's vertical part
    turns with its sign, so the reversed pulse is no mirror image)."""
    scene = _scene_from_key(key)
    from .map_cells import reversed_mirrors

    signs = (1,) if reversed_mirrors(scene, vertical) else (1, -1)
    out: list[tuple[str, dict[str, Any]]] = []
    for f in _FREE_PHI0:
        for s in signs:
            out.append(("free", {"kind": "free", "f": f, "s": s}))
    A_up = uplift_threshold(scene)
    for W in W_GRID:
        for shape, sign in _PULSES:
            if sign not in signs:
                continue
            A_ov = overturn_threshold(scene, W, shape, sign, vertical=vertical)
            if not math.isfinite(A_ov):
                continue
            tag = _short(shape, sign)
            base = {"W": W, "shape": shape, "sign": sign, "A_ov": A_ov, "v": vertical}
            if A_ov > A_up:
                for f in AWAY_LEVELS:
                    A = round(A_up + f * (A_ov - A_up), 4)
                    if A < (1 - NEAR_MARGIN) * A_ov:
                        out.append((f"away:{tag}", {"kind": "pulse", "A": A, **base}))
            for f in NEAR_LEVELS:
                out.append(("near", {"kind": "pulse", "A": round(f * A_ov, 4), **base}))
            out.append(("overturn", {"kind": "pulse", "A": round(OVER_LEVEL * A_ov, 4), **base}))
    from ..scene.records import bundled_records

    pga_up = G * A_up * math.tan(scene.alpha)
    for rec in bundled_records():
        for f in RECORD_FACTORS:
            for s in signs:
                out.append(("record", {"kind": "record", "path": str(rec["path"]),
                                       "name": rec["name"], "f": f, "s": s,
                                       "pga_target": f * pga_up, "v": vertical}))
    return tuple(out)


def _case_name(desc: dict[str, Any]) -> str:
    if desc["kind"] == "free":
        return f"free{'+' if desc['s'] > 0 else '-'}{desc['f']:g}"
    if desc["kind"] == "pulse":
        return f"{_short(desc['shape'], desc['sign'])} W={desc['W']:g} A={desc['A']:.4g}"
    return f"{desc['name']} {'+' if desc['s'] > 0 else '-'}{desc['f']:g}x uplift PGA"


@functools.lru_cache(maxsize=4096)
def _make_case(key: str, desc_json: str) -> ValidationCase | None:
    """The case of one candidate, labelled with the analytic model (None: left out)."""
    scene = _scene_from_key(key)
    desc = json.loads(desc_json)
    name = _case_name(desc)
    if desc["kind"] == "free":
        phi0 = desc["s"] * desc["f"] * scene.alpha
        return ValidationCase("free", name, None, phi0, round(_free_duration(scene, phi0), 3),
                              None, desc["f"],
                              measure="history" if scene.has_devices else "eta")
    if desc["kind"] == "pulse":
        fall = _fall(scene)
        sc = scene.replace(fall_angle=fall)
        A, W, shape, sign = desc["A"], desc["W"], desc["shape"], desc["sign"]
        ratio = A / desc["A_ov"]
        near = abs(ratio - 1.0) <= NEAR_MARGIN
        vr = float(desc.get("v", 0.0))
        p = _pulse(sc, A, W, shape, sign, vr)
        if not motion_validity(sc, p):           # outside the model: its base would slide
            return None
        dur = run_length(p, _OVER_TAIL if (near or ratio > 1) else _AWAY_TAIL,
                         window="strong")
        r = _analytic(sc, p, dur, compiled=True)
        if not r.summary.uplifted or r.summary.max_abs_phi_over_alpha < MIN_PEAK:
            return None
        kind = "overturn" if r.summary.overturned else "survive"
        agree = _verdict_agreement(sc, p, dur)
        spec = (("A", A), ("W", W), ("kind", "ricker"), ("shape", shape), ("sign", sign)) + (
            (("vertical_ratio", vr),) if vr else ())
        return ValidationCase(kind, name, spec, 0.0, dur, fall,
                              float(r.summary.max_abs_phi_over_alpha),
                              near_boundary=near or agree < 1.0, a_ratio=round(ratio, 4),
                              measure="verdict" if kind == "overturn" else "peak",
                              verdict_agreement=agree)
    from ..scene.motion import motion_from_spec

    spec = {"kind": "record", "path": desc["path"], "scale": 1.0}
    rec = motion_from_spec(spec, scene.structure)
    scale = round(desc["s"] * desc["pga_target"] / rec.peak, 4)
    spec["scale"] = scale
    rec = rec.scaled(scale)
    if desc.get("v"):                  # the vertical channel: r times the scaled horizontal
        spec["vertical_ratio"] = float(desc["v"])
        rec = rec.with_vertical_ratio(spec["vertical_ratio"])
    if not motion_validity(scene, rec):          # outside the model: its base would slide
        return None
    dur = round(min(_RECORD_DURATION, rec.t_end - rec.t_start), 3)
    r = _analytic(scene, rec, dur, compiled=True)
    if not r.summary.uplifted or r.summary.max_abs_phi_over_alpha < MIN_PEAK:
        return None
    agree = _verdict_agreement(scene, rec, dur)
    over = bool(r.summary.overturned)
    return ValidationCase("overturn" if over else "record", name,
                          tuple(sorted(spec.items())), 0.0, dur, None,
                          float(r.summary.max_abs_phi_over_alpha), near_boundary=agree < 1.0,
                          measure="verdict" if over else "band", verdict_agreement=agree)


def _verdict_agreement(scene, motion, duration: float) -> float:
    """The fraction of the case's sensitivity-band runs (:mod:`rockbench.studies.sensitivity`)
    whose overturning verdict is the unperturbed one [-]: below 1, the case's own verdict is
    uncertain (near the boundary, whatever its kind)."""
    from .sensitivity import band

    return float(band(scene, motion, duration=duration).verdict_agreement)


def candidate_cases(scene) -> list[tuple[str, str]]:
    """(group, case name) of every candidate case of ``scene`` (before the analytic model
    labels them; thresholds computed): the catalogue the sizes draw from."""
    return [(g, _case_name(d)) for g, d in _candidates(_scene_key(scene))]


@functools.lru_cache(maxsize=16)
def _validation_set(key: str, size: str, seed: int,
                    vertical: float = 0.0) -> tuple[ValidationCase, ...]:
    groups: dict[str, list[tuple[str, dict[str, Any]]]] = {}
    for g, d in _candidates(key, vertical):    # the away cells of the four pulses: one group
        groups.setdefault(g.split(":")[0], []).append((g, d))
    sizes = GROUP_SIZES[size]
    out: list[ValidationCase] = []
    for g, items in groups.items():
        k = sizes[g]
        ordered = sorted(items, key=lambda it: _order(seed, _case_name(it[1])))
        taken: dict[str, int] = {}
        n = 0
        for sub, d in ordered:     # in order; a candidate left out does not take a place
            if taken.get(sub, 0) >= k:
                continue
            c = _make_case(key, json.dumps(d, sort_keys=True))
            if c is None:
                continue
            out.append(replace(c, group=sub, rank=n,
                               part="choice" if n % 2 == 0 else "held-out"))
            taken[sub] = taken.get(sub, 0) + 1
            n += 1
    return tuple(out)


def validation_set(scene, *, quick: bool = False, size: str | None = None,
                   seed: int = SEED, vertical: float = 0.0) -> list[ValidationCase]:
    """The evidence of ``scene`` (module docstring) of size ``size`` ("quick", "default" or
    "full"; ``quick=True`` is ``size="quick"``), split into choice and held-out parts
    (``case.part``) with ``seed``. quick is a subset of default, default of full: the same
    cases. ``vertical``: r in [0, 3] (limit ``vertical_ratio``): every pulse and record of
    the evidence also moves the ground vertically, a_v = r times its horizontal acceleration
    (in phase; thresholds and labels computed with it); 0: horizontal only. Cached in memory
    per scene data."""
    from .map_cells import check_vertical_ratio

    vertical = check_vertical_ratio(vertical, "vertical")
    if size is None:
        size = "quick" if quick else "default"
    if size not in GROUP_SIZES:
        raise ParameterError("size", size, f"one of {', '.join(GROUP_SIZES)}")
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ParameterError("seed", seed, "an integer")
    return list(_validation_set(_scene_key(scene), size, int(seed), vertical))

"""The analytic model's own sensitivity: a predictability band for one case, and an engine judged
against it (Bachmann et al. 2018, "Is rocking motion predictable?").

For one scene and ground motion, :func:`band` runs the analytic model unperturbed and under
small perturbations that no one can claim to know better than (:data:`PERTURBATIONS`):

* ``eta``: the coefficient of restitution of every impact x (1 +- 0.5 %) and x (1 +- 1 %);
* ``pivot``: a geometric imperfection of 1 mm at the pivots: the half-width b of the columns
  (or of the block) +- 1 mm, i.e. ``column_width`` +- 2 mm, so that every pivot corner moves
  1 mm outwards (inwards) from its column's axis. Masses and inertias follow the width (density
  is kept). The equivalent change of the uplift threshold is reported in :attr:`Band.runs`
  (``lambda_ccw`` / ``lambda_cw`` columns): for the paper's frame 1 mm of b moves lambda by
  about 0.2 % (lambda ~ b / H);
* ``scale``: the ground acceleration x (1 +- 1 %);
* ``phase`` (records only): the sampling phase. A record is samples of a continuous signal at
  instants that are arbitrary with respect to it; we resample its linear interpolation half a
  sample later, a_k' = (a_k + a_{k+1}) / 2. A shift of the record by a *whole* sample (or a
  pulse by any time) changes nothing: the model starts from rest and is time-invariant, so the
  response is the same history shifted in time (checked in ``tests/test_sensitivity.py``). The
  half-sample resampling is the one-sample shift that does change the input: the same record
  seen through another sampling grid (shifting by - half a sample gives the same samples one
  sample later, hence the same response: one run covers both signs). Pulses are analytic
  functions of time and have no sampling phase: they get no ``phase`` run.

Every peak is max|phi| divided by alpha of the *unperturbed* scene, so all runs share one
scale. The band is [min, max] of the peaks over the unperturbed and perturbed runs; the verdict
spread is the fraction of perturbed runs whose overturning verdict equals the unperturbed one.

:meth:`Band.judge` places an engine's peak (a :class:`~rockbench.result.Result`, measured from
its history, or a number): inside the band ("within the model's own sensitivity") or outside it,
by a distance in units of alpha and relative to the nearest edge of the band.
:func:`assert_within_band` is the pytest-style check built on it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from ..analytic.reference import reference_of
from ..errors import ParameterError
from ..result import Result
from ..scene.motion import Record
from ..scene.scene import Scene
from ..scene.structure import Frame

__all__ = ["PERTURBATIONS", "Perturbation", "Band", "Judgement", "band", "perturbed_case",
           "assert_within_band"]


class Perturbation(NamedTuple):
    """One perturbed run: ``kind`` (eta | pivot | scale | phase) and ``value`` (factor for eta
    and scale [-], change of the half-width b [m] for pivot, fraction of a sample [-] for
    phase)."""

    kind: str
    value: float

    @property
    def label(self) -> str:
        if self.kind in ("eta", "scale"):
            return f"{self.kind} x{self.value:g}"
        if self.kind == "pivot":
            return f"pivot {self.value * 1e3:+g} mm"
        return f"phase {self.value:+g} sample"


#: The perturbations of :func:`band`, in order (module docstring).
PERTURBATIONS: tuple[Perturbation, ...] = (
    Perturbation("eta", 0.995), Perturbation("eta", 1.005),
    Perturbation("eta", 0.99), Perturbation("eta", 1.01),
    Perturbation("pivot", -1e-3), Perturbation("pivot", 1e-3),
    Perturbation("scale", 0.99), Perturbation("scale", 1.01),
    Perturbation("phase", 0.5),
)

RUN_COLUMNS = ("perturbation", "kind", "value", "peak_over_alpha", "overturned", "fractured",
               "t_fracture", "n_impacts", "lambda_ccw", "lambda_cw", "status")


# ------------------------------------------------------------------------------------------------
def _widened(scene: Scene, db: float) -> Scene:
    """``scene`` with the half-width b of its columns (block) changed by ``db`` [m]."""
    st = scene.structure
    if isinstance(st, Frame):
        w = st.column_width + 2.0 * db
        beam = max(st.beam_width, st.span + w)      # the beam must still cover both columns
        new = dataclasses.replace(st, column_width=w, beam_width=beam)
    else:
        new = dataclasses.replace(st, width=st.width + 2.0 * db)
    return dataclasses.replace(scene, structure=new)


def _resampled(record: Record, frac: float) -> Record:
    """The record's linear interpolation sampled ``frac`` of a sample later (0 < frac < 1)."""
    t, a = record.time, record.samples
    a2 = (1.0 - frac) * a[:-1] + frac * a[1:]
    out = Record(t[:-1], a2, name=f"{record.name} phase+{frac:g}", source=record.source,
                 units_in=record.units_in)
    return out


def perturbed_case(scene: Scene, motion, p: Perturbation) -> tuple[Scene, Any, float]:
    """(scene, motion, eta factor) of perturbation ``p`` applied to a case."""
    if p.kind == "eta":
        return scene, motion, float(p.value)
    if p.kind == "pivot":
        return _widened(scene, float(p.value)), motion, 1.0
    if p.kind == "scale":
        if motion is None:
            raise ParameterError("perturbation", p.label, "eta or pivot for free rocking")
        return scene, motion.scaled(float(p.value)), 1.0
    if p.kind == "phase":
        if not isinstance(motion, Record):
            raise ParameterError("perturbation", p.label, "a phase perturbation of a Record")
        return scene, _resampled(motion, float(p.value)), 1.0
    raise ParameterError("perturbation", p.kind, "one of eta, pivot, scale, phase")


def _simulate(scene: Scene, motion, *, duration: float | None, phi0: float,
              eta_factor: float = 1.0, compiled: bool = True) -> Result:
    """One analytic run (history "minimal", ``AnalyticSettings.eta_factor``): the compiled
    path (which applies ``eta_factor`` as the plain solver does; the run's validity is not
    assessed: a band reads verdicts and peaks) when numba is importable and ``compiled``, the
    plain solver otherwise."""
    from ..analytic import solver

    settings = solver.AnalyticSettings(history="minimal", eta_factor=eta_factor)
    if compiled:
        try:
            from ..analytic.compiled import NUMBA_AVAILABLE, simulate_compiled
            if NUMBA_AVAILABLE:
                return simulate_compiled(scene, motion, duration=duration, phi0=phi0,
                                         settings=settings, assess_validity=False)
        except ImportError:
            pass
    return solver.simulate(scene, motion, duration=duration, phi0=phi0, settings=settings,
                           reference=reference_of(scene))


# ------------------------------------------------------------------------------------------------
class Judgement(NamedTuple):
    """Where a peak stands against a :class:`Band`.

    peak : max|phi| / alpha judged [-]; inside : within [low, high];
    distance : signed distance to the band [alpha] (> 0 above ``high``, < 0 below ``low``, 0
    inside); relative : peak / (nearest edge) - 1 (0 inside); text : one line for a report.
    """

    peak: float
    inside: bool
    distance: float
    relative: float
    text: str


@dataclass(frozen=True)
class Band:
    """The analytic model's peak and verdict under :data:`PERTURBATIONS` (module docstring).

    nominal, low, high : unperturbed, smallest and largest max|phi| / alpha [-] (low <= nominal
    <= high); overturned : unperturbed verdict; verdict_agreement : fraction of perturbed runs
    with the same verdict [-]; fracture_agreement : same for the fracture verdict; runs : one row
    per run (:data:`RUN_COLUMNS`), the unperturbed first.
    """

    scene: str
    motion: str
    alpha: float
    nominal: float
    low: float
    high: float
    overturned: bool
    verdict_agreement: float
    fractured: bool
    fracture_agreement: float
    runs: pd.DataFrame = dataclasses.field(repr=False, compare=False)

    @property
    def width(self) -> float:
        """high - low [alpha]."""
        return self.high - self.low

    @property
    def relative_width(self) -> float:
        """(high - low) / nominal [-] (NaN if the unperturbed run never uplifts)."""
        return self.width / self.nominal if self.nominal > 0 else math.nan

    def judge(self, peak: float | Result, overturned: bool | None = None) -> Judgement:
        """Place ``peak`` (max|phi| / alpha, or a Result: max|phi| of its history / alpha of
        this band) against the band.

        A run that overturned (a Result's summary says so, or ``overturned=True`` with a
        number) is judged by its verdict, not its peak (which is then the fall angle plus what
        the engine's last step overshoots): inside if some run of the band overturns too;
        otherwise by its peak, like any other."""
        if isinstance(peak, Result):
            phi = peak.history["phi"].to_numpy(dtype=float)
            overturned = bool(peak.summary.overturned)
            peak = float(np.max(np.abs(phi))) / self.alpha if phi.size else math.nan
        if overturned and math.isfinite(float(peak)):
            ok = self.runs[self.runs["status"] == "ok"]
            n_over = int(ok["overturned"].astype(bool).sum())
            if n_over:
                return Judgement(float(peak), True, 0.0, 0.0, "within the model's own "
                                 f"sensitivity (overturned, as {n_over} of {len(ok)} analytic "
                                 "runs do)")
        x = float(peak)
        if not math.isfinite(x):
            return Judgement(x, False, math.nan, math.nan, "no peak to judge")
        tol = 1e-12 * max(1.0, abs(self.high))
        if self.low - tol <= x <= self.high + tol:
            return Judgement(x, True, 0.0, 0.0, "within the model's own sensitivity")
        edge = self.high if x > self.high else self.low
        d = x - edge
        rel = x / edge - 1.0 if edge > 0 else math.inf
        where = "above" if d > 0 else "below"
        return Judgement(x, False, d, rel, f"outside it, by {abs(d):.3g} alpha "
                                           f"({rel * 100:+.1f} % {where} the band's edge)")

    def to_dict(self) -> dict[str, Any]:
        """The scalar fields (JSON-safe), for a metrics table."""
        return {k: getattr(self, k) for k in ("scene", "motion", "alpha", "nominal", "low",
                                             "high", "overturned", "verdict_agreement",
                                             "fractured", "fracture_agreement")}


def band(scene: Scene, motion=None, *, duration: float | None = None, phi0: float = 0.0,
         perturbations: tuple[Perturbation, ...] | None = None, compiled: bool = True) -> Band:
    """The predictability band of one case (module docstring): the unperturbed analytic run
    and one run per perturbation (``perturbations``, default :data:`PERTURBATIONS`; ``phase``
    is skipped unless ``motion`` is a Record, ``scale`` for free rocking). ``duration`` [s] and
    ``phi0`` [rad] as in :func:`rockbench.run` (use the case's). ``compiled`` uses the compiled
    analytic path when numba is present (same answers: ``tests/test_sensitivity.py``; about 50
    times faster on records)."""
    if not isinstance(scene, Scene):
        raise ParameterError("scene", type(scene).__name__, "a rockbench Scene")
    perts = PERTURBATIONS if perturbations is None else tuple(perturbations)
    alpha = scene.alpha
    rows = []

    def one(label, kind, value, sc, mot, ef):
        r = _simulate(sc, mot, duration=duration, phi0=phi0, eta_factor=ef, compiled=compiled)
        ref = reference_of(sc)
        s = r.summary
        rows.append(dict(perturbation=label, kind=kind, value=value,
                         peak_over_alpha=s.max_abs_phi / alpha, overturned=bool(s.overturned),
                         fractured=bool(s.fractured),
                         t_fracture=s.t_fracture if s.t_fracture is not None else math.nan,
                         n_impacts=int(s.n_impacts), lambda_ccw=ref.lam[1],
                         lambda_cw=ref.lam[-1], status=s.status))

    one("unperturbed", "none", math.nan, scene, motion, 1.0)
    for p in perts:
        if (p.kind == "phase" and not isinstance(motion, Record)) or (
                p.kind == "scale" and motion is None):
            continue
        sc, mot, ef = perturbed_case(scene, motion, p)
        one(p.label, p.kind, p.value, sc, mot, ef)
    runs = pd.DataFrame(rows, columns=list(RUN_COLUMNS))
    ok = runs[runs["status"] == "ok"]
    if ok.empty or ok.iloc[0]["perturbation"] != "unperturbed":
        raise RuntimeError(f"analytic run of {scene.name} failed: "
                           f"{runs.iloc[0]['status']}")
    pk = ok["peak_over_alpha"].to_numpy(dtype=float)
    pert = ok.iloc[1:]
    over0, frac0 = bool(ok.iloc[0]["overturned"]), bool(ok.iloc[0]["fractured"])
    agree = float((pert["overturned"] == over0).mean()) if len(pert) else 1.0
    fagree = float((pert["fractured"] == frac0).mean()) if len(pert) else 1.0
    label = motion.label() if motion is not None else f"free rocking from {phi0:g} rad"
    return Band(scene=scene.name, motion=label, alpha=alpha, nominal=float(pk[0]),
                low=float(pk.min()), high=float(pk.max()), overturned=over0,
                verdict_agreement=agree, fractured=frac0, fracture_agreement=fagree, runs=runs)


def assert_within_band(result: Result, band_: Band, *, verdict: bool = True) -> Judgement:
    """AssertionError unless ``result``'s peak lies within ``band_`` (and, with ``verdict``,
    its overturning verdict is one the perturbed analytic runs reach). Returns the
    :class:`Judgement`."""
    j = band_.judge(result)
    if not j.inside:
        raise AssertionError(f"{result.backend} on {band_.scene} / {band_.motion}: peak "
                             f"{j.peak:.4g} alpha, band [{band_.low:.4g}, {band_.high:.4g}] "
                             f"(unperturbed {band_.nominal:.4g}): {j.text}")
    if verdict:
        seen = set(band_.runs.loc[band_.runs["status"] == "ok", "overturned"].astype(bool))
        if bool(result.summary.overturned) not in seen:
            raise AssertionError(f"{result.backend} on {band_.scene} / {band_.motion}: "
                                 f"overturned={result.summary.overturned}, which no perturbed "
                                 f"analytic run reaches")
    return j

"""Input limits, in one place: the size of a run and the ranges outside which an input means
nothing for a rocking structure (``docs/errors.md`` lists them with their reasons).

Every entry point (command line, :func:`rockbench.run`, compare, sweeps and maps, scene files,
record files, settings) passes through a check here *before anything is allocated*:

* sizes: history samples = duration / output_dt (:data:`LIMITS` ``max_samples``) and engine
  steps = duration / dt (``max_steps``), estimated in :func:`rockbench.engines.base.run_window`;
* ranges: the dimensionless pulse coordinates A and W, a pulse's amplitude and period, a
  record's time step, file size and number of samples, the analytic solver's tolerances and
  the output interval.

Each limit can be changed without editing code by an environment variable, which every error
message names: ``ROCKBENCH_MAX_SAMPLES=1e8`` (a maximum) or ``ROCKBENCH_W_RANGE=0.001,1e4`` (a
range: ``lo,hi``). The variable is read at each check, so it may be set for one run.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError, check_finite

__all__ = ["Limit", "LIMITS", "limit", "check_in_limit", "check_size", "check_count",
           "override_hint"]


@dataclass(frozen=True)
class Limit:
    """A documented bound on an input.

    key : name in :data:`LIMITS` (``max_samples``, ``W``, ...).
    lo, hi : the bounds (``lo`` None for a plain maximum).
    lo_open, hi_open : whether the bound itself is excluded.
    unit : unit of the bounds ("" for dimensionless or counts).
    why : one line: what the limit protects.
    """

    key: str
    lo: float | None
    hi: float
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    why: str = ""

    @property
    def env(self) -> str:
        """The environment variable that overrides the limit."""
        return f"ROCKBENCH_{self.key.upper()}"

    @property
    def is_range(self) -> bool:
        return self.lo is not None

    def current(self) -> tuple[float | None, float]:
        """(lo, hi) now: the defaults, or the environment variable's value."""
        raw = os.environ.get(self.env)
        if raw is None or not raw.strip():
            return self.lo, self.hi
        parts = [p.strip() for p in raw.split(",")]
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            vals = []
        want = 2 if self.is_range else 1
        if len(vals) != want or any(math.isnan(v) for v in vals) \
                or (want == 2 and not vals[0] < vals[1]) or (want == 1 and not vals[0] > 0):
            form = "lo,hi with lo < hi" if self.is_range else "a number > 0"
            raise ParameterError(self.env, raw, form, "environment variable overriding the "
                                 f"limit {self.key}")
        return (vals[0], vals[1]) if want == 2 else (None, vals[0])

    def describe(self, lo: float | None = None, hi: float | None = None) -> str:
        """The bound as text: ``"<= 2e+06"`` or ``"in (0, 100]"`` (with the unit)."""
        if lo is None and hi is None:
            lo, hi = self.current()
        unit = f" {self.unit}" if self.unit else ""
        if lo is None:
            return f"<= {hi:g}{unit}"
        lb, rb = ("(" if self.lo_open else "["), (")" if self.hi_open else "]")
        return f"in {lb}{lo:g}, {hi:g}{rb}{unit}"


#: Every limit, by key. Defaults are generous: the paper's maps use A up to ~20 and W 0.3-50;
#: a history sample of a frame costs ~250 bytes, an engine step ~10-50 microseconds.
LIMITS: dict[str, Limit] = {lim.key: lim for lim in (
    Limit("max_samples", None, 2e6,
          why="history rows of one run, duration / output_dt (2e6 rows ~ 0.5 GB of history)"),
    Limit("max_steps", None, 2e7,
          why="engine steps of one run, duration / dt (2e7 steps: 1.4 CPU min for pymunk, "
              "24-32 for OpenSees, PyBullet, Drake; benchmarks/results/longest_run.md)"),
    Limit("A", 0.0, 100.0, lo_open=True,
          why="pulse amplitude A = a_g / (g tan alpha); uplift needs A > 1, the paper's maps "
              "end near 20"),
    Limit("W", 0.01, 1000.0,
          why="pulse frequency W = omega_g / p; the paper's maps use 0.3-50"),
    Limit("amplitude", 0.0, 1e4, lo_open=True, unit="m/s^2",
          why="pulse amplitude a_g (1e4 m/s^2 ~ 1000 g)"),
    Limit("period", 1e-4, 1e4, unit="s",
          why="pulse period T_g (a run spans at least the pulse window 6 T_g)"),
    Limit("vertical_ratio", 0.0, 3.0,
          why="peak vertical over peak horizontal ground acceleration of a pulse: 0 (none) to "
              "3; near-fault records reach about 2 (docs/sliding.md)"),
    Limit("record_dt", 1e-4, 0.1, lo_open=True, hi_open=True, unit="s",
          why="time step of a ground-motion record (accelerograms use 0.001-0.02 s)"),
    Limit("record_bytes", None, 1e8, unit="bytes",
          why="size of a record file (an accelerogram is ~100 kB)"),
    Limit("record_samples", None, 2e6,
          why="samples of one record (2e6 samples = 5.6 h at 0.01 s; a Record holds ~60 "
              "bytes per sample; the files are parsed in blocks and refused as soon as they "
              "pass it)"),
    Limit("bootstrap", 1.0, 1e5,
          why="bootstrap resamples of a fragility fit (each one lognormal fit per backend, "
              "~1 ms: 1e5 resamples ~ 2 CPU min per backend; more adds nothing to a 95 % "
              "interval)"),
    Limit("map_cells", None, 1e6,
          why="cells of one overturning map, grid NA x NW x pulses (the paper's maps: "
              "100 x 100 x 4 = 40 000)"),
    Limit("rtol", 1e-13, 1e-3,
          why="relative tolerance of the analytic solver (rtol >= 1 is no accuracy at all)"),
    Limit("atol", 1e-16, 1e-3,
          why="absolute tolerance of the analytic solver [rad, rad/s]"),
    Limit("output_dt", 1e-5, 1.0, unit="s",
          why="history sampling interval: finer than 1e-5 s is all memory, coarser than "
              "1 s misses every impact"),
    # physical ranges of a scene's fields (docs/scenes.md lists which field takes which)
    Limit("length", 1e-3, 1e3, unit="m",
          why="every length of a scene: from a 1 mm model to a 1 km structure"),
    Limit("density", 1.0, 25000.0, unit="kg/m^3",
          why="mass density: from the lightest solids (aerogels, ~1 kg/m^3) to beyond the "
              "densest (osmium, 22590 kg/m^3)"),
    Limit("mass_ratio", 1e-3, 1e3,
          why="beam mass / left column mass: from a light steel beam on masonry piers to a "
              "heavy deck on slender piers (the paper: 10)"),
    Limit("stiffness", 0.0, 1e12, unit="N/m",
          why="tendon stiffness EA/l: 0 (none) to a steel bar of 1 m^2 over 0.2 m (the "
              "paper: 23.5e6)"),
    Limit("damping", 0.0, 1e12, unit="N s/m",
          why="damper constant: 0 (none) to far beyond any built viscous damper (the paper: "
              "25.3e6)"),
)}


def limit(key: str) -> tuple[float | None, float]:
    """(lo, hi) of limit ``key`` now (environment override applied)."""
    return LIMITS[key].current()


def override_hint(key: str) -> str:
    """How to change limit ``key``: ``"limit max_samples; raise it with ROCKBENCH_..."``."""
    lim = LIMITS[key]
    if lim.is_range:
        return f"limit {key}; to widen it set the environment variable {lim.env}=lo,hi"
    return f"limit {key}; to raise it set the environment variable {lim.env}"


def check_in_limit(key: str, name: str, value: Any) -> float:
    """Return ``value`` as float; :class:`ParameterError` naming ``name`` unless it is a finite
    number within limit ``key`` (the message names the override)."""
    x = check_finite(name, value)
    lim = LIMITS[key]
    lo, hi = lim.current()
    bad_hi = x >= hi if lim.hi_open else x > hi
    bad_lo = lo is not None and (x <= lo if lim.lo_open else x < lo)
    if bad_lo or bad_hi:
        raise ParameterError(name, value, lim.describe(lo, hi), override_hint(key))
    return x


def check_size(key: str, name: str, value: Any, count: float, what: str) -> None:
    """Refuse a run whose estimated ``count`` (of ``what``: "history samples (duration /
    output_dt)") exceeds limit ``key``; the error names ``name`` = ``value``, the count, the
    limit and how to raise it."""
    _, hi = LIMITS[key].current()
    if not count <= hi:  # also NaN
        raise ParameterError(name, value, f"small enough for <= {hi:g} {what.split(' (')[0]}",
                             f"it gives {count:.3g} {what}; {override_hint(key)}")


def check_count(key: str, name: str, count: int, what: str) -> None:
    """Refuse ``count`` items (``what``: "samples") of ``name`` beyond the maximum ``key``
    (checked on a length, before anything is copied or allocated)."""
    _, hi = LIMITS[key].current()
    if not count <= hi:
        raise ParameterError(name, f"{count} {what}", f"at most {hi:g} {what}",
                             override_hint(key))

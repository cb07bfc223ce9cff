"""The divergence checks on an engine run's output samples (:class:`SampleChecks`), shared by
the stepping loop (:func:`rockbench.engines.loop.step_run`, chunk by chunk while it steps) and
MuJoCo's batched path (once, on every sample): a non-finite state, mechanical energy growing
without input (free rocking), contact penetration or sliding beyond the settings' tolerances.
A failed check raises :class:`Diverged` (the run's status becomes "diverged").

Units: SI and radians.
"""

from __future__ import annotations

import math

import numpy as np

from ..constants import G
from ..progress import sim_time
from ..verdict import past_critical

__all__ = ["Diverged", "SampleChecks", "falling_or_none"]


class Diverged(Exception):
    """Raised inside a run when the engine state is unphysical; becomes status "diverged"."""


def falling_or_none(phi: np.ndarray, intact: np.ndarray, crit: dict) -> np.ndarray | None:
    """The mask of the samples past their critical angle (:func:`rockbench.verdict.past_critical`),
    or None when none is (the common case)."""
    falling = past_critical(phi, intact, crit)
    return falling if falling.any() else None


class SampleChecks:
    """The divergence checks that run on the output samples, in vectorized chunks: a
    non-finite state, mechanical energy growing without input (free rocking), contact
    penetration or sliding beyond the settings' tolerances (sliding only without a scene
    friction: ``sliding=True`` measures it and never fails on it). Samples past the critical angle
    (the structure falling) are not checked here: whether their violations count is decided
    by :func:`finish` (they do unless the run overturns: a falling body that slides or sinks
    still falls, and the verdict is what matters). Each raises :class:`Diverged` naming the
    first offending sample."""

    def __init__(self, cfg, specs, probe, crit, uplift_phi, *, free: bool,
                 energy_floor: float = 0.0, sliding: bool = False):
        self.cfg, self.probe, self.crit, self.uplift_phi = cfg, probe, crit, uplift_phi
        self.free = free
        #: sliding is the physics modelled (the scene gives a friction): measured, never a
        #: divergence
        self.sliding = sliding
        #: [J] added to |E0| as the scale of energy growth (:func:`_energy_floor`): a structure
        #: released where its potential is ~0 (2 alpha, beyond its critical angle) has E0 ~ 0
        self.energy_floor = energy_floor
        self.mass = np.array([sp.mass for sp in specs])
        self.inertia = np.array([sp.inertia for sp in specs])
        self.y0 = np.array([sp.y for sp in specs])
        self.checked = 0
        self.energy0 = None
        self.max_pen = self.max_slide = 0.0
        self.stop_at = None
        self.contact = None            # (pen, sl, opened) per sample, filled as checked

    def _fail(self, i: int, message: str):
        self.stop_at = i
        raise Diverged(message)

    def check(self, states, intact, grid, n: int, out) -> None:
        start, cfg = self.checked, self.cfg
        self.checked = n
        if n <= start:
            return
        sim_time(grid[n - 1], grid[0], grid[-1])   # progress of a long run (rockbench.progress)
        S = states[start:n]
        if not math.isfinite(float(S.sum())):      # (a finite sum: every state finite)
            bad = ~np.isfinite(S).all(axis=(1, 2))
            if bad.any():
                i = int(np.argmax(bad))
                self._fail(start + i, f"non-finite body state at t={grid[start + i]:.6g} s")
        ph = S[:, 0, 2]
        # the samples past the critical angle (none when |phi| stays below every one of them)
        falling = falling_or_none(ph, intact[start:n], self.crit)
        if self.free:
            e = (0.5 * (self.mass * (S[:, :, 3] ** 2 + S[:, :, 4] ** 2)
                        + self.inertia * S[:, :, 5] ** 2).sum(axis=1)
                 + G * (self.mass * (S[:, :, 1] - self.y0)).sum(axis=1))
            if self.energy0 is None:
                self.energy0 = float(e[0])
            scale = max(abs(self.energy0) + self.energy_floor, 1e-300)
            # not while falling past the critical angle (as the contact checks): the verdict
            # is what matters there, and a fall's energies dwarf E0 ~ 0 of a release near 2 alpha
            grew = e > self.energy0 + cfg.energy_gain_tol * scale
            if falling is not None:
                grew &= ~falling
            if grew.any():
                i = int(np.argmax(grew))
                self._fail(start + i, f"mechanical energy grew by "
                                      f"{100 * (e[i] - self.energy0) / scale:.2f} % without "
                                      f"input (t={grid[start + i]:.4g} s)")
        modes = np.where(np.abs(ph) <= self.uplift_phi, 0, np.sign(ph))
        pen, sl, op = self.probe.measure_many(S, modes)
        if self.contact is None:
            size = states.shape[0]
            self.contact = (np.zeros(size), np.zeros(size), np.zeros(size, dtype=bool))
        for whole, part in zip(self.contact, (pen, sl, op)):
            whole[start:n] = part
        if falling is not None:
            pen, sl = pen[~falling], sl[~falling]
        self.max_pen = max(self.max_pen, float(pen.max(initial=0.0)))
        self.max_slide = max(self.max_slide, float(sl.max(initial=0.0)))
        if self.max_pen > cfg.max_penetration:
            raise Diverged(f"penetration {self.max_pen:.3g} m > max_penetration "
                           f"{cfg.max_penetration:g} m")
        if self.max_slide > cfg.max_sliding and not self.sliding:
            raise Diverged(f"sliding {self.max_slide:.3g} m > max_sliding "
                           f"{cfg.max_sliding:g} m")

"""Contacts, the same way for every engine: the friction coefficient each body gets so that
every contact *pair* has exactly the scene's (:func:`body_frictions`), and the diagnostics
measured from body poses only: penetration, sliding and opening of the contacts the analytic
model assumes (:class:`ContactProbe`).

Lengths in m (``docs/conventions.md``).
"""

from __future__ import annotations

import math

import numpy as np

from ..scene.scene import Scene
from ..scene.structure import Frame
from .bodies import BodySpec, body_specs

__all__ = ["ContactProbe", "contact_diagnostics", "body_frictions", "COMBINATION_RULES"]

#: How engines combine two bodies' Coulomb coefficients mu1, mu2 into the pair's: "product"
#: (Chipmunk/pymunk, Bullet) mu1 mu2; "harmonic" (Drake) 2 mu1 mu2 / (mu1 + mu2).
COMBINATION_RULES = ("product", "harmonic")


def body_frictions(base: float, beam: float, rule: str) -> tuple[float, float, float]:
    """The coefficients [-] to give the foundation, the block or columns, and the beam, so that
    under the engine's combination ``rule`` (:data:`COMBINATION_RULES`) a base pair (foundation
    and column) gets exactly ``base`` and a beam-on-column pair exactly ``beam``.

    * "product": columns and foundation sqrt(base), the beam beam / sqrt(base);
    * "harmonic": with 1/c = 1/max(base, beam), the foundation 1 / (2/base - 1/c) and the beam
      1 / (2/beam - 1/c) (both positive: 2/mu > 1/c for mu <= max).

    With base == beam every body gets the same value (sqrt(mu) or mu). The beam's value
    matters only where it touches the columns; the foundation's only where a column (or block)
    stands on it."""
    if rule not in COMBINATION_RULES:
        raise ValueError(f"rule {rule!r}: one of {COMBINATION_RULES}")
    if base == beam:                     # one value for every body (exactly, no round-off)
        v = math.sqrt(base) if rule == "product" else float(base)
        return v, v, v
    if rule == "product":
        r = math.sqrt(base)
        return r, r, beam / r
    inv_c = 1.0 / max(base, beam)
    return 1.0 / (2.0 / base - inv_c), 1.0 / inv_c, 1.0 / (2.0 / beam - inv_c)


def _corners(sp: BodySpec):
    hw, hh = sp.half_width, sp.half_height
    return {"bl": (-hw, -hh), "br": (hw, -hh), "tl": (-hw, hh), "tr": (hw, hh)}


class ContactProbe:
    """Penetration, sliding and opening of the contacts the analytic model assumes, computed
    from body poses only (so every engine is measured the same way).

    * base contacts: the two base corners of each column (block) on the foundation surface
      (y = 0, or the step's top under the right column);
    * top contacts: the two top corners of each column against the beam soffit, in the beam's
      frame.

    Penetration [m]: depth of a corner below (inside) the surface it rests on. Sliding [m]:
    tangential distance of a corner from its rest position along its surface, counted while
    the corner is in contact (gap < ``tol``), so a pivot that creeps or a beam that slides on
    the column tops shows up, but a heel that swings while lifted does not. Opened: a contact
    the analytic model keeps closed has a gap above ``open_tol``: a pivot of the current
    mechanism while the structure rocks (mode +1: bottom-left and top-right corners, mode -1:
    bottom-right and top-left), or any of them at rest (mode 0).
    """

    def __init__(self, scene: Scene, specs: list[BodySpec], tol: float = 1e-3,
                 open_tol: float = 5e-3):
        self.specs = specs
        self.tol = tol
        self.open_tol = open_tol
        self.frame = isinstance(scene.structure, Frame)
        self.cols = [0, 2] if self.frame else [0]
        self.base_y = {i: specs[i].y - specs[i].half_height for i in self.cols}
        self.rest = {}
        for i in self.cols:
            sp = specs[i]
            for name, (lx, ly) in _corners(sp).items():
                self.rest[(i, name)] = (sp.x + lx, sp.y + ly)
        self.beam = specs[1] if self.frame else None
        self._table = None             # corners for the compiled probe (built on first use)

    def measure(self, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
        """(penetration [m], sliding [m], contact opened) for one state (n_bodies, 6) and
        rocking mode (+1, -1, 0)."""
        pen, sl, op = self.measure_many(np.asarray(state, dtype=float)[None],
                                        np.array([mode]))
        return float(pen[0]), float(sl[0]), bool(op[0])

    def measure_many(self, states: np.ndarray, modes: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorized :meth:`measure` over states (n, n_bodies, 6) and modes (n,): arrays of
        penetration [m], sliding [m] and opened flags. Compiled (numba: one pass over the
        samples, a map cell probes every sample) when numba imports; the same arithmetic as
        :meth:`measure_numpy` (``tests/engines/test_fast_paths.py``)."""
        if _probe_kernel is None:
            return self.measure_numpy(states, modes)
        states = np.ascontiguousarray(states, dtype=float)
        modes = np.ascontiguousarray(modes, dtype=np.float64)
        n = states.shape[0]
        pen, slide, opened = np.zeros(n), np.zeros(n), np.zeros(n, dtype=np.bool_)
        if self._table is None:
            rows = []
            for i in self.cols:
                sp = self.specs[i]
                for k, (name, (lx, ly)) in enumerate(_corners(sp).items()):
                    if name in ("tl", "tr") and not self.frame:
                        continue
                    rows.append((i, lx, ly, k, self.rest[(i, name)][0], self.base_y[i]))
            self._table = np.array(rows, dtype=float)
        bh, bx = (self.beam.half_height, self.beam.x) if self.frame else (0.0, 0.0)
        _probe_kernel(states, modes, self._table, self.frame, self.tol, self.open_tol, bh, bx,
                      pen, slide, opened)
        return pen, slide, opened

    def measure_numpy(self, states: np.ndarray, modes: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`measure_many` in numpy (vectorized over the samples): the reference."""
        states = np.asarray(states, dtype=float)
        modes = np.asarray(modes)
        n = states.shape[0]
        pen = np.zeros(n)
        slide = np.zeros(n)
        opened = np.zeros(n, dtype=bool)
        rocking = modes != 0
        if self.frame:
            bx, by, bth = states[:, 1, 0], states[:, 1, 1], states[:, 1, 2]
            bc, bs_ = np.cos(bth), np.sin(bth)
        for i in self.cols:
            sp = self.specs[i]
            x, y, th = states[:, i, 0], states[:, i, 1], states[:, i, 2]
            c, s = np.cos(th), np.sin(th)
            for name, (lx, ly) in _corners(sp).items():
                X = x + c * lx - s * ly
                Y = y + s * lx + c * ly
                rx0, _ = self.rest[(i, name)]
                if name in ("bl", "br"):
                    gap = Y - self.base_y[i]
                    tang = X - rx0
                    pivot = modes > 0 if name == "bl" else modes < 0
                else:
                    if not self.frame:
                        continue
                    rx, ry = X - bx, Y - by
                    u = bc * rx + bs_ * ry
                    v = -bs_ * rx + bc * ry
                    gap = -(v + self.beam.half_height)      # < 0: corner inside the beam
                    tang = u - (rx0 - self.beam.x)
                    pivot = modes > 0 if name == "tr" else modes < 0
                np.maximum(pen, -gap, out=pen)
                touch = gap < self.tol
                np.maximum(slide, np.where(touch, np.abs(tang), 0.0), out=slide)
                opened |= (gap > self.open_tol) & (pivot | ~rocking)
        return pen, slide, opened


def _probe(states, modes, table, frame, tol, open_tol, beam_hh, beam_x, pen, slide, opened):
    """:meth:`ContactProbe.measure_numpy` sample by sample: ``table`` rows (body, lx, ly,
    corner 0 bl / 1 br / 2 tl / 3 tr, rest x, base y) in the numpy loop's order."""
    for j in range(states.shape[0]):
        mode = modes[j]
        rocking = mode != 0.0
        if frame:
            bxj, byj, bth = states[j, 1, 0], states[j, 1, 1], states[j, 1, 2]
            bc, bs_ = np.cos(bth), np.sin(bth)
        p, sl, op = 0.0, 0.0, False
        last, c, s = -1, 1.0, 0.0
        for r in range(table.shape[0]):
            i = int(table[r, 0])
            lx, ly, kind, rx0 = table[r, 1], table[r, 2], int(table[r, 3]), table[r, 4]
            x, y, th = states[j, i, 0], states[j, i, 1], states[j, i, 2]
            if i != last:                            # a body's rows are consecutive
                c, s, last = np.cos(th), np.sin(th), i
            X = x + c * lx - s * ly
            Y = y + s * lx + c * ly
            if kind < 2:
                gap = Y - table[r, 5]
                tang = X - rx0
                pivot = mode > 0.0 if kind == 0 else mode < 0.0
            else:
                rx, ry = X - bxj, Y - byj
                u = bc * rx + bs_ * ry
                v = -bs_ * rx + bc * ry
                gap = -(v + beam_hh)
                tang = u - (rx0 - beam_x)
                pivot = mode > 0.0 if kind == 3 else mode < 0.0
            if -gap > p or gap != gap:               # NaN propagates as np.maximum's
                p = -gap
            if gap < tol and (abs(tang) > sl or tang != tang):
                sl = abs(tang)
            if gap > open_tol and (pivot or not rocking):
                op = True
        pen[j], slide[j], opened[j] = p, sl, op


try:
    from numba import njit as _njit
    _probe_kernel = _njit(cache=True)(_probe)
except ImportError:  # pragma: no cover - numba is a dependency
    _probe_kernel = None


def contact_diagnostics(scene: Scene, state: np.ndarray, mode: int) -> tuple[float, float, bool]:
    """Convenience wrapper of :class:`ContactProbe` for one state."""
    return ContactProbe(scene, body_specs(scene)).measure(state, mode)

"""Everything the analytic model derives from a scene, once: per-direction dynamics, uplift
thresholds lambda (Eq. 20), coefficients of restitution eta, fall, fracture and critical angles.

Part of the physics library (pure functions of the scene); engines may use it to measure
themselves (critical angles, energies), the analytic solver uses it to integrate.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ..scene.scene import Scene
from .dynamics import Dynamics
from .impact import eta as eta_of

__all__ = ["Reference", "reference_of", "CONSTANTS"]


#: Units and meaning of the keys of :meth:`Reference.constants` (``rockbench info``).
CONSTANTS: dict[str, tuple[str, str]] = {
    "alpha": ("rad", "slenderness of the taller column, atan(b/H)"),
    "p": ("rad/s", "frequency parameter of the taller column, sqrt(3g/(4R))"),
    "eta_ccw": ("-", "restitution of an impact after which it rocks counterclockwise"),
    "eta_cw": ("-", "restitution of an impact after which it rocks clockwise"),
    "lambda_ccw": ("g", "ground acceleration that uplifts counterclockwise (signed)"),
    "lambda_cw": ("g", "ground acceleration that uplifts clockwise (signed)"),
    "phi_cr_ccw": ("rad", "critical angle, counterclockwise"),
    "phi_cr_cw": ("rad", "critical angle, clockwise"),
    "phi_fall_ccw": ("rad", "fall angle (overturned), counterclockwise"),
    "phi_fall_cw": ("rad", "fall angle (overturned), clockwise"),
    "phi_cr_ccw_fractured": ("rad", "critical angle after tendon fracture, counterclockwise"),
    "phi_cr_cw_fractured": ("rad", "critical angle after tendon fracture, clockwise"),
    "phi_fracture_ccw": ("rad", "rotation at which a tendon fractures, counterclockwise"),
    "phi_fracture_cw": ("rad", "rotation at which a tendon fractures, clockwise"),
    "mass": ("kg", "mass of the block"),
    "mass_left": ("kg", "mass of the left (taller) column"),
    "mass_right": ("kg", "mass of the right column"),
    "mass_beam": ("kg", "mass of the beam"),
    "alpha_right": ("rad", "slenderness of the right column"),
    "r_BC_ccw": ("m", "beam centre of mass from the pivot, counterclockwise"),
    "psi_BC_ccw": ("rad", "angle of r_BC, counterclockwise"),
    "r_BC_cw": ("m", "beam centre of mass from the pivot, clockwise"),
    "psi_BC_cw": ("rad", "angle of r_BC, clockwise"),
}


def _sinusoid_root(f, lim: float) -> float | None:
    """The first root in (0, ``lim``) of ``f`` [N m] (inf when there is none) when ``f`` is one
    sinusoid, f(x) = a cos x + b sin x with a = f(0) > 0: the gravity term of a free-standing
    block (its centre of mass turns about the pivot) or of a frame whose columns stay parallel
    (every body turns about a fixed point, or translates along a circle, at the rate phi'), whose
    root is x = atan2(b, a) + pi/2. a and b are read at x = 0 and x = d; the form is accepted
    only when it predicts f at two other angles to 1e-9 of |f(0)| and the root's residual is as
    small (None otherwise: tendons, an asymmetric linkage)."""
    a = f(0.0)
    if not (math.isfinite(a) and a > 0.0):
        return None
    d = min(0.25, 0.5 * lim)
    b = (f(d) - a * math.cos(d)) / math.sin(d)
    tol = 1e-9 * a
    for x in (1.5 * d, 2.0 * d):
        if not abs(f(x) - (a * math.cos(x) + b * math.sin(x))) <= tol:
            return None
    root = math.atan2(b, a) + 0.5 * math.pi
    if root >= lim:
        return math.inf if f(lim) > 0.0 else None
    return root if abs(f(root)) <= tol else None


@functools.lru_cache(maxsize=128)
def reference_of(scene: Scene) -> "Reference":
    """The :class:`Reference` of ``scene``, computed once per scene *parameters* (scenes are
    frozen and hashable: two equal scenes share one Reference) and reused by every run,
    measurement and comparison of that scene in this process."""
    return Reference(scene)


class Reference:
    """Everything the analytic model derives from a scene: per-direction dynamics, thresholds,
    restitution, fall, fracture and critical angles. Shared by :func:`simulate` and ``info``."""

    def __init__(self, scene: Scene):
        self.scene = scene
        st = scene.structure
        dev = scene.devices if scene.has_devices else None
        self.dyn = {s: Dynamics(st, s, dev) for s in (1, -1)}
        self.lam = {s: self.dyn[s].uplift_threshold() for s in (1, -1)}
        self.eta = {s: eta_of(st, s) for s in (1, -1)}
        self.fall = dict(scene.fall_angles)
        self.alpha = st.alpha
        self.p = st.p
        eps = dev.fracture_strain if dev is not None else None
        self.fracture_angle = {s: (self._fracture_angle(s, eps) if eps is not None else math.inf)
                               for s in (1, -1)}
        self.critical = {(s, intact): self._critical_angle(s, intact)
                         for s in (1, -1) for intact in (True, False)}

    # --- derived angles -------------------------------------------------------------------
    def strain(self, phi: float) -> float:
        """Largest tendon strain [-] at rotation phi (geometric, whatever k is)."""
        s = 1 if phi >= 0 else -1
        ds = self.dyn[s].device_state(self.dyn[s].configuration(phi))
        return max(ds.elong_left, ds.elong_right) / self.scene.devices.tendon_length

    def _fracture_angle(self, s: int, eps: float) -> float:
        lim = self.fall[s]
        f = lambda x: self.strain(s * x) - eps  # noqa: E731
        if f(lim) < 0:
            return math.inf
        from scipy.optimize import brentq

        return brentq(f, 0.0, lim, xtol=1e-14, rtol=1e-13)

    def _critical_angle(self, s: int, intact: bool) -> float:
        """First |phi| > 0 where dV/dphi vanishes (gravity + intact tendons), inf if none before
        the fall angle: in closed form when dV/dphi is one sinusoid (:func:`_sinusoid_root`),
        else by a scan and Brent's method (:meth:`_searched_critical_angle`)."""
        dyn, lim = self.dyn[s], self.fall[s]
        f = lambda x: s * dyn.potential_gradient(s * x, intact)  # noqa: E731
        root = _sinusoid_root(f, lim)
        return root if root is not None else self._searched_critical_angle(s, intact)

    def _searched_critical_angle(self, s: int, intact: bool) -> float:
        """:meth:`_critical_angle` by a scan of 400 steps to the fall angle and Brent's method
        on the first sign change (any mechanism, any tendon)."""
        dyn, lim = self.dyn[s], self.fall[s]
        f = lambda x: s * dyn.potential_gradient(s * x, intact)  # noqa: E731
        xs = np.linspace(0.0, lim, 400)[1:]
        prev_x, prev = 0.0, f(0.0)
        for x in xs:
            v = f(x)
            if prev > 0 >= v:
                from scipy.optimize import brentq

                return brentq(f, prev_x, x, xtol=1e-14, rtol=1e-13)
            prev_x, prev = x, v
        return math.inf

    def constants(self) -> dict[str, Any]:
        """The constants table (JSON keys of ``rockbench info``)."""
        nan_if_inf = lambda v: (None if not math.isfinite(v) else v)  # noqa: E731
        st = self.scene.structure
        out = {"scene": self.scene.name, "type": st.kind, "alpha": self.alpha, "p": self.p,
               "eta_ccw": self.eta[1], "eta_cw": self.eta[-1],
               "lambda_ccw": self.lam[1], "lambda_cw": self.lam[-1],
               "phi_cr_ccw": nan_if_inf(self.critical[(1, True)]),
               "phi_cr_cw": nan_if_inf(-self.critical[(-1, True)]),
               "phi_fall_ccw": self.fall[1], "phi_fall_cw": -self.fall[-1]}
        if self.scene.has_devices:
            out["phi_cr_ccw_fractured"] = nan_if_inf(self.critical[(1, False)])
            out["phi_cr_cw_fractured"] = nan_if_inf(-self.critical[(-1, False)])
            out["phi_fracture_ccw"] = nan_if_inf(self.fracture_angle[1])
            out["phi_fracture_cw"] = nan_if_inf(-self.fracture_angle[-1])
        if st.kind == "frame":
            out.update(mass_left=st.mass_left, mass_right=st.mass_right, mass_beam=st.mass_beam,
                       alpha_right=st.alpha1)
            for s, tag in ((1, "ccw"), (-1, "cw")):
                r, psi = st.beam_offset(s)
                out[f"r_BC_{tag}"] = r
                out[f"psi_BC_{tag}"] = psi
        else:
            out["mass"] = st.mass
        return out

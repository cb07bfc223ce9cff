"""pymunk (Chipmunk 2-D) backend: the planar engine.

Each body of the scene is one ``pymunk.Body`` with its true mass and moment of inertia (the
beam's m rho^2 of the scene, not its box's) and one box ``Poly``; the foundation (a ground
segment and, for the asymmetric frame, the step box) is static. pymunk multiplies a pair's
coefficients: the shapes get :func:`~rockbench.engines.contacts.body_frictions` ("product":
sqrt(mu) each when one coefficient serves every pair), so that every base pair has exactly
the base friction and the beam on the columns the beam friction; no elasticity. Ground motion
(horizontal and vertical) is the shared time-varying gravity. Tendons and dampers are the shared
:class:`rockbench.engines.devices.DeviceGeometry` forces (tendon elongation = base opening + top
opening, exactly), summed into one force and one torque per body before every step; pymunk's
own ``DampedSpring`` is not used (a straight spring from the foundation to the beam would be up
to 0.4 % shorter over the rocking range, see ``tests/engines/test_pymunk.py``).

Settings, defaults and the measurements behind them: ``docs/engines/pymunk.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..constants import G
from ..errors import ParameterError, check_int
from .base import EngineBackend, EngineSettings
from .contacts import body_frictions
from .devices import DAMPER_MODELS, PointForce, net_wrenches

__all__ = ["PymunkBackend", "PymunkSettings", "MAX_ITERATIONS"]

#: The most solver iterations per step a setting may ask for. Chipmunk's counter is a C int
#: (2^31 - 1; 1e12 was an OverflowError reported as "diverged") and every iteration is paid on
#: every step: 1e4 iterations cost 0.07 s of CPU per 0.3 s of a block's free rocking (measured),
#: 2^31 - 1 does not finish; the default 30 already converges the frame's impacts.
MAX_ITERATIONS = 10_000


@dataclass(frozen=True)
class PymunkSettings(EngineSettings):
    """pymunk settings. Every default is justified by the measurements in
    ``docs/engines/pymunk.md`` (``benchmarks/pymunk_settings.py --sweep``); structures are in
    metres and tonnes, while pymunk's own defaults assume pixels.

    dt : time step [s] (default 1e-3: every cross-engine bar met with a factor >= 2 to spare;
        5e-4 halves the errors at half the speed, 2e-3 fails the eta bar).
    friction : Coulomb coefficient of every contact pair [-] when the scene gives no friction
        (default 2: the results are identical from 0.7 to 10; at 0.5 a hybrid frame slides by
        4 cm). A scene's ``[contact]`` friction replaces it (``docs/engines/README.md``).
    iterations : solver iterations per step, an integer in [1, :data:`MAX_ITERATIONS` = 1e4]
        (default 30; pymunk's 10 leaves the three-body frame's impacts unconverged: eta off by
        0.9 %, 18 mm of slip).
    collision_slop : overlap [m] left uncorrected (default 3e-4 m; pymunk's 0.1 is meant for
        pixels; 0 puts the asymmetric frame's eta 0.8 % off, 1e-4 lets a frame slip 1.3 mm).
    collision_bias : fraction of the overlap beyond the slop left after 1 s (pymunk's default
        (1 - 0.1)^60; the results hardly depend on it).
    damper : how the dampers' force reaches the bodies, one of
        :data:`~rockbench.engines.devices.DAMPER_MODELS` (default "distributed": the damper power
        taken from each body in proportion to its momentum; "couple" and "heel" make the
        hybrid frame slide by 4 cm to 1 m, see :class:`~rockbench.engines.devices.DeviceGeometry`).
    loop : "compiled" (default: the stepping loop runs in numba, calling Chipmunk's C functions,
        where :func:`rockbench.engines.chipmunk.available` says it can; otherwise Python) or
        "python" (the Python loop: the plain path the compiled one is tested against). The
        numbers are the same (``docs/engines/pymunk.md``).

    Inherited (:class:`~rockbench.engines.base.EngineSettings`): output_dt, uplift_tol,
    max_penetration, max_sliding, energy_gain_tol.
    """

    dt: float = 1e-3
    friction: float = 2.0
    iterations: int = 30
    collision_slop: float = 3e-4
    collision_bias: float = (1.0 - 0.1) ** 60
    damper: str = "distributed"
    loop: str = "compiled"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.loop not in ("compiled", "python"):
            raise ParameterError("loop", self.loop, "'compiled' or 'python'")
        check_int("iterations", self.iterations, 1, MAX_ITERATIONS)
        if not (0.0 <= self.collision_slop < 0.01):
            raise ParameterError("collision_slop", self.collision_slop, "in [0, 0.01) m")
        if not (0.0 <= self.collision_bias < 1.0):
            raise ParameterError("collision_bias", self.collision_bias, "in [0, 1)")
        if self.damper not in DAMPER_MODELS:
            raise ParameterError("damper", self.damper, f"one of {', '.join(DAMPER_MODELS)}")


class PymunkBackend(EngineBackend):
    """The scene in pymunk (planar rigid bodies, box contacts)."""

    name: ClassVar[str] = "pymunk"
    Settings: ClassVar[type] = PymunkSettings
    #: The contact settings a search may try (rockbench advise --full; engines/base.py).
    contact_variants: ClassVar[tuple] = (
        {"iterations": 60}, {"iterations": 100}, {"collision_slop": 1e-4},
        {"collision_slop": 1e-3}, {"collision_bias": 0.9 ** 300})
    fast: ClassVar[bool] = True     # real-time factor 44-341 (benchmarks/results/results.md)

    @classmethod
    def _probe(cls) -> tuple[bool, str]:
        try:
            import pymunk
        except Exception as e:  # pragma: no cover - depends on the machine
            return False, f"pymunk does not import: {e}"
        return True, f"pymunk {pymunk.version} (Chipmunk {pymunk.chipmunk_version})"

    def _build(self) -> None:
        import pymunk

        cfg = self.settings
        space = pymunk.Space()
        space.iterations = int(cfg.iterations)
        space.collision_slop = cfg.collision_slop
        space.collision_bias = cfg.collision_bias
        space.gravity = (0.0, -G)
        fd = self.foundation
        static = space.static_body
        shapes = [pymunk.Segment(static, (fd.x_min, 0.0), (fd.x_max, 0.0), 0.0)]
        if fd.step_x0 is not None:
            x0, x1, hgt = fd.step_x0, fd.step_x1, fd.step_height
            shapes.append(pymunk.Poly(static, [(x0, 0.0), (x1, 0.0), (x1, hgt), (x0, hgt)]))
        self._bodies = []
        for sp, pose in zip(self.specs, self.poses0):
            body = pymunk.Body(sp.mass, sp.inertia)
            body.position = (float(pose[0]), float(pose[1]))
            body.angle = float(pose[2])
            box = pymunk.Poly.create_box(body, (2 * sp.half_width, 2 * sp.half_height), 0.0)
            shapes.append(box)
            space.add(body)
            self._bodies.append(body)
        # pymunk multiplies the two coefficients of a pair: foundation, columns, beam
        mu_g, mu_c, mu_b = body_frictions(*self.friction_pairs, "product")
        n_static = len(shapes) - len(self.specs)
        for k, s in enumerate(shapes):
            beam = len(self.specs) == 3 and k - n_static == 1
            s.friction = mu_g if k < n_static else (mu_b if beam else mu_c)
            s.elasticity = 0.0
        space.add(*shapes)
        self._space = space
        # Chipmunk's C entry points (pymunk's cffi library): gravity, step and the state read
        # are the per-step work, and pymunk's Python wrappers (locking for callbacks, Vec2d
        # objects) cost as much as the step itself. rockbench adds and removes nothing during
        # a run and registers no callback, so calling Chipmunk directly is exact.
        from pymunk._chipmunk_cffi import lib
        self._cspace = space._space
        self._cbodies = [b._body for b in self._bodies]
        self._c = (lib.cpSpaceSetGravity, lib.cpSpaceStep, lib.cpBodyGetPosition,
                   lib.cpBodyGetAngle, lib.cpBodyGetVelocity, lib.cpBodyGetAngularVelocity)

    def _compiled_loop(self):
        if self.settings.loop != "compiled":
            return None
        from . import chipmunk

        if not chipmunk.available()[0]:
            return None
        from .compiled_loop import CHIPMUNK, run_kernel

        eng = chipmunk.engine(self._cspace, self._cbodies)

        def loop(*args):
            return run_kernel(CHIPMUNK, eng, *args)
        return loop

    def _step(self, gravity_x: float, forces: list[PointForce], gravity_y: float = -G) -> None:
        self._c[0](self._cspace, (gravity_x, gravity_y))
        if forces:
            # one force and one torque per body (Chipmunk clears them after every step)
            for body, (fx, fy, tau) in zip(self._bodies,
                                           net_wrenches(forces, self._last).tolist()):
                if fx or fy or tau:
                    body.force = (fx, fy)
                    body.torque = tau
        self._c[1](self._cspace, self.settings.dt)

    def _state(self) -> np.ndarray:
        _, _, pos, ang, vel, omega = self._c
        out = []
        for b in self._cbodies:
            p, v = pos(b), vel(b)
            out.append((p.x, p.y, ang(b), v.x, v.y, omega(b)))
        self._last = np.array(out)
        return self._last

    def _close(self) -> None:
        self._space = self._cspace = None
        self._bodies = self._cbodies = []

"""The backend contract, in the spirit of ``scipy.integrate.OdeSolver``: :class:`Backend` is
what every backend is (the analytic reference and the engines), :class:`EngineBackend` what a
rigid-body engine stepped from Python is. Their docstrings are the checklists an adapter's
author follows: what to declare, what to implement, what the harness then gives.

Beside them, what every backend shares: :func:`run_window` (a run's time window, validated
once), :func:`check_vertical` (a vertical motion refused by a backend that cannot move its
ground vertically), :func:`resolve_friction` (the scene's friction in an engine's settings)
and :class:`EngineSettings` (the settings every engine has). The shared machinery of the
engines lives beside this file, one job each: ``bodies.py`` (scene -> bodies), ``devices.py``
(tendons and dampers from poses), ``contacts.py`` (penetration, sliding, opening),
``loop.py`` (stepping, and samples -> Result), ``verdicts.py`` (what the samples say);
:mod:`rockbench.measure` measures events and the effective eta from the sampled history.
"""

from __future__ import annotations

import abc
import threading
from dataclasses import asdict, dataclass, fields
from typing import Any, ClassVar

import numpy as np

from ..constants import G
from ..errors import BackendUnavailable, ParameterError, check_positive
from ..result import Result
from ..run_length import describe, run_length
from ..scene.scene import Scene
from .bodies import body_specs, foundation_spec, initial_poses
from .devices import DeviceGeometry, PointForce

__all__ = ["Backend", "EngineBackend", "EngineSettings", "run_window", "check_vertical",
           "resolve_friction"]

#: Backend class -> (available, version or reason): each probe runs once per process.
_STATUS: dict[type, tuple[bool, str]] = {}
_STATUS_LOCK = threading.RLock()


class Backend(abc.ABC):
    """Base class of every backend (the analytic reference and the engines).

    To add a backend, follow these steps (scipy's ``OdeSolver`` asks the same of a solver):

    1. **Subclass** :class:`Backend` in one file - a rigid-body engine stepped from Python
       subclasses :class:`EngineBackend` instead, whose checklist follows this one - and
       register it by name: one line in ``rockbench/registry.py`` (``REGISTRY``), or an entry
       point of the group ``rockbench.engines`` in your own distribution.

    2. **Declare** (class attributes; those with a default here may be left out):

       - ``name`` - the registry name;
       - ``Settings`` - a frozen dataclass of the backend's own settings (time step, solver
         iterations, contact parameters, ...), every field with a default that
         ``docs/engines/<name>.md`` justifies by a measurement; invalid values raise
         :class:`rockbench.errors.ParameterError` in ``__post_init__``. A backend never
         changes the scene: engine-only parameters live here. A setting typed as text
         (``--setting ENGINE.KEY=VALUE``) takes the type of its field's default
         (:mod:`rockbench.engines.setting_text`);
       - ``package`` (default "": the registry name) - the distribution that provides the
         engine (e.g. "openseespy"), for ``rockbench engines`` and the engine versions read
         from package metadata;
       - its capabilities, read by sweeps, campaigns and searches through
         ``rockbench.engines.get_backend(name)``, so that no module outside ``engines/``
         names an engine:

         * ``batched`` (default False) - it runs many ground motions of one scene in one call:
           it then implements the classmethods ``run_batch(scene, motions, *, duration,
           nthread, keep, **settings) -> list[Result]`` and ``batch_refusal(scene, settings)
           -> str | None`` (why a scene cannot run batched; callers then use ``run`` case by
           case);
         * ``fast`` (default False) - real-time factor >= 20 through rockbench on the
           benchmark cases (``benchmarks/results/results.md``): the report gives such engines
           the larger default map grids;
         * ``relative_cost`` (default 1.0) - CPU cost of a run relative to the fast engines:
           the order in which campaigns schedule jobs (longest first) and searches try
           engines (cheapest first); from the ``total_s`` column of
           ``benchmarks/results/results.md``;
         * ``contact_variants`` (default none) - the contact settings a search may try besides
           the defaults (``rockbench advise --full``): a tuple of override mappings of
           ``Settings`` fields, each one a variant;
         * ``precision_sweeps`` (default ``(("dt", None, {}),)``: the time step) - the
           work-precision curves: a tuple of (knob, values coarse to fine or None for the
           sweep's time steps, the dt ladder :data:`rockbench.constants.DT_LADDER`,
           overrides held along it); an error-controlled integrator declares its own knob
           (e.g. an accuracy);
         * ``vertical_motion`` (default False; True for every :class:`EngineBackend`) - it
           moves its ground vertically too: a motion's ``vertical`` component (a GroundMotion
           of the vertical ground acceleration [m/s^2], positive up, or None) enters its run.
           A backend without it refuses such a motion in one line (:func:`check_vertical`),
           never ignores it.

    3. **Implement**:

       - ``_probe()`` - classmethod returning ``(True, version)`` or ``(False, why)``: whether
         the engine imports here (it may raise: an exception is a ``(False, why)``);
       - ``run(motion=None, *, duration=None, phi0=0.0, keep="all") -> Result`` - one
         simulation of the scene the backend was constructed with: start with
         :func:`run_window` (the window of every backend: from the motion's start, for
         ``duration`` or the run length of :func:`rockbench.run_length.run_length`), return
         a :class:`rockbench.result.Result` whose ``history`` has every column of
         :data:`~rockbench.result.HISTORY_COLUMNS` (and, for engines,
         :data:`~rockbench.result.CONTACT_COLUMNS`) sampled every ``settings.output_dt``
         seconds on :func:`~rockbench.result.output_grid`, whose ``phi`` is the rotation of
         the left column's body from rest (positive counterclockwise), whose verdict follows
         the rule of every backend (:mod:`rockbench.verdict`: a fall under way at the end is
         finished) and whose failures are reported, not raised: an engine error, NaN, or an
         unphysical state yields a Result with ``summary.status == "diverged"`` and the
         reason. ``keep="summary"``: only what a map keeps (the engines' ``Outcome``: the same
         summary and cost, no history); a backend with nothing lighter refuses it;
       - optionally ``remedy(why)`` - what makes the backend available (default:
         ``pip install 'rockbench[<name>]'``; an adapter whose engine needs a system library
         says which).

    4. **What the harness then gives**, with no other edit: ``available()``, which runs the
       probe **once per process** (a cached fact: every table and report of one process sees
       the same engines; callers never call ``_probe``); ``version()``; settings built and
       validated from overrides, with the scene's friction (:func:`resolve_friction`);
       ``rockbench.run`` / ``compare`` / ``map`` / ``tradeoff`` / ``advise`` / ``stress`` /
       ``fragility`` and the report; ``rockbench.testing.check_backend(name)``, the contract's
       checks run on it; and the pytest plugin.
    """

    name: ClassVar[str]
    Settings: ClassVar[type]
    #: Capabilities (the class docstring, step 2): batched runs, speed class, relative cost,
    #: contact variants, work-precision curves, vertical ground motion.
    batched: ClassVar[bool] = False
    fast: ClassVar[bool] = False
    relative_cost: ClassVar[float] = 1.0
    contact_variants: ClassVar[tuple[dict[str, Any], ...]] = ()
    precision_sweeps: ClassVar[tuple] = (("dt", None, {}),)
    vertical_motion: ClassVar[bool] = False
    #: The distribution that provides the engine ("": the registry name).
    package: ClassVar[str] = ""

    def __init__(self, scene: Scene, settings: Any = None, **overrides: Any):
        if not isinstance(scene, Scene):
            raise ParameterError("scene", type(scene).__name__, "a rockbench Scene")
        if settings is None:
            settings = _replace(self.Settings(), overrides) if overrides else self.Settings()
        elif overrides:
            settings = _replace(settings, overrides)
        if not isinstance(settings, self.Settings):
            raise ParameterError("settings", type(settings).__name__,
                                 f"a {self.Settings.__qualname__}")
        settings = resolve_friction(scene, settings, overrides)
        self.scene = scene
        self.settings = settings

    @classmethod
    @abc.abstractmethod
    def _probe(cls) -> tuple[bool, str]:
        """(True, engine version) if the engine imports here, else (False, reason); may
        raise (then unavailable, the exception is the reason). Called once per process by
        :meth:`available`."""

    @classmethod
    def available(cls) -> tuple[bool, str]:
        """(True, engine version) if the backend can run here, else (False, reason): the
        adapter's :meth:`_probe`, run once per process and kept (an engine never appears in
        one table and vanishes from the next). An interrupt (Ctrl-C) propagates and decides
        nothing."""
        with _STATUS_LOCK:
            got = _STATUS.get(cls)
            if got is None:
                try:
                    ok, info = cls._probe()
                except Exception as e:  # noqa: BLE001 - any failure to import is the reason
                    ok, info = False, f"{type(e).__name__}: {e}"
                got = _STATUS[cls] = (bool(ok), str(info))
        return got

    @classmethod
    def remedy(cls, reason: str = "") -> str:
        """What makes the backend available when :meth:`available` says why it is not."""
        return f"pip install 'rockbench[{cls.name}]'"

    @abc.abstractmethod
    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0,
            keep: str = "all") -> Result:
        """Simulate the scene under ``motion`` (None: free rocking from ``phi0`` [rad]) for
        ``duration`` [s] (None: :func:`rockbench.run_length.run_length`); ``keep``: "all"
        (the Result) or "summary" (what a map keeps; class docstring, step 3)."""

    @classmethod
    def batch_refusal(cls, scene: Scene, settings: Any) -> str | None:
        """Why :meth:`run_batch` cannot run ``scene`` (None: it can); a backend that is not
        ``batched`` refuses every scene."""
        return None if cls.batched else f"backend {cls.name!r} has no batched path"

    @classmethod
    def run_batch(cls, scene: Scene, motions, **kwargs: Any) -> list[Result]:
        """Many ground motions of ``scene`` in one call (``batched`` backends only)."""
        raise ParameterError("engine", cls.name, "a backend with batched runs (batched=True)")

    @classmethod
    def version(cls) -> str:
        """The engine version, or "unavailable"."""
        ok, v = cls.available()
        return v if ok else "unavailable"


def _replace(settings, overrides: dict[str, Any]):
    names = {f.name for f in fields(settings)}
    bad = set(overrides) - names
    if bad:
        raise ParameterError(sorted(bad)[0], overrides[sorted(bad)[0]],
                             f"a setting of {type(settings).__qualname__}: {sorted(names)}")
    vals = asdict(settings)
    vals.update(overrides)
    return type(settings)(**vals)


def resolve_friction(scene: Scene, settings, overrides: dict[str, Any] | None = None):
    """``settings`` with the scene's friction: unchanged when the scene gives none (the
    engine's own ``friction``, the rocking model's non-sliding pivots) or when the settings have
    no ``friction`` field; else with ``friction`` = the scene's ``contact.friction``.

    An engine ``friction`` given together with a scene friction is refused (ParameterError
    naming ``friction``): an override ``friction=...`` in ``overrides``, or a Settings object
    whose friction is neither the engine's default nor the scene's value."""
    mu = scene.contact.friction
    names = {f.name for f in fields(settings)}
    if mu is None or "friction" not in names:
        return settings
    default = type(settings)().friction
    given = (overrides or {}).get("friction", settings.friction)
    explicit = "friction" in (overrides or {}) or settings.friction not in (default, mu)
    if explicit:
        raise ParameterError("friction", given, "not set when the scene gives a friction",
                             f"friction is the scene's [contact] friction ({mu:g}) for every "
                             "engine: change contact.friction (--set contact.friction=...), "
                             "not the engine setting")
    if settings.friction == mu:
        return settings
    return _replace(settings, {"friction": mu})


def check_vertical(backend: type, motion) -> None:
    """Refuse, in one line, a ``motion`` with a vertical component (``motion.vertical`` not
    None) for a backend class that cannot move its ground vertically (``vertical_motion``
    False): a ParameterError naming the motion and the reason, never a run that ignores it."""
    if motion is None or getattr(motion, "vertical", None) is None:
        return
    if not backend.vertical_motion:
        raise ParameterError("motion", motion.label() if hasattr(motion, "label") else motion,
                             "a motion without a vertical component for backend "
                             f"{backend.name!r}",
                             f"{backend.name} cannot move its ground vertically")


def run_window(scene: Scene, motion, duration: float | None, phi0: float, *,
               settings: Any = None) -> tuple[float, float]:
    """Validate a run's time window and initial rotation; return (t0, t_end) [s].

    Shared by every backend so that they all start and stop at the same times: from the motion's
    ``t_start`` (-3 T_g for a Ricker pulse) or 0 for free rocking, for ``duration`` seconds
    (default: :func:`rockbench.run_length.run_length`, the motion's length + 10 s, or 10 s of
    free rocking).

    ``motion`` must be a :class:`~rockbench.scene.motion.GroundMotion` or None; ``phi0`` [rad]
    must be below the fall angle of its own direction (``scene.fall_angles[sign(phi0)]``).
    With the backend's ``settings``, the run's size is estimated before anything is allocated:
    history samples = duration / ``settings.output_dt`` and, for a backend with a time step,
    engine steps = duration / ``settings.dt`` must be within the limits ``max_samples`` and
    ``max_steps`` of :mod:`rockbench.limits` (the error names the override).
    """
    from ..errors import check_finite
    from ..limits import check_size
    from ..scene.motion import GroundMotion

    if motion is not None and not isinstance(motion, GroundMotion):
        shown_motion = f"{motion!r}"[:60] + f" ({type(motion).__name__})"
        raise ParameterError("motion", shown_motion,
                             "a GroundMotion (RickerPulse, Record) or None for free rocking")
    t0 = float(motion.t_start) if motion is not None else 0.0
    given = duration is not None
    if duration is None:
        duration = run_length(motion)
    duration = check_positive("duration", duration)
    phi0 = check_finite("phi0", phi0)
    if phi0 != 0.0:
        sign = 1 if phi0 > 0 else -1
        fall = scene.fall_angles[sign]
        if abs(phi0) >= fall:
            way = "counterclockwise" if sign == 1 else "clockwise"
            raise ParameterError("phi0", phi0,
                                 f"|phi0| < the {way} fall angle {fall:.4g} rad "
                                 f"(= {fall / scene.alpha:.4g} alpha)")
    if motion is None and phi0 == 0.0:
        raise ParameterError("phi0", phi0, "non-zero for a free-rocking run (no ground motion)")
    if settings is not None:
        shown: Any = duration if given else (f"{duration:g} s (the default: "
                                             f"{describe('motion', motion=motion)})")
        output_dt = getattr(settings, "output_dt", None)
        if isinstance(output_dt, (int, float)) and output_dt > 0:
            n = duration / output_dt
            check_size("max_samples", "duration", shown, n,
                       f"history samples (duration / output_dt = {duration:g} s / "
                       f"{output_dt:g} s)")
        dt = getattr(settings, "dt", None)
        if isinstance(dt, (int, float)) and dt > 0:
            check_size("max_steps", "duration", shown, duration / dt,
                       f"engine steps (duration / dt = {duration:g} s / {dt:g} s)")
    return t0, t0 + duration


#: The default history interval [s] of every engine (follows a coarser dt).
_DEFAULT_OUTPUT_DT = 1e-3


@dataclass(frozen=True)
class EngineSettings:
    """Settings every engine has (adapters subclass this and add their own).

    dt : engine time step [s], in [1e-6, 1e-2].
    output_dt : history sampling interval [s] (>= dt, and in [1e-5, 1] s: limit ``output_dt`` of
        :mod:`rockbench.limits`), the same grid as the analytic backend. Left at its default
        (1 ms), it follows a coarser ``dt`` (output_dt = dt): the one rule, for the Python API
        and the command line alike.
    friction : Coulomb friction coefficient [-] of every contact pair (the value the pair gets,
        whatever the engine's combination rule), > 0, **used when the scene gives no friction**
        (the rocking model's pivots that do not slide; each engine's default is in
        ``docs/engines/README.md``). A scene's ``[contact] friction`` replaces it (then setting
        it is refused: :func:`resolve_friction`), and its ``beam_friction`` applies to the beam
        on the column tops (:attr:`EngineBackend.friction_pairs`).
    uplift_tol : |phi| / alpha above which the structure counts as uplifted (engine contacts
        are never perfectly rigid) [-], in (0, 1).
    max_penetration, max_sliding : a run whose contacts penetrate or slide more than this [m]
        is reported ``diverged`` (sliding only when the scene gives no friction: with a scene
        friction sliding is the physics modelled, and ``Summary.max_sliding`` reports it).
    energy_gain_tol : relative growth of mechanical energy without input (free rocking) that
        marks a run ``diverged`` [-].
    """

    dt: float = 1e-3
    output_dt: float = _DEFAULT_OUTPUT_DT
    friction: float = 1.0
    uplift_tol: float = 1e-3
    max_penetration: float = 0.05
    max_sliding: float = 0.05
    energy_gain_tol: float = 0.02

    def __post_init__(self) -> None:
        dt = check_positive("dt", self.dt)
        if not 1e-6 <= dt <= 1e-2:
            raise ParameterError("dt", self.dt, "in [1e-6, 1e-2] s")
        od = check_positive("output_dt", self.output_dt)
        if od == _DEFAULT_OUTPUT_DT and dt > od:     # the default grid follows a coarser step
            od = dt
            object.__setattr__(self, "output_dt", dt)
        if od < dt * (1 - 1e-9):
            raise ParameterError("output_dt", self.output_dt, f">= dt = {dt:g} s")
        from ..limits import check_in_limit
        check_in_limit("output_dt", "output_dt", od)  # [1e-5, 1] s unless overridden
        check_positive("friction", self.friction)
        if check_positive("uplift_tol", self.uplift_tol) >= 1.0:
            raise ParameterError("uplift_tol", self.uplift_tol, "in (0, 1) (|phi| / alpha)")
        check_positive("max_penetration", self.max_penetration)
        check_positive("max_sliding", self.max_sliding)
        check_positive("energy_gain_tol", self.energy_gain_tol)
        # store plain floats (a numeric string or numpy scalar passes float(); keep no string)
        for name in ("dt", "output_dt", "friction", "uplift_tol", "max_penetration",
                     "max_sliding", "energy_gain_tol"):
            object.__setattr__(self, name, float(getattr(self, name)))


class EngineBackend(Backend):
    """A rigid-body engine stepped from Python: ``run`` is written once
    (:mod:`rockbench.engines.loop`), the adapter supplies four primitives.

    To add one, follow :class:`Backend`'s checklist with these steps in place of its steps 2-3:

    1. **Declare** ``name``, ``package`` and the capabilities as for every backend, and a
       ``Settings`` that subclasses :class:`EngineSettings` (dt, output_dt, friction and the
       divergence tolerances every engine has) with the engine's own fields. An engine that
       can build the devices as its own elements (tendons, dampers) declares a ``devices``
       field ("native" | "forces"): :attr:`native_devices` reads it, no other declaration.
       A ``damper`` field, if present and one of
       :data:`~rockbench.engines.devices.DAMPER_MODELS`, selects how the shared damper forces
       reach the bodies.

    2. **Implement** the four primitives:

       ``_build(self)``
           Create the world from ``self.specs`` (:class:`~rockbench.engines.bodies.BodySpec`:
           true mass, inertia about the centre of mass, box half sizes, rest centre of mass, in
           the order [block] or [left column, beam, right column]), ``self.foundation``
           (:class:`~rockbench.engines.bodies.FoundationSpec`: ground and optional step) and
           ``self.poses0`` (initial poses on the exact mechanism), with contacts of friction
           :attr:`friction_pairs` (every base pair exactly the first coefficient, every
           beam-on-column pair the second, whatever the engine's rule of combining two bodies'
           coefficients: :func:`~rockbench.engines.contacts.body_frictions`) and no
           restitution. Planar engines stay planar; 3-D engines keep the bodies in the x-y
           plane with joints (not free bodies). Build native tendons/dampers only if
           :attr:`native_devices` and ``self.scene.has_devices``: a free-standing scene has no
           device elements.
       ``_step(self, gravity_x, forces, gravity_y=-g)``
           Advance the world by ``settings.dt`` with gravity ``(gravity_x, gravity_y)``
           [m/s^2]: the ground motion as a time-varying gravity vector,
           ``(-u_g''(t), -(g + u_v''(t)))`` with u_v'' the vertical ground acceleration
           (positive up), exact for rigid bodies in the foundation's frame (the bodies' poses
           are relative to the moving ground; the loop passes ``gravity_y`` only when the
           motion has a vertical component), and the given
           :class:`~rockbench.engines.devices.PointForce` list (device forces computed by the
           loop from the poses; empty for a free-standing scene) applied during the step.
       ``_state(self) -> ndarray (n_bodies, 6)``
           A new float array (the loop keeps it) of x, y [m], theta [rad] (rotation from rest,
           continuous, + counterclockwise), vx, vy [m/s], omega [rad/s] of each body's centre
           of mass, in the order of ``self.specs``.
       ``_close(self)``
           Release engine resources (physics clients, ...).

       and, optionally, ``_remove_devices(self)`` (native devices: switch them off at
       fracture), ``_native_device_report(self, devices, state, elongations)`` (native
       devices: the tendon tensions and damper forces [N] the engine applies, for the history)
       and ``_compiled_loop(self)`` (the whole stepping loop in compiled code, when the
       engine's C step function can be called directly).

    3. **What the harness then gives**, besides :class:`Backend`'s step 4: ``run`` (stepping,
       the divergence checks, the verdict, events and the effective eta), ``build()`` (the
       world outside a run: inspection, tests, batched paths), the counters ``steps`` (engine
       steps) and ``wall_s`` (seconds inside ``_step``, building and the Python loop
       excluded), and the attributes ``specs``, ``foundation``, ``poses0`` (set before
       ``_build``).
    """

    Settings: ClassVar[type] = EngineSettings
    vertical_motion: ClassVar[bool] = True

    @property
    def native_devices(self) -> bool:
        """Whether this run builds the scene's devices as the engine's own elements: the
        adapter's ``devices`` setting is "native" (an adapter without that setting applies
        the shared device forces, :mod:`rockbench.engines.devices`)."""
        return getattr(self.settings, "devices", "forces") == "native"

    @property
    def friction_pairs(self) -> tuple[float, float]:
        """(base, beam) [-]: the Coulomb coefficient every base contact pair gets (a block's or
        the columns' base on the foundation) and every beam-on-column pair gets. The scene's
        ``contact.friction`` and ``beam_friction`` (default: friction) when it gives one, else
        ``settings.friction`` for both."""
        c = self.scene.contact
        if c.given:
            return float(c.friction), float(c.beam)
        mu = float(self.settings.friction)
        return mu, mu

    # --- primitives -------------------------------------------------------------------------
    @abc.abstractmethod
    def _build(self) -> None: ...

    @abc.abstractmethod
    def _step(self, gravity_x: float, forces: list[PointForce],
              gravity_y: float = -G) -> None: ...

    @abc.abstractmethod
    def _state(self) -> np.ndarray: ...

    def _close(self) -> None:
        pass

    def _compiled_loop(self):
        """Optional: the whole stepping loop in compiled code for the world just built, a
        callable with the protocol of :func:`rockbench.engines.compiled_loop.run_kernel`
        minus its first two arguments; None (the default) runs the Python loop of
        :func:`~rockbench.engines.loop.step_run`. It must give the Python loop's numbers."""
        return None

    def _remove_devices(self) -> None:
        if self.native_devices:
            raise NotImplementedError("an adapter with native devices must remove them")

    def _native_device_report(self, devices: DeviceGeometry, state: np.ndarray,
                              elongations: list[float]) -> tuple[list[float], list[float]]:
        """Tendon tensions and damper forces [N] of native devices for the history, at one
        output sample ``state`` (n_bodies, 6) while the devices are intact, with the shared
        geometry's ``elongations`` [m] there. Default: k times the elongations, and no damper
        force; adapters report what their engine applies in that state."""
        return [devices.k * e for e in elongations], [0.0, 0.0]

    # --- public ----------------------------------------------------------------------------
    def build(self, phi0: float = 0.0) -> None:
        """Set ``specs``, ``foundation`` and ``poses0`` for rotation ``phi0`` [rad] and build
        the world (outside a run: inspection, tests, batched paths). ``_close()`` releases it."""
        self.specs = body_specs(self.scene)
        self.foundation = foundation_spec(self.scene)
        self.poses0 = initial_poses(self.scene, phi0)
        self._build()

    def run(self, motion=None, *, duration: float | None = None, phi0: float = 0.0,
            keep: str = "all") -> Result:
        """The run's Result; ``keep="summary"``: only what a map keeps, an
        :class:`~rockbench.engines.loop.Outcome` (no history or events frames)."""
        from .loop import device_geometry, finish, step_run

        t0, t_end = run_window(self.scene, motion, duration, phi0, settings=self.settings)
        check_vertical(type(self), motion)
        ok, why = self.available()
        if not ok:
            raise BackendUnavailable(f"backend {self.name!r} is not available: {why}")
        self.specs = body_specs(self.scene)
        self.foundation = foundation_spec(self.scene)
        self.poses0 = initial_poses(self.scene, phi0)
        from .._jit import CpuClock

        with CpuClock() as clock:
            stepped = step_run(self, motion, t0, t_end, phi0)
            result = finish(self.scene, motion, self.settings, self.specs, stepped, phi0=phi0,
                            t0=t0, backend_name=self.name, engine_version=self.version(),
                            devices=device_geometry(self), keep=keep)
        result.cost.cpu_s, result.cost.compile_cpu_s = clock.cpu_s, clock.compile_s
        return result

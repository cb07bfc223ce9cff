"""Running backends: the only module that instantiates them.

* :func:`run` - one scene, one motion, one backend -> :class:`~rockbench.result.Result`;
* :func:`run_all` - one scene, one motion, several backends (the reference first) -> Results
  and the reasons of the backends that could not run here;
* :func:`info` - the analytic constants of a scene (``rockbench info``);
* :func:`resolve_engines` - validate backend names (None: every available one).

Everything above (compare, sweeps, maps, the campaign, the command line) goes through here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from .engines import REGISTRY, available_backends, get_backend
from .engines.base import run_window
from .errors import BackendUnavailable, ParameterError, check_finite, check_positive
from .registry import REFERENCE  # the reference every metric is measured against
from .result import Result
from .scene.scene import Scene

__all__ = ["REFERENCE", "run", "run_all", "info", "resolve_engines"]



def run(scene: Scene, motion=None, *, engine: str = "analytic",
        duration: float | None = None, phi0: float = 0.0, settings: Any = None,
        keep: str = "all", **setting_overrides: Any) -> Result:
    """Simulate ``scene`` under ``motion`` with one backend.

    Parameters
    ----------
    scene : Scene
    motion : GroundMotion or None
        A Ricker pulse or a record; None for free rocking from ``phi0``.
    engine : str
        A registered backend name (``rockbench.backend_names()``).
    duration : float, optional
        Simulated time [s] from the motion's start (default: motion length + 10 s).
    phi0 : float
        Initial rotation [rad] (free rocking).
    settings : the backend's Settings, optional; ``setting_overrides`` replace single fields
        (e.g. ``dt=2e-4``).
    keep : "all" (default: the Result) or "summary" (engines only: what a map keeps, an
        :class:`~rockbench.engines.loop.Outcome` with the same summary but ``eta_measured``,
        which is empty: impacts are counted, eta is measured only where a verdict needs it;
        no history frame).
    """
    _check_scene(scene)
    _check_motion(motion)
    if not isinstance(engine, str):
        raise ParameterError("engine", engine, f"a backend name: {', '.join(REGISTRY)}")
    backend = get_backend(engine)(scene, settings, **setting_overrides)
    if keep != "all" and (keep != "summary" or engine == REFERENCE):
        raise ParameterError("keep", keep, "'all', or 'summary' for an engine (not the "
                                           "analytic reference)")
    # the run's size (samples, steps) is checked before the backend allocates anything
    run_window(scene, motion, duration, phi0, settings=backend.settings)
    # backends get plain floats (run_window accepted what float() converts, e.g. "0.1")
    phi0 = check_finite("phi0", phi0)
    duration = None if duration is None else check_positive("duration", duration)
    if keep == "summary":
        return backend.run(motion, duration=duration, phi0=phi0, keep=keep)
    return backend.run(motion, duration=duration, phi0=phi0)


def _check_scene(scene: Any) -> None:
    if not isinstance(scene, Scene):
        raise ParameterError("scene", _shown(scene),
                             "a rockbench Scene (rockbench.load_scene(name) or rockbench.Scene)")


def _check_motion(motion: Any) -> None:
    from .scene.motion import GroundMotion

    if motion is not None and not isinstance(motion, GroundMotion):
        raise ParameterError("motion", _shown(motion),
                             "a GroundMotion (rockbench.RickerPulse, a Record from "
                             "rockbench.load_record) or None for free rocking")


def _shown(x: Any) -> str:
    text = repr(x)
    text = text if len(text) <= 50 else text[:47] + "..."
    return f"{text} ({type(x).__name__})"


def resolve_engines(engines: str | Sequence[str] | None, *, name: str = "engines"
                    ) -> list[str]:
    """Backend names, in order, without duplicates; None: every available backend. Unknown
    names raise ParameterError naming ``name`` and the registered names."""
    if engines is None:
        return available_backends()
    if isinstance(engines, str):
        engines = [engines]
    if not isinstance(engines, Sequence):
        raise ParameterError(name, _shown(engines), "a backend name or a list of them: "
                             f"{', '.join(REGISTRY)}")
    for n in engines:
        if not isinstance(n, str) or n not in REGISTRY:
            raise ParameterError(name, n, f"registered backend names: {', '.join(REGISTRY)}")
    return list(dict.fromkeys(engines))


def _settings_for(settings: Mapping[str, Any] | None, name: str) -> tuple[Any, dict[str, Any]]:
    """(settings object or None, overrides dict) for backend ``name``."""
    if not settings or name not in settings or settings[name] is None:
        return None, {}
    s = settings[name]
    if isinstance(s, Mapping):
        return None, dict(s)
    return s, {}


def run_all(scene: Scene, motion=None, *, engines: str | Sequence[str] | None = None,
            phi0: float = 0.0, duration: float | None = None,
            settings: Mapping[str, Any] | None = None, progress: bool = False
            ) -> tuple[dict[str, Result], dict[str, str]]:
    """Run the reference and every selected backend on one scene and motion.

    Returns ``(results, unavailable)``: backend name -> Result (the reference ``"analytic"``
    first), and backend name -> why it could not run here (its engine does not import).
    ``settings`` maps a backend name to its Settings object or a dict of overrides (e.g.
    ``{"pymunk": {"dt": 2e-4}}``); ``progress`` shows each backend's simulated time
    (:mod:`rockbench.progress`: a bar on a terminal, a line every few seconds otherwise).
    """
    _check_scene(scene)
    _check_motion(motion)
    names = resolve_engines(engines)
    if settings is not None:
        if not isinstance(settings, Mapping):
            raise ParameterError("settings", type(settings).__name__,
                                 "a dict: backend name -> Settings or dict of overrides")
        for k in settings:
            if k not in REGISTRY:
                raise ParameterError("settings", k,
                                     f"keyed by backend names: {', '.join(REGISTRY)}")
    order = [REFERENCE] + [n for n in names if n != REFERENCE]
    from .progress import simulated_time

    results: dict[str, Result] = {}
    unavailable: dict[str, str] = {}
    for i, name in enumerate(order, 1):
        obj, over = _settings_for(settings, name)
        # progress: the simulated time of each backend's run, named with its place in the order
        with simulated_time(f"{scene.name}: {name} ({i}/{len(order)})", show=progress):
            try:
                results[name] = run(scene, motion, engine=name, duration=duration, phi0=phi0,
                                    settings=obj, **over)
            except BackendUnavailable as e:
                if name == REFERENCE:
                    raise
                unavailable[name] = str(e)
    return results, unavailable


def info(scene: Scene) -> dict[str, Any]:
    """The analytic constants of ``scene``: alpha [rad], p [rad/s], eta and lambda of both
    directions, critical, fall and fracture angles [rad], masses [kg] (keys and units:
    :data:`rockbench.analytic.reference.CONSTANTS`, as in ``rockbench info --json``)."""
    from .analytic.reference import reference_of

    _check_scene(scene)
    return reference_of(scene).constants()

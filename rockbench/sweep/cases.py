"""Cases: what one run of a sweep is (plain data), its hash, grids of them, and the catalogue.

A *case* is a plain dict (picklable, JSON-able, so it travels to worker processes and Dask
workers and can be hashed)::

    {"scene": "paper-asymmetric",          # built-in name or path to a .toml file
     "overrides": {"span": 9.0},           # scene overrides (load_scene), optional
     "engine": "pymunk",                   # backend name (default "analytic")
     "settings": {"dt": 2e-4},             # backend setting overrides, optional
     "motion": {"kind": "ricker", "shape": "symmetric", "sign": 1, "A": 3.0, "W": 4.0},
               # or {"kind": "ricker", ..., "amplitude": a_g [m/s^2], "period": T_g [s]}
               # or {"kind": "record", "path": ..., "dt": ..., "units": ..., "scale": ...}
               # either may add "vertical_ratio" (a_v = r u_g''), a record instead
               # "vertical_path" (its vertical channel; "vertical_dt", "vertical_units" for a
               # headerless file)
               # or None (free rocking from phi0)
     "phi0": 0.0,                          # rad
     "duration": None}                     # s (None: the motion's length + 10 s)

:func:`normalize_case` checks its shape and fills defaults, :func:`case_id` hashes it (the
store's key), :func:`pulse_grid` builds the cases of a Ricker-pulse map.

The **catalogue** (:func:`catalogue`, from ``rockbench/scenarios/cases.toml``) holds the named
cases every part of rockbench shares: the cross-engine cases (free rocking, pulses the analytic
frame survives, pulses that overturn it: :class:`FreeCase`, :class:`PulseCase`), the default
and the benchmarks' cases. The campaign's plans are read by :mod:`rockbench.campaign.plan`.
"""

from __future__ import annotations

import functools
import math
import os
import tomllib
from dataclasses import dataclass
from importlib import resources
from itertools import product
from pathlib import Path
from typing import Any, Mapping, NamedTuple

import numpy as np

from ..errors import ParameterError
from ..result import motion_label
from .store import key

__all__ = ["CASE_KEYS", "normalize_case", "case_id", "flatten_case", "case_label", "pulse_grid",
           "scene_name", "load_case_scene",
           "FreeCase", "PulseCase", "Catalogue", "catalogue"]

#: The keys a case may have (every other key is an error).
CASE_KEYS = ("scene", "overrides", "engine", "settings", "motion", "phi0", "duration")

_MOTION_KINDS = ("ricker", "record", "none")
_RICKER_KEYS = {"kind", "shape", "sign", "A", "W", "amplitude", "period", "vertical_ratio"}
_RECORD_KEYS = {"kind", "path", "dt", "units", "scale", "vertical_path", "vertical_dt",
                "vertical_units", "vertical_ratio"}


# =========================================================================================
# Cases: normalization and hashing
# =========================================================================================
def _plain(x: Any, name: str) -> Any:
    """``x`` as plain JSON-able Python (numpy scalars -> Python, Path -> str)."""
    if isinstance(x, Mapping):
        return {str(k): _plain(v, f"{name}.{k}") for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v, name) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        v = float(x)
        if not math.isfinite(v):
            raise ParameterError(name, x, "a finite number")
        return v
    if x is None or isinstance(x, str):
        return x
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    raise ParameterError(name, x, "a number, string, bool, None, list or dict (cases are data)")


def normalize_case(case: Mapping[str, Any]) -> dict[str, Any]:
    """The case with every key of :data:`CASE_KEYS` present (defaults filled), plain Python
    values, checked for shape (unknown keys, motion kind and its keys, engine name). Physics
    validation (ranges) happens when the case runs."""
    from ..engines import REGISTRY

    if not isinstance(case, Mapping):
        raise ParameterError("case", type(case).__name__,
                             "a dict with keys " + ", ".join(CASE_KEYS))
    bad = sorted(set(case) - set(CASE_KEYS))
    if bad:
        raise ParameterError(f"case key {bad[0]!r}", case[bad[0]], f"one of {', '.join(CASE_KEYS)}")
    c = _plain(dict(case), "case")
    scene = c.get("scene")
    if not (isinstance(scene, str) and scene) and not isinstance(scene, dict):
        raise ParameterError("scene", scene, "a built-in scene name, a path to a .toml file or "
                                             "a scene's table (Scene.to_dict())")
    engine = c.get("engine", "analytic")
    if engine not in REGISTRY:
        raise ParameterError("engine", engine, f"one of {', '.join(REGISTRY)}")
    out: dict[str, Any] = {"scene": scene}
    for k in ("overrides", "settings"):
        v = c.get(k) or {}
        if not isinstance(v, dict):
            raise ParameterError(k, v, "a dict (or None)")
        out[k] = {name: v[name] for name in sorted(v)}
    out["engine"] = engine
    out["motion"] = _normalize_motion(c.get("motion"))
    phi0 = c.get("phi0", 0.0)
    if isinstance(phi0, bool) or not isinstance(phi0, (int, float)):
        raise ParameterError("phi0", phi0, "a finite number [rad]")
    out["phi0"] = float(phi0)
    dur = c.get("duration")
    if dur is not None:
        if isinstance(dur, bool) or not isinstance(dur, (int, float)) or dur <= 0:
            raise ParameterError("duration", dur, "> 0 [s] or None")
        dur = float(dur)
    out["duration"] = dur
    return out


def _normalize_motion(m: Any) -> dict[str, Any] | None:
    if m is None:
        return None
    if not isinstance(m, dict):
        raise ParameterError("motion", m, "a dict with 'kind' in ricker, record, none (or None)")
    kind = m.get("kind")
    if kind not in _MOTION_KINDS:
        raise ParameterError("motion.kind", kind, f"one of {', '.join(_MOTION_KINDS)}")
    if kind == "none":
        if set(m) != {"kind"}:
            raise ParameterError("motion", m, "{'kind': 'none'} with no other key")
        return None
    allowed = _RICKER_KEYS if kind == "ricker" else _RECORD_KEYS
    bad = sorted(set(m) - allowed)
    if bad:
        raise ParameterError(f"motion.{bad[0]}", m[bad[0]],
                             f"a key among {', '.join(sorted(allowed))} for a {kind} motion")
    out = {k: m[k] for k in sorted(m)}
    if kind == "ricker":
        out.setdefault("shape", "symmetric")
        out.setdefault("sign", 1)
        if isinstance(out["sign"], (int, float)) and out["sign"] in (1, -1):
            out["sign"] = int(out["sign"])
        has_dimless = "A" in out and "W" in out
        has_dim = "amplitude" in out and "period" in out
        if has_dimless == has_dim or len(set(out) & {"A", "W", "amplitude", "period"}) != 2:
            raise ParameterError("motion", m, "a ricker motion with either A and W, or amplitude "
                                              "[m/s^2] and period [s]")
    else:
        if not isinstance(out.get("path"), str):
            raise ParameterError("motion.path", out.get("path"), "a path to a record file")
        out.setdefault("scale", 1.0)
        if out.get("vertical_path") is None:      # no vertical channel: the keys are left out
            for k in ("vertical_path", "vertical_dt", "vertical_units"):
                if out.pop(k, None) is not None:
                    raise ParameterError(f"motion.{k}", m[k], "given only with vertical_path")
        elif not isinstance(out["vertical_path"], str):
            raise ParameterError("motion.vertical_path", out["vertical_path"],
                                 "a path to the record file of the vertical channel")
    if "vertical_ratio" in out:            # 0 is no vertical part: the case without the key
        vr = out["vertical_ratio"]
        if isinstance(vr, bool) or not isinstance(vr, (int, float, np.number)):
            raise ParameterError("motion.vertical_ratio", vr, "a number in [0, 3]")
        if vr == 0:
            del out["vertical_ratio"]
    return {k: out[k] for k in sorted(out)}


def case_id(case: Mapping[str, Any]) -> str:
    """A stable 16-hex-digit hash of the normalized case (the store's key,
    :func:`rockbench.sweep.store.key`): the same case gets the same id in any process, on any
    machine, in any key order."""
    return key(normalize_case(case))


def scene_name(case: dict[str, Any]) -> str:
    """The case's scene as text: its name or path (a scene table: its ``name``)."""
    sc = case["scene"]
    return str(sc.get("name") or "scene") if isinstance(sc, dict) else sc


def load_case_scene(case: dict[str, Any]):
    """The Scene of a normalized case (a name or path with its overrides, or a table)."""
    from ..scene.scene import Scene, apply_overrides, load_scene

    sc = case["scene"]
    if isinstance(sc, dict):
        data = apply_overrides(dict(sc), case["overrides"]) if case["overrides"] else sc
        return Scene.from_dict(data, source=f"scene {scene_name(case)!r}")
    return load_scene(sc, case["overrides"] or None)


def flatten_case(case: dict[str, Any]) -> dict[str, Any]:
    """scene (a table: its name), overrides.<k>, engine, settings.<k>, motion.kind,
    motion.<k>, phi0, duration."""
    out: dict[str, Any] = {"scene": scene_name(case)}
    for k, v in case["overrides"].items():
        out[f"overrides.{k}"] = v
    out["engine"] = case["engine"]
    for k, v in case["settings"].items():
        out[f"settings.{k}"] = v
    m = case["motion"]
    out["motion.kind"] = "none" if m is None else m["kind"]
    for k, v in (m or {}).items():
        if k != "kind":
            out[f"motion.{k}"] = v
    out["phi0"] = case["phi0"]
    out["duration"] = case["duration"]
    return out


def case_label(case: dict[str, Any]) -> str:
    """A short human label (progress bars): engine, scene, the motion's label."""
    mot = motion_label(case["motion"])
    if case["motion"] is None:
        mot += f" phi0={case['phi0']:.3g} rad"
    return f"{case['engine']} {Path(scene_name(case)).stem} {mot}"


# =========================================================================================
# Grids
# =========================================================================================
def _as_list(x: Any, name: str) -> list:
    if isinstance(x, (str, int, float, np.number)):
        return [x]
    try:
        out = list(x)
    except TypeError:
        raise ParameterError(name, x, "a value or a list of values") from None
    if not out:
        raise ParameterError(name, x, "at least one value")
    return out


def pulse_grid(scene: str | Path, shapes, signs, A_values, W_values, engines, *,
               overrides: Mapping[str, Any] | None = None,
               settings: Mapping[str, Mapping[str, Any]] | None = None, phi0: float = 0.0,
               duration: float | None = None) -> list[dict[str, Any]]:
    """Cases of a Ricker-pulse map: every engine x shape x sign x A x W.

    ``scene`` a built-in name or a .toml path; ``shapes`` "symmetric"/"antisymmetric" (or a list);
    ``signs`` +1/-1 (or a list); ``A_values`` = a_g / (g tan alpha) > 0 and ``W_values`` =
    omega_g / p > 0 (lists, alpha and p of the taller column); ``engines`` a name or a list;
    ``settings`` maps an engine name to its setting overrides; ``duration`` [s] (None: pulse
    length + 10 s).
    """
    if not isinstance(scene, (str, os.PathLike)):
        raise ParameterError("scene", scene, "a built-in scene name or a path (cases are data)")
    engines_l = _as_list(engines, "engines")
    settings = dict(settings or {})
    unknown = set(settings) - set(engines_l)
    if unknown:
        raise ParameterError("settings", sorted(unknown)[0], f"keyed by one of the engines "
                                                            f"{engines_l}")
    for a in _as_list(A_values, "A_values"):
        if not float(a) > 0:
            raise ParameterError("A_values", a, "> 0")
    for w in _as_list(W_values, "W_values"):
        if not float(w) > 0:
            raise ParameterError("W_values", w, "> 0")
    cases = []
    for eng, shape, sign, A, W in product(engines_l, _as_list(shapes, "shapes"),
                                          _as_list(signs, "signs"), _as_list(A_values, "A_values"),
                                          _as_list(W_values, "W_values")):
        case = {"scene": os.fspath(scene), "overrides": dict(overrides or {}), "engine": eng,
                "settings": dict(settings.get(eng, {})),
                "motion": {"kind": "ricker", "shape": shape, "sign": int(sign), "A": float(A),
                           "W": float(W)},
                "phi0": float(phi0), "duration": duration}
        cases.append(normalize_case(case))
    return cases


# =========================================================================================
# The catalogue (rockbench/scenarios/cases.toml)
# =========================================================================================
class FreeCase(NamedTuple):
    """Free rocking of ``scene`` from phi0 = ``phi0`` alpha for ``duration`` seconds."""

    scene: str
    duration: float
    phi0: float = 0.5

    @property
    def id(self) -> str:
        return f"free-{self.scene}"

    def load(self):
        from ..scene import load_scene
        return load_scene(self.scene)

    def kwargs(self, scene) -> dict:
        """Keyword arguments of ``rockbench.run`` (besides scene and engine)."""
        return dict(motion=None, duration=self.duration, phi0=self.phi0 * scene.alpha)


class PulseCase(NamedTuple):
    """``scene`` under the Ricker pulse (A, W, shape, sign), from -3 T_g to ``end`` seconds
    after the pulse centre; ``fall`` (a multiple of alpha, or None for the scene's own)
    overrides the scene's fall angle."""

    scene: str
    A: float
    W: float
    shape: str
    sign: int
    end: float
    fall: float | None = None

    @property
    def id(self) -> str:
        return (f"{self.scene}-A{self.A:.4g}-W{self.W:g}-{self.shape[:4]}"
                f"{'+' if self.sign > 0 else '-'}")

    def load(self):
        from ..scene import load_scene
        scene = load_scene(self.scene)
        if self.fall is not None:
            scene = scene.replace(fall_angle=self.fall * scene.alpha)
        return scene

    def pulse(self, scene):
        from ..scene.motion import RickerPulse
        return RickerPulse.dimensionless(self.A, self.W, scene.structure, self.shape, self.sign)

    def kwargs(self, scene) -> dict:
        p = self.pulse(scene)
        return dict(motion=p, duration=self.end - p.t_start)


@dataclass(frozen=True)
class Catalogue:
    """The named cases of ``rockbench/scenarios/cases.toml`` (its comments say why each was
    chosen). Cross-engine cases: ``free_cases``, ``survive_cases``, ``overturn_cases`` and the
    constants they are made of;
    ``benchmarks``: the cases of ``benchmarks/run.py`` and ``benchmarks/mujoco_rollout.py``
    (plain data: label, scene, motion spec, phi0 [alpha], duration [s])."""

    pulses: tuple[tuple[str, int], ...]
    free_phi0: float
    nrmse_window: float
    free_durations: dict[str, float]
    survive_points: dict[str, tuple[tuple[float, float], ...]]
    survive_end: float
    overturn_w: dict[str, tuple[float, ...]]
    overturn_factor: float
    overturn_end: float
    overturn_fall: float
    overturn_thresholds: dict[tuple[str, float, str, int], float]
    benchmarks: dict[str, Any]

    @property
    def free_cases(self) -> list[FreeCase]:
        return [FreeCase(s, d, self.free_phi0) for s, d in self.free_durations.items()]

    @property
    def survive_cases(self) -> list[PulseCase]:
        return [PulseCase(s, A, W, shape, sign, self.survive_end)
                for s, points in self.survive_points.items() for A, W in points
                for shape, sign in self.pulses]

    @property
    def overturn_cases(self) -> list[PulseCase]:
        return [PulseCase(s, round(self.overturn_factor
                                   * self.overturn_thresholds[(s, W, shape, sign)], 4),
                          W, shape, sign, self.overturn_end, self.overturn_fall)
                for s, Ws in self.overturn_w.items() for W in Ws for shape, sign in self.pulses]


def _pairs(rows, kinds=(float, float)) -> tuple[tuple, ...]:
    return tuple(tuple(k(v) for k, v in zip(kinds, r, strict=True)) for r in rows)


@functools.lru_cache(maxsize=1)
def catalogue() -> Catalogue:
    """The case catalogue, read once from ``rockbench/scenarios/cases.toml``."""
    data = tomllib.loads((resources.files("rockbench") / "scenarios" / "cases.toml")
                        .read_text(encoding="utf-8"))
    x = data["cross_engine"]
    s, o = x["survive"], x["overturn"]
    return Catalogue(
        pulses=_pairs(x["pulses"], (str, int)), free_phi0=float(x["free_phi0"]),
        nrmse_window=float(x["nrmse_window"]),
        free_durations={k: float(v) for k, v in x["free_durations"].items()},
        survive_points={k: _pairs(v) for k, v in s["points"].items()},
        survive_end=float(s["end"]),
        overturn_w={k: tuple(map(float, v)) for k, v in o["W"].items()},
        overturn_factor=float(o["factor"]), overturn_end=float(o["end"]),
        overturn_fall=float(o["fall"]),
        overturn_thresholds={(r[0], float(r[1]), str(r[2]), int(r[3])): float(r[4])
                             for r in o["thresholds"]["rows"]},
        benchmarks=data["benchmarks"])

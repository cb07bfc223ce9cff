"""The names of the backends and where their adapters live: name -> ``"module:Class"``.

Plain data, importing no engine and no adapter, so that any layer (the report's colours and
order included) may read which backends exist; :mod:`rockbench.engines` resolves a name to its
class. Backends of this package are listed here; other distributions register theirs through
an entry point of the group :data:`ENTRY_POINT_GROUP` (:func:`discover_engines`, run when this
module is imported).
"""

from __future__ import annotations

__all__ = ["REGISTRY", "ENTRY_POINT_GROUP", "discover_engines", "REFERENCE"]

#: The registered backends. The analytic reference comes first.
REGISTRY: dict[str, str] = {
    "analytic": "rockbench.engines.analytic:AnalyticBackend",
    "pymunk": "rockbench.engines.pymunk:PymunkBackend",
    "mujoco": "rockbench.engines.mujoco:MujocoBackend",
    "pybullet": "rockbench.engines.pybullet:PybulletBackend",
    "opensees": "rockbench.engines.opensees:OpenseesBackend",
    "drake": "rockbench.engines.drake:DrakeBackend",
}

#: The entry-point group through which other distributions register backends.
ENTRY_POINT_GROUP = "rockbench.engines"


def discover_engines() -> dict[str, str]:
    """Add the backends other installed distributions register under
    :data:`ENTRY_POINT_GROUP` to :data:`REGISTRY` (run once when this module is imported; call
    it again after installing one in a running process); return the ones added. A name the
    package already registers is not replaced: a warning names the distribution."""
    import warnings
    from importlib import metadata

    added: dict[str, str] = {}
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in REGISTRY:
            if REGISTRY[ep.name] != ep.value:
                from .errors import RockbenchWarning
                warnings.warn(f"engine {ep.name!r} of the entry point {ep.value!r} is not "
                              f"registered: the name is taken by {REGISTRY[ep.name]!r}",
                              RockbenchWarning, stacklevel=2)
            continue
        REGISTRY[ep.name] = added[ep.name] = ep.value
    return added


#: The analytic reference's name (the registry's first entry).
REFERENCE = next(iter(REGISTRY))

discover_engines()

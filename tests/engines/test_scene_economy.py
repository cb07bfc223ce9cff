"""Model only what a scene requires, in every backend: a block is one body, a frame three; a
free-standing scene builds no tendon, damper or device force; a hybrid scene builds them."""

from __future__ import annotations

import pytest

import rockbench as rb
from rockbench.testing import engine_params
from rockbench.engines import get_backend

ENGINES = engine_params(names=["pymunk", "mujoco", "pybullet"])
COMPILED = engine_params(names=["pymunk", "mujoco"])


def _count(engine: str, b) -> dict:
    """Bodies, constraints/tendons and damping elements an engine adapter built."""
    if engine == "pymunk":
        return {"bodies": len(b._space.bodies), "constraints": len(b._space.constraints),
                "devices": 0}
    if engine == "mujoco":
        m = b.model
        return {"bodies": m.nbody - 1, "constraints": m.neq,
                "devices": int(m.ntendon) + int((m.dof_damping != 0).sum())}
    import pybullet as pb
    n = pb.getNumBodies(physicsClientId=b._cid)
    return {"bodies": n - len(b._static), "constraints": pb.getNumConstraints(
        physicsClientId=b._cid), "devices": 0}


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name, bodies, devices", [("housner-block", 1, False),
                                                   ("paper-asymmetric", 3, False),
                                                   ("paper-asymmetric-hybrid-eps1", 3, True)])
def test_each_engine_builds_only_what_the_scene_has(engine, name, bodies, devices):
    scene = rb.load_scene(name)
    b = get_backend(engine)(scene)
    b.build(0.01)
    try:
        c = _count(engine, b)
    finally:
        b._close()
    assert c["bodies"] == bodies
    assert c["constraints"] == 0
    if engine == "mujoco":                       # native tendons exist only with devices
        assert (c["devices"] > 0) == devices


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name, devices", [("paper-asymmetric", False),
                                           ("paper-asymmetric-hybrid", True)])
def test_the_loop_computes_device_forces_only_for_a_scene_with_devices(engine, name, devices,
                                                                       monkeypatch):
    from rockbench.engines import devices as D

    calls = {"forces": 0}
    real = D.DeviceGeometry.forces

    def counted(self, state):
        calls["forces"] += 1
        return real(self, state)

    monkeypatch.setattr(D.DeviceGeometry, "forces", counted)
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1)
    cls = get_backend(engine)
    seen = []
    orig = cls._step

    def spy(self, gx, forces):
        seen.append(len(forces))
        return orig(self, gx, forces)

    monkeypatch.setattr(cls, "_step", spy)
    python_loop = {"loop": "python"} if engine in ("pymunk", "mujoco") else {}
    r = rb.run(scene, pulse, engine=engine, duration=0.3, **python_loop)
    assert r.ok
    native = getattr(r.settings, "get", lambda *_: None)("devices") == "native"
    if not devices:
        assert calls["forces"] == 0 and max(seen) == 0
    elif not native:
        assert calls["forces"] > 0 and max(seen) > 0


@pytest.mark.parametrize("engine", COMPILED)
@pytest.mark.parametrize("name, devices", [("paper-asymmetric", False),
                                           ("paper-asymmetric-hybrid", True)])
def test_the_compiled_loop_gets_device_parameters_only_for_a_scene_with_devices(
        engine, name, devices, monkeypatch):
    from rockbench.engines import device_kernel as K

    calls = []
    real = K.device_params
    monkeypatch.setattr(K, "device_params", lambda d: calls.append(d) or real(d))
    scene = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1)
    r = rb.run(scene, pulse, engine=engine, duration=0.3)
    assert r.ok and r.cost.steps > 0
    assert len(calls) == (1 if devices else 0)

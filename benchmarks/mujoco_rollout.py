"""Ground motion in MuJoCo: gravity set every step (the backend) versus ``mujoco.rollout``.

The backend applies the ground acceleration as a time-varying gravity vector, set from Python
before every ``mj_step``. An equivalent that runs a whole pulse in C is ``mujoco.rollout`` with
the horizontal inertia force -m_i u_g''(t + dt/2) of every body as an open-loop generalized force
on its slide-x joint (``control_spec = mjSTATE_QFRC_APPLIED``, no actuators needed). This script
checks that the two give the same motion and times them, for a scene without devices (with
devices the per-step work of the shared loop -- fracture, damper coefficients -- needs Python
between steps, so rollout could only run between such events).

Usage: ``python benchmarks/mujoco_rollout.py [SCENE] [A] [W]`` (default: ``[benchmarks] rollout``
of rockbench's case catalogue, paper-asymmetric 6 6).
"""

from __future__ import annotations

import sys
import time

import numpy as np

import rockbench as rb
from rockbench.engines.mujoco import MujocoBackend
from rockbench.sweep.cases import catalogue


def main(argv=None):
    import mujoco
    from mujoco import rollout

    argv = sys.argv[1:] if argv is None else argv
    default = catalogue().benchmarks["rollout"]
    name = argv[0] if argv else default["scene"]
    A = float(argv[1]) if len(argv) > 1 else float(default["A"])
    W = float(argv[2]) if len(argv) > 2 else float(default["W"])
    sc = rb.load_scene(name)
    pulse = rb.RickerPulse.dimensionless(A, W, sc.structure, "symmetric", 1)
    duration = pulse.t_end - pulse.t_start + float(default["tail"])

    # 1. the backend (shared loop, gravity set every step)
    t = time.perf_counter()
    res = rb.run(sc, pulse, engine="mujoco", duration=duration)
    total = time.perf_counter() - t
    dt = res.settings["dt"]

    # 2. the same model stepped from Python (gravity every step), states recorded
    b = MujocoBackend(sc)
    m = b.compile(0.0)
    d = b.data
    n = int(round(duration / dt))
    times = pulse.t_start + dt * (np.arange(n) + 0.5)
    acc = np.array([pulse.acceleration(x) for x in times])
    phi_loop = np.empty(n)
    t = time.perf_counter()
    for k in range(n):
        m.opt.gravity[0] = -acc[k]
        mujoco.mj_step(m, d)
        phi_loop[k] = d.qpos[2]
    loop_s = time.perf_counter() - t

    # 3. rollout: gravity fixed at (0, -g), inertia force on every slide-x joint
    m2 = b.compile(0.0)
    m2.opt.gravity[0] = 0.0
    d2 = mujoco.MjData(m2)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    x0 = np.empty(mujoco.mj_stateSize(m2, spec))
    mujoco.mj_getState(m2, b.data, x0, spec)
    masses = np.array([sp.mass for sp in b.specs])
    ctrl = np.zeros((n, m2.nv))
    ctrl[:, 0::3] = -acc[:, None] * masses[None, :]
    t = time.perf_counter()
    states, _ = rollout.rollout(m2, d2, x0[None, :], ctrl[None],
                                control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED)
    roll_s = time.perf_counter() - t
    iq = 1 + 2  # state layout of FULLPHYSICS: time, qpos...; qpos[2] is phi
    phi_roll = states[0, :, iq]

    alpha = sc.alpha
    print(f"scene {name}, symmetric Ricker pulse A={A:g} W={W:g}, {n} steps of {dt:g} s")
    print(f"backend run (shared loop, total wall): {total:.3f} s, stepping only "
          f"{res.cost.wall_s:.3f} s (real-time factor {res.cost.sim_time / res.cost.wall_s:.0f})")
    print(f"mj_step loop with gravity every step: {loop_s:.3f} s "
          f"(real-time factor {duration / loop_s:.0f})")
    print(f"mujoco.rollout with slide-x forces:   {roll_s:.3f} s "
          f"(real-time factor {duration / roll_s:.0f})")
    print(f"max |phi_rollout - phi_loop| / alpha = {np.max(np.abs(phi_roll - phi_loop)) / alpha:.2e}")
    print(f"peak |phi| / alpha: loop {np.max(np.abs(phi_loop)) / alpha:.4f}, rollout "
          f"{np.max(np.abs(phi_roll)) / alpha:.4f}, backend {res.summary.max_abs_phi_over_alpha:.4f}")


if __name__ == "__main__":
    main()

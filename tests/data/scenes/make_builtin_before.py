"""Snapshot (tests/data/scenes/builtin_before.json; the script that wrote it is in tests/scene/test_scene_format.py's docstring) of every built-in scene computed by the code before the scene-format change."""
import json, math, subprocess
from rockbench.scene.scene import builtin_scenes, load_scene
from rockbench.analytic.reference import Reference

out = {"commit": subprocess.check_output(["git", "rev-parse", "HEAD"], text=True).strip(), "scenes": {}}
for name in builtin_scenes():
    sc = load_scene(name)
    st = sc.structure
    d = {"to_dict": sc.to_dict(), "fall_angles": {str(k): v for k, v in sc.fall_angles.items()}}
    q = {}
    names = (["b", "H", "R", "alpha", "p", "mass", "inertia_cm", "eta_housner"] if st.kind == "block" else
             ["b", "H", "H1", "h", "L", "step", "R0", "R1", "alpha", "alpha1", "p", "mass_left", "mass_right",
              "mass_beam", "inertia_left", "inertia_right", "inertia_beam", "gamma"])
    for n in names:
        q[n] = getattr(st, n)
    if st.kind == "frame":
        q["com_left"], q["com_right"], q["com_beam"] = st.com_left, st.com_right, st.com_beam
        for s in (1, -1):
            q[f"pivots_{s}"] = st.pivots(s)
            q[f"beam_offset_{s}"] = st.beam_offset(s)
    d["structure"] = q
    if sc.devices is not None:
        d["devices"] = sc.devices.to_dict()
    c = Reference(sc).constants()
    d["reference"] = {k: v for k, v in c.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    from rockbench.analytic.dynamics import Dynamics
    d["terms"] = {}
    for s in (1, -1):
        dyn = Dynamics(st, s, sc.devices)
        for f in (0.0, 0.5, 1.0):
            phi = s * f * st.alpha
            d["terms"][f"{s}:{f}"] = list(dyn.terms(phi))
    out["scenes"][name] = d
print(json.dumps(out, indent=1, sort_keys=True))

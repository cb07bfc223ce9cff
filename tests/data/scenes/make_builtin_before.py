"""Numbers of every built-in scene (structure, devices, analytic constants, equation-of-motion
terms), as the code computes them.

``builtin_before.json`` beside this file was written by this script with the code of commit
c34a4e7, before the scene format changed (no paper defaults, beam_mass, physical ranges):
``python tests/data/scenes/make_builtin_before.py > tests/data/scenes/builtin_before.json``.
tests/scene/test_scene_format.py recomputes :func:`snapshot` with today's code and requires the
same numbers, so that the paper's scenes build the same structures as before.
"""
import json
import subprocess


def snapshot() -> dict:
    from rockbench.analytic.dynamics import Dynamics
    from rockbench.analytic.reference import Reference
    from rockbench.scene.scene import builtin_scenes, load_scene

    scenes = {}
    for name in builtin_scenes():
        sc = load_scene(name)
        st = sc.structure
        d = {"to_dict": sc.to_dict(),
             "fall_angles": {str(k): v for k, v in sc.fall_angles.items()}}
        names = (["b", "H", "R", "alpha", "p", "mass", "inertia_cm", "eta_housner"]
                 if st.kind == "block" else
                 ["b", "H", "H1", "h", "L", "step", "R0", "R1", "alpha", "alpha1", "p",
                  "mass_left", "mass_right", "mass_beam", "inertia_left", "inertia_right",
                  "inertia_beam", "gamma"])
        q = {n: getattr(st, n) for n in names}
        if st.kind == "frame":
            q["com_left"], q["com_right"], q["com_beam"] = st.com_left, st.com_right, st.com_beam
            for s in (1, -1):
                q[f"pivots_{s}"] = st.pivots(s)
                q[f"beam_offset_{s}"] = st.beam_offset(s)
        d["structure"] = q
        if sc.devices is not None:
            d["devices"] = sc.devices.to_dict()
        c = Reference(sc).constants()
        d["reference"] = {k: v for k, v in c.items()
                          if isinstance(v, (int, float)) and not isinstance(v, bool)}
        d["terms"] = {}
        for s in (1, -1):
            dyn = Dynamics(st, s, sc.devices)
            for f in (0.0, 0.5, 1.0):
                d["terms"][f"{s}:{f}"] = list(dyn.terms(s * f * st.alpha))
        scenes[name] = d
    # JSON's view (tuples as lists, int keys as strings), as the committed file holds it
    return json.loads(json.dumps(scenes))


if __name__ == "__main__":
    commit = subprocess.check_output(["git", "rev-parse", "HEAD"], text=True).strip()
    print(json.dumps({"commit": commit, "scenes": snapshot()}, indent=1, sort_keys=True))

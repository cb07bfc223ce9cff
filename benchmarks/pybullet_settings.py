"""PyBullet backend: accuracy and speed against the analytic reference, per setting.

    python benchmarks/pybullet_settings.py [--sweep NAME ...] [--suite free|pulses|all]
                                           [--engine pybullet] [--csv PATH]

Every row is one variant of the pybullet settings (one or two fields changed from the
defaults, or a "trap": a Bullet default this backend overrides, restored on purpose), run on
the cross-engine cases of ``tests/engines/cases.py`` (the bars of issue 3):

* free rocking from phi0 = 0.5 alpha of housner-block, paper-symmetric, paper-asymmetric:
  ``eta`` the largest |eta / eta_analytic - 1| over the impacts, ``nrmse`` the largest RMS of
  (phi - phi_analytic) / alpha over the first 2 s;
* (``--suite pulses`` or ``all``) the 16 survive pulses (paper-asymmetric and
  paper-asymmetric-hybrid-eps1): ``peak`` the largest |max|phi| / max|phi_analytic| - 1|;
  and the 16 overturn pulses: ``overturned`` how many of them overturn;

with the largest penetration and sliding [m] of all those runs, the real-time factor
(simulated s / wall s of the stepping only, summed over the runs) and the status (the first
run that did not finish cleanly). ``--engine pymunk`` (or mujoco) runs the same cases at that
engine's defaults, for the side-by-side table of ``docs/engines/pybullet.md``. Timings depend
on the machine's load.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import rockbench as rb
from rockbench.compare import history_error
from rockbench.engines import pybullet as pbmod

_CASES_FILE = Path(__file__).resolve().parents[1] / "tests" / "engines" / "cases.py"


def _cases():
    """The cross-engine cases (tests/engines/cases.py), loaded by path."""
    spec = importlib.util.spec_from_file_location("_rockbench_cases", _CASES_FILE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


#: sweep name -> list of (label, settings overrides); keys starting with "_" are traps
SWEEPS: dict[str, list[tuple[str, dict]]] = {
    "default": [("defaults", {})],
    "dt": [(f"dt={v:g}", {"dt": v, "output_dt": max(v, 1e-3)})
           for v in (4e-3, 2e-3, 1e-3, 5e-4, 2e-4)],
    "dt_iterations": [(f"dt={d:g}, solver_iterations={n}",
                       {"dt": d, "output_dt": 1e-3, "solver_iterations": n})
                      for d in (1e-3, 5e-4, 2e-4) for n in (50, 100, 200)],
    "iterations": [(f"solver_iterations={v}", {"solver_iterations": v})
                   for v in (5, 10, 20, 50, 100)],
    "erp": [(f"contact_erp={v:g}", {"contact_erp": v})
            for v in (0.02, 0.05, 0.08, 0.1, 0.2, 0.5, 0.8)],
    "breaking": [(f"contact_breaking_threshold={v:g}", {"contact_breaking_threshold": v})
                 for v in (0.02, 5e-3, 1e-3, 1e-4)],
    "anchor": [(f"friction_anchor={v}", {"friction_anchor": v}) for v in (True, False)],
    "stiffness": [(f"contact_stiffness={k:g}, damping={c:g}",
                   {"contact_stiffness": k, "contact_damping": c})
                  for k, c in ((1e7, 1e5), (1e8, 1e6), (1e9, 1e7), (1e10, 1e8))],
    "solver": [("solver=si", {"solver": "si"}), ("solver=dantzig (rejected)", {"solver": "dantzig"}),
               ("solver=pgs (trap)", {"solver": "pgs"})],
    "damper": [(f"damper={v}", {"damper": v}) for v in ("distributed", "couple", "heel")],
    "friction": [(f"friction={v:g}", {"friction": v}) for v in (0.6, 1.0, 2.0)],
    "traps": [("Bullet multibody damping 0.04 (trap)", {"_damping": 0.04}),
              ("friction=0.6 not square-rooted: pair 0.36 (trap)",
               {"friction": 0.6, "_raw_friction": True})],
}


class _TrapBackend(pbmod.PybulletBackend):
    """The backend with one Bullet default restored, to measure what overriding it buys."""

    trap: dict = {}

    def _build(self) -> None:
        super()._build()
        pb, cid = self._pb, self._cid
        if "_damping" in self.trap:
            d = float(self.trap["_damping"])
            for bid in self._bodies:
                pb.changeDynamics(bid, -1, linearDamping=d, angularDamping=d,
                                  physicsClientId=cid)
        if self.trap.get("_raw_friction"):
            mu = float(self.settings.friction)   # each body mu: the pair gets mu^2
            for bid in self._bodies:
                pb.changeDynamics(bid, 2, lateralFriction=mu, physicsClientId=cid)
            for bid in self._static:
                pb.changeDynamics(bid, -1, lateralFriction=mu, physicsClientId=cid)


def _run(scene, engine: str, over: dict, kwargs: dict):
    trap = {k: v for k, v in over.items() if k.startswith("_")}
    over = {k: v for k, v in over.items() if not k.startswith("_")}
    if engine == "pybullet" and trap:
        cls = type("Trap", (_TrapBackend,), {"trap": trap})
        kw = dict(kwargs)
        motion = kw.pop("motion")
        return cls(scene, **over).run(motion, **kw)
    return rb.run(scene, engine=engine, **kwargs, **over)


class _Row(dict):
    def add(self, r) -> None:
        if not r.ok:
            if self["status"] == "ok":
                self["status"] = f"{r.status}: {r.summary.reason}"
            return
        self["pen_max"] = max(self["pen_max"], float(r.summary.max_penetration))
        self["slide_max"] = max(self["slide_max"], float(r.summary.max_sliding))
        self["sim_s"] += r.cost.sim_time
        self["wall_s"] += r.cost.wall_s


def measure(engine: str, over: dict, suite: str, cases=None) -> dict:
    """One row of the table (see the module docstring) for ``engine`` with ``over``."""
    C = cases or _cases()
    row = _Row(eta_err_max=math.nan, nrmse_max=math.nan, peak_err_max=math.nan,
               overturned=math.nan, pen_max=0.0, slide_max=0.0, sim_s=0.0, wall_s=0.0,
               status="ok")
    etas, nrmses = [], []
    for case in C.FREE_CASES:
        sc = case.load()
        eta_ref = {1: rb.info(sc)["eta_ccw"], -1: rb.info(sc)["eta_cw"]}
        ref = rb.run(sc, engine="analytic", **case.kwargs(sc))
        r = _run(sc, engine, over, case.kwargs(sc))
        row.add(r)
        if not r.ok:
            continue
        imp = r.impacts()
        e = [abs(x / eta_ref[int(d)] - 1.0) for x, d in zip(imp["eta"], imp["direction"])]
        row[f"eta_err[{case.scene}]"] = max(e) if e else math.nan
        etas.append(row[f"eta_err[{case.scene}]"])
        t, d = history_error(r, ref)
        m = t <= t[0] + C.NRMSE_WINDOW + 1e-9
        nrmses.append(float(np.sqrt(np.mean(d[m] ** 2))))
        row[f"nrmse[{case.scene}]"] = nrmses[-1]
    row["eta_err_max"] = max(etas) if etas else math.nan
    row["nrmse_max"] = max(nrmses) if nrmses else math.nan
    if suite in ("pulses", "all"):
        peaks = []
        for case in C.SURVIVE_CASES:
            sc = case.load()
            ref = rb.run(sc, engine="analytic", **case.kwargs(sc))
            r = _run(sc, engine, over, case.kwargs(sc))
            row.add(r)
            peaks.append(abs(r.summary.max_abs_phi_over_alpha
                             / ref.summary.max_abs_phi_over_alpha - 1.0) if r.ok else math.inf)
        row["peak_err_max"] = max(peaks)
        n = 0
        for case in C.OVERTURN_CASES:
            sc = case.load()
            r = _run(sc, engine, over, case.kwargs(sc))
            row.add(r)
            n += bool(r.ok and r.summary.overturned)
        row["overturned"] = f"{n}/{len(C.OVERTURN_CASES)}"
    row["rtf"] = row.pop("sim_s") / max(row.pop("wall_s"), 1e-12)
    return dict(row)


def _fmt(r: dict) -> str:
    if "eta_err_max" not in r:
        return f"| {r['variant']} | {r['status']} |"
    return (f"| {r['variant']} | {100 * r['eta_err_max']:.3f} | {r['nrmse_max']:.5f} | "
            f"{100 * r['peak_err_max']:.3f} | {r['overturned']} | "
            f"{1e3 * r['pen_max']:.3f} | {1e3 * r['slide_max']:.3f} | {r['rtf']:.1f} | "
            f"{r['status']} |")


HEADER = ("| variant | eta err max [%] | nrmse max [-] | peak err max [%] | overturned | "
          "penetration max [mm] | sliding max [mm] | real-time factor | status |\n"
          "|---|---|---|---|---|---|---|---|---|")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sweep", nargs="*", default=["default"], choices=list(SWEEPS))
    ap.add_argument("--suite", default="all", choices=("free", "pulses", "all"))
    ap.add_argument("--engine", default="pybullet")
    ap.add_argument("--csv", default=None, help="also write the table to this CSV file")
    a = ap.parse_args(argv)
    # the rejected solvers, on purpose
    pbmod._SOLVERS.setdefault("dantzig", "CONSTRAINT_SOLVER_LCP_DANTZIG")
    pbmod._SOLVERS.setdefault("pgs", "CONSTRAINT_SOLVER_LCP_PGS")
    cases = _cases()
    rows = []
    sweeps = a.sweep if a.engine == "pybullet" else ["default"]
    print(HEADER, flush=True)
    for sw in sweeps:
        for label, over in SWEEPS[sw]:
            try:
                row = measure(a.engine, dict(over), a.suite, cases)
            except Exception as e:  # a bad variant is a row, not a crash
                row = {"status": f"error: {type(e).__name__}: {e}"}
            label = label if a.engine == "pybullet" else f"{a.engine} defaults"
            row = {"sweep": sw, "variant": label, **row}
            rows.append(row)
            print(_fmt(row), flush=True)
    if a.csv:
        pd.DataFrame(rows).to_csv(a.csv, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())

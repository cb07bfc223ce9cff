"""PyBullet backend: accuracy and speed against the analytic reference, per setting.

    python benchmarks/pybullet_settings.py [--sweep NAME ...] [--pulses] [--engine pybullet]
                                           [--csv PATH]

Every row is one variant of the pybullet settings (one field changed from the defaults, or a
"trap": a Bullet default this backend overrides, restored on purpose) measured on

* free rocking from phi0 = 0.5 alpha of housner-block, paper-symmetric and paper-asymmetric
  (5 s): the largest |eta / eta_analytic - 1| over the impacts whose following excursion is
  complete (all but the last), and the RMS of (phi - phi_analytic) / alpha over the first 2 s;
* with ``--pulses``: 8 Ricker pulses on paper-asymmetric (symmetric and antisymmetric, both
  signs, at (A, W) = (3, 4) and (3.5, 4), where the analytic frame survives with max |phi| /
  alpha in 0.3..0.8): the largest |max|phi| / max|phi_analytic| - 1|;

and reports the largest penetration and sliding (m) of those runs, the real-time factor
(simulated s / wall s of the stepping only) and the status. ``--engine pymunk`` runs the same
cases on another engine at its defaults (side-by-side numbers for docs/engines/pybullet.md).
Timings depend on the machine's load.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
import pandas as pd

import rockbench as rb
from rockbench.compare import history_error
from rockbench.engines import pybullet as pbmod

FREE_SCENES = ("housner-block", "paper-symmetric", "paper-asymmetric")
PULSE_POINTS = ((3.0, 4.0), (3.5, 4.0))

#: sweep name -> list of (label, settings overrides)
SWEEPS: dict[str, list[tuple[str, dict]]] = {
    "default": [("defaults", {})],
    "dt": [(f"dt={v:g}", {"dt": v, "output_dt": max(v, 1e-3)})
           for v in (4e-3, 2e-3, 1e-3, 5e-4, 2e-4)],
    "dt_iterations": [(f"dt={d:g}, solver_iterations={n}",
                       {"dt": d, "output_dt": 1e-3, "solver_iterations": n})
                      for d in (1e-3, 5e-4, 2e-4) for n in (50, 100, 200)],
    "breaking": [(f"contact_breaking_threshold={v:g}", {"contact_breaking_threshold": v})
                 for v in (0.02, 5e-3, 1e-3, 1e-4)],
    "anchor": [(f"friction_anchor={v}", {"friction_anchor": v}) for v in (True, False)],
    "iterations": [(f"solver_iterations={v}", {"solver_iterations": v})
                   for v in (5, 10, 20, 50, 100)],
    "erp": [(f"contact_erp={v:g}", {"contact_erp": v}) for v in (0.05, 0.08, 0.1, 0.2, 0.5, 0.8)],
    "stiffness": [(f"contact_stiffness={k:g}", {"contact_stiffness": k, "contact_damping": c})
                  for k, c in ((1e7, 1e5), (1e8, 1e6), (1e9, 1e7), (1e10, 1e8))],
    "solver": [("solver=si", {"solver": "si"}), ("solver=dantzig", {"solver": "dantzig"}),
               ("solver=pgs (trap)", {"solver": "pgs"})],
    "friction": [(f"friction={v:g}", {"friction": v}) for v in (0.5, 1.0, 2.0)],
    "traps": [("Bullet multibody damping 0.04 (trap)", {"_damping": 0.04}),
              ("friction=0.6, not square-rooted: pair 0.36 (trap)",
               {"friction": 0.6, "_raw_friction": True}),
              ("friction=0.6", {"friction": 0.6})],
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


def _run(scene, motion, engine, over, duration, phi0=0.0):
    trap = {k: v for k, v in over.items() if k.startswith("_")}
    over = {k: v for k, v in over.items() if not k.startswith("_")}
    if engine == "pybullet" and trap:
        cls = type("Trap", (_TrapBackend,), {"trap": trap})
        return cls(scene, **over).run(motion, duration=duration, phi0=phi0)
    return rb.run(scene, motion, engine=engine, duration=duration, phi0=phi0, **over)


def measure(engine: str, over: dict, pulses: bool) -> dict:
    row = {"eta_err_max": 0.0, "nrmse_max": 0.0, "peak_err_max": math.nan, "pen_max": 0.0,
           "slide_max": 0.0, "sim_s": 0.0, "wall_s": 0.0, "status": "ok"}
    for name in FREE_SCENES:
        sc = rb.load_scene(name)
        info = rb.info(sc)
        ref = rb.run(sc, engine="analytic", phi0=0.5 * sc.alpha, duration=5.0)
        r = _run(sc, None, engine, over, 5.0, 0.5 * sc.alpha)
        _collect(row, r)
        if not r.ok:
            continue
        imp = r.impacts()
        errs = [abs(e / (info["eta_ccw"] if d == 1 else info["eta_cw"]) - 1.0)
                for e, d in zip(imp["eta"].to_numpy()[:-1], imp["direction"].to_numpy()[:-1])]
        row[f"eta_err[{name}]"] = max(errs) if errs else math.nan
        row["eta_err_max"] = max(row["eta_err_max"], row[f"eta_err[{name}]"])
        t, d = history_error(r, ref)   # on the analytic output grid
        nr = float(np.sqrt(np.mean(d[t <= 2.0 + 1e-9] ** 2)))
        row[f"nrmse[{name}]"] = nr
        row["nrmse_max"] = max(row["nrmse_max"], nr)
    if pulses:
        sc = rb.load_scene("paper-asymmetric")
        worst = 0.0
        for A, W in PULSE_POINTS:
            for shape in ("symmetric", "antisymmetric"):
                for sign in (1, -1):
                    m = rb.RickerPulse.dimensionless(A, W, sc.structure, shape, sign)
                    dur = m.t_end - m.t_start + 3.0
                    ref = rb.run(sc, m, engine="analytic", duration=dur)
                    r = _run(sc, m, engine, over, dur)
                    _collect(row, r)
                    if r.ok:
                        worst = max(worst, abs(r.summary.max_abs_phi_over_alpha
                                               / ref.summary.max_abs_phi_over_alpha - 1.0))
        row["peak_err_max"] = worst
    row["rtf"] = row.pop("sim_s") / max(row.pop("wall_s"), 1e-12)
    return row


def _collect(row: dict, r) -> None:
    if not r.ok:
        row["status"] = f"{r.status}: {r.summary.reason}"
        return
    row["pen_max"] = max(row["pen_max"], float(r.summary.max_penetration))
    row["slide_max"] = max(row["slide_max"], float(r.summary.max_sliding))
    row["sim_s"] += r.cost.sim_time
    row["wall_s"] += r.cost.wall_s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sweep", nargs="*", default=list(SWEEPS), choices=list(SWEEPS))
    ap.add_argument("--pulses", action="store_true", help="also the 8 Ricker pulses")
    ap.add_argument("--engine", default="pybullet")
    ap.add_argument("--csv", default=None, help="write the table to this CSV file")
    a = ap.parse_args(argv)
    pbmod._SOLVERS.setdefault("pgs", "CONSTRAINT_SOLVER_LCP_PGS")  # the trap, on purpose
    rows = []
    sweeps = a.sweep if a.engine == "pybullet" else ["default"]
    for sw in sweeps:
        for label, over in SWEEPS[sw]:
            try:
                row = measure(a.engine, dict(over), a.pulses)
            except Exception as e:  # a bad variant is a row, not a crash
                row = {"status": f"error: {type(e).__name__}: {e}"}
            row = {"sweep": sw, "variant": label, **row}
            rows.append(row)
            print(_fmt(row), flush=True)
    if a.csv:
        pd.DataFrame(rows).to_csv(a.csv, index=False)
    return 0


def _fmt(r: dict) -> str:
    if "eta_err_max" not in r:
        return f"{r['sweep']:10s} {r['variant']:45s} {r['status']}"
    return (f"{r['sweep']:10s} {r['variant']:45s} eta {100 * r['eta_err_max']:6.3f} % "
            f"nrmse {r['nrmse_max']:.5f} peak {100 * r['peak_err_max']:6.3f} % "
            f"pen {1e3 * r['pen_max']:6.3f} mm slide {1e3 * r['slide_max']:7.3f} mm "
            f"rtf {r['rtf']:6.1f} {r['status']}")


if __name__ == "__main__":
    sys.exit(main())

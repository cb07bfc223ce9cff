"""What a scene's friction and a vertical ground motion cost in each engine, and how close the
sliding block comes to Newmark's (issue 38).

    python benchmarks/contact_cost.py [--repeat 3] [--out benchmarks/results]

Per engine and case, process CPU time (``time.process_time``: another process's load does not
enter) of a whole ``rb.run`` per simulated second, median of ``--repeat`` runs after one untimed
run (compilation, imports), with the min-max spread, for three variants of the same case:

* ``no friction given``: the scene as the rocking model has it (each engine's own friction,
  nothing slides);
* ``friction``: the scene's ``[contact] friction`` (the squat block slides; the frame's pivots
  and beam may slip);
* ``friction + vertical``: the same with a vertical Ricker pulse of half the horizontal
  amplitude, in phase (the ground moved vertically too).

Cases: a squat block (1 m x 1 m, b/h = 1) on mu = 0.3 under a Ricker pulse of 0.6 g, T_g = 0.5 s
(it slides 35 mm, 22 mm with the vertical pulse, and does not rock); the paper's asymmetric frame
on mu = beam_friction = 0.8 under a pulse that rocks it (A = 3, W = 4). For the block, each
engine's peak and permanent slip against Newmark's sliding block (exact; with the vertical
motion's normal force). Engine settings: the defaults, and MuJoCo with ``impedance = 0.999``
for the sliding block (its default 0.99 lets a block on mu = 0.8 tip: docs/engines/README.md).
Writes ``contact_cost.md`` with the machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from rockbench.analytic.sliding import sliding_response  # noqa: E402
from rockbench.constants import G  # noqa: E402
from rockbench.scene.contact import Contact  # noqa: E402
from rockbench.scene.motion import GroundMotion, RickerPulse  # noqa: E402
from run import machine_section  # noqa: E402


class WithVertical(GroundMotion):
    """A horizontal motion with a vertical component (``vertical``, positive up, same clock)."""

    def __init__(self, horizontal, vertical):
        self._h, self._v = horizontal, vertical
        self.t_start = min(horizontal.t_start, vertical.t_start)
        self.t_end = max(horizontal.t_end, vertical.t_end)

    @property
    def vertical(self):
        return self._v

    def acceleration(self, t):
        return self._h.acceleration(t)

    def knots(self, t0, t1):
        return self._h.knots(t0, t1)

    def max_abs_after(self, t):
        return self._h.max_abs_after(t)

    @property
    def peak(self):
        return self._h.peak

    def describe(self):
        return dict(self._h.describe(), vertical=self._v.describe())

    def scaled(self, factor):
        return WithVertical(self._h.scaled(factor), self._v.scaled(factor))


def cpu(fn, repeat: int):
    """((median, min, max) process CPU s of ``fn()`` over ``repeat`` calls after an untimed
    one, the last call's value)."""
    out = fn()
    xs = []
    for _ in range(repeat):
        c = time.process_time()
        out = fn()
        xs.append(time.process_time() - c)
    return (statistics.median(xs), min(xs), max(xs)), out


def cases():
    """(label, scene without friction, contact, horizontal pulse, vertical pulse, sliding mu)."""
    block = rb.Scene(rb.Block(width=1.0, height=1.0), name="squat block b/h = 1")
    h = RickerPulse(0.6 * G, 0.5)
    frame = rb.load_scene("paper-asymmetric")
    hf = rb.RickerPulse.dimensionless(3.0, 4.0, frame.structure, "symmetric", 1)
    vf = RickerPulse(0.5 * hf.amplitude, hf.period)
    return [("squat block, mu 0.3", block, Contact(0.3), h, RickerPulse(0.3 * G, 0.5), 0.3),
            ("paper-asymmetric, mu 0.8", frame, Contact(0.8, 0.8), hf, vf, None)]


SLIDING = {"mujoco": {"impedance": 0.999}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--engines", default=None, help="comma-separated (default: all available)")
    args = ap.parse_args(argv)
    load0 = os.getloadavg()[0]
    engines = (args.engines.split(",") if args.engines else
               [e for e in rb.available_backends() if e != "analytic"])
    lines = ["| case | engine | no friction given | friction | friction + vertical | "
             "x friction | x vertical | peak slip err % (flat / vertical) | final slip err % "
             "(flat / vertical) | status |", "|---|---|---|---|---|---|---|---|---|---|"]
    fmt = lambda c, d: f"{c[0] / d:.4g} ({c[1] / d:.3g}-{c[2] / d:.3g})"  # noqa: E731
    for label, scene, contact, h, v, mu in cases():
        duration = h.t_end - h.t_start + 1.0
        refs = ((sliding_response(h, mu).summary, sliding_response(h, mu, vertical=v).summary)
                if mu is not None else None)
        for eng in engines:
            kw = SLIDING.get(eng, {}) if mu is not None else {}
            rough = scene.replace(contact=contact)
            runs = [cpu(lambda s=s, m=m: rb.run(s, m, engine=eng, duration=duration, **kw),
                        args.repeat)
                    for s, m in ((scene, h), (rough, h), (rough, WithVertical(h, v)))]
            (c0, _), (c1, r1), (c2, r2) = runs
            err = "-", "-"
            if refs is not None:
                pk = [100 * (r.summary.max_sliding / f.max_abs_displacement - 1)
                      for r, f in ((r1, refs[0]), (r2, refs[1]))]
                fn = [100 * (r.history["sliding"].iloc[-1] / abs(f.final_displacement) - 1)
                      for r, f in ((r1, refs[0]), (r2, refs[1]))]
                err = f"{pk[0]:+.3f} / {pk[1]:+.3f}", f"{fn[0]:+.3f} / {fn[1]:+.3f}"
            lines.append(f"| {label} | {eng} | {fmt(c0, duration)} | {fmt(c1, duration)} | "
                         f"{fmt(c2, duration)} | {c1[0] / c0[0]:.3g} | {c2[0] / c1[0]:.3g} | "
                         f"{err[0]} | {err[1]} | {r1.summary.status} / {r2.summary.status} |")
            print(lines[-1], flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = ("# What a scene's friction and a vertical ground motion cost (issue 38)\n\n"
            f"Measured by `benchmarks/contact_cost.py --repeat {args.repeat}`: process CPU "
            "seconds of a whole `rb.run` per simulated second, median (min-max) of the repeats "
            "after an untimed run; `x friction` = friction / no friction given, `x vertical` "
            "= friction + vertical / friction (medians). Slip errors against Newmark's "
            "sliding block (exact), peak = `Summary.max_sliding`, final = the history's last "
            "slip; flat = horizontal pulse only, vertical = with the vertical pulse. Engine "
            "settings: defaults; MuJoCo `impedance = 0.999` on the sliding block.\n\n"
            + machine_section(load0) + "\n\n## Results\n\n" + "\n".join(lines) + "\n")
    (out / "contact_cost.md").write_text(text)
    print(f"wrote {out / 'contact_cost.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

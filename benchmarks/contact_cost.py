"""What a scene's friction and a vertical ground motion cost in each engine, and how close the
sliding block comes to Newmark's.

    python benchmarks/contact_cost.py [--repeat 3] [--out benchmarks/results]
    python benchmarks/contact_cost.py --render benchmarks/results/contact_cost.md

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
Writes ``contact_cost.md`` with the machine and a reading of the numbers, written by
:func:`reading` from the table (``--render FILE`` writes FILE again from its own table and
machine section, without running anything).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from rockbench.analytic.sliding import sliding_response  # noqa: E402
from rockbench.constants import G  # noqa: E402
from rockbench.scene.contact import Contact  # noqa: E402
from rockbench.scene.motion import RickerPulse, WithVertical  # noqa: E402
from run import machine_section  # noqa: E402



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


@dataclass(frozen=True)
class Row:
    """One line of the table: a case and an engine. Costs are (median, min, max) process CPU s
    per simulated second; ``x_friction`` and ``x_vertical`` the ratios of their medians (of the
    unrounded ones when measured); errors [%] are (flat, vertical) against Newmark's sliding
    block, None for the frame; ``status`` "flat / vertical"."""

    case: str
    engine: str
    plain: tuple[float, float, float]
    friction: tuple[float, float, float]
    vertical: tuple[float, float, float]
    x_friction: float
    x_vertical: float
    peak_err: tuple[float, float] | None
    final_err: tuple[float, float] | None
    status: str


HEADER = ("| case | engine | no friction given | friction | friction + vertical | x friction | "
          "x vertical | peak slip err % (flat / vertical) | final slip err % (flat / vertical) "
          "| status |")


def table(rows: list[Row]) -> str:
    """The results table (the stored form :func:`parse_table` reads back)."""
    def cost(c):
        return f"{c[0]:.4g} ({c[1]:.3g}-{c[2]:.3g})"

    def err(e):
        return "-" if e is None else f"{e[0]:+.3f} / {e[1]:+.3f}"

    lines = [HEADER, "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.case} | {r.engine} | {cost(r.plain)} | {cost(r.friction)} | "
                     f"{cost(r.vertical)} | {r.x_friction:.3g} | {r.x_vertical:.3g} | "
                     f"{err(r.peak_err)} | {err(r.final_err)} | {r.status} |")
    return "\n".join(lines)


_COST = re.compile(r"^\s*([-+0-9.eE]+) \(([-+0-9.eE]+)-([-+0-9.eE]+)\)\s*$")


def parse_table(text: str) -> list[Row]:
    """The rows of the results table in ``text`` (a ``contact_cost.md``)."""
    def cost(cell):
        m = _COST.match(cell)
        return tuple(float(x) for x in m.groups())

    def err(cell):
        cell = cell.strip()
        return None if cell == "-" else tuple(float(x) for x in cell.split(" / "))

    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 10 or cells[0] in ("case", "---") or not _COST.match(cells[2]):
            continue
        rows.append(Row(cells[0], cells[1], cost(cells[2]), cost(cells[3]), cost(cells[4]),
                        float(cells[5]), float(cells[6]), err(cells[7]), err(cells[8]),
                        cells[9]))
    return rows


def _overlap(a, b) -> bool:
    """Whether the min-max spreads of two (median, min, max) costs overlap."""
    return a[1] <= b[2] and b[1] <= a[2]


def _span(xs) -> str:
    return f"{min(xs):.2g}-{max(xs):.2g}"


def reading(rows: list[Row], machine: str = "") -> str:
    """The ``## Reading`` section: what the table says, every number from ``rows`` (and the
    load average from the ``machine`` section)."""
    out = ["## Reading (written by `benchmarks/contact_cost.py` from the table below)", ""]
    load = re.search(r"load average \(1 min\) before / after: ([0-9.]+) / ([0-9.]+)", machine)
    cores = re.search(r"^- cores: (\d+)", machine, re.M)
    if load:
        lo, hi = sorted(float(x) for x in load.groups())
        out.append(f"The machine was shared (load average {lo:g}-{hi:g}"
                   + (f" on {cores.group(1)} cores" if cores else "")
                   + "): read a ratio with the spreads of its two runs.")
        out.append("")
    n = len(rows)
    same = [r for r in rows if _overlap(r.plain, r.friction)]
    apart = [r for r in rows if r not in same]
    text = (f"* **The scene's friction.** `x friction` spans {_span([r.x_friction for r in rows])}"
            f" (median {statistics.median(r.x_friction for r in rows):.2f}); the runs with the "
            f"scene's friction overlap those without it, in their min-max spread, in {len(same)} "
            f"of {n} cases")
    text += (": a friction costs nothing measurable of its own (every engine builds one "
             "coefficient per contact pair, whatever the scene gives)." if not apart else
             "; not in " + ", ".join(f"{r.case}, {r.engine} (x{r.x_friction:.3g})"
                                     for r in apart) + ".")
    out.append(text)
    for case in dict.fromkeys(r.case for r in rows):
        group = [r for r in rows if r.case == case]
        same = [r for r in group if _overlap(r.friction, r.vertical)]
        apart = [r for r in group if r not in same]
        text = (f"* **A vertical ground motion, {case}.** `x vertical` spans "
                f"{_span([r.x_vertical for r in group])}; with and without it the runs overlap "
                f"in {len(same)} of {len(group)} engines")
        text += ("." if not apart else "; not for " + ", ".join(
            f"{r.engine} (x{r.x_vertical:.3g})" for r in apart) + ".")
        out.append(text)
    out.append("* **What a vertical ground motion adds to a step**: one gravity component (or "
               "nodal load, or generalized force) per body; a run under it is also another "
               "motion, whose cost per simulated second need not be the same.")
    judged = [r for r in rows if r.peak_err is not None]
    if judged:
        worst = []
        for r in judged:
            errs = [(abs(e[i]), e[i], "flat" if i == 0 else "with the vertical pulse")
                    for e in (r.peak_err, r.final_err) for i in (0, 1)]
            worst.append((max(errs), r))
        top = max(w[0][0] for w in worst)
        out.append(f"* **Accuracy against Newmark's sliding block** ({judged[0].case}; peak and "
                   f"permanent slip, flat and with the vertical pulse): every engine within "
                   f"{top:.2g} %; the largest error of each: " + ", ".join(
                       f"{r.engine} {w[1]:+.3g} % ({w[2]})" for w, r in worst) + ".")
    bad = [r for r in rows if r.status != "ok / ok"]
    out.append("* **Status**: " + ("every run ok." if not bad else ", ".join(
        f"{r.case}, {r.engine}: {r.status}" for r in bad) + "."))
    return "\n".join(out)


INTRO = ("Measured by `benchmarks/contact_cost.py --repeat {repeat}`: process CPU seconds of a "
         "whole `rb.run` per simulated second, median (min-max) of the repeats after an untimed "
         "run; `x friction` = friction / no friction given, `x vertical` = friction + vertical "
         "/ friction (medians). Slip errors against Newmark's sliding block (exact), peak = "
         "`Summary.max_sliding`, final = the history's last slip; flat = horizontal pulse only, "
         "vertical = with the vertical pulse. Engine settings: defaults; MuJoCo "
         "`impedance = 0.999` on the sliding block.")


def render(rows: list[Row], repeat: int, machine: str) -> str:
    """The whole ``contact_cost.md``: intro, machine, reading, table."""
    return ("# What a scene's friction and a vertical ground motion cost\n\n"
            + INTRO.format(repeat=repeat) + "\n\n" + machine.strip() + "\n\n"
            + reading(rows, machine) + "\n\n## Results\n\n" + table(rows) + "\n")


def rerender(path: Path) -> str:
    """``path`` (a ``contact_cost.md``) written again from its own table, repeat count and
    machine section."""
    text = path.read_text()
    repeat = int(re.search(r"--repeat (\d+)", text).group(1))
    machine = re.search(r"^## Machine\n.*?(?=^## )", text, re.S | re.M).group(0)
    return render(parse_table(text), repeat, machine)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--engines", default=None, help="comma-separated (default: all available)")
    ap.add_argument("--render", metavar="FILE", help="write FILE again from its own table "
                    "(the reading included), running nothing")
    args = ap.parse_args(argv)
    if args.render:
        Path(args.render).write_text(rerender(Path(args.render)))
        print(f"wrote {args.render}")
        return 0
    load0 = os.getloadavg()[0]
    engines = (args.engines.split(",") if args.engines else
               [e for e in rb.available_backends() if e != "analytic"])
    rows = []
    for label, scene, contact, h, v, mu in cases():
        duration = h.t_end - h.t_start + 1.0
        refs = ((sliding_response(h, mu).summary,
                 sliding_response(WithVertical(h, v), mu).summary) if mu is not None else None)
        for eng in engines:
            kw = SLIDING.get(eng, {}) if mu is not None else {}
            rough = scene.replace(contact=contact)
            runs = [cpu(lambda s=s, m=m: rb.run(s, m, engine=eng, duration=duration, **kw),
                        args.repeat)
                    for s, m in ((scene, h), (rough, h), (rough, WithVertical(h, v)))]
            (c0, _), (c1, r1), (c2, r2) = runs
            pk = fn = None
            if refs is not None:
                pk = tuple(100 * (r.summary.max_sliding / f.max_abs_displacement - 1)
                           for r, f in ((r1, refs[0]), (r2, refs[1])))
                fn = tuple(100 * (r.history["sliding"].iloc[-1] / abs(f.final_displacement) - 1)
                           for r, f in ((r1, refs[0]), (r2, refs[1])))
            per_s = [tuple(x / duration for x in c) for c in (c0, c1, c2)]
            rows.append(Row(label, eng, *per_s, c1[0] / c0[0], c2[0] / c1[0], pk, fn,
                            f"{r1.summary.status} / {r2.summary.status}"))
            print(table(rows[-1:]).splitlines()[-1], flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "contact_cost.md").write_text(render(rows, args.repeat, machine_section(load0)))
    print(f"wrote {out / 'contact_cost.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

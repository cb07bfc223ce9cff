"""What a decision costs the user: `rockbench report SCENE --quick` and `rockbench advise SCENE
--tolerance 0.02` (every engine, the default evidence), each a fresh process with a fresh
store, in process CPU time (user + system, children included), on structures written from
docs/scenes.md (``benchmarks/scenes/``), and what each decided.

    python benchmarks/decision.py [--repeat R] [--scene FILE ...] [--commands both|quick|advise]
                                  [--out DIR]

Writes ``decision.md`` (``decision_quick.md`` or ``decision_advise.md`` with ``--commands``):
per structure and command, the CPU time (median and range over the
repeats), the wall time, and the decision (per tolerance: the recommended engine and setting, or
nothing confirmed). The numba kernels are loaded from the cache before anything is timed: a
quick report of the first structure with the compiled engines runs first, untimed (a first run
of an installation compiles them once: ``startup.md``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

SCENES = tuple(HERE / "scenes" / f"{n}.toml" for n in ("stone-portal", "heavy-deck",
                                                     "precast-portal"))


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(argv: list[str], cwd: Path) -> tuple[float, float, str]:
    """(CPU s, wall s, stdout) of one command."""
    c0, w0 = _children_cpu(), time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "rockbench", *argv], capture_output=True,
                       text=True, cwd=cwd, env=dict(os.environ, ROCKBENCH_REQUIRE_ENGINES=""))
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed: {r.stderr[-800:]}")
    return _children_cpu() - c0, time.perf_counter() - w0, r.stdout


def quick_report(scene: Path) -> tuple[float, float, list[str]]:
    with tempfile.TemporaryDirectory() as tmp:
        cpu, wall, _ = timed(["report", str(scene), "--quick", "--out", "r", "--quiet"],
                             Path(tmp))
        import pandas as pd
        adv = pd.read_csv(Path(tmp) / "r" / "advice.csv")
    return cpu, wall, _answers(adv)


def advise(scene: Path) -> tuple[float, float, list[str]]:
    with tempfile.TemporaryDirectory() as tmp:
        cpu, wall, out = timed(["advise", str(scene), "--tolerance", "0.02", "--json",
                                "--quiet"], Path(tmp))
    j = json.loads(out)
    lines = []
    for a in j["answers"]:
        rec = a["recommended"]
        lines.append(f"{100 * a['tolerance']:g} %: " + (
            f"{rec['engine']} {rec['setting']} ({rec['cpu_per_sim_s']:.3g} CPU s/s)"
            if rec else "nothing confirmed"
            + (f"; next: {a['next_step']['engine']} {a['next_step']['setting']}"
               if a.get("next_step") else "")))
    return cpu, wall, lines


def _answers(adv) -> list[str]:
    out = []
    for tol, g in adv.groupby("tolerance", sort=False):
        r = g[g["recommended"].astype(bool)]
        out.append(f"{100 * tol:g} %: " + (f"{r.iloc[0]['engine']} {r.iloc[0]['setting']} "
                                          f"({float(r.iloc[0]['cpu_per_sim_s']):.3g} CPU s/s)"
                                          if len(r) else "nothing confirmed"))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--scene", action="append", default=None)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--commands", choices=("both", "quick", "advise"), default="both",
                    help="which commands to time (default both)")
    args = ap.parse_args(argv)
    from compiled_analytic import machine

    scenes = [Path(s).resolve() for s in args.scene] if args.scene else list(SCENES)
    with tempfile.TemporaryDirectory() as tmp:        # kernels into the JIT cache first:
        # every compiled kernel a decision loads (the analytic grid and run kernels, records,
        # the compiled engine loops), so that no timed command compiles one
        timed(["report", str(scenes[0]), "--quick", "--engine", "pymunk", "--engine", "mujoco",
               "--out", "warm", "--quiet"], Path(tmp))
    engines = subprocess.run([sys.executable, "-m", "rockbench", "engines", "--json"],
                             capture_output=True, text=True, cwd=ROOT).stdout
    ran = [e["name"] for e in json.loads(engines) if e["available"]]
    lines = ["# What a decision costs", "",
             "Measured by `benchmarks/decision.py`: each command a fresh process with a fresh "
             "store, process CPU time (user + system, children included) and wall time, "
             f"median (range, n = {args.repeat}).", "", "## Machine", ""]
    lines += [f"- {k}: {v}" for k, v in machine().items()]
    lines += [f"- engines that ran: {', '.join(ran)}", ""]
    lines += ["| structure | command | CPU s | wall s | decision |", "|:--|:--|--:|--:|:--|"]
    for scene in scenes:
        for name, fn in (("report SCENE --quick", quick_report),
                         ("advise SCENE --tolerance 0.02", advise)):
            if args.commands != "both" and not name.startswith(
                    "report" if args.commands == "quick" else "advise"):
                continue
            cpus, walls, said = [], [], []
            for _ in range(args.repeat):
                c, w, said = fn(scene)
                cpus.append(c)
                walls.append(w)
            lines.append(f"| {scene.stem} | `{name}` | {statistics.median(cpus):.0f} "
                         f"({min(cpus):.0f}-{max(cpus):.0f}) | {statistics.median(walls):.0f} "
                         f"| {'; '.join(said)} |")
            print(lines[-1], flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = "decision.md" if args.commands == "both" else f"decision_{args.commands}.md"
    (out / name).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())

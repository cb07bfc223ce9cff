"""What labelling a decision's evidence with the analytic model costs, and where it goes.

    python benchmarks/evidence_labels.py [--repeat 3] [--out DIR]

A decision's evidence (:func:`rockbench.studies.validation.validation_set`) is labelled by the
analytic model before any engine runs: every Ricker pulse's overturning threshold A_ov (a scan
and a bisection, about 13 verdicts per pulse and W), then each case's run and its sensitivity
band (about 9 perturbed runs per case, whose verdicts say whether the case is near the
boundary). Measured here, per scene, in this process, process CPU time
(``time.process_time``), median and min-max of ``--repeat`` interleaved passes after an
untimed one (compilation, imports, the scene's tabulated terms):

* the thresholds of every (W, pulse shape, sign) of the evidence, the same bisection
  (:func:`rockbench.studies.validation.bisect_threshold`) with two verdicts: a whole analytic
  run (``rb.run(method="compiled")``: history, events, the friction demand along the run)
  and the maps' kernel (``run_pulse_grid``: the verdict alone, what the evidence uses), each
  finishing a fall under way at the run's end (:mod:`rockbench.verdict`); how many thresholds
  agree, and the largest relative difference;
* the sensitivity-band runs of the evidence's pulse cases, with and without their friction
  demand (``simulate_compiled(assess_validity=...)``: a band reads verdicts and peaks only);
  the peaks agree to the last bit, the verdicts are the same;
* the whole default evidence (``validation_set(size="default")``) in a fresh process, once.

Writes ``evidence_labels.md`` with the machine.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rockbench as rb  # noqa: E402
from rockbench.analytic.compiled import simulate_compiled  # noqa: E402
from rockbench.analytic.solver import AnalyticSettings  # noqa: E402
from rockbench.run_length import run_length  # noqa: E402
from rockbench.studies import sensitivity as SE  # noqa: E402
from rockbench.studies import validation as V  # noqa: E402
from rockbench.studies.map_cells import reversed_mirrors  # noqa: E402
from run import machine_section  # noqa: E402

HERE = Path(__file__).resolve().parent
#: the scenes measured: the paper's decision scene, and two structures the package does not
#: ship as scenes (a block: docs/examples; a frame with sliding contacts: benchmarks/scenes)
SCENES = ("paper-asymmetric", str(HERE.parent / "docs" / "examples" / "museum-pedestal.toml"),
          str(HERE / "scenes" / "precast-portal.toml"))


def _pulses(scene):
    signs = (1,) if reversed_mirrors(scene, 0.0) else (1, -1)
    return [(W, shape, sign) for W in V.W_GRID for shape, sign in V._PULSES if sign in signs]


def thresholds(scene, verdict: str) -> list[float]:
    """A_ov of every pulse of the evidence with ``verdict`` "result" (a whole analytic run per
    verdict, ``rb.run(method="compiled")``, a fall under way finished by the backend) or
    "kernel" (the package's path: the maps' kernel, the fall finished the same way; its
    memory cache bypassed)."""
    sc = scene.replace(fall_angle=V._fall(scene))
    key = V._scene_key(scene)
    out = []
    for W, shape, sign in _pulses(scene):
        if verdict == "kernel":
            out.append(V._threshold.__wrapped__(key, W, shape, sign, 1e-3, 0.0))
            continue
        dur = run_length(V._pulse(sc, 1.0, W, shape, sign), V._OVER_TAIL, window="strong")

        def over(A, W=W, shape=shape, sign=sign, dur=dur):
            return bool(rb.run(sc, V._pulse(sc, A, W, shape, sign), engine="analytic",
                               duration=dur, method="compiled").summary.overturned)
        out.append(V.bisect_threshold(over, 1e-3))
    return out


def band_runs(scene, cases, validity: bool) -> list[tuple[float, bool]]:
    """(peak [rad], overturned) of every sensitivity-band run of the pulse ``cases``."""
    out = []
    for c in cases:
        sc0, motion = c.load(scene)
        for p in (None, *SE.PERTURBATIONS):
            if p is not None and p.kind == "phase":
                continue
            sc, mot, ef = (sc0, motion, 1.0) if p is None else SE.perturbed_case(sc0, motion, p)
            r = simulate_compiled(sc, mot, duration=c.duration, settings=AnalyticSettings(
                history="minimal", eta_factor=ef), assess_validity=validity)
            out.append((r.summary.max_abs_phi, bool(r.summary.overturned)))
    return out


def _fresh_evidence(scene: str) -> tuple[float, int]:
    """CPU s of ``validation_set(size="default")`` in a fresh process (imports and kernel
    loading excluded), and its case count."""
    code = ("import time, json, rockbench as rb\n"
            "from rockbench.studies.validation import validation_set\n"
            f"sc = rb.load_scene({scene!r})\n"
            "from rockbench.analytic.compiled import run_pulse_grid\n"
            "run_pulse_grid(rb.load_scene('paper-symmetric'), [('symmetric', 1, 2.0, 3.0)])\n"
            "c = time.process_time(); v = validation_set(sc, size='default')\n"
            "print(json.dumps([time.process_time() - c, len(v)]))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=dict(os.environ, PYTHONDONTWRITEBYTECODE="1"))
    cpu, n = json.loads(out.stdout.strip().splitlines()[-1])
    return float(cpu), int(n)


def _med(ts):
    return f"{statistics.median(ts):.3g} ({min(ts):.3g}-{max(ts):.3g})"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    load0 = os.getloadavg()[0]
    lines = ["| scene | part | runs | CPU s, old path, median (min-max) | CPU s, new path | "
             "old / new | agreement |", "|---|---|--:|--:|--:|--:|:--|"]
    for name in SCENES:
        scene = rb.load_scene(name)
        cases = [c for c in V.validation_set(scene, size="default")
                 if c.motion is not None and dict(c.motion).get("kind") == "ricker"]
        label = Path(name).stem
        variants = [lambda: thresholds(scene, "result"), lambda: thresholds(scene, "kernel"),
                    lambda: band_runs(scene, cases, True), lambda: band_runs(scene, cases, False)]
        res = [v() for v in variants]                       # untimed: kernels, tabulations
        times: list[list[float]] = [[] for _ in variants]
        for _ in range(args.repeat):
            for i, v in enumerate(variants):
                c = time.process_time()
                res[i] = v()
                times[i].append(time.process_time() - c)
        a, b = res[0], res[1]
        same = sum(x == y for x, y in zip(a, b))
        rel = max((abs(x / y - 1) for x, y in zip(a, b) if math.isfinite(x) and math.isfinite(y)),
                  default=0.0)
        lines.append(f"| {label} | thresholds: Result per verdict / maps' kernel | "
                     f"{len(a)} pulses | {_med(times[0])} | {_med(times[1])} | "
                     f"{statistics.median(times[0]) / statistics.median(times[1]):.3g} | "
                     f"{same} of {len(a)} equal, largest difference {100 * rel:.3g} % |")
        peaks = all(x[0] == y[0] and x[1] == y[1] for x, y in zip(res[2], res[3]))
        lines.append(f"| {label} | band runs of {len(cases)} pulse cases: with / without the "
                     f"friction demand | {len(res[2])} runs | {_med(times[2])} | "
                     f"{_med(times[3])} | "
                     f"{statistics.median(times[2]) / statistics.median(times[3]):.3g} | "
                     f"{'peaks and verdicts identical' if peaks else 'DIFFER'} |")
        cpu, n = _fresh_evidence(name)
        lines.append(f"| {label} | the default evidence, fresh process (new paths) | {n} cases | "
                     f"| {cpu:.3g} | | |")
        print("\n".join(lines[-3:]), flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = ("# What labelling a decision's evidence costs\n\n"
            f"Measured by `benchmarks/evidence_labels.py --repeat {args.repeat}` (the script's "
            "docstring says what each row is): process CPU time in one process, median "
            "(min-max) of interleaved passes after an untimed one; the last row of each scene "
            "once, in a fresh process. The old path of each part is what the evidence used "
            "before (a whole Result per verdict; the friction demand along every band run); "
            "the new path is what it uses now.\n\n"
            + machine_section(load0) + "\n\n## Results\n\n" + "\n".join(lines) + "\n")
    (out / "evidence_labels.md").write_text(text)
    print(f"wrote {out / 'evidence_labels.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Measure the slower engines' fragility runs into ``reports/fragility-engines`` (what
``rockbench report --full`` does for that folder, without the rest of the long campaign).

    python tools/measure_fragility_engines.py [--out reports] [--workers N]

The engines without a compiled stepping loop (PyBullet, OpenSees, Drake) run the default
report's fragility cells on the paper plan's Fig. 9 frames (``rockbench.campaign.
fragility_measured``); the default report then reuses them after re-running one per engine and
frame. Resumable: runs already in the folder for the same engine version are kept. About 20
minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="reports", help="the report folder (default reports)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes")
    args = ap.parse_args()

    from rockbench.campaign.fragility import fragility_section
    from rockbench.campaign.plan import campaign_plan
    from rockbench.engines import engine_states
    from rockbench.machine import tree_cpu_s
    from rockbench.sweep import store as S

    out = Path(args.out)
    names = [r["name"] for r in engine_states() if r["state"] == "ran"]
    c0, w0 = tree_cpu_s(), time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        sec = fragility_section(campaign_plan()["record_frames"], names, size="default",
                                store=S.store_path(out / "store", "fragility", keyed=False),
                                export_dir=tmp, measured=out / "fragility-engines",
                                measure=True, workers=args.workers, progress=True)
    if "error" in sec:
        raise SystemExit(sec["error"])
    for line in sec["provenance"]:
        print(line)
    print(f"{time.perf_counter() - w0:.0f} s wall, {tree_cpu_s() - c0:.0f} CPU s")


if __name__ == "__main__":
    main()

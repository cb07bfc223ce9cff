"""Command-line start-up cost, measured as process CPU time of fresh processes (issue 27 §5).

    python benchmarks/startup.py [--repeat 7] [--commit HEAD] [--before COMMIT] [--out DIR]

Each case runs ``--repeat`` times in a fresh Python process; the cost is the child's CPU time
(user + system, from ``getrusage(RUSAGE_CHILDREN)``), reported as the median with the range.
Cases: ``rockbench --help``; ``import rockbench``; a one-cell analytic map; a short analytic
``run``; a short pymunk ``run``. "warm": the compiled kernels are in the JIT cache
(``rockbench/_jit.py``); "cold": an empty cache folder (``ROCKBENCH_CACHE_DIR``), i.e. the
one-off compilation a new installation pays. ``--before COMMIT`` measures the same cases on
the sources of an older commit (exported with ``git archive``; its numba cache is the in-tree
``__pycache__``, emptied for the cold case), side by side. The table of imports (``python -X
importtime``, wall microseconds, cumulative) says where the rest goes.

Writes ``startup.md``; commit it with any change to imports or the JIT cache.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MAP = ["map", "paper-symmetric", "--grid", "1x1", "--pulses", "symmetric+", "--json"]
RUN = ["run", "housner-block", "--phi0-alpha", "0.3", "--duration", "1", "--json"]
PYMUNK = ["run", "housner-block", "--engine", "pymunk", "--phi0-alpha", "0.3", "--duration",
          "1", "--json"]


from run import cpu_name  # noqa: E402  (benchmarks/ is on sys.path when run)

_cpu = cpu_name   # one reader of the processor's name: benchmarks/run.py


def child_cpu(argv: list[str], env: dict, cwd: Path) -> float:
    """CPU seconds (user + system) of one child process running ``argv``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(argv, env=env, cwd=cwd, capture_output=True, text=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{proc.stderr}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cli_argv(src: Path, args: list[str], phi0_alpha: bool) -> list[str]:
    """``python -c`` running rockbench's CLI from the sources in ``src``."""
    if not phi0_alpha:   # older sources: --phi0 meant multiples of alpha
        args = ["--phi0" if a == "--phi0-alpha" else a for a in args]
    code = ("import sys; sys.path.insert(0, sys.argv[1])\n"
            "try:\n    from rockbench.cli.main import main\n"
            "except ImportError:   # sources before the cli/ package\n"
            "    from rockbench.cli import main\n"
            "raise SystemExit(main(sys.argv[2:]))")
    return [sys.executable, "-c", code, str(src), *args]


def measure(src: Path, repeat: int, work: Path) -> dict[str, list[float]]:
    """{case: [CPU s per repeat]} for the sources in ``src``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    cache = work / "jit-cache"
    env["ROCKBENCH_CACHE_DIR"] = str(cache)
    cli = src / "rockbench" / "cli"
    phi0_alpha = "phi0-alpha" in ((cli / "common.py") if cli.is_dir()
                                  else cli.with_suffix(".py")).read_text()
    out: dict[str, list[float]] = {}

    def clear_cache() -> None:
        shutil.rmtree(cache, ignore_errors=True)
        if src != ROOT:      # an exported commit: numba's in-tree cache (never the tree's)
            for p in (src / "rockbench").rglob("*.nb[ic]"):
                p.unlink()

    def case(name: str, args: list[str], n: int, cold: bool = False) -> None:
        times = []
        for i in range(n):
            if cold:
                clear_cache()
            store = work / f"store-{name}-{i}"
            a = [*args, "--store", str(store)] if args[:1] == ["map"] else args
            times.append(child_cpu(cli_argv(src, a, phi0_alpha), env, work))
            shutil.rmtree(store, ignore_errors=True)
        out[name] = times

    case("rockbench --help", ["--help"], repeat)
    out["import rockbench"] = [child_cpu([sys.executable, "-c", "import sys; sys.path.insert("
                                          "0, sys.argv[1]); import rockbench", str(src)],
                                         env, work) for _ in range(repeat)]
    case("map, 1 cell (cold: JIT compile)", MAP, 2, cold=True)
    case("map, 1 cell (warm)", MAP, repeat)
    case("run analytic, 1 s (warm)", RUN, repeat)
    case("run pymunk, 1 s (cold: JIT compile)", PYMUNK, 2, cold=True)
    case("run pymunk, 1 s (warm)", PYMUNK, repeat)
    return out


def imports(src: Path, work: Path) -> list[tuple[str, float]]:
    """Cumulative import time [ms, wall] of the top-level packages of a warm 1-cell map."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["ROCKBENCH_CACHE_DIR"] = str(work / "jit-cache")
    argv = cli_argv(src, [*MAP, "--store", str(work / "imports-store")], True)
    proc = subprocess.run([argv[0], "-X", "importtime", *argv[1:]], env=env, cwd=work,
                          capture_output=True, text=True, check=False)
    tops: dict[str, float] = {}
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cum, name = line.split("|")
        if name.startswith(" ") and not name.startswith("  "):   # depth 0
            try:
                tops[name.strip()] = tops.get(name.strip(), 0.0) + int(cum) / 1e3
            except ValueError:
                continue
    return sorted(tops.items(), key=lambda kv: -kv[1])[:10]


def export(commit: str, where: Path) -> Path:
    """The ``rockbench`` package of ``commit``, exported into ``where`` (returned)."""
    archive = subprocess.run(["git", "archive", commit, "rockbench"], cwd=ROOT,
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    return where


def summary(times: list[float]) -> str:
    return (f"{statistics.median(times):.3f} ({min(times):.3f}-{max(times):.3f}, "
            f"n={len(times)})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--commit", metavar="COMMIT", help="measure this commit's sources "
                    "(exported with git archive) instead of the working tree")
    ap.add_argument("--before", metavar="COMMIT", help="also measure this older commit")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        now = tmp / "now"
        now.mkdir()
        src = ROOT
        if args.commit:
            src = export(args.commit, now)
        after = measure(src, args.repeat, now)
        tops = imports(src, now)
        before = None
        if args.before:
            old = tmp / "old"
            old.mkdir()
            before = measure(export(args.before, old), args.repeat, old)

    head = subprocess.run(["git", "rev-parse", "--short", args.commit or "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip()
    head += "" if args.commit else " (working tree)"
    lines = ["# CLI start-up cost", "",
             f"`python benchmarks/startup.py --repeat {args.repeat}"
             f"{' --commit ' + args.commit if args.commit else ''}"
             f"{' --before ' + args.before if args.before else ''}` on "
             f"{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d %H:%M} UTC, commit {head}; "
             f"{_cpu()}, {os.cpu_count()} cores **shared with other jobs** (CPU time, not "
             f"wall time, is what is compared), Python {platform.python_version()}.", "",
             "Process CPU time [s] of a fresh process (user + system), median (range, "
             "repeats). cold = an empty JIT cache: the one-off compilation of a new "
             "installation; warm = every later call.", ""]
    header = "| case | now |" + (f" before ({args.before}) |" if before else "")
    lines += [header, "|---|---|" + ("---|" if before else "")]
    for name, times in after.items():
        row = f"| {name} | {summary(times)} |"
        if before:
            row += f" {summary(before[name])} |"
        lines.append(row)
    lines += ["", "Where a warm 1-cell map's imports go (`python -X importtime`, cumulative "
              "wall ms of the top-level imports, one run):", "",
              "| module | ms |", "|---|---|"]
    lines += [f"| {name} | {ms:.0f} |" for name, ms in tops]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "startup.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""Render the generated parts of the documentation from their one source, so that no number or
option is copied by hand (``make docs``; ``tests/test_docs.py`` fails when a committed page
differs from what this writes):

* ``docs/cli.md`` - the block between ``<!-- generated: cli -->`` and ``<!-- /generated -->``:
  every command's ``--help``, from the parser itself;
* ``docs/plans.md`` - the plan format, from :mod:`rockbench.campaign.plan_schema`;
* ``docs/report.md`` - the block ``campaign-files``: the campaign's CSV files and their
  columns, from :data:`rockbench.report.tables.CAMPAIGN_COLUMNS`;
* ``README.md`` - the blocks ``<!-- generated: NAME -->`` ... ``<!-- /generated -->``, from the
  report's tables (``reports/*.csv``) and the benchmarks' results (``benchmarks/results``):
  :mod:`rockbench.report.numbers` renders each block.

Usage: ``python tools/render_docs.py`` (writes the pages), ``--check`` (exit 1 and name the
pages that differ).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"(<!-- generated: (?P<name>[a-z0-9_-]+) -->\n)(?P<body>.*?)"
                   r"(<!-- /generated -->)", re.S)


def cli_reference() -> str:
    """Every command's help, as the parser prints it (80 columns)."""
    os.environ["COLUMNS"] = "100"
    from rockbench.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    out = []
    for name, p in sub.choices.items():
        out.append(f"### `rockbench {name}`\n\n```\n{p.format_help().rstrip()}\n```\n")
    return "\n".join(out)


#: Commands whose output docs/cli.md shows (deterministic: no timing in their output).
EXAMPLES = ("rockbench scenes",
            "rockbench info paper-asymmetric",
            "rockbench map paper-symmetric --grid 8x8 --pulses symmetric+ --store {tmp}/sym",
            "rockbench engines")


def cli_examples() -> str:
    """The commands of :data:`EXAMPLES`, run now, with their output."""
    import subprocess
    import tempfile

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for cmd in EXAMPLES:
            argv = cmd.format(tmp=tmp).split()
            r = subprocess.run([sys.executable, "-m", "rockbench", *argv[1:], "--quiet"]
                               if argv[1] == "map" else [sys.executable, "-m", "rockbench",
                                                         *argv[1:]],
                               capture_output=True, text=True, cwd=ROOT,
                               env=dict(os.environ, COLUMNS="100"))
            shown = cmd.replace("{tmp}/", "maps/")
            text = r.stdout.replace(tmp + "/", "maps/").rstrip()
            out.append(f"```\n$ {shown}\n{text}\n```\n")
    return "\n".join(out)


def campaign_files() -> str:
    """The campaign's CSV files and their columns with units, from
    :data:`rockbench.report.tables.CAMPAIGN_COLUMNS` (the one place they are defined)."""
    from rockbench.report.tables import CAMPAIGN_COLUMNS

    out = []
    for name, cols in CAMPAIGN_COLUMNS.items():
        out.append(f"**`{name}`**\n")
        for col, text in cols.items():
            unit, _, meaning = text.partition(", ")
            if col == "(then)":
                out.append(f"* then {text}")
            else:
                out.append(f"* `{col}` [{unit}]" + (f": {meaning}" if meaning else ""))
        out.append("")
    return "\n".join(out)


def blocks(name: str, root: Path = ROOT) -> str:
    """The text of one generated block."""
    if name == "cli":
        return cli_reference()
    if name == "campaign-files":
        return campaign_files()
    if name == "cli-examples":
        return cli_examples()
    from rockbench.report.numbers import render_block

    return render_block(name, root)


#: Blocks rendered only on request (``--examples``): their output is real, not compared.
ON_REQUEST = ("cli-examples",)


def fill(text: str, root: Path = ROOT, *, examples: bool = False) -> str:
    """``text`` with every generated block rendered anew (the on-request ones kept as they
    are unless ``examples``)."""
    def sub(m: re.Match) -> str:
        if m.group("name") in ON_REQUEST and not examples:
            return m.group(0)
        return m.group(1) + blocks(m.group("name"), root).rstrip() + "\n" + m.group(4)
    return BLOCK.sub(sub, text)


def pages(root: Path = ROOT, *, examples: bool = False) -> dict[Path, str]:
    """Every generated page and what it should hold."""
    from rockbench.campaign.plan_schema import markdown as plans

    out = {root / "docs" / "plans.md": plans()}
    for rel in ("README.md", "docs/cli.md", "docs/report.md"):
        p = root / rel
        out[p] = fill(p.read_text(encoding="utf-8"), root, examples=examples)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="only say which pages differ")
    ap.add_argument("--examples", action="store_true",
                    help="also run the commands of docs/cli.md's examples and paste their output")
    args = ap.parse_args(argv)
    stale = []
    for path, text in pages(examples=args.examples).items():
        if path.read_text(encoding="utf-8") != text:
            stale.append(path)
            if not args.check:
                path.write_text(text, encoding="utf-8")
    if args.check and stale:
        print("stale: " + ", ".join(str(p.relative_to(ROOT)) for p in stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

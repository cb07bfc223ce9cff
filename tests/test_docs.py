"""Every number told once: the generated parts of the documentation equal what their source
renders (tools/render_docs.py), the README quotes no result outside its generated blocks, and
the user documentation tells no project history (that is CHANGELOG.md's)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _tool():
    spec = importlib.util.spec_from_file_location("render_docs", ROOT / "tools" /
                                                  "render_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_every_generated_page_is_current():
    """README blocks (from reports/*.csv), docs/cli.md's reference (from the parser) and
    docs/plans.md (from the plan schema) equal what tools/render_docs.py writes."""
    tool = _tool()
    stale = [p.relative_to(ROOT).as_posix() for p, text in tool.pages().items()
             if p.read_text(encoding="utf-8") != text]
    assert not stale, f"run `python tools/render_docs.py`: {stale}"


def _prose(text: str) -> str:
    """``text`` without its code fences and generated blocks."""
    text = re.sub(r"```.*?```", " ", text, flags=re.S)
    return re.sub(r"<!-- generated: [a-z0-9_-]+ -->.*?<!-- /generated -->", " ", text,
                  flags=re.S)


#: A measured result written by hand: a number with a percentage, a CPU cost or a factor.
RESULT = re.compile(r"\d[\d.,]*\s*(?:%|CPU\s*s|x\s+(?:faster|slower|the|cheaper)|"
                    r"times (?:faster|slower|the))")


def test_the_readme_quotes_no_result_by_hand():
    bad = RESULT.findall(_prose((ROOT / "README.md").read_text(encoding="utf-8")))
    assert not bad, f"numbers outside the README's generated blocks: {bad}"


HISTORY = re.compile(r"\b(?:session \d+|this session|issue \d+|\(issue|before this|"
                     r"rounds? ago|in the last (?:note|session))", re.I)


@pytest.mark.parametrize("page", ["README.md"] + sorted(
    p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").rglob("*.md")))
def test_the_documentation_tells_what_is_true_now_not_its_history(page):
    text = (ROOT / page).read_text(encoding="utf-8")
    hits = [m.group(0) for m in HISTORY.finditer(text)]
    assert not hits, f"{page}: project history ({hits[:5]}); it belongs in CHANGELOG.md"


def test_a_planted_row_changes_the_readme():
    """The README's blocks are rendered from the tables: a planted advice row changes the
    decision sentence, a planted map row the agreement cell."""
    from rockbench.report.numbers import render_block

    root = ROOT
    text = render_block("results", root)
    adv = pd.read_csv(root / "reports" / "advice.csv")
    first = adv.iloc[0]
    assert str(first["engine"]) in text
    tmp = Path(pytest.importorskip("tempfile").mkdtemp())
    (tmp / "reports").mkdir()
    (tmp / "rockbench" / "scenarios").mkdir(parents=True)
    (tmp / "rockbench" / "scenarios" / "paper-plan.toml").write_text(
        (root / "rockbench" / "scenarios" / "paper-plan.toml").read_text())
    for name in ("eta_summary.csv", "map_agreement.csv", "record_peaks.csv"):
        (tmp / "reports" / name).write_text((root / "reports" / name).read_text())
    planted = adv.copy()
    i = planted.index[(planted["tolerance"] == 0.005)][0]
    planted.loc[i, ["status", "recommended", "setting", "cpu_per_sim_s",
                    "worst_error_choice", "worst_error_heldout"]] = [
        "meets", True, "dt=0.00042", 0.0123, 0.001, 0.002]
    planted.loc[i, "rank"] = 0
    planted.to_csv(tmp / "reports" / "advice.csv", index=False)
    said = render_block("decision", tmp)
    assert "use " + str(planted.loc[i, "engine"]) + " at dt=0.00042" in said

"""The reading of ``benchmarks/results/contact_cost.md`` is written by
``benchmarks/contact_cost.py`` from the table's numbers: the committed page is what the script
renders from its own table, and a planted row changes the sentences."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "benchmarks" / "results" / "contact_cost.md"


def _bench():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    spec = importlib.util.spec_from_file_location("contact_cost", ROOT / "benchmarks" /
                                                  "contact_cost.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["contact_cost"] = mod            # its dataclass looks itself up there
    spec.loader.exec_module(mod)
    return mod


def test_the_committed_page_is_what_the_script_renders_from_its_table():
    cc = _bench()
    text = PAGE.read_text()
    assert cc.rerender(PAGE) == text
    rows = cc.parse_table(text)
    assert len(rows) == 10 and cc.table(rows) in text       # the table reads back as written


def test_a_planted_row_changes_the_reading():
    cc = _bench()
    rows = cc.parse_table(PAGE.read_text())
    base = cc.reading(rows)
    i = next(k for k, r in enumerate(rows) if r.peak_err is not None and r.engine == "pybullet")
    worse = list(rows)
    worse[i] = dataclasses.replace(rows[i], peak_err=(rows[i].peak_err[0], 7.5))
    text = cc.reading(worse)
    assert "every engine within 7.5 %" in text and "pybullet +7.5 % (with the vertical" in text
    assert text != base
    dear = list(rows)
    r = rows[0]
    dear[0] = dataclasses.replace(r, friction=(10 * r.plain[2], 9 * r.plain[2],
                                               11 * r.plain[2]), x_friction=20.0)
    text = cc.reading(dear)
    assert "a friction costs nothing measurable" not in text
    assert f"in {len(rows) - 1} of {len(rows)} cases; not in {r.case}, {r.engine} (x20)" in text
    broken = list(rows)
    broken[3] = dataclasses.replace(rows[3], status="ok / diverged")
    assert f"{rows[3].engine}: ok / diverged" in cc.reading(broken)
    assert "every run ok" in base

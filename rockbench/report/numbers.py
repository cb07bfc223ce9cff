"""The numbers the README quotes, rendered from the report's tables (``reports/*.csv``) by
``tools/render_docs.py``: every figure in a README block comes from a committed results file,
and ``tests/test_docs.py`` fails when a block differs from what these functions render.

Blocks (``<!-- generated: NAME -->``):

* ``decision`` - one sentence per tolerance on the report's choice scene
  (:func:`rockbench.report.decision.decision_sentences` of ``advice.csv``);
* ``results`` - one row per engine: its fate and cost at two tolerances (``advice.csv``), the
  worst free-rocking eta error (``eta_summary.csv``), the agreement of its finest overturning
  map with the analytic one (``map_agreement.csv``), its record runs inside the analytic
  model's own sensitivity band (``record_peaks.csv``).
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from .decision import decision_sentences, pct, tol_text

__all__ = ["render_block", "BLOCKS"]

#: The tolerances the README's results table shows (columns of ``advice.csv``).
README_TOLERANCES = (0.02, 0.005)


def _read(root: Path, name: str) -> pd.DataFrame:
    p = Path(root) / "reports" / name
    return pd.read_csv(p) if p.is_file() else pd.DataFrame()


def _decision(root: Path) -> str:
    adv = _read(root, "advice.csv")
    scene = _choice_scene(root)
    return "\n".join(f"* {s}" for s in decision_sentences(adv, scene))


def _choice_scene(root: Path) -> str:
    import tomllib

    plan = tomllib.loads((Path(root) / "rockbench" / "scenarios" / "paper-plan.toml")
                         .read_text(encoding="utf-8"))
    return str(plan["campaign"]["choice_scene"])


def _fate(adv: pd.DataFrame, engine: str, tol: float) -> str:
    g = adv[(adv["engine"] == engine) & (adv["tolerance"].astype(float).sub(tol).abs() < 1e-12)]
    if not len(g):
        return "-"
    r = g.iloc[0]
    if r["status"] == "meets":
        return f"{r['setting']}, {float(r['cpu_per_sim_s']):.3g} CPU s/s"
    err = float(r["worst_error_choice"]) if pd.notna(r["worst_error_choice"]) else math.nan
    return str(r["status"]) + (f" ({pct(err)})" if math.isfinite(err) else "")


def _results(root: Path) -> str:
    adv = _read(root, "advice.csv")
    eta = _read(root, "eta_summary.csv")
    ag = _read(root, "map_agreement.csv")
    rec = _read(root, "record_peaks.csv")
    engines = [e for e in dict.fromkeys(adv["engine"])] if len(adv) else []
    head = (["engine"] + [f"within {tol_text(t)} on {_choice_scene(root)}: setting, cost"
                          for t in README_TOLERANCES]
            + ["free-rocking eta error (worst)", "map agreement (finest map)",
               "record runs in the model's band"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for e in engines:
        cells = [e] + [_fate(adv, e, t) for t in README_TOLERANCES]
        s = eta[eta["backend"] == e]["rel_error"].astype(float).abs() if len(eta) else []
        cells.append(pct(s.max()) if len(s) else "-")
        a = ag[ag["backend"] == e] if len(ag) else ag
        if len(a):
            cellsn = a["cells"].astype(int)
            w = a.loc[cellsn.idxmax()]
            differ = int(w["differ"]) if "differ" in w and pd.notna(w.get("differ")) else \
                int(round(int(w["cells"]) * (1 - float(w["agree_fraction"]))))
            bad = int(w["not_ok"]) if pd.notna(w.get("not_ok")) else 0
            cells.append(f"{w['scene']} {w['grid']}: {differ} of {int(w['cells'])} cells "
                         f"differ, kappa {float(w['kappa']):.3f}"
                         + (f", {bad} not ok" if bad else ""))
        else:
            cells.append("not mapped")
        r = rec[rec["backend"] == e] if len(rec) else rec
        if len(r) and "within_band" in r:
            ok = r["within_band"].dropna()
            cells.append(f"{int(ok.astype(bool).sum())} of {len(ok)}" if len(ok) else "-")
        else:
            cells.append("-")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: name -> renderer(root) of every README block.
BLOCKS = {"decision": _decision, "results": _results}


def render_block(name: str, root: str | Path) -> str:
    """The Markdown of README block ``name`` from the results under ``root`` (the repository)."""
    if name not in BLOCKS:
        raise KeyError(f"no generated block {name!r}: one of {', '.join(BLOCKS)}")
    try:
        return BLOCKS[name](Path(root))
    except KeyError as e:        # a results file written by older code lacks a column
        from ..errors import RockbenchError

        raise RockbenchError(f"README block {name!r}: the results under {Path(root) / 'reports'} "
                             f"lack the column {e.args[0]!r} (written by older code): run "
                             "`make report`, then `make docs`") from None

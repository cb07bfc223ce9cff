"""The slower engines' fragility runs, measured once and reused after a check.

The report's fragility section runs every engine on the same cells (records, polarities and
steps of :data:`rockbench.campaign.fragility.REPORT_SIZES`). The engines without a compiled
stepping loop (PyBullet, OpenSees, Drake: 0.3-0.5 CPU s per simulated second at their default
settings) would cost about 2500 CPU s there, more than twice the whole report's budget. So, as
for the engine maps (``reports/engine-maps``), ``rockbench report --full`` measures their runs
at the default report's cells into a folder kept with the report
(``reports/fragility-engines``), and the default report reuses an engine's runs only when

* the folder holds every run the section needs for it (the same scene, records - by the
  SHA-256 of their files, not their paths -, signed scales, run lengths, settings and vertical
  part), measured with the engine version installed here, and
* one of them (the one that took the least CPU, to keep the check cheap) re-run now gives the same status and
  verdict and max |phi| / alpha within :data:`rockbench.studies.maps.VERIFY_RTOL`;

otherwise the engine is left out of the section and the page says why. An engine's numerical
uncertainty (:func:`rockbench.studies.fragility.numerical_terms`) is measured with its runs
and kept beside them.

Files, per frame label and engine: ``<label>_<engine>.parquet`` (one row per run: the
:func:`rockbench.sweep.run_cases` row and its ``portable_key``) and ``<label>_<engine>.json``
(engine version, numerical term, how many runs and their CPU [s], when, on which machine).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

__all__ = ["portable_key", "measure_runs", "reuse_runs"]


def _sha(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()[:16]


def portable_key(case: Mapping[str, Any], label: str) -> str:
    """A run's key that does not depend on where its files are: the normalized case with the
    scene by its label and every record file (horizontal and vertical channels) by the SHA-256
    of its content."""
    from ..sweep.cases import normalize_case
    from ..sweep.store import key

    n = normalize_case(case)
    m = dict(n["motion"])
    for k in ("path", "vertical_path"):
        if isinstance(m.get(k), str):
            m[k] = _sha(m[k])
    return key(dict(n, scene=label, motion=m))


def _files(folder: Path, label: str, engine: str) -> tuple[Path, Path]:
    from ..sweep.map_store import map_store_path

    table = map_store_path(folder, label, engine)
    return table, table.with_suffix(".json")


def _version(engine: str) -> str:
    from ..engines import get_backend

    ok, info = get_backend(engine).available()
    return str(info) if ok else ""


def measure_runs(folder: str | Path, label: str, engine: str, cases: Sequence[Mapping],
                 numerical: Mapping[str, Any] | None, **run: Any) -> Path:
    """Run ``cases`` (one engine's, of the frame ``label``) and keep them in ``folder`` with
    the engine's numerical term; runs already kept there for the same engine version are not
    run again (a measurement resumes). ``run``: :func:`rockbench.sweep.run_cases` options."""
    from ..machine import describe
    from ..sweep import run_cases

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    table, meta = _files(folder, label, engine)
    version = _version(engine)
    keys = [portable_key(c, label) for c in cases]
    old = pd.DataFrame()
    if table.is_file() and meta.is_file():
        if json.loads(meta.read_text(encoding="utf-8")).get("engine_version") == version:
            old = pd.read_parquet(table)
            old = old[old["status"] != "error"]
    have = set(old["portable_key"]) if len(old) else set()
    todo = [(k, c) for k, c in zip(keys, cases) if k not in have]
    new = pd.DataFrame()
    if todo:
        new = run_cases([c for _, c in todo], **run)
        new["portable_key"] = [k for k, _ in todo]
    rows = pd.concat([old, new], ignore_index=True) if len(old) else new
    rows = rows[rows["portable_key"].isin(set(keys))].drop_duplicates("portable_key",
                                                                      keep="last")
    from ..sweep.store import write_table

    write_table(table, rows.reset_index(drop=True))
    meta.write_text(json.dumps({
        "label": label, "engine": engine, "engine_version": version, "runs": int(len(rows)),
        "runs_cpu_s": float(pd.to_numeric(rows["cpu_s"], errors="coerce").sum()),
        "numerical": dict(numerical or {}), "machine": describe(),
        "measured_at": pd.Timestamp.now(tz="UTC").isoformat(timespec="seconds")},
        indent=1, default=float), encoding="utf-8")
    return table


def reuse_runs(folder: str | Path, label: str, engine: str, cases: Sequence[Mapping],
               store: Path) -> tuple[dict[str, Any] | None, str]:
    """Put the kept runs of ``engine`` on the frame ``label`` into the section's run ``store``
    (the directory :func:`rockbench.sweep.run_cases` reads, under the current case ids) when
    they can be trusted (module docstring). Returns (the engine's numerical term, how they
    were checked; ``{}`` when none was kept) or (None, why they are not reused)."""
    from ..studies.maps import VERIFY_RTOL
    from ..sweep.runs import case_columns, run_case
    from ..sweep.store import load_store, write_row

    table, meta = _files(Path(folder), label, engine)
    if not table.is_file() or not meta.is_file():
        return None, f"no measured runs in {Path(folder).name}/ (rockbench report --full " \
                     "measures them)"
    info = json.loads(meta.read_text(encoding="utf-8"))
    version = _version(engine)
    if info.get("engine_version") != version:
        return None, (f"its runs were measured with {info.get('engine_version')}, this is "
                      f"{version}")
    kept = pd.read_parquet(table).set_index("portable_key")
    keys = [portable_key(c, label) for c in cases]
    missing = [k for k in keys if k not in kept.index]
    if missing:
        return None, (f"the measured runs lack {len(missing)} of the {len(keys)} this "
                      "section needs (other records, steps or settings)")
    # the check: the run that took the least CPU when measured (an overturning run ends
    # early), re-run now
    def cost(kc) -> tuple[float, str]:
        c = float(kept.loc[kc[0]].get("cpu_s", math.nan))
        return (c if math.isfinite(c) else math.inf, kc[0])
    k0, c0 = min(zip(keys, cases), key=cost)
    now, was = run_case(c0), kept.loc[k0]
    for c in ("status", "overturned"):
        if bool(now[c] == was[c]) is False:
            return None, (f"its measured runs do not reproduce: a re-run's {c} was "
                          f"{was[c]}, is {now[c]} now")
    a, b = float(was["max_abs_phi_over_alpha"]), float(now["max_abs_phi_over_alpha"])
    d = abs(a - b) / max(abs(a), 1e-12)
    if not d <= VERIFY_RTOL:
        return None, (f"its measured runs do not reproduce: a re-run's max |phi|/alpha was "
                      f"{a:.9g}, is {b:.9g} now")
    store.mkdir(parents=True, exist_ok=True)
    there = set(load_store(store, damaged="quiet")["case_id"]) if any(
        store.glob("*.parquet")) else set()
    for k, c in zip(keys, cases):
        row = {col: v for col, v in kept.loc[k].items()}
        row.update(case_columns(c))
        if row["case_id"] not in there:
            write_row(store, row)
    num = dict(info.get("numerical") or {})
    return num, (f"measured earlier ({len(keys)} runs, {version}, on "
                 f"{info.get('machine', {}).get('processor', '?')}), one re-run now "
                 f"reproduced (max |phi|/alpha within {VERIFY_RTOL:g})")

"""Record ensembles: the folders, files and bundled ensembles a fragility study runs over,
resolved to records identified by their path (never by their file stem alone), and the
intensity measures of each (:mod:`rockbench.studies.intensity`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from .intensity import intensity

__all__ = ["ensemble_dir", "bundled_ensembles", "resolve_records", "record_ims"]


def ensemble_dir(name: str) -> Path | None:
    """The package folder of a bundled ensemble: ``"bundled"`` (the records shipped at the top
    of ``rockbench/records``) or a subfolder of it (e.g. ``sac-la-2in50`` when it is shipped)."""
    from ..scene.records import bundled_dir

    root = bundled_dir()
    if name == "bundled":
        return root
    sub = root / name
    return sub if "/" not in name and sub.is_dir() else None


def bundled_ensembles() -> list[str]:
    """Names usable as ``--records NAME``: ``bundled`` and every subfolder of the package's
    ``rockbench/records``."""
    from ..scene.records import bundled_dir
    return ["bundled"] + sorted(p.name for p in bundled_dir().iterdir() if p.is_dir()
                                and not p.name.startswith(("_", ".")))


def resolve_records(sources: str | os.PathLike | Sequence[str | os.PathLike]
                    ) -> list[dict[str, Any]]:
    """Records of ``sources``: folders (searched like
    :func:`rockbench.scene.records.find_records`: ``.AT2`` files and headerless files listed in a
    ``records.csv``), single files (``.AT2``, or headerless beside a ``records.csv`` listing
    them), bundled ensemble names (:func:`bundled_ensembles`), or records this function
    returned. Each record a dict name, path, dt [s] or None, units or None; ParameterError when
    a source is none of these or no record is found. A record is identified by its resolved
    path: the same file given twice is kept once, and two files that share a name (``LA21`` in
    two folders) are both kept, named by their folders (``a/LA21``, ``b/LA21``)."""
    from ..scene.records import find_records, listed_metadata

    items = [sources] if isinstance(sources, (str, os.PathLike)) else list(sources)
    if not items:
        raise ParameterError("records", sources, "at least one folder, file or ensemble name")
    out: dict[str, dict[str, Any]] = {}            # resolved path -> record
    top = None
    for src in items:
        if isinstance(src, Mapping):          # already resolved (a dict of this function)
            out.setdefault(str(src["path"]), dict(src))
            continue
        p = Path(src)
        if p.is_dir():
            recs, notes = find_records(p)
            if not recs:
                raise ParameterError("records", str(src), "a folder holding at least one "
                                     "record (.AT2, or listed in a records.csv)",
                                     "; ".join(notes[:3]) or "it holds no file")
        elif p.is_file():
            if p.suffix.lower() == ".at2":
                recs = [{"name": p.stem, "path": str(p.resolve()), "dt": None, "units": None}]
            else:
                meta = listed_metadata(p)
                if meta is None:
                    raise ParameterError("records", str(src), "an .AT2 file, or a headerless "
                                         "file listed with its dt in a records.csv beside it")
                recs = [{"name": p.stem, "path": str(p.resolve()), **meta}]
        elif ensemble_dir(str(src)) is not None:
            if str(src) == "bundled":
                recs = [r for r in find_records(ensemble_dir("bundled"))[0]
                        if Path(r["path"]).parent == ensemble_dir("bundled")]
            else:
                recs = find_records(ensemble_dir(str(src)))[0]
        else:
            top = top or ", ".join(bundled_ensembles())
            raise ParameterError("records", str(src), f"an existing folder or record file, or "
                                 f"a bundled ensemble: {top}")
        for r in recs:
            out.setdefault(str(r["path"]), r)
    if not out:
        raise ParameterError("records", sources, "folders or files holding at least one record "
                             "(.AT2, or listed in a records.csv)")
    return _unique_names(list(out.values()))


def _unique_names(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``records`` with names that tell them apart: a name two records share gets the name of
    each one's folder in front (``a/LA21``), then the whole path if that is not enough."""
    def clashes(recs):
        seen: dict[str, int] = {}
        for r in recs:
            seen[r["name"]] = seen.get(r["name"], 0) + 1
        return {n for n, k in seen.items() if k > 1}

    dup = clashes(records)
    for r in records:
        if r["name"] in dup:
            r["name"] = f"{Path(r['path']).parent.name}/{Path(r['name']).name}"
    dup = clashes(records)
    for r in records:
        if r["name"] in dup:
            r["name"] = str(Path(r["path"]).with_suffix(""))
    return records


def record_ims(records: Sequence[Mapping[str, Any]]) -> pd.DataFrame:
    """name, path, pga [m/s^2], pgv [m/s], duration [s] of each record (loaded once)."""
    from ..scene.records import load_record

    rows = []
    for r in records:
        rec = load_record(r["path"], dt=r.get("dt"), units=r.get("units"))
        if not np.any(np.asarray(rec.samples) != 0.0):
            raise ParameterError("records", r["path"], "records with a non-zero acceleration",
                                 "every sample of this one is 0 (PGA 0): no scale of it can "
                                 "move anything")
        rows.append({"record": r["name"], "path": r["path"], "pga": intensity(rec, "pga"),
                     "pgv": intensity(rec, "pgv"), "duration": rec.t_end - rec.t_start})
    return pd.DataFrame(rows)

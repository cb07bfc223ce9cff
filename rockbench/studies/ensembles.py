"""Record ensembles: the folders, files, bundled ensembles and the named synthetic ensemble a
fragility study runs over, resolved to records identified by their path (never by their file
stem alone), what kind of ensemble they are (:func:`describe_ensemble`), and the intensity
measures of each (:mod:`rockbench.studies.intensity`).

The synthetic ensemble (``synthetic``, ``synthetic:seed=S``, ``synthetic:n=N,seed=S``): N
(default :data:`SYNTHETIC_N`) records of :func:`rockbench.scene.synthetic.ensemble` for the
default scenario (:data:`rockbench.scene.synthetic.DEFAULT_SCENARIO`), seed S (default 0), dt
:data:`SYNTHETIC_DT`, written once into a cache folder named by all of these
(:func:`synthetic_folder`) and read from there like any folder of records.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from .intensity import MEASURES, Structure, intensities, strong_motion_end

__all__ = ["SYNTHETIC", "SYNTHETIC_N", "SYNTHETIC_DT", "SyntheticEnsemble", "parse_synthetic",
           "synthetic_folder", "ensemble_dir", "bundled_ensembles", "resolve_records",
           "describe_ensemble", "record_ims"]

#: The name of the synthetic ensemble (``--records synthetic``), its default size and the
#: time step of its records [s] (the model's own 0.01 s: ``docs/synthetic.md``).
SYNTHETIC, SYNTHETIC_N, SYNTHETIC_DT = "synthetic", 20, 0.01


# =========================================================================================
# The synthetic ensemble
# =========================================================================================
@dataclass(frozen=True)
class SyntheticEnsemble:
    """A synthetic ensemble by name: ``n`` records of the default scenario from ``seed``."""

    n: int = SYNTHETIC_N
    seed: int = 0

    @property
    def scenario(self):
        from ..scene.synthetic import DEFAULT_SCENARIO
        return DEFAULT_SCENARIO

    @property
    def name(self) -> str:
        """``synthetic`` or ``synthetic:n=N,seed=S`` (what parses back to it)."""
        if (self.n, self.seed) == (SYNTHETIC_N, 0):
            return SYNTHETIC
        return f"{SYNTHETIC}:n={self.n},seed={self.seed}"

    def describe(self) -> dict[str, Any]:
        """kind, model, scenario, n, seed, dt [s], name: what the page and the JSON print."""
        return {"kind": "synthetic", "name": self.name,
                "model": "Rezaeian & Der Kiureghian (2010) stochastic ground-motion model",
                "scenario": self.scenario.describe(), "n": self.n, "seed": self.seed,
                "dt": SYNTHETIC_DT}


def parse_synthetic(text: Any) -> SyntheticEnsemble | None:
    """The :class:`SyntheticEnsemble` that ``text`` names (``synthetic``,
    ``synthetic:seed=S``, ``synthetic:n=N,seed=S``; N in [1, 10000], S >= 0 integers), None
    when ``text`` does not start with ``synthetic``; ParameterError for a bad option."""
    if not isinstance(text, str) or not (text == SYNTHETIC or text.startswith(SYNTHETIC + ":")):
        return None
    opts: dict[str, int] = {}
    for part in filter(None, text[len(SYNTHETIC) + 1:].split(",")):
        k, eq, v = part.partition("=")
        k = k.strip()
        try:
            if not eq or k not in ("n", "seed") or k in opts:
                raise ValueError
            opts[k] = int(v.strip())
        except ValueError:
            raise ParameterError("records", text, "synthetic, synthetic:seed=S or "
                                 "synthetic:n=N,seed=S (integers)") from None
    if not 1 <= opts.get("n", SYNTHETIC_N) <= 10000:
        raise ParameterError("records", text, "synthetic:n=N with N in [1, 10000]")
    if opts.get("seed", 0) < 0:
        raise ParameterError("records", text, "synthetic:seed=S with S >= 0")
    return SyntheticEnsemble(**opts)


def _synthetic_stamp(spec: SyntheticEnsemble) -> str:
    """What makes the records of ``spec`` what they are: the model's source file, NumPy's and
    SciPy's versions (the records are bit for bit the same for one platform and versions)."""
    import scipy

    from ..scene import synthetic as S

    h = hashlib.sha256(Path(S.__file__).read_bytes())
    h.update(json.dumps([spec.n, spec.seed, SYNTHETIC_DT, spec.scenario.describe(),
                         np.__version__, scipy.__version__]).encode())
    return h.hexdigest()[:16]


def synthetic_folder(spec: SyntheticEnsemble, cache: str | os.PathLike | None = None) -> Path:
    """The folder of the records of ``spec`` under ``cache`` (default: the system's temporary
    folder, ``rockbench-records``), written by :func:`rockbench.scene.synthetic.write_ensemble`
    when it is missing or was written by other code (a ``stamp.json`` names the model's source
    and NumPy's and SciPy's versions). Named ``synthetic-rdk10-M7.0-R15-V760-strike-slip-n20-
    seed0-dt0.01``: the records of a name and seed are found again by every run."""
    from ..scene.synthetic import ensemble, write_ensemble

    sc = spec.scenario
    root = Path(cache) if cache is not None else Path(tempfile.gettempdir()) / "rockbench-records"
    folder = root / (f"synthetic-rdk10-{sc.label()}-V{sc.vs30:g}-{sc.fault}-n{spec.n}-"
                     f"seed{spec.seed}-dt{SYNTHETIC_DT:g}")
    stamp = _synthetic_stamp(spec)
    try:
        if json.loads((folder / "stamp.json").read_text())["stamp"] == stamp:
            return folder
    except (OSError, ValueError, KeyError, TypeError):
        pass
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=folder.name + ".", dir=root))
    write_ensemble(ensemble(sc, n=spec.n, seed=spec.seed, dt=SYNTHETIC_DT), tmp)
    (tmp / "stamp.json").write_text(json.dumps({"stamp": stamp, **spec.describe()}))
    shutil.rmtree(folder, ignore_errors=True)
    try:
        tmp.rename(folder)
    except OSError:             # another process wrote it meanwhile: theirs is the same
        shutil.rmtree(tmp, ignore_errors=True)
    return folder


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


def resolve_records(sources: str | os.PathLike | Sequence[str | os.PathLike], *,
                    cache: str | os.PathLike | None = None) -> list[dict[str, Any]]:
    """Records of ``sources``: folders (searched like
    :func:`rockbench.scene.records.find_records`: ``.AT2`` files and headerless files listed in a
    ``records.csv``), single files (``.AT2``, or headerless beside a ``records.csv`` listing
    them), bundled ensemble names (:func:`bundled_ensembles`), the synthetic ensemble's name
    (:func:`parse_synthetic`; its records are written under ``cache``,
    :func:`synthetic_folder`), or records this function returned. Each record a dict name,
    path, dt [s] or None, units or None, with ``vertical`` (the path of its vertical channel),
    ``vertical_dt`` and ``vertical_units`` when a ``records.csv`` lists one
    (:func:`rockbench.scene.records.find_records`), and ``ensemble`` (what
    :func:`describe_ensemble` reads: ``{"kind": "synthetic", ...}``, ``{"kind": "bundled", ...}`` or
    ``{"kind": "real", "folder": ...}``); ParameterError when a source is none of these or no
    record is found. A record is identified by its resolved
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
        spec = parse_synthetic(src) if isinstance(src, str) else None
        if spec is not None:
            recs = find_records(synthetic_folder(spec, cache))[0]
            for r in recs:
                r["ensemble"] = spec.describe()
        elif p.is_dir():
            recs, notes = find_records(p)
            if not recs:
                raise ParameterError("records", str(src), "a folder holding at least one "
                                     "record (.AT2, or listed in a records.csv)",
                                     "; ".join(notes[:3]) or "it holds no file")
        elif p.is_file():
            if p.suffix.lower() == ".at2":
                meta = listed_metadata(p) or {}        # a vertical channel it may list
                recs = [{"name": p.stem, "path": str(p.resolve()), "dt": None, "units": None,
                         **{k: v for k, v in meta.items() if k.startswith("vertical")}}]
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
            for r in recs:
                r["ensemble"] = {"kind": "bundled", "name": str(src),
                                 "folder": str(ensemble_dir(str(src)))}
        else:
            top = top or ", ".join(bundled_ensembles() + [SYNTHETIC])
            raise ParameterError("records", str(src), f"an existing folder or record file, or "
                                 f"a named ensemble: {top}")
        for r in recs:
            r.setdefault("ensemble", {"kind": "real", "folder": str(Path(r["path"]).parent)})
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


def describe_ensemble(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """What kind of ensemble ``records`` (of :func:`resolve_records`) are: ``kind``
    "synthetic" (with model, scenario, n, seed, dt [s], name), "bundled" (name, folder),
    "real" (``folders``: the folders the records are in) or "mixed"; ``n`` records and
    ``text``, one sentence for a page."""
    kinds = [dict(r.get("ensemble") or {"kind": "real",
                                        "folder": str(Path(r["path"]).parent)}) for r in records]
    n = len(records)
    first = kinds[0] if kinds else {"kind": "real"}
    if kinds and all(k == first for k in kinds) and first["kind"] == "synthetic":
        out = dict(first, n=n)
        out["text"] = (f"synthetic ensemble {out['name']!r}: {n} ground motions of the "
                       f"{out['model']}, scenario {out['scenario']}, seed {out['seed']}, "
                       f"dt {out['dt']:g} s (docs/synthetic.md)")
        return out
    if kinds and all(k == first for k in kinds) and first["kind"] == "bundled":
        return dict(first, n=n, text=f"recorded: {n} records of the bundled ensemble "
                                     f"{first['name']!r} ({first['folder']})")
    if any(k["kind"] == "synthetic" for k in kinds):
        return {"kind": "mixed", "n": n,
                "text": f"mixed: {n} records, synthetic and recorded"}
    folders = sorted({str(k.get("folder", "")) for k in kinds})
    return {"kind": "real", "n": n, "folders": folders,
            "text": f"recorded: {n} records from {', '.join(folders)}"}


def record_ims(records: Sequence[Mapping[str, Any]], structure: Structure | None = None
               ) -> pd.DataFrame:
    """record, path, duration [s], t95 [s] (the end of the strong motion:
    :func:`rockbench.studies.intensity.strong_motion_end`) and the intensity measures of each
    record at scale 1, in the units of :data:`MEASURES`: pga [m/s^2] and pgv [m/s], and with
    ``structure`` (:class:`rockbench.studies.intensity.Structure`) pga_norm [-], pgv_norm [-]
    and sa [m/s^2] (each record loaded once)."""
    rows = []
    for r in records:
        st = os.stat(r["path"])
        rows.append({"record": r["name"], "path": r["path"],
                     **_measured(str(r["path"]), st.st_mtime_ns, st.st_size, r.get("dt"),
                                 r.get("units"), structure)})
    return pd.DataFrame(rows)


@functools.lru_cache(maxsize=4096)
def _measured(path: str, mtime_ns: int, size: int, dt: float | None, units: str | None,
              structure: Structure | None) -> dict[str, float]:
    """The measures, duration and t95 of one record file (cached per file version: a study
    reads its records' measures several times)."""
    from ..scene.records import load_record

    rec = load_record(path, dt=dt, units=units)
    if not np.any(np.asarray(rec.samples) != 0.0):
        raise ParameterError("records", path, "records with a non-zero acceleration",
                             "every sample of this one is 0 (PGA 0): no scale of it can "
                             "move anything")
    keys = [k for k in MEASURES if structure is not None or k in ("pga", "pgv")]
    return {**intensities(rec, structure, keys), "duration": rec.t_end - rec.t_start,
            "t95": strong_motion_end(rec)}

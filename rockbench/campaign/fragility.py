"""The default campaign's fragility section (``docs/fragility.md``): the runs and analyses of
:mod:`rockbench.studies.fragility` on the paper's Fig. 9 frames, over the user's records or the
package's synthetic ensemble, at a size that keeps ``make report`` within its budget
(:data:`REPORT_SIZES`; every engine on the whole ladder with ``rockbench report --full``). The
page block is :func:`rockbench.report.fragility_figures.fragility_html`.

The ladder of each frame is found, not fixed (incremental dynamic analysis "hunt, then fill",
Vamvatsikos & Cornell 2004): the analytic model first runs a few coarse steps (``pilot``, PGA
targets of the ensemble's median record, extended by factors of 4 until the analytic model
overturns in less than half of the runs at the lowest step and in more than half at the
highest), its lognormal fit places ``fine`` steps at the quantiles (i + 1/2) / fine of the
fitted capacity, and the engines run the ``engine_steps`` fine steps whose quantiles are
nearest to evenly spaced probabilities (3/8 and 5/8 of 4 steps for two: nearest to 1/3 and
2/3): where the records' verdicts are mixed, which is where a fit and a test of the peaks learn
the most. Every analytic run of the pilot is kept in the fit.
"""

from __future__ import annotations

import math
import os
import tempfile
from contextlib import ExitStack
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..studies.ensembles import describe_ensemble, record_ims, resolve_records
from ..studies.fragility import run_fragility

__all__ = ["REPORT_SIZES", "fragility_section", "section_table", "measures_table",
           "write_exports"]


#: Sizes of the report's fragility section. ``records``: the ensemble when the user gives none
#: (``docs/synthetic.md``); ``pilot``: the coarse steps, PGA targets [m/s^2] of the ensemble's
#: median record (extended by factors of 4 until they bracket the analytic median; on the
#: synthetic ensemble one frame of the paper overturns near 12 m/s^2, the hybrid one near 70);
#: ``fine``: steps at the quantiles of the pilot's fit; ``engine_steps`` of them (None: every
#: step of the ladder) on ``engine_records`` records (None: all; at least
#: :data:`rockbench.studies.fragility_stats.MIN_RECORDS` for a verdict) for ``engines``
#: (``fast``: those with a compiled stepping loop; ``all``); bootstrap resamples; ``tail``:
#: each run ends this long [s] after the record's strong motion (:func:`rockbench.studies.
#: fragility.run_lengths`; measured: it changes 2 of 560 analytic verdicts of the free-standing
#: frame on the synthetic ensemble and none of the hybrid one, docs/fragility.md).
REPORT_SIZES: dict[str, dict[str, Any]] = {
    "quick": {"records": "synthetic:n=8", "pilot": (6.0, 24.0), "fine": 3,
              "engine_steps": 2, "engine_records": 8, "engines": "fast", "n_boot": 100,
              "tail": 10.0},
    "default": {"records": "synthetic", "pilot": (6.0, 24.0), "fine": 4,
                "engine_steps": 2, "engine_records": 8, "engines": "fast", "n_boot": 500,
                "tail": 10.0},
    "full": {"records": "synthetic", "pilot": (6.0, 24.0), "fine": 8,
             "engine_steps": None, "engine_records": None, "engines": "all", "n_boot": 1000,
             "tail": 10.0},
}

#: Dispersion bounds [-] of the fine steps' spread: a pilot fit at its bound (a step) or very
#: wide still places the steps near the median.
_SPAN_BETA = (0.15, 1.0)
#: Extensions of the pilot (factors of 4) before the section gives up bracketing the median.
_MAX_EXTENSIONS = 4


def _fast(names: Sequence[str]) -> list[str]:
    """The engines whose adapter has a compiled stepping loop (the cheap ones on records)."""
    from ..engines import get_backend
    from ..engines.base import EngineBackend

    out = []
    for n in names:
        cls = get_backend(n)
        if (isinstance(cls, type) and issubclass(cls, EngineBackend)
                and cls._compiled_loop is not EngineBackend._compiled_loop):
            out.append(n)
    return out


def _steps(targets: Sequence[float], median_pga: float) -> np.ndarray:
    return np.unique(np.round(np.asarray(targets, float) / median_pga, 6))


def _ladder(scene: str, recs, median_pga: float, cfg: Mapping[str, Any], run: dict
            ) -> tuple[np.ndarray, np.ndarray]:
    """(the ladder, the engines' steps) of ``scene``: the pilot (extended until it brackets
    the analytic median), then the fine steps at the quantiles of the pilot's fit, the engines
    at the fine steps nearest to 1/(k+1) ... k/(k+1) (module docstring)."""
    from scipy.stats import norm

    from ..runner import REFERENCE

    targets = list(cfg["pilot"])
    for _ in range(_MAX_EXTENSIONS + 1):
        f = run_fragility(scene, recs, engines=[REFERENCE], scales=_steps(targets, median_pga),
                          n_boot=1, numerical=None, tail=cfg["tail"], **run)
        p = f.stripes.set_index("scale")["p_overturn"].sort_index()
        if p.iloc[0] > 0.5:
            targets.insert(0, targets[0] / 4.0)
        elif p.iloc[-1] < 0.5:
            targets.append(targets[-1] * 4.0)
        else:
            break
    a = f.analysis["backends"][REFERENCE]
    if not math.isfinite(a["median"]):       # no bracket found: the pilot is the ladder
        ladder = _steps(targets, median_pga)
        return ladder, _pick(ladder, np.full(ladder.size, 0.5), cfg["engine_steps"])
    beta = min(max(a["dispersion"], _SPAN_BETA[0]), _SPAN_BETA[1])
    q = (np.arange(cfg["fine"]) + 0.5) / cfg["fine"]
    fine, first = np.unique(np.round(a["median"] * np.exp(beta * norm.ppf(q)) / median_pga, 6),
                            return_index=True)
    ladder = np.unique(np.concatenate([_steps(targets, median_pga), fine]))
    if cfg["engine_steps"] is None:
        return ladder, ladder
    return ladder, _pick(fine, q[first], cfg["engine_steps"])


def _pick(steps: np.ndarray, p: np.ndarray, k: int | None) -> np.ndarray:
    """``k`` of ``steps`` (their overturning probabilities ``p``) nearest to 1/(k+1), ...,
    k/(k+1), each once (None or k >= their number: all)."""
    if k is None or k >= steps.size:
        return steps
    chosen: list[int] = []
    for target in np.arange(1, k + 1) / (k + 1):
        order = np.argsort(np.abs(p - target), kind="stable")
        chosen.append(next(int(i) for i in order if int(i) not in chosen))
    return np.sort(steps[chosen])


def _slow_cases(scene: str, recs, ims, e_ladder, engine: str,
                cfg: Mapping[str, Any], ratio: float) -> list[dict[str, Any]]:
    """One engine's cases on ``scene`` at the engines' steps ``e_ladder`` of the size ``cfg``
    (:func:`_ladder`)."""
    from ..studies.fragility import planned_cases

    e_recs = recs[:cfg["engine_records"]] if cfg["engine_records"] else recs
    return planned_cases(scene, e_recs, ims, [engine], e_ladder, tail=cfg["tail"],
                         vertical=ratio)


def _measure_slow(frames: Mapping[str, str], slow: Sequence[str], recs, median_pga: float,
                  measured: Path, opts: dict, ratio: float, store) -> None:
    """``rockbench report --full``: the slower engines' runs at the default report's cells,
    measured into ``measured`` (:mod:`rockbench.campaign.fragility_measured`), with each
    engine's numerical term."""
    from ..scene.scene import load_scene
    from ..studies.fragility import numerical_evidence, numerical_terms
    from ..studies.intensity import Structure
    from .fragility_measured import measure_runs
    from .maps import scene_label

    cfg = REPORT_SIZES["default"]
    run = {k: opts[k] for k in ("executor", "workers", "progress") if k in opts}
    if opts.get("scheduler"):
        run["dask_address"] = opts["scheduler"]
    for scene in frames.values():
        ims = record_ims(recs, Structure.of(load_scene(scene)))
        _, e_ladder = _ladder(scene, recs, median_pga, cfg, opts)
        for eng in slow:
            cases = _slow_cases(scene, recs, ims, e_ladder, eng, cfg, ratio)
            num = numerical_terms(numerical_evidence(scene, [eng], store=store)).get(eng)
            measure_runs(measured, scene_label(scene), eng, cases, num, **run)


def fragility_section(frames: Mapping[str, str], engines: Sequence[str], *,
                      records: Any = None, size: str = "default",
                      store: str | os.PathLike | None = None,
                      numerical: Any = "measure", export_dir: str | os.PathLike | None = None,
                      vertical: float | None = None, measured: str | os.PathLike | None = None,
                      measure: bool = False, **run: Any) -> dict[str, Any]:
    """The fragility section of the default campaign: for each frame (``frames``: label ->
    scene) the runs and the analysis of :func:`run_fragility` over ``records`` (default: the
    size's ensemble, ``synthetic``: :data:`REPORT_SIZES`) on a ladder found per frame (module
    docstring) and the engines of ``REPORT_SIZES[size]``. ``store``: a folder (rows under its
    code fingerprint; without one, a temporary folder for the section's own reuse).
    ``numerical``: as :func:`run_fragility` ("measure": each engine's error on the frame at
    its setting). ``export_dir``: where the fitted curves are written for OpenQuake and
    pelicun (:func:`write_exports`; default ``store/export``; none without a store).
    ``vertical``: as :func:`run_fragility` (records without a vertical channel of their own
    move the ground vertically by this ratio; None: the recorded channels only).
    ``measured``: the folder of the slower engines' runs (those without a compiled stepping
    loop) at the default size's cells (:mod:`rockbench.campaign.fragility_measured`): a size
    that runs only the fast engines adds each slower one whose kept runs are complete and
    reproduce, and says why any other is left out; ``measure`` (``rockbench report --full``)
    measures them into it first. ``run``:
    executor options (``executor``, ``workers``, ``scheduler``, ``progress``). Returns
    ``{"what": sentence, "ensemble": the ensemble's description
    (:func:`rockbench.studies.ensembles.describe_ensemble`), "frames": [{"label", "scene",
    "runs", "analysis", "stripes", "record_ims", "scales", "engine_scales", "fig9_scale"}],
    "fig9": True, "records": the records, "size": ..., "exports": {file name: path}}``, or
    ``{"error": text}`` if the runs cannot be made."""
    from ..runner import REFERENCE

    if size not in REPORT_SIZES:
        raise ParameterError("size", size, f"one of {', '.join(REPORT_SIZES)}")
    from ..scene.scene import load_scene
    from ..studies.intensity import Structure
    from ..sweep import store as S
    from .fragility_measured import reuse_runs
    from .maps import scene_label

    cfg = REPORT_SIZES[size]
    records = cfg["records"] if records is None else records
    every = [e for e in engines if e != REFERENCE]
    engs = _fast(every) if cfg["engines"] == "fast" else every
    slow = [e for e in every if e not in engs]
    ratio = float(vertical or 0.0)
    out_frames = []
    provenance: list[str] = []
    try:
        with ExitStack() as stack:
            if export_dir is None and store is not None:
                export_dir = Path(store) / "export"
            if store is None:
                store = stack.enter_context(tempfile.TemporaryDirectory(prefix="rb-frag-"))
            recs = resolve_records(records, cache=Path(store) / "records")
            median_pga = float(np.median(record_ims(recs)["pga"]))
            opts = dict(run, store=store, vertical=vertical)
            if measure and measured is not None:
                slow_all = [e for e in every if e not in _fast(every)]
                if slow_all:
                    _measure_slow(frames, slow_all, recs, median_pga, Path(measured), opts,
                                  ratio, store)
            for label, scene in frames.items():
                ladder, e_ladder = _ladder(scene, recs, median_pga, cfg, opts)
                frame_engs, given = list(engs), {}
                if slow:
                    ims = record_ims(recs, Structure.of(load_scene(scene)))
                for eng in slow:
                    why = "no folder of measured runs"
                    if measured is not None:
                        cases = _slow_cases(scene, recs, ims, e_ladder, eng, cfg, ratio)
                        num, why = reuse_runs(measured, scene_label(scene), eng, cases,
                                              S.store_path(store, "", keyed=True))
                        if num is not None:                  # reused
                            frame_engs.append(eng)
                            if num:
                                given[eng] = num
                            provenance.append(f"{eng} on {label}: {why}")
                            continue
                    provenance.append(f"{eng} on {label}: left out ({why})")
                f = run_fragility(scene, recs, engines=[REFERENCE, *frame_engs],
                                  scales=ladder, engine_scales=e_ladder,
                                  engine_records=cfg["engine_records"], n_boot=cfg["n_boot"],
                                  tail=cfg["tail"], numerical=numerical,
                                  numerical_given=given or None, **opts)
                out_frames.append({"label": label, "scene": scene, "runs": f.runs,
                                   "analysis": f.analysis, "stripes": f.stripes,
                                   "record_ims": f.records, "engines": frame_engs,
                                   "scales": ladder.tolist(), "engine_scales": e_ladder.tolist(),
                                   "fig9_scale": float(e_ladder[len(e_ladder) // 2])})
    except Exception as e:  # noqa: BLE001 - the page says what failed; the campaign goes on
        return {"error": f"{type(e).__name__}: {e}"}
    engs = list(dict.fromkeys(e for fr in out_frames for e in fr["engines"])) or engs
    ens = describe_ensemble(recs)
    n_e = min(cfg["engine_records"] or len(recs), len(recs))
    st = out_frames[0]["analysis"]["structure"] if out_frames else {}
    ladders = "; ".join(
        f"{fr['label']}: {len(fr['scales'])} factors {fr['scales'][0]:.3g} to "
        f"{fr['scales'][-1]:.3g}, the engines at "
        + ", ".join(f"{s:.3g}" for s in fr["engine_scales"]) for fr in out_frames)
    what = (f"Ensemble: {ens['text']}. Every record, as recorded and reversed, scaled step by "
            f"step (incremental dynamic analysis; the ensemble's median PGA is "
            f"{median_pga:.3g} m/s^2): the analytic model (compiled path) on every record at "
            f"every factor of its frame's ladder, found per frame from coarse steps at "
            f"{', '.join(f'{x:g}' for x in cfg['pilot'])} m/s^2 of the median record "
            f"(times 4 until they bracket the analytic median) and {cfg['fine']} steps at "
            f"the quantiles of their fit ({ladders}); the engines "
            f"({', '.join(engs) if engs else 'none'}) on {n_e} records at the steps where the "
            f"analytic verdicts are most mixed"
            + ("" if size == "full" else "; the whole ladder for every engine with "
               "rockbench report --full")
            + f". Each run ends {cfg['tail']:g} s after the record's strong motion (95 % of "
              "its Arias intensity). The analytic curve drawn is its fit on the whole ladder; "
              "the tests, the difference of the medians and the intensity-measure table "
              "compare only the runs both made (fragility.csv has both analytic fits)."
            + (f" Sa is taken at T_p = 2 pi / p = {st['sa_period']:.3g} s (p = "
               f"{st['p']:.3g} rad/s of the taller column)." if st else "")
            + " docs/fragility.md defines every number.")
    section = {"what": what, "frames": out_frames, "fig9": True, "size": size,
               "records": recs, "ensemble": ens, "provenance": provenance,
               "scales": out_frames[0]["scales"] if out_frames else [],
               "engine_scales": out_frames[0]["engine_scales"] if out_frames else []}
    try:
        section["exports"] = ({k: str(v) for k, v in write_exports(section, export_dir).items()}
                              if export_dir is not None else {})
    except OSError as e:          # the page says so; the section stands
        section["exports"] = {}
        section["export_error"] = f"{type(e).__name__}: {e}"
    return section


def section_table(section: Mapping[str, Any]) -> pd.DataFrame:
    """The section as one table (``fragility.csv`` of the report): per frame and backend the
    ensemble (its kind and name), the median [IM unit], dispersion [-], their intervals, the
    numerical dispersion beta_num [-] and beta_total [-], the most efficient intensity measure,
    runs, overturned, smallest p and the median difference with its interval (the analytic
    model's whole-ladder fit as backend ``analytic (whole ladder)``)."""
    rows = []
    ens = section.get("ensemble") or {}
    kind = f"{ens.get('kind', '')}: {ens.get('name', '') or ', '.join(ens.get('folders', []))}"
    for fr in section.get("frames", []):
        a = fr["analysis"]
        items = list(a["backends"].items())
        if "reference_full" in a:
            items.append((f"{a['reference']} (whole ladder)", a["reference_full"]))
        for b, v in items:
            rows.append({"frame": fr["label"], "scene": fr["scene"], "backend": b,
                         "ensemble": kind,
                         "intensity": a["intensity"]["name"], "unit": a["intensity"]["unit"],
                         "median": v["median"], "median_low": v["median_ci"][0],
                         "median_high": v["median_ci"][1], "dispersion": v["dispersion"],
                         "dispersion_low": v["dispersion_ci"][0],
                         "dispersion_high": v["dispersion_ci"][1],
                         "dispersion_numerical": v.get("dispersion_numerical", math.nan),
                         "dispersion_total": v.get("dispersion_total", math.nan),
                         "im_best": v.get("im_best"),
                         "runs": v["runs"],
                         "overturned": v["overturned"], "not_ok": v["not_ok"],
                         "statistic": v.get("statistic", math.nan),
                         "p_value": v.get("p_value", math.nan),
                         "median_difference": v.get("median_difference", math.nan),
                         "median_difference_low": v.get("median_difference_ci",
                                                        [math.nan] * 2)[0],
                         "median_difference_high": v.get("median_difference_ci",
                                                         [math.nan] * 2)[1],
                         "verdict": v.get("verdict", ""), "note": v["note"]})
    return pd.DataFrame(rows)


def measures_table(section: Mapping[str, Any]) -> pd.DataFrame:
    """The intensity-measure table of the section: per frame, backend and measure the median
    [the measure's unit], the dispersion [-] and its rank (1: the most efficient), on the runs
    the engines and the analytic model both made, and whether the engine's best measure is the
    analytic model's (``same_best``)."""
    rows = []
    for fr in section.get("frames", []):
        m = fr["analysis"].get("measures")
        if not m:
            continue
        for b, v in m["backends"].items():
            for k, f in v["fits"].items():
                rows.append({"frame": fr["label"], "scene": fr["scene"], "backend": b,
                             "measure": k, "name": m["measures"][k]["name"],
                             "unit": m["measures"][k]["unit"], "median": f["median"],
                             "dispersion": f["dispersion"], "rank": f["rank"],
                             "best": v["best"], "same_best": v.get("same_best"),
                             "note": f["note"]})
    return pd.DataFrame(rows)


def write_exports(section: Mapping[str, Any], folder: str | os.PathLike) -> dict[str, Path]:
    """The section's fitted curves for the risk tools (``docs/fragility-export.md``), one pair
    per frame: ``<scene>.xml`` (OpenQuake NRML) and ``<scene>.csv`` (pelicun), and the
    intensity-measure table ``measures.csv``, in ``folder`` (created). Returns name -> path of
    what was written (a frame without a regular fit has no file)."""
    from ..studies.fragility_export import write_fragility_exports

    root = Path(folder)
    out: dict[str, Path] = {}
    for fr in section.get("frames", []):
        a = dict(fr["analysis"])
        if "reference_full" in a:     # the analytic curve: its fit on the whole ladder
            a["backends"] = dict(a["backends"], **{a["reference"]: a["reference_full"]})
        try:
            out.update(write_fragility_exports(a, root, stem=Path(str(fr["scene"])).stem,
                                               runs=fr["runs"],
                                               record_ims=fr.get("record_ims")))
        except ParameterError:
            continue
    tab = measures_table(section)
    if len(tab):
        root.mkdir(parents=True, exist_ok=True)
        tab.to_csv(root / "measures.csv", index=False)
        out["measures.csv"] = root / "measures.csv"
    return out

"""The default campaign's fragility section (``docs/fragility.md``): the runs and
analyses of :mod:`rockbench.studies.fragility` on the paper's Fig. 9 frames, at a size that keeps
``make report`` within its budget (:data:`REPORT_SIZES`; the whole ladder for every engine with
``rockbench report --full``). The page block is
:func:`rockbench.report.fragility_figures.fragility_html`."""

from __future__ import annotations

import math
import os
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..studies.ensembles import ensemble_dir, record_ims, resolve_records
from ..studies.fragility import run_fragility

__all__ = ["REPORT_SIZES", "fragility_section", "section_table"]


#: Sizes of the report's fragility section: the ladder as PGA targets [m/s^2], geometrically
#: spaced (each record ensemble is scaled by target / its median PGA, so any ensemble spans the
#: same intensities; 1 to 40 m/s^2 spans the analytic medians of both Fig. 9 frames on the SAC
#: LA set, about 7 and 26 m/s^2),
#: the engines' share (``engine_steps`` of the ladder's steps, spread evenly; ``engine_records``
#: records, None = all), which engines (``fast``: those with a compiled stepping loop), and the
#: bootstrap resamples.
REPORT_SIZES: dict[str, dict[str, Any]] = {
    "quick": {"pga": (2.0, 30.0, 3), "engine_steps": 2, "engine_records": 1, "engines": "fast",
              "n_boot": 100},
    "default": {"pga": (1.0, 40.0, 14), "engine_steps": 3, "engine_records": 2,
                "engines": "fast", "n_boot": 500},
    "full": {"pga": (1.0, 40.0, 14), "engine_steps": None, "engine_records": None,
             "engines": "all", "n_boot": 1000},
}


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


def fragility_section(frames: Mapping[str, str], engines: Sequence[str], *,
                      records: Any = None, size: str = "default",
                      store: str | os.PathLike | None = None, **run: Any) -> dict[str, Any]:
    """The fragility section of the default campaign: for each frame (``frames``: label ->
    scene) the runs and the analysis of :func:`run_fragility` over ``records`` (default: the
    bundled ensemble ``sac-la-2in50`` when the package ships it, else ``bundled``) at the
    ladder and engines of ``REPORT_SIZES[size]``. ``store``: a folder (rows under its code
    fingerprint). ``run``: executor options (``executor``, ``workers``, ``scheduler``,
    ``progress``). Returns ``{"what": sentence, "frames": [{"label", "scene", "runs",
    "analysis", "stripes"}], "fig9": True, "records": frame of the records, "size": ...}``,
    or ``{"error": text}`` if the runs cannot be made."""
    from ..runner import REFERENCE

    if size not in REPORT_SIZES:
        raise ParameterError("size", size, f"one of {', '.join(REPORT_SIZES)}")
    cfg = REPORT_SIZES[size]
    if records is None:
        records = "sac-la-2in50" if ensemble_dir("sac-la-2in50") is not None else "bundled"
    engs = [e for e in engines if e != REFERENCE]
    engs = _fast(engs) if cfg["engines"] == "fast" else engs
    try:
        recs = resolve_records(records)
        median_pga = float(np.median(record_ims(recs)["pga"]))
        lo, hi, n = cfg["pga"]
        ladder = np.round(np.geomspace(lo, hi, n) / median_pga, 6)
        steps = cfg["engine_steps"]
        e_ladder = (ladder if steps is None else
                    ladder[np.unique(np.round(np.linspace(n // 4, n - 1, steps)).astype(int))])
        out_frames = []
        for label, scene in frames.items():
            f = run_fragility(scene, recs, engines=engs, scales=ladder, engine_scales=e_ladder,
                              engine_records=cfg["engine_records"], store=store,
                              n_boot=cfg["n_boot"], **run)
            out_frames.append({"label": label, "scene": scene, "runs": f.runs,
                               "analysis": f.analysis, "stripes": f.stripes})
    except Exception as e:  # noqa: BLE001 - the page says what failed; the campaign goes on
        return {"error": f"{type(e).__name__}: {e}"}
    n_e = cfg["engine_records"] or len(recs)
    what = (f"Every record of the ensemble ({len(recs)} records: "
            f"{', '.join(r['name'] for r in recs[:6])}{' ...' if len(recs) > 6 else ''}), as "
            f"recorded and reversed, scaled by the factors that bring the ensemble's median PGA "
            f"({median_pga:.3g} m/s^2) to {lo:g} ... {hi:g} m/s^2 in geometric steps: "
            f"{len(ladder)} scale factors {ladder[0]:.3g} to {ladder[-1]:.3g}, through the "
            f"analytic model (compiled path); the engines "
            f"({', '.join(engs) if engs else 'none'}) on {min(n_e, len(recs))} records at "
            f"{len(e_ladder)} of these factors ({', '.join(f'{s:.3g}' for s in e_ladder)})"
            + ("" if size == "full" else "; the whole ladder for every engine with "
               "rockbench report --full")
            + ". The analytic curve drawn is its fit on the whole ladder; the tests and the "
              "difference of the medians compare only the runs both made (fragility.csv has both "
              "analytic fits). docs/fragility.md defines every number.")
    return {"what": what, "frames": out_frames, "fig9": True, "size": size,
            "records": recs, "scales": ladder.tolist(), "engine_scales": e_ladder.tolist()}


def section_table(section: Mapping[str, Any]) -> pd.DataFrame:
    """The section as one table (``fragility.csv`` of the report): per frame and backend the
    median [IM unit], dispersion [-], their intervals, runs, overturned, smallest p and the
    median difference with its interval (the analytic model's whole-ladder fit as backend
    ``analytic (whole ladder)``)."""
    rows = []
    for fr in section.get("frames", []):
        a = fr["analysis"]
        items = list(a["backends"].items())
        if "reference_full" in a:
            items.append((f"{a['reference']} (whole ladder)", a["reference_full"]))
        for b, v in items:
            rows.append({"frame": fr["label"], "scene": fr["scene"], "backend": b,
                         "intensity": a["intensity"]["name"], "unit": a["intensity"]["unit"],
                         "median": v["median"], "median_low": v["median_ci"][0],
                         "median_high": v["median_ci"][1], "dispersion": v["dispersion"],
                         "dispersion_low": v["dispersion_ci"][0],
                         "dispersion_high": v["dispersion_ci"][1], "runs": v["runs"],
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

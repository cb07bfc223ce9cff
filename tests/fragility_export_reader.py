"""Load a rockbench fragility export with the risk tool's own reader and print what it read.

Run by ``tests/test_fragility_export.py`` in whichever interpreter has the tool (this one, or the
one named by ``ROCKBENCH_OPENQUAKE_PYTHON`` / ``ROCKBENCH_PELICUN_PYTHON``): it needs the tool
and the standard library only, not rockbench, so that the tool can live in a separate venv
(``docs/fragility-export.md``).

    python fragility_export_reader.py openquake FILE.xml [FILE.xml ...] [--at X,X,... ...]
    python fragility_export_reader.py pelicun FILE.csv [FILE.csv ...] [--at X,X,... ...]
                                      [--samples N]

``--at`` is given once per FILE, in order (or not at all). Prints one JSON object on stdout,
{"tool", "version", "files": [what was read from each FILE]}; exit status 3 (and the import
error on stderr) when the tool cannot be imported here, 0 when it read every file, anything else
when reading failed. The tool is imported once for all files (OpenQuake takes seconds).

* ``openquake``: ``openquake.hazardlib.nrml.to_python`` (with ``openquake.risklib.read_nrml``,
  which registers the fragility model's converter) - the reader the engine's
  ``riskmodels.get_risk_functions`` uses. For each fragility function: the IMT, the ``mean``
  and ``stddev`` as read, minIML, maxIML, noDamageLimit, and the probabilities of OpenQuake's
  own curve (``FragilityFunctionList.build``: ``scientific.FragilityFunctionContinuous``) at the
  ``--at`` intensities [OpenQuake's unit of the IMT].
* ``pelicun``: ``Assessment.damage.load_model_parameters`` with every ID of the file in the
  asset model (it checks the table, drops incomplete rows and converts the units to pelicun's
  base units). For each component: the parameters as loaded, and, at each ``--at`` demand
  [the file's Demand-Unit], the share of ``--samples`` realizations (seed 0) in which pelicun's
  own damage calculation puts it in DS1, the component at location 0, direction 1, under that
  demand (``<acronym>-0-1``), and pelicun's multipliers of non-directional demands.
"""

from __future__ import annotations

import argparse
import json
import sys


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def read_openquake(path: str, at: list[float]) -> dict:
    import numpy as np
    from openquake.hazardlib import nrml
    from openquake.risklib import read_nrml  # noqa: F401  (registers fragilityModel)

    model = nrml.to_python(path)
    out = {"path": path, "id": model.id,
           "assetCategory": model.assetCategory, "lossCategory": model.lossCategory,
           "limitStates": list(model.limitStates), "functions": []}
    for (imt, fid), ffl in model.items():
        (function,) = ffl.build(model.limitStates)
        out["functions"].append({
            "imt": str(imt), "id": str(fid), "format": ffl.format,
            "mean": float(function.mean), "stddev": float(function.stddev),
            "minIML": float(ffl.minIML), "maxIML": float(ffl.maxIML),
            "noDamageLimit": float(ffl.nodamage),
            "at": at, "poes": [float(p) for p in function(np.array(at, dtype=float))]})
    return out


def read_pelicun(path: str, at: list[float], samples: int) -> dict:
    import pandas as pd
    from pelicun import assessment

    ids = sorted(set(pd.read_csv(path)["ID"].astype(str)))
    options = {"PrintLog": False, "Verbose": False, "Seed": 0}
    a = assessment.Assessment(options)
    a.damage.load_model_parameters([path], set(ids))
    params = a.damage.ds_model.damage_params
    out = {"path": path, "missing": list(a.damage.missing_components),
           "nondirectional_multipliers": dict(a.options.nondir_multi_dict),
           "components": {}}
    for cid, row in params.iterrows():
        out["components"][str(cid)] = {
            "demand_type": str(row[("Demand", "Type")]),
            "directional": int(row[("Demand", "Directional")]),
            "offset": int(row[("Demand", "Offset")]),
            "incomplete": int(row[("Incomplete", "")]) if ("Incomplete", "") in row.index
            else None,
            "family": str(row[("LS1", "Family")]),
            "theta_0": float(row[("LS1", "Theta_0")]),
            "theta_1": float(row[("LS1", "Theta_1")]),
            "p_ds1": []}
    if at:
        from pelicun.base import EDP_to_demand_type

        raw = pd.read_csv(path).set_index("ID")
        for x in at:
            run = assessment.Assessment(options)
            cols = {}
            for cid in out["components"]:
                acronym = EDP_to_demand_type[str(raw.loc[cid, "Demand-Type"])]
                cols[f"{acronym}-0-1"] = str(raw.loc[cid, "Demand-Unit"])
            demand = pd.DataFrame([list(cols.values())] + [[x] * len(cols)] * samples,
                                  columns=list(cols), index=["Units"] + list(range(samples)))
            run.demand.load_sample(demand)
            marginals = pd.DataFrame({"Units": "ea", "Location": "0", "Direction": "1",
                                      "Theta_0": "1", "Blocks": "1"},
                                     index=list(out["components"]))
            run.asset.load_cmp_model({"marginals": marginals})
            run.asset.generate_cmp_sample()
            run.damage.load_model_parameters([path], run.asset.list_unique_component_ids())
            run.damage.calculate()
            sample = run.damage.ds_model.sample
            for cid in out["components"]:
                ds = sample.xs(cid, axis=1, level="cmp")
                ds1 = ds.loc[:, ds.columns.get_level_values("ds") == "1"]
                out["components"][cid]["p_ds1"].append(float(ds1.to_numpy().mean()))
        out["samples"] = samples
        out["at"] = at
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("tool", choices=("openquake", "pelicun"))
    p.add_argument("paths", nargs="+", metavar="FILE")
    p.add_argument("--at", type=_floats, action="append", default=[],
                   help="intensities or demands at which to evaluate the tool's curves, "
                        "once per FILE")
    p.add_argument("--samples", type=int, default=20000)
    args = p.parse_args(argv)
    try:
        if args.tool == "openquake":
            import openquake.hazardlib.nrml
            import openquake.risklib.read_nrml  # noqa: F401
        else:
            import pelicun.assessment  # noqa: F401
    except Exception as e:                     # noqa: BLE001 (any failure to import says so)
        print(f"{args.tool} cannot be imported by {sys.executable}: "
              f"{type(e).__name__}: {e}", file=sys.stderr)
        return 3
    if args.at and len(args.at) != len(args.paths):
        p.error(f"--at given {len(args.at)} times for {len(args.paths)} files")
    at = args.at or [[] for _ in args.paths]
    if args.tool == "openquake":
        from openquake.baselib import __version__ as version
        files = [read_openquake(path, x) for path, x in zip(args.paths, at)]
        out = {"tool": "openquake.engine", "version": version, "files": files}
    else:
        from pelicun import __version__ as version
        files = [read_pelicun(path, x, args.samples) for path, x in zip(args.paths, at)]
        out = {"tool": "pelicun", "version": version, "files": files}
    json.dump(out, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

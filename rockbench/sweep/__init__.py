"""Many runs: grids of cases, parallel execution and a resumable result store
(``docs/sweeps.md``).

* :mod:`.cases` - what a case is (:func:`normalize_case`, :func:`case_id`), grids
  (:func:`pulse_grid`) and the case catalogue (``rockbench/scenarios/cases.toml``);
* :mod:`.executors` - the one executor (serial | process pool | Dask);
* :mod:`.store` - the one store (Parquet rows, comparison payloads, code fingerprint, the
  writer lock); :mod:`.map_store` - the map rows' schema and store folder (``docs/maps.md``);
* :mod:`.adaptive` - adaptive maps (simulate where the verdict can change, infer the rest);
* :mod:`.runs` - :func:`run_case` and :func:`run_cases`.

:func:`overturn_map` (defined in :mod:`rockbench.comparison`) pivots a sweep frame into an A x W
table (paper Figs. 4-8).
"""

from __future__ import annotations

from .cases import CASE_KEYS, case_id, normalize_case, pulse_grid
from .executors import EXECUTORS
from .runs import TIMING_COLUMNS, run_case, run_cases
from .store import load_store
from ..comparison import overturn_map

__all__ = ["run_cases", "run_case", "normalize_case", "case_id", "load_store", "pulse_grid",
           "overturn_map", "CASE_KEYS", "TIMING_COLUMNS", "EXECUTORS"]

"""Studies built on single runs, each a pure function of scenes, motions and settings that
returns pandas frames:

* :mod:`.maps` - overturning maps over (A, W, pulse) grids, their store and agreement;
* :mod:`.sensitivity` - the analytic model's own sensitivity band for a record;
* :mod:`.validation` - the validation set of a scene (the evidence advice is chosen on);
* :mod:`.tradeoff`, :mod:`.tradeoff_tables` - work-precision: error against CPU cost;
* :mod:`.advise` - the cheapest setting that meets a tolerance, confirmed on held-out cases;
* :mod:`.robustness` - stability at the extremes (what ``rockbench stress`` runs);
* :mod:`.fragility` - records judged at a ladder of scales (IDA, fragility curves).

Modules are imported on use, so importing the package costs nothing.
"""

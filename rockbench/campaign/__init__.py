"""The campaign: a plan (data; the paper's plan ships as ``scenarios/paper-plan.toml``, users
pass their own or derive one from their scenes) -> runs -> comparison tables -> report pages.

* :mod:`.plan` - plans: read, validate, derive from scenes;
* :mod:`.run` - ``run_campaign``: the whole campaign behind ``rockbench report``;
* :mod:`.maps`, :mod:`.choice`, :mod:`.fragility` - its map, decision and fragility parts.

Modules are imported on use (``import rockbench.campaign.run``), so importing the package
costs nothing.
"""

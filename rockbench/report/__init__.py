"""Reports: figures, the self-contained HTML page of one comparison, and the default campaign.

>>> from rockbench.compare import compare                                  # doctest: +SKIP
>>> from rockbench.report import write_case_report, run_campaign          # doctest: +SKIP
>>> write_case_report(compare(scene, pulse), "reports/my-case")           # doctest: +SKIP
>>> run_campaign("reports")           # what `make report` runs            # doctest: +SKIP

The report layer only reads Results and comparison tables (it never imports an engine). What
the pages show, the agreement colours and their thresholds: ``docs/report.md``.
"""

from __future__ import annotations

from .campaign import run_campaign
from .html import write_case_report

__all__ = ["run_campaign", "write_case_report"]

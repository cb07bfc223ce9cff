"""Reports: figures and the self-contained HTML pages. This layer reads Results and comparison
tables only: it imports no engine, scene, sweep, runner or campaign module.

>>> from rockbench.comparison import compare                                  # doctest: +SKIP
>>> from rockbench.report import write_case_report                        # doctest: +SKIP
>>> write_case_report(compare(scene, pulse), "reports/my-case")           # doctest: +SKIP

The default campaign (what `make report` runs) is :func:`rockbench.campaign.run.run_campaign`. What
the pages show, the agreement colours and their thresholds: ``docs/report.md``.
"""

from __future__ import annotations

from .case_page import write_case_report

__all__ = ["write_case_report"]

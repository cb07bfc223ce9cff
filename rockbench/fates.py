"""The words of a decision, defined once: the fate of an engine at a tolerance.

The search that decides (:func:`rockbench.studies.search.search`) writes them, and the command
line, the JSON and the report's page read them from its tables; no other word is used for a
setting's fate. The order is the order of the decision tables (best first).
"""

from __future__ import annotations

__all__ = ["FATES", "ORDER", "CONFIRMED", "ALMOST", "ABSENT"]

#: fate -> what it means.
FATES: dict[str, str] = {
    "meets": "converged on the choice part and within the tolerance on the held-out part",
    "fails held-out": "a converged setting missed the tolerance on the held-out part, and no "
                      "finer one was confirmed",
    "not converged": "within the tolerance at some setting, but not at two in a row (a lucky "
                     "or erratic step, or only at the finest one run)",
    "dearer": "not searched further: its next setting would cost more than a confirmed one",
    "budget ended": "not searched further: the search's CPU budget ended before its next "
                    "setting (what to run next, with its estimated cost, says how to go on)",
    "not reached": "beyond the tolerance at every setting run",
    "diverged": "no setting ran ok on the evidence",
    "not installed": "its engine does not import here",
    "left out": "not selected",
}

#: The fates in the order of a decision table.
ORDER: tuple[str, ...] = tuple(FATES)

#: The one fate of a recommendation.
CONFIRMED = "meets"

#: Fates of an engine that reaches the tolerance somewhere without being confirmed: a page
#: says "reaches it but is not confirmed, because ..." for them, never "no engine reaches".
ALMOST: tuple[str, ...] = ("fails held-out", "not converged")

#: Fates of an engine that did not run at all.
ABSENT: tuple[str, ...] = ("not installed", "left out")

"""The campaign's conclusion: plain-language findings computed from its tables
(``docs/report.md``, "The campaign page", section 1). Reads tables only."""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from . import figures as F

__all__ = ["campaign_conclusion"]


def _pct(x: float) -> str:
    """A percentage with 2 decimals, "n/a" when missing."""
    return "n/a" if x is None or pd.isna(x) else f"{100.0 * x:.2f} %"


def _groups(df: pd.DataFrame, hybrid: Mapping[str, bool],
            noun: str = "frames") -> list[tuple[str, pd.DataFrame]]:
    """(label, rows) for the free-standing and the hybrid scenes of ``df`` (column scene);
    ``hybrid`` says which scenes have devices (a scene missing from it: judged by its name);
    ``noun``: what they are ("frames"; "structures" when a block is among them)."""
    if not len(df):
        return []
    hyb = df["scene"].map({s: bool(hybrid.get(s, "hybrid" in str(s)))
                           for s in df["scene"].unique()}).astype(bool)
    out = [(f"free-standing {noun}", df[~hyb]), (f"hybrid {noun}", df[hyb])]
    return [(k, v) for k, v in out if len(v)]


def campaign_conclusion(engines: pd.DataFrame, metrics: pd.DataFrame, eta_summary: pd.DataFrame,
                        records: pd.DataFrame, *,
                        hybrid: Mapping[str, bool] | None = None,
                        noun: str = "frames") -> list[str]:
    """Plain-language findings computed from the campaign's tables (numbers: nrmse and
    real-time factors ``.3g``, relative errors in percent with 2 decimals).

    ``hybrid``: scene name -> whether it has devices (tendons, dampers), to group the
    findings into free-standing and hybrid frames (default: judged by the name); ``noun``: what
    the scenes are ("frames"; "structures" when a block is among them). The maps' agreement is
    said by the maps part (:func:`rockbench.report.words.agreement_words`)."""
    hybrid = dict(hybrid or {})
    lines: list[str] = []
    eng = engines[engines["backend"] != "analytic"] if len(engines) else engines
    ranked = eng[eng["n_ok"] > 0].sort_values("nrmse_median") if len(eng) else eng
    pulses = metrics[(metrics["part"] == "pulse") & (metrics["backend"] != "analytic")] \
        if len(metrics) else metrics
    order = list(ranked["backend"]) if len(ranked) else []
    if not len(eng):
        lines.append("Only the analytic reference ran: there is no engine to compare.")
    elif not len(ranked):
        lines.append("No engine finished a pulse case cleanly: nothing to compare with the "
                     "analytic model.")
    else:
        # each engine's accuracy at its default setting, best first (the cost of accuracy
        # is the decision's, in CPU time: report/decision.py)
        for _, r in ranked.iterrows():
            lines.append(
                f"{r['backend']} at its default setting: median nrmse {r['nrmse_median']:.3g} "
                f"over {int(r['n_ok'])} pulse cases (largest {r['nrmse_max']:.3g}), median peak "
                f"rotation error {_pct(r['peak_rel_error_median'])} (largest "
                f"{_pct(r['peak_rel_error_max'])}).")
        ok = pulses[pulses["status"] == "ok"]
        for label, g in _groups(ok, hybrid, noun):
            parts = []
            for name in order:
                s = g[g["backend"] == name]
                if len(s):
                    parts.append(f"{name} {s['nrmse'].median():.3g} / "
                                 f"{_pct(s['peak_rel_error'].abs().median())}")
            if parts:
                lines.append(f"Pulse cases on {label}, median nrmse / median |peak error|: "
                             + ", ".join(parts) + ".")
    if len(eta_summary):
        es = eta_summary[eta_summary["backend"] != "analytic"].dropna(subset=["rel_error"])
        for b, g in es.groupby("backend", sort=False):
            worst = g.loc[g["rel_error"].abs().idxmax()]
            per = "; ".join(f"{label} {_pct(x['rel_error'].abs().mean())}"
                            for label, x in _groups(g, hybrid, noun))
            lines.append(
                f"Free rocking: the effective eta of {b} is off the analytic eta by "
                f"{_pct(g['rel_error'].abs().mean())} on average over scenes and directions "
                f"({per}); worst {worst['scene']} "
                f"({'counterclockwise' if worst['direction'] == 1 else 'clockwise'}): "
                f"{worst['eta_mean']:.4f} against {worst['eta_ref']:.4f} "
                f"({100 * worst['rel_error']:+.2f} %).")
    if len(metrics):
        dis = pulses[pulses["verdict_agrees"].fillna(True).astype(bool) == False]
        for _, r in dis.iterrows():
            what = "overturns" if bool(r["overturned"]) else "survives"
            lines.append(f"{r['backend']} {what} under {r['case']}, unlike the analytic "
                         f"model.")
        bad = metrics[~metrics["status"].isin(["ok", "unavailable"])]
        for case, g in bad.groupby("case", sort=False):
            refrow = metrics[(metrics["case"] == case) & (metrics["backend"] == "analytic")]
            verdict = ""
            if len(refrow) and pd.notna(refrow.iloc[0]["overturned"]):
                verdict = (" (the analytic model overturns there)"
                           if bool(refrow.iloc[0]["overturned"]) else
                           " (the analytic model survives there)")
            who = ", ".join(f"{r['backend']} ({r['status']}: {r['reason'] or 'no reason'})"
                            for _, r in g.iterrows())
            lines.append(f"{case}: not finished cleanly by {who}{verdict}.")
        if not len(bad):
            lines.append("No pulse or free-rocking run diverged.")
        flags = pulses[pulses["status"] == "ok"]
        if len(flags) and not flags["energy_gained_at_impact"].fillna(False).astype(bool).any():
            lines.append("No engine gained energy at an impact in any pulse case.")
            order_flags: list[str] = []
        else:
            order_flags = order
        for b in order_flags:
            parts = []
            for label, g in _groups(flags[flags["backend"] == b], hybrid, noun):
                n = int(g["energy_gained_at_impact"].fillna(False).astype(bool).sum())
                parts.append(f"{n} of {len(g)} on {label}")
            if parts:
                lines.append(f"Energy gained at an impact (an effective eta >= 1, or kinetic "
                             f"energy that grows across an impact), {b}: " + ", ".join(parts)
                             + " (pulse cases).")
    if len(records):
        ref = records[records["backend"] == "analytic"]
        for frame, g in ref.groupby("frame", sort=False):
            ot = g["overturned"].fillna(False).astype(bool)
            rest = g.loc[~ot, "max_abs_phi_over_alpha"]
            lines.append(f"Records, {frame} frame: the analytic model overturns in "
                         f"{int(ot.sum())} of {len(g)} record runs (both polarities)"
                         + (f"; largest peak max |phi| / alpha of the others "
                            f"{rest.max():.3g}." if len(rest) else "."))
        for b in [x for x in F._order(records["backend"]) if x != "analytic"]:
            s = records[records["backend"] == b]
            v = s["verdict_agrees"].dropna().astype(bool)
            pk = s["peak_rel_error"].astype(float).abs().dropna()
            nok = int((s["status"] != "ok").sum())
            lines.append(f"Records, {b}: {int(v.sum())} of {len(v)} verdicts agree with the "
                         f"analytic model; median |peak error| "
                         f"{_pct(pk.median()) if len(pk) else 'n/a'}"
                         + (f"; {nok} run{'s' if nok > 1 else ''} not ok." if nok else "."))
    return lines

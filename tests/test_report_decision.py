"""The report's first screen (the decision) and the legibility of its figures."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from rockbench.report.choice_page import advice_display
from rockbench.report.decision import decision_html, decision_sentences, decision_table, pct
from rockbench.report.legibility import (MIN_TEXT_PX, make_legible, overlapping_texts,
                                         text_px)


def _advice(held_out: bool = True) -> pd.DataFrame:
    rows = [
        dict(tolerance=0.02, rank=1, engine="pymunk", status="meets", setting="dt=0.0005",
             dt=5e-4, worst_error=0.0168, cpu_per_sim_s=0.0135, reason=""),
        dict(tolerance=0.02, rank=2, engine="mujoco", status="meets", setting="dt=0.001",
             dt=1e-3, worst_error=0.0057, cpu_per_sim_s=0.0142, reason=""),
        dict(tolerance=0.002, rank=1, engine="mujoco", status="cannot reach",
             setting="dt=0.0001", dt=1e-4, worst_error=0.00205, cpu_per_sim_s=0.11,
             reason="best 0.205 %"),
        dict(tolerance=0.002, rank=2, engine="pymunk", status="cannot reach",
             setting="dt=0.00025", dt=2.5e-4, worst_error=0.0138, cpu_per_sim_s=0.024,
             reason="best 1.38 %"),
    ]
    df = pd.DataFrame(rows)
    if held_out:
        df["held_out_worst_error"] = [0.019, 0.008, np.nan, np.nan]
    return df


def test_pct_formats_fractions_as_percentages():
    assert pct(0.0168) == "1.68 %"
    assert pct(0.02, 0) == "2 %"
    assert pct(None) == "n/a" and pct(float("nan")) == "n/a" and pct(float("inf")) == "∞"


def test_one_sentence_per_tolerance_names_engine_setting_cost_and_held_out_error():
    s = decision_sentences(_advice(), "my-bent")
    assert len(s) == 2
    assert "use pymunk at dt=0.0005" in s[0] and "0.0135 CPU s" in s[0]
    assert "1.68 %" in s[0] and "1.90 % on held-out" in s[0] and "my-bent" in s[0]
    assert "no engine reaches it" in s[1] and "closest: mujoco (0.21 %" in s[1]


def test_a_setting_within_the_tolerance_but_unconfirmed_is_said_so():
    adv = _advice()
    adv.loc[0, "status"] = "unconfirmed"
    adv.loc[1, "status"] = "fails held-out"
    s = decision_sentences(adv, "x")
    assert s[0].startswith("For 2 % on x: no setting is confirmed. mujoco at dt=0.001")
    assert "fails on the held-out cases" in s[0]
    t = decision_table(adv)
    assert t.set_index("engine").loc["pymunk", "within 2 %"].startswith("unconfirmed (best")


def test_without_held_out_column_the_sentence_does_not_invent_one():
    s = decision_sentences(_advice(held_out=False), "x")
    assert "held-out" not in s[0]


def test_decision_table_one_row_per_engine_with_percentages():
    agreement = pd.DataFrame({"scene": ["x", "x"], "backend": ["pymunk", "mujoco"],
                              "agree_fraction": [0.998, 1.0], "kappa": [0.996, 1.0]})
    eta = pd.DataFrame({"scene": ["x"] * 4, "backend": ["pymunk", "pymunk", "mujoco", "mujoco"],
                        "direction": [1, -1, 1, -1], "rel_error": [0.0007, -0.0021, 0.001, 0.0]})
    breaks = pd.DataFrame({"engine": ["pymunk"], "axis": ["dt"], "side": ["above"],
                           "value": [0.01], "class": ["off"], "reason": ["sliding"]})
    t = decision_table(_advice(), agreement=agreement, eta_summary=eta, breaks=breaks, scene="x")
    assert list(t["engine"]) == ["pymunk", "mujoco"]
    row = t.set_index("engine").loc["pymunk"]
    assert row["within 2 %"].startswith("dt=0.0005: 0.0135 CPU s/s, worst 1.68 %")
    assert row["within 0.2 %"] == "not reached (best 1.38 %)"
    assert row["map agreement"] == "99.8 %, kappa 0.996"
    assert row["free-rocking eta error (worst, every scene)"] == "0.21 %"
    assert row["breaks first at"] == "dt 0.01 (off)"
    assert t.set_index("engine").loc["mujoco", "breaks first at"] == "nowhere tried"


def test_decision_html_is_short_prose():
    html = decision_html(_advice(), scene="x", work_precision_html="<figure></figure>")
    import re
    text = re.sub(r"<table.*?</table>", " ", html, flags=re.S)
    words = re.sub(r"<[^>]+>", " ", text).split()
    assert len(words) <= 250


def test_advice_display_shows_percentages_and_no_setting_that_cannot_reach():
    d = advice_display(_advice())
    assert d["worst error [%]"].iloc[0] == "1.68 %"
    assert d["tolerance [%]"].iloc[2] == "0.20 %"
    assert "dt" not in d and "rank" not in d
    assert d["setting"].iloc[2] == "" and d["setting"].iloc[0] == "dt=0.0005"


def _small_text_figure() -> Figure:
    fig = Figure(figsize=(16, 4), layout="constrained")
    axes = fig.subplots(1, 4)
    for ax in axes:
        ax.plot([1e-3, 1e-2, 1e-1], [1, 2, 3])
        ax.set_xscale("log")
        ax.set_title("panel", fontsize=6)
        ax.tick_params(labelsize=5)
        ax.set_xlabel("cost [CPU s/s]", fontsize=6)
    return fig


def test_make_legible_raises_small_text_to_the_minimum_as_shown():
    fig = _small_text_figure()
    assert text_px(fig, 100) < MIN_TEXT_PX
    shown = make_legible(fig, 100)
    assert shown == pytest.approx(MIN_TEXT_PX)
    assert text_px(fig, 100) >= MIN_TEXT_PX - 1e-9


def test_overlap_detector_finds_overlapping_labels():
    fig = Figure(figsize=(2, 2))
    ax = fig.subplots()
    ax.set_xticks(np.arange(20))
    ax.set_xticklabels([f"label{i}" for i in range(20)], fontsize=12)
    assert overlapping_texts(fig)
    fig2 = Figure(figsize=(6, 4), layout="constrained")
    ax2 = fig2.subplots()
    ax2.plot([0, 1], [0, 1])
    assert overlapping_texts(fig2) == []


def test_the_evidence_is_named_with_its_size():
    from rockbench.report.decision import evidence_note

    t = pd.DataFrame({"n_choice": [6, 6], "n_heldout": [6, 5]})
    text = evidence_note(t, size="quick")
    assert "quick set" in text and "6 to choose on and 6 held out" in text
    assert "default evidence" in text
    text = evidence_note(t, size="default")
    assert "default set" in text and "--full" in text
    assert "full set" in evidence_note(t, size="full")
    assert evidence_note(pd.DataFrame(), size="quick") == ""

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


def _advice() -> pd.DataFrame:
    """An advice table (advice.csv) of two tolerances: at 2 % pymunk meets, MuJoCo ties; at
    0.5 % nothing is confirmed."""
    rows = [
        dict(tolerance=0.02, rank=1, engine="pymunk", status="meets", recommended=True,
             setting="dt=0.0005", worst_error_choice=0.0168, worst_error_heldout=0.019,
             cpu_per_sim_s=0.0135, tie_with_cheapest=True, reason=""),
        dict(tolerance=0.02, rank=2, engine="mujoco", status="meets", recommended=False,
             setting="dt=0.001", worst_error_choice=0.0057, worst_error_heldout=0.008,
             cpu_per_sim_s=0.0142, tie_with_cheapest=True, reason=""),
        dict(tolerance=0.005, rank=1, engine="mujoco", status="not reached", recommended=False,
             setting="dt=0.0001", worst_error_choice=0.0071, worst_error_heldout=np.nan,
             cpu_per_sim_s=0.11, tie_with_cheapest=False, reason="choice: ..."),
        dict(tolerance=0.005, rank=2, engine="pymunk", status="not reached",
             recommended=False, setting="dt=0.00025", worst_error_choice=0.0138,
             worst_error_heldout=np.nan, cpu_per_sim_s=0.024, tie_with_cheapest=False,
             reason="choice: ..."),
        dict(tolerance=0.005, rank=3, engine="opensees", status="not installed",
             recommended=False, setting=None, worst_error_choice=np.nan,
             worst_error_heldout=np.nan, cpu_per_sim_s=np.nan, tie_with_cheapest=False,
             reason="openseespy does not import"),
    ]
    return pd.DataFrame(rows)


def test_pct_formats_fractions_as_percentages():
    assert pct(0.0168) == "1.68 %"
    assert pct(0.02, 0) == "2 %"
    assert pct(None) == "n/a" and pct(float("nan")) == "n/a" and pct(float("inf")) == "∞"


def test_one_sentence_per_tolerance_rendered_from_the_table():
    s = decision_sentences(_advice(), "my-bent")
    assert len(s) == 2
    assert s[0].startswith("Within 2 % on my-bent: use pymunk at dt=0.0005 (0.0135 CPU s")
    assert "1.68 % on the cases it was chosen on, 1.90 % on the held-out ones" in s[0]
    assert "as cheap within the machine's noise: mujoco at dt=0.001" in s[0]
    assert s[1].startswith("Within 0.5 % on my-bent: no engine reaches it")
    assert "closest: mujoco (0.71 % at dt=0.0001)" in s[1]


def test_a_planted_row_changes_the_sentence():
    """The page cannot contradict its table: a row that meets the tolerance on both parts makes
    the sentence recommend it; a held-out failure is said as such, never "no engine reaches";
    a setting within the tolerance but not converged is "reaches it but is not confirmed"."""
    adv = _advice()
    meets = dict(tolerance=0.005, rank=0, engine="drake", status="meets", recommended=True,
                 setting="dt=0.001,accuracy=1e-07", worst_error_choice=0.00035,
                 worst_error_heldout=0.0012, cpu_per_sim_s=0.2, tie_with_cheapest=False,
                 reason="")
    s = decision_sentences(pd.concat([adv, pd.DataFrame([meets])], ignore_index=True), "x")
    assert s[1].startswith("Within 0.5 % on x: use drake at dt=0.001,accuracy=1e-07")
    adv.loc[2, "status"] = "fails held-out"
    adv.loc[2, "worst_error_choice"], adv.loc[2, "worst_error_heldout"] = 0.004, 0.0063
    s = decision_sentences(adv, "x")
    assert s[1].startswith("Within 0.5 % on x: no engine is confirmed. mujoco reaches it at "
                           "dt=0.0001 on the chosen cases (0.40 %) but misses it on the "
                           "held-out ones (0.63 %)")
    assert "no engine reaches" not in s[1]
    adv.loc[2, "status"] = "not converged"
    s = decision_sentences(adv, "x")
    assert "mujoco reaches it (0.40 % at dt=0.0001) but is not confirmed" in s[1]


def test_a_sentence_says_what_to_run_next():
    s = decision_sentences(_advice(), "x", next_steps={0.005: {
        "engine": "mujoco", "setting": "dt=5e-05", "cpu_s": 123.4, "command": "..."}})
    assert s[1].endswith("To try next: mujoco at dt=5e-05, about 123 CPU s.")


def test_decision_table_one_row_per_engine_every_fate_shown():
    agreement = pd.DataFrame({"scene": ["x", "x"], "backend": ["pymunk", "mujoco"],
                              "cells": [40000, 40000], "differ": [13, 0],
                              "agree_fraction": [1 - 13 / 40000, 1.0], "kappa": [0.996, 1.0]})
    eta = pd.DataFrame({"scene": ["x"] * 4, "backend": ["pymunk", "pymunk", "mujoco", "mujoco"],
                        "direction": [1, -1, 1, -1], "rel_error": [0.0007, -0.0021, 0.001, 0.0]})
    breaks = pd.DataFrame({"engine": ["pymunk"], "axis": ["dt"], "side": ["above"],
                           "value": [0.01], "unit": ["s"], "class": ["off"],
                           "reason": ["sliding 3.2 mm > 2 mm; more"]})
    t = decision_table(_advice(), agreement=agreement, eta_summary=eta, breaks=breaks, scene="x")
    assert set(t["engine"]) == {"pymunk", "mujoco", "opensees"}
    row = t.set_index("engine").loc["pymunk"]
    assert row["within 2 %"] == "dt=0.0005 · 0.013 CPU s/s · 1.68 % / 1.90 %"
    assert row["within 0.5 %"] == "not reached (1.38 % at dt=0.00025)"
    assert row["map agreement"] == "13 of 40000 differ, kappa 0.996"
    assert row["free-rocking eta error (worst)"] == "0.21 %"
    # the axis's unit and the reason measured, not the footnote's generic one
    assert row["breaks first at"] == "dt = 0.01 s: off (sliding 3.2 mm > 2 mm)"
    assert t.set_index("engine").loc["mujoco", "breaks first at"] == "holds at every point tried"
    assert t.set_index("engine").loc["opensees", "within 0.5 %"] == "not installed"


def test_decision_html_is_short_prose():
    html = decision_html(_advice(), scene="x", work_precision_html="<figure></figure>")
    import re
    text = re.sub(r"<table.*?</table>", " ", html, flags=re.S)
    text = re.sub(r"<small>.*?</small>", " ", text, flags=re.S)
    words = re.sub(r"<[^>]+>", " ", text).split()
    assert len(words) <= 250


def test_advice_display_shows_percentages():
    d = advice_display(_advice())
    assert d["worst error choice [%]"].iloc[0] == "1.68 %"
    assert d["tolerance [%]"].iloc[2] == "0.50 %"
    assert "rank" not in d


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


def test_the_evidence_is_named_with_its_size_and_coverage():
    from rockbench.report.decision import evidence_note

    t = pd.DataFrame({"n_choice": [6, 6], "n_heldout": [6, 5]})
    text = evidence_note(t, size="quick")
    assert "quick set" in text and "6 to choose on and 6 held out" in text
    assert "default evidence" in text
    cov = {"counted": 4, "overturning": 0, "records": 1, "near_boundary": 2,
           "thin": "thin held-out evidence: 4 counted case(s), without an overturning case"}
    text = evidence_note(t, size="quick", coverage=cov, cpu_s=61.2)
    assert "held out: 4 counted (0 overturning, 1 record), 2 near the boundary" in text
    assert "Note: thin held-out evidence" in text and "spent 61 CPU s" in text
    text = evidence_note(t, size="default")
    assert "default set" in text and "--full" in text
    assert "full set" in evidence_note(t, size="full")
    assert evidence_note(pd.DataFrame(), size="quick") == ""


def test_the_analytic_model_is_a_row_of_the_decision_with_its_cost_and_validity():
    """The decision covers models: the analytic model's row first (exact inside its validity,
    at its measured cost), its sentence first, the ratio to the cheapest confirmed setting
    computed from the table (0.0135 / 0.00135 = 10)."""
    model = {"cpu_per_sim_s": 0.00135, "holds": "PGA <= mu g = 0.5 g",
             "breaks": "PGA > 0.5 g: the base slides (outside the model)"}
    tab = decision_table(_advice(), model=model)
    assert tab.iloc[0]["engine"] == "analytic model"
    assert tab.iloc[0]["within 2 %"].startswith("exact · 0.0014 CPU s/s")
    assert tab.iloc[0]["breaks first at"].startswith("PGA > 0.5 g")
    assert list(tab["engine"][1:]) == list(decision_table(_advice())["engine"])
    words = decision_sentences(_advice(), "frame", model=model)
    assert words[0].startswith("Inside the analytic model's validity (PGA <= mu g = 0.5 g)")
    assert "the cheapest confirmed engine setting costs 10 times as much" in words[0]
    assert words[1:] == decision_sentences(_advice(), "frame")
    dearer = dict(model, cpu_per_sim_s=0.027)
    assert "costs 0.5 times as much" in decision_sentences(_advice(), "f", model=dearer)[0]

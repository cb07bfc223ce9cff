"""The one search (``rockbench advise`` and the report): the rules on controlled error curves
(a fake work-precision measurement), the fates' vocabulary, the order and the budget, the
answer's JSON and words, and real runs on a user's scene."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.fates import FATES
from rockbench.studies import advise as A
from rockbench.studies import decide as D
from rockbench.studies import search as S
from rockbench.studies import tradeoff as T


# =========================================================================================
# The convergence rule (pure)
# =========================================================================================
def test_convergence_accepts_a_monotone_curve():
    c = D.convergence([(4e-3, 0.08), (2e-3, 0.03), (1e-3, 0.015), (5e-4, 0.007)], 0.02)
    assert c["step"] == 1e-3 and c["status"] == "converged" and not c["erratic"]


def test_convergence_refuses_a_lucky_step_and_names_an_erratic_curve():
    bent = [(4e-3, 0.05), (2e-3, 0.01), (1e-3, 0.06), (5e-4, 0.05)]
    c = D.convergence(bent, 0.03)
    assert c["step"] is None and c["status"] == "lucky steps only" and c["erratic"]
    c = D.convergence(bent + [(2.5e-4, 0.001), (1e-4, 0.0002)], 0.03)
    assert c["step"] == 2.5e-4


def test_convergence_accepts_converged_noise():
    c = D.convergence([(2e-3, 0.004), (1e-3, 0.005)], 0.02)
    assert c["step"] == 2e-3 and c["status"] == "converged" and not c["erratic"]


@pytest.mark.parametrize("tol", [0, -0.1, 1.5, "x"])
def test_tolerance_is_checked(tol):
    with pytest.raises(rb.ParameterError, match="tolerance"):
        S.search("housner-block", [tol])


# =========================================================================================
# The search on controlled curves
# =========================================================================================
def _cases():
    from rockbench.studies.validation import ValidationCase
    return [ValidationCase("free", f"free{i}", None, 0.01, 1.0, part=p, group="free",
                           peak_ref=0.3)
            for i, p in enumerate(["choice", "held-out", "choice", "held-out"])]


def _fake(errors, costs, calls):
    """A tradeoff whose runs have, for engine E at knob value v on part P, the error
    errors[E][P][v] (missing: inf) and cost costs[E] x (1e-3 / v) CPU s per simulated s."""
    def fake(scene, engines, *, exact, cases, on_row=None, **kw):
        (eng,), (over,) = engines, exact
        knob = "dt" if "dt" in over else next(iter(over))
        v = over[knob]
        parts = {c.part for c in cases}
        calls.append((eng, v, "choice" if parts == {"choice"} else "held-out"))
        cost = costs[eng] * (1e-3 / v if knob == "dt" else 1.0)
        rows = []
        for c in cases:
            e = errors[eng][c.part].get(v, math.inf)
            rows.append({"engine": eng, "setting": f"{knob}={v:g}", "dt": v, "case": c.name,
                         "kind": c.kind, "part": c.part, "group": c.group,
                         "near_boundary": False, "status": "ok" if e < math.inf else
                         "diverged", "verdict_agrees": True, "error": e, "sim_time": 1.0,
                         "_cpu": np.array([cost]), "cpu_s_median": cost,
                         "build_cpu_s": 0.0, "warmup_cpu_s": math.nan})
            if on_row is not None:
                on_row({"cpu_s": [cost]})
        runs = pd.DataFrame(rows)
        for col in T.RUN_COLUMNS:
            if col not in runs:
                runs[col] = math.nan
        return T.Tradeoff(scene=scene.name, cases=list(cases), runs=runs, table=pd.DataFrame())
    return fake


@pytest.fixture
def fake(monkeypatch):
    """Install a controlled measurement; returns (set_curves, calls)."""
    import rockbench.engines as E

    calls = []
    monkeypatch.setattr(T, "validation_set", lambda scene, **kw: _cases())
    monkeypatch.setattr("rockbench.studies.validation.validation_set",
                        lambda scene, **kw: _cases())

    def states(selected=None):
        names = list(selected or [])
        return [{"name": n, "state": "ran", "detail": "fake"} for n in names]
    monkeypatch.setattr(E, "engine_states", states)

    def set_curves(errors, costs):
        monkeypatch.setattr(T, "tradeoff", _fake(errors, costs, calls))
    return set_curves, calls


def _curve(choice, held):
    return {"choice": choice, "held-out": held}


def test_the_search_converges_confirms_and_stops_where_it_may_not_pay(fake):
    """pymunk (cheap) meets 2 % at dt 2e-3 (confirmed by 1e-3 and held out); mujoco (dearer per
    run) is not searched further than its coarsest rung: its next rung costs more than
    pymunk's confirmed answer."""
    set_curves, calls = fake
    set_curves({"pymunk": _curve({4e-3: 0.05, 2e-3: 0.01, 1e-3: 0.005}, {2e-3: 0.012}),
                "mujoco": _curve({4e-3: 0.04, 2e-3: 0.01, 1e-3: 0.001}, {2e-3: 0.01})},
               {"pymunk": 0.001, "mujoco": 0.01})
    d = S.search("housner-block", [0.02], ["pymunk", "mujoco"], dts=[4e-3, 2e-3, 1e-3],
                 executor="serial")
    rec = d.recommended(0.02)
    assert rec["engine"] == "pymunk" and rec["setting"] == "dt=0.002"
    assert rec["worst_error_heldout"] == pytest.approx(0.012)
    assert ("pymunk", 2e-3, "held-out") in calls
    assert [c for c in calls if c[0] == "mujoco"] == [("mujoco", 4e-3, "choice")]
    mj = d.at(0.02).set_index("engine").loc["mujoco"]
    assert mj["status"] == "dearer" and "more than pymunk's confirmed" in mj["reason"]
    assert set(d.outcomes["status"]) <= set(FATES)


def test_a_held_out_failure_sends_the_engine_to_its_next_finer_step(fake):
    set_curves, calls = fake
    set_curves({"pymunk": _curve({4e-3: 0.05, 2e-3: 0.01, 1e-3: 0.005, 5e-4: 0.004},
                                 {2e-3: 0.05, 1e-3: 0.015})}, {"pymunk": 0.001})
    d = S.search("housner-block", [0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3, 5e-4],
                 executor="serial")
    rec = d.recommended(0.02)
    assert rec is not None and rec["setting"] == "dt=0.001"
    assert ("pymunk", 2e-3, "held-out") in calls and ("pymunk", 1e-3, "held-out") in calls


def test_a_held_out_failure_at_the_end_of_the_ladder_is_its_fate(fake):
    set_curves, _ = fake
    set_curves({"pymunk": _curve({4e-3: 0.05, 2e-3: 0.01, 1e-3: 0.005},
                                 {2e-3: 0.05, 1e-3: 0.05, 5e-4: 0.05})}, {"pymunk": 0.001})
    d = S.search("housner-block", [0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3],
                 executor="serial")
    r = d.at(0.02).iloc[0]
    assert d.recommended(0.02) is None and r["status"] == "fails held-out"
    assert "held out > 2 %" in r["reason"]


@pytest.mark.parametrize("choice, fate", [
    ({4e-3: 0.05, 2e-3: 0.03, 1e-3: 0.01}, "not converged"),   # only at the finest, then:
    ({4e-3: 0.05, 2e-3: 0.04, 1e-3: 0.03}, "not reached"),
    ({}, "diverged"),
])
def test_each_fate_says_what_happened(fake, choice, fate):
    set_curves, _ = fake
    if fate == "not converged":        # the finer step that would confirm 1e-3 misses
        choice = {**choice, 5e-4: 0.03}
    set_curves({"pymunk": _curve(choice, {})}, {"pymunk": 0.001})
    d = S.search("housner-block", [0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3],
                 executor="serial")
    assert d.at(0.02).iloc[0]["status"] == fate


def test_the_budget_stops_the_search_and_says_what_to_run_next(fake):
    set_curves, calls = fake
    set_curves({"pymunk": _curve({4e-3: 0.05, 2e-3: 0.03, 1e-3: 0.025}, {})},
               {"pymunk": 1.0})
    d = S.search("housner-block", [0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3, 5e-4],
                 executor="serial", budget_cpu_s=3.0)
    assert d.stopped.startswith("CPU budget")
    r = d.at(0.02).iloc[0]
    assert r["status"] == "budget ended" and "budget" in r["reason"]
    nxt = d.next_steps[0.02]
    assert nxt["engine"] == "pymunk" and nxt["cpu_s"] > 0 and "rockbench advise" in \
        nxt["command"]
    assert nxt["value"] == min(v for _, v, _ in calls) / 2     # one finer than the finest run
    assert d.cpu_s <= 3.0 + 1e-9


def test_advise_is_the_search_read_at_its_tolerances(fake):
    """The command's answer is the search's: the same recommendation, its settings run as they
    are, and JSON that names the fates and what was left out."""
    set_curves, _ = fake
    set_curves({"pymunk": _curve({4e-3: 0.05, 2e-3: 0.01, 1e-3: 0.005}, {2e-3: 0.012})},
               {"pymunk": 0.001})
    a = A.advise("housner-block", [0.1, 0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3],
                 executor="serial")
    d = S.search("housner-block", [0.1, 0.02], ["pymunk"], dts=[4e-3, 2e-3, 1e-3],
                 executor="serial")
    pd.testing.assert_frame_equal(a.decision.outcomes.drop(columns="reason"),
                                  d.outcomes.drop(columns="reason"))
    rec = a.recommended(0.02)
    assert rec["settings"] == {"dt": 0.002, "output_dt": 0.002}
    j = json.loads(json.dumps(a.to_json()))
    assert j["tolerances"] == [0.1, 0.02] and set(j["fates"]) == set(FATES)
    assert j["answers"][1]["setting_args"] == ["pymunk.dt=0.002", "pymunk.output_dt=0.002"]
    assert "use pymunk --setting pymunk.dt=0.002" in a.text()


def test_json_settings_round_trip_to_run_and_the_cli_grammar():
    from rockbench.cli.common import engine_settings

    settings = A._settings_of("pymunk", "dt=0.002,iterations=60")
    assert settings == {"dt": 0.002, "iterations": 60, "output_dt": 0.002}
    block = rb.load_scene("housner-block")
    r = rb.run(block, None, engine="pymunk", duration=0.2, phi0=0.3 * block.alpha, **settings)
    assert r.summary.status == "ok"
    args = A.setting_args("pymunk", settings)
    assert engine_settings(args, ["pymunk"]) == {"pymunk": settings}


def test_the_report_and_advise_give_one_answer(fake, tmp_path):
    """The report's choice part runs the same search: for the same scene and evidence its
    advice table holds advise's recommendation at every tolerance."""
    from rockbench.campaign.choice import run_choice

    set_curves, _ = fake
    set_curves({"pymunk": _curve({d: 0.001 for d in T.DT_LADDER}, {d: 0.001 for d in
                                                                    T.DT_LADDER})},
               {"pymunk": 0.001})
    a = A.advise("housner-block", None, ["pymunk"], executor="serial")
    c = run_choice(["pymunk"], tmp_path, quick=True, scene="housner-block", evidence="quick")
    adv = c["advice"]
    for t in a.tolerances:
        rec = a.recommended(t)
        row = adv[(adv["tolerance"] == t) & adv["recommended"]].iloc[0]
        assert (row["engine"], row["setting"]) == (rec["engine"], rec["setting"])


@pytest.mark.parametrize("engine", [n for n in rb.backend_names() if n != "analytic"])
def test_every_contact_variant_is_a_valid_setting_of_its_engine(engine):
    from rockbench.engines import get_backend

    cls = get_backend(engine)
    for v in cls.contact_variants:
        s = cls.Settings(**v)
        assert all(getattr(s, k) == x for k, x in v.items())


def test_the_advice_follows_the_backends_own_precision_knob():
    from rockbench.engines import get_backend
    from rockbench.studies.advise import precision_knob
    from rockbench.studies.tradeoff_tables import DT_LADDER

    for n in rb.backend_names():
        knob, values, fixed = get_backend(n).precision_sweeps[0]
        if knob == "dt":
            assert precision_knob(n) == ("dt", tuple(DT_LADDER))
        else:
            assert precision_knob(n) == (knob, tuple(float(v) for v in values))


def test_coverage_says_when_the_held_out_part_is_thin():
    from rockbench.studies.validation import ValidationCase

    def case(kind, near=False, part="held-out"):
        return ValidationCase(kind, f"{kind}{near}", None, 0.0, 1.0, part=part,
                              near_boundary=near)
    thin = S.coverage([case("survive"), case("free"), case("overturn", near=True)])
    assert thin["counted"] == 2 and thin["near_boundary"] == 1
    assert "without an overturning case or a record" in thin["thin"]
    ok = S.coverage([case("survive")] * 4 + [case("overturn"), case("record")])
    assert ok["thin"] == ""


# =========================================================================================
# Real runs
# =========================================================================================
def test_cli_advise_on_a_user_scene_file_decides_every_tolerance(tmp_path, capsys,
                                                                 monkeypatch):
    """`rockbench advise FILE --quick --json` on a user's block (1 x 4 m): pymunk is confirmed at
    every tolerance of the ladder (its worst errors are >= 2x inside even the tightest, 0.5 %,
    at its finer steps); the JSON's fields agree with each other (the recommended setting is a
    measured row whose errors on both parts are within the tolerance; no coarser, cheaper row
    would have been confirmed; a tighter tolerance never gets a coarser step) and the store
    makes a rerun free."""
    from rockbench.cli.main import main

    monkeypatch.setenv("ROCKBENCH_SEARCH_BUDGET", "none")     # not the machine's load
    f = tmp_path / "my-block.toml"
    f.write_text('name = "my-block"\n[structure]\ntype = "block"\nwidth = 1.0\nheight = 4.0\n')
    store = str(tmp_path / "store")
    argv = ["advise", str(f), "--engines", "pymunk", "--quick", "--json", "--workers", "1",
            "--store", store, "--quiet"]
    assert main(argv) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["scene"] == "my-block" and len(j["answers"]) == len(S.TOLERANCE_LADDER)
    assert [a["tolerance"] for a in j["answers"]] == list(S.TOLERANCE_LADDER) == j["tolerances"]
    rows = {e["setting"]: e for e in j["evidence"] if e["engine"] == "pymunk"}
    steps = []
    for ans in j["answers"]:
        tol, rec = ans["tolerance"], ans["recommended"]
        assert rec is not None, ans                        # confirmed at every tolerance
        r = ans["ranking"][0]
        assert r["engine"] == rec["engine"] == "pymunk" and r["status"] == "meets"
        assert r["recommended"] and r["setting"] == rec["setting"]
        assert rec["worst_error_heldout"] <= tol and rec["worst_error_choice"] <= tol
        assert f"pymunk.{rec['setting']}" in ans["setting_args"]
        # the recommendation is a measured row, with the same errors, on both parts
        row = rows[rec["setting"]]
        assert row["n_ok"] == row["n_cases"] > 0
        assert row["worst_error_choice"] == pytest.approx(rec["worst_error_choice"])
        assert row["worst_error_heldout"] == pytest.approx(rec["worst_error_heldout"])
        assert max(row["worst_error_choice"], row["worst_error_heldout"]) <= tol
        # cost ordering: no coarser (cheaper) measured step was within the tolerance on both
        # parts with its next finer step also within it on the choice part (confirmable)
        ladder = sorted(rows.values(), key=lambda e: -e["dt"])
        for k, e in enumerate(ladder[:-1]):
            if e["dt"] <= rec["value"]:
                break
            held = e["worst_error_heldout"]
            confirmable = (e["worst_error_choice"] <= tol and held is not None and held <= tol
                           and ladder[k + 1]["worst_error_choice"] <= tol)
            assert not confirmable, (tol, e["setting"], rec["setting"])
        steps.append(rec["value"])
    # a tighter tolerance never recommends a coarser step
    assert steps == sorted(steps, reverse=True) and steps[-1] < steps[0]
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["runs_cpu_s"] == 0.0                           # every run from the store
    assert [a["recommended"]["setting"] for a in again["answers"]] == \
        [a["recommended"]["setting"] for a in j["answers"]]


def test_cli_advise_rejects_a_bad_tolerance(capsys):
    from rockbench.cli.main import main

    assert main(["advise", "housner-block", "--tolerance", "2"]) == 2
    assert "tolerance" in capsys.readouterr().err


def test_a_tie_recommends_the_more_accurate_of_equals():
    """Two settings as cheap within the machine's noise: the recommendation is the more
    accurate one, whichever measured a little cheaper; one beyond the tie margin stays behind."""
    from rockbench.studies.search_outcomes import tie_order

    a = {"engine": "pymunk", "cpu_per_sim_s": 0.0060, "worst_error_choice": 0.04,
         "worst_error_heldout": 0.03, "value": 4e-3}
    b = {"engine": "mujoco", "cpu_per_sim_s": 0.0064, "worst_error_choice": 0.01,
         "worst_error_heldout": math.nan, "value": 4e-3}
    c = {"engine": "drake", "cpu_per_sim_s": 0.02, "worst_error_choice": 0.001,
         "worst_error_heldout": 0.001, "value": 1e-2}
    assert [g["engine"] for g in tie_order([a, b, c])] == ["mujoco", "pymunk", "drake"]
    b2 = dict(b, cpu_per_sim_s=0.0059)
    assert [g["engine"] for g in tie_order([b2, a, c])] == ["mujoco", "pymunk", "drake"]


def test_a_rung_that_may_be_confirmed_is_budgeted_with_its_held_out_part(fake, monkeypatch):
    """The budget counts the held-out runs a rung may bring: with room for the next choice
    part alone but not for its confirmation, the search stops before it."""
    monkeypatch.setattr("rockbench.machine.tree_cpu_s", lambda: 0.0)   # the fake runs' CPU
    set_curves, calls = fake
    set_curves({"pymunk": _curve({4e-3: 0.01, 2e-3: 0.01}, {4e-3: 0.01})}, {"pymunk": 0.5})
    # the coarsest rung (2 choice cases x 1 s x 0.125 CPU s/s) is within 2 %: the next rung
    # (0.25 CPU s/s) may confirm it, choice and held-out: 2 x 0.25 + 2 x 0.25 = 1 CPU s
    d = S.search("housner-block", [0.02], ["pymunk"], dts=[4e-3, 2e-3],
                 executor="serial", budget_cpu_s=0.25 + 0.75)
    assert d.stopped.startswith("CPU budget")
    assert ("pymunk", 2e-3, "choice") not in calls


def test_the_default_budget_can_be_set_for_every_search(monkeypatch):
    monkeypatch.setenv("ROCKBENCH_SEARCH_BUDGET", "none")
    assert S._auto_budget("quick") is None
    monkeypatch.setenv("ROCKBENCH_SEARCH_BUDGET", "90")
    assert S._auto_budget("default") == 90.0
    monkeypatch.setenv("ROCKBENCH_SEARCH_BUDGET", "-1")
    with pytest.raises(rb.ParameterError, match="ROCKBENCH_SEARCH_BUDGET"):
        S._auto_budget("quick")
    monkeypatch.delenv("ROCKBENCH_SEARCH_BUDGET")
    assert S._auto_budget("quick") == S.BUDGETS["quick"]


def test_the_docs_state_the_budgets_the_code_has():
    """docs/choosing.md gives the default budgets by value: they are the constants'."""
    from pathlib import Path

    from rockbench.constants import BUDGETS

    text = (Path(__file__).resolve().parents[1] / "docs" / "choosing.md").read_text()
    assert (f"`rockbench.studies.search.BUDGETS`: {BUDGETS['quick']:g} CPU s for the quick "
            "evidence") in " ".join(text.split())
    assert f"{BUDGETS['default']:g} for the default, none for the full" in " ".join(text.split())
    assert BUDGETS["full"] is None

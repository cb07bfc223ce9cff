"""The third independent set of bad inputs and faults: fragility, plan files, records, compared
maps and the sweep store. Each case ends in exit 2 with one line naming the parameter or file,
or works and is right; a fault (full disk, read-only store, second writer, damaged file,
Ctrl-C) is one line, loses nothing, and leaves the store consistent."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rockbench.cli.main import main
from rockbench.errors import ParameterError, RecordError, RockbenchError, RockbenchWarning
from rockbench.scene.records import find_records
from rockbench.sweep.store import load_store

ROOT = Path(__file__).resolve().parents[1]


def _at2(path: Path, acc, dt=0.01) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = ["TEST", "TEST", "ACCELERATION TIME HISTORY IN UNITS OF G",
             f"NPTS= {len(acc)}, DT= {dt:.5f} SEC"]
    lines += ["".join(f"{x:15.7E}" for x in acc[i:i + 5]) for i in range(0, len(acc), 5)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _pulse(t, a, f):
    return a * np.sin(2 * np.pi * f * t) * np.exp(-((t - 3) / 1.5) ** 2)


def _one_line(capsys, *argv) -> str:
    rc = main(list(argv))
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2, (rc, err)
    assert len(err) == 1 and err[0].startswith("rockbench: error: "), err
    return err[0]


# =========================================================================================
# Records: identified by path, never by stem; a broken listing or an empty record named
# =========================================================================================
def test_two_records_with_one_name_in_two_folders_are_both_kept(tmp_path):
    from rockbench.studies.ensembles import resolve_records

    t = np.arange(800) * 0.01
    a = _at2(tmp_path / "a" / "R.AT2", _pulse(t, 0.3, 1.5))
    b = _at2(tmp_path / "b" / "R.AT2", _pulse(t, 0.5, 0.8))
    recs, _ = find_records(tmp_path)
    assert sorted(r["name"] for r in recs) == ["a/R", "b/R"]
    both = resolve_records([tmp_path / "a", tmp_path / "b"])
    assert sorted(r["path"] for r in both) == sorted([str(a.resolve()), str(b.resolve())])
    assert len({r["name"] for r in both}) == 2
    assert len(resolve_records([a, a, str(a)])) == 1          # the same file once


def test_a_listing_that_names_a_missing_file_or_an_unknown_unit_is_named(tmp_path, capsys):
    t = np.arange(400) * 0.01
    d = tmp_path / "missing"
    d.mkdir()
    np.savetxt(d / "X.dat", 100 * np.sin(t))
    (d / "records.csv").write_text("record,dt_s,units\nX,0.01,cm/s^2\nGONE,0.01,cm/s^2\n")
    with pytest.raises(RecordError, match="lists record 'GONE'.*no file GONE"):
        find_records(d)
    u = tmp_path / "unit"
    u.mkdir()
    np.savetxt(u / "Y.dat", 100 * np.sin(t))
    (u / "records.csv").write_text("record,dt_s,units\nY,0.01,furlongs/fortnight\n")
    line = _one_line(capsys, "fragility", "housner-block", "--records", str(u), "-q",
                     "--store", str(tmp_path / "s"))
    assert "records.csv" in line and "furlongs" in line


def test_a_record_of_zeros_is_refused_before_any_run(tmp_path, capsys):
    z = _at2(tmp_path / "zero" / "Z.AT2", np.zeros(300))
    line = _one_line(capsys, "fragility", "housner-block", "--records", str(z.parent), "-q",
                     "--store", str(tmp_path / "s"))
    assert str(z.resolve()) in line and "PGA 0" in line
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("argv, name", [(["--seed", "-1"], "--seed"),
                                        (["--seed", str(2 ** 32)], "--seed"),
                                        (["--boot", "100000000"], "--boot"),
                                        (["--boot", "0"], "--boot")])
def test_fragility_bounds_are_checked_before_any_run(argv, name, tmp_path, capsys):
    t = np.arange(500) * 0.01
    _at2(tmp_path / "r" / "R.AT2", _pulse(t, 0.3, 1.5))
    line = _one_line(capsys, "fragility", "housner-block", "--records", str(tmp_path / "r"),
                     "-q", "--store", str(tmp_path / "s"), *argv)
    assert name in line
    assert not (tmp_path / "s").exists()


# =========================================================================================
# Plans: validated completely, from one schema, before any work
# =========================================================================================
BAD_PLANS = {
    "typo": ('pulse_pionts = [[2.0, 3.0]]', "pulse_pionts", "pulse_points"),
    "negative A": ('pulse_points = [[-2.0, 3.0]]', "pulse_points", "A in"),
    "unknown shape": ('pulse_shapes = [["sawtooth", 1]]', "pulse_shapes", "sawtooth"),
    "sign": ('pulse_shapes = [["symmetric", 2]]', "pulse_shapes", "sign"),
    "nan": ("free_duration = nan", "free_duration", "finite"),
    "negative duration": ("record_duration = -5.0", "record_duration", "(0, 3600]"),
    "string for a list": ('pulse_points = "2.0"', "pulse_points", "a list"),
    "evidence": ('choice_evidence = "huge"', "choice_evidence", "quick"),
    "short fracture case": ('fracture_cases = [["housner-block", "symmetric", 1, 2.0]]',
                            "fracture_cases", "W"),
    "no time-step sweep": ("dt_sweep = [1e-3]", "dt_sweep", "a key of the plan format"),
    "unknown scene": ('choice_scene = "nope-scene"', "choice_scene", "nope-scene"),
    "absurd grid": ("[campaign.maps]\nanalytic_grid = [100000, 100000]", "maps.analytic_grid",
                    "map_cells"),
    "equal axis ends": ('[campaign.maps]\nengine_amplitude = "2:2"', "maps.engine_amplitude",
                        "LO < HI"),
    "quick typo": ("[campaign.quick]\nmax_record = 1", "quick.max_record", "max_records"),
}


@pytest.mark.parametrize("name", list(BAD_PLANS))
def test_a_bad_plan_is_one_line_naming_the_key_before_any_work(name, tmp_path, capsys):
    body, key, hint = BAD_PLANS[name]
    plan = tmp_path / "plan.toml"
    head, _, table = body.partition("[campaign.")
    plan.write_text('kind = "campaign-plan"\n[campaign]\nscenes = ["housner-block"]\n'
                    + (head if not table else "") + ("\n[campaign." + table if table else "")
                    + "\n")
    out = tmp_path / "report"
    line = _one_line(capsys, "report", "--plan", str(plan), "--quick", "--out", str(out), "-q")
    assert f"plan {plan}: {key}" in line and hint in line, line
    assert not (out / "index.html").exists()


def test_a_string_where_the_scenes_belong_is_not_read_letter_by_letter(tmp_path, capsys):
    plan = tmp_path / "plan.toml"
    plan.write_text('kind = "campaign-plan"\n[campaign]\nscenes = "housner-block"\n')
    line = _one_line(capsys, "report", "--plan", str(plan), "--out", str(tmp_path / "o"), "-q")
    assert "scenes" in line and "a list" in line and "unknown scene 'h'" not in line


def test_the_papers_plan_passes_its_own_schema_and_the_docs_are_generated_from_it():
    from rockbench.campaign.plan import campaign_plan
    from rockbench.campaign.plan_schema import KEYS, markdown

    assert campaign_plan()["scenes"][0] == "paper-symmetric"
    assert (ROOT / "docs" / "plans.md").read_text() == markdown()
    data = __import__("tomllib").loads((ROOT / "rockbench" / "scenarios" / "paper-plan.toml")
                                       .read_text())
    used = set(data["campaign"]) - {"maps", "quick"}
    assert used <= {k.name for k in KEYS if k.table == "campaign"}


# =========================================================================================
# Maps: an axis that repeats, comparisons that say what they compare
# =========================================================================================
def test_equal_axis_ends_on_a_grid_of_several_points_are_refused():
    from rockbench.studies.maps import map_cells

    with pytest.raises(ParameterError, match="amplitude.*LO < HI"):
        map_cells(grid=(4, 4), amplitude="2:2", frequency="3:6")
    assert len(map_cells(grid=(1, 4), amplitude="2:2", frequency="3:6", pulses="symmetric+")
               ) == 4
    with pytest.raises(ParameterError, match="grid"):
        map_cells(grid=(1000, 1000), amplitude="1:8", frequency="1:10")


@pytest.fixture(scope="module")
def two_maps(tmp_path_factory):
    d = tmp_path_factory.mktemp("maps")
    from rockbench.studies.maps import run_map

    common = dict(frequency="3:6", pulses="symmetric+", tail=0.5, progress=False)
    run_map("housner-block", "analytic", grid=(4, 2), amplitude="1:7", store=d / "a.parquet",
            **common)
    run_map("housner-block", "analytic", grid=(7, 2), amplitude="1:7", store=d / "b.parquet",
            **common)
    return d


def test_compare_of_different_grids_says_what_it_compared(two_maps, capsys):
    rc = main(["map", "--compare", str(two_maps / "a.parquet"), str(two_maps / "b.parquet")])
    out = capsys.readouterr().out
    assert rc == 0
    assert "0 of 8 cells differ from the first map" in out, out
    assert "compared on the cells both maps hold (0 only in the first, 6 only in the second, " \
        "left out)" in out, out


@pytest.mark.parametrize("extra", [["housner-block"], ["--grid", "3x3"], ["--engine", "pymunk"],
                                   ["--amplitude", "1:2"], ["--adaptive"]])
def test_compare_with_options_of_a_run_is_refused(extra, two_maps, capsys):
    line = _one_line(capsys, "map", *extra, "--compare", str(two_maps / "a.parquet"),
                     str(two_maps / "b.parquet"))
    assert "--compare" in line


def test_compare_with_a_store_that_is_not_a_map_is_named(two_maps, tmp_path, capsys):
    other = tmp_path / "sweep"
    other.mkdir()
    (other / "notes.txt").write_text("not a map")
    line = _one_line(capsys, "map", "--compare", str(two_maps / "a.parquet"), str(other))
    assert str(other) in line and "not a map store" in line


def test_agreement_is_never_rounded_up_to_all():
    from rockbench.cli.maps import agreement_words

    ag = {"n": 40000, "differ": 13, "fraction": 1 - 13 / 40000, "kappa": 0.999,
          "cells_first": 40000, "cells_second": 40000, "common": 40000, "not_ok_first": 0,
          "not_ok_second": 195}
    words = agreement_words(ag)
    assert words.startswith("13 of 40000 cells differ from the first map (99.97 % agree)")
    assert "195 runs not ok, left out" in words
    one = dict(ag, differ=1, fraction=1 - 1 / 40000, not_ok_second=0)
    assert agreement_words(one) == ("1 of 40000 cells differ from the first map (99.998 % "
                                    "agree), Cohen's kappa 0.999")


# =========================================================================================
# The sweep store: one line for a full disk or a read-only folder; one writer; damage said
# =========================================================================================
def _cases(n=3):
    return [{"scene": "housner-block", "engine": "analytic", "motion": None,
             "phi0": 0.02 + 0.01 * i, "duration": 0.5} for i in range(n)]


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EACCES, errno.EROFS])
def test_a_store_that_cannot_be_written_is_one_line_and_keeps_what_finished(code, tmp_path,
                                                                              monkeypatch):
    from rockbench.sweep import run_cases
    from rockbench.sweep import store as S

    store = tmp_path / "store"
    run_cases(_cases(1), store=store, executor="serial", progress=False)
    real = pd.DataFrame.to_parquet

    def full(self, path, *a, **k):
        if "part-" in str(path):
            raise OSError(code, os.strerror(code), str(path))
        return real(self, path, *a, **k)

    monkeypatch.setattr(pd.DataFrame, "to_parquet", full)
    with pytest.raises(RockbenchError) as e:
        run_cases(_cases(3), store=store, executor="serial", progress=False)
    msg = str(e.value)
    assert "\n" not in msg and str(store) in msg and os.strerror(code) in msg
    assert ("free some disk space" in msg) == (code == errno.ENOSPC)
    assert not list(store.glob(".tmp-*"))                  # nothing half-written
    monkeypatch.setattr(pd.DataFrame, "to_parquet", real)
    assert len(S.load_store(store)) == 1                   # what finished is still there
    assert len(run_cases(_cases(3), store=store, executor="serial", progress=False)) == 3


def test_a_second_writer_of_a_sweep_store_is_refused(tmp_path):
    from rockbench.sweep import run_cases
    from rockbench.sweep.store import writer_lock

    store = tmp_path / "store"
    code = ("import sys, time; from pathlib import Path; "
            "from rockbench.sweep.store import writer_lock\n"
            f"with writer_lock(Path({str(store)!r}), 'store'):\n"
            "    print('held', flush=True); time.sleep(30)")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "held"
        with pytest.raises(RockbenchError, match=f"being written by another process.*pid "
                                                 f"{p.pid}"):
            run_cases(_cases(1), store=store, executor="serial", progress=False)
    finally:
        p.kill()
        p.wait()
    assert len(run_cases(_cases(1), store=store, executor="serial", progress=False)) == 1
    with writer_lock(store, "store"):       # released: a store is free again after its writer
        pass


def test_a_damaged_part_is_said_moved_aside_and_recomputed(tmp_path):
    from rockbench.sweep import run_cases

    store = tmp_path / "store"
    first = run_cases(_cases(2), store=store, executor="serial", progress=False)
    (f,) = list(store.glob("compact-*.parquet"))
    f.write_bytes(b"garbage")
    with pytest.warns(RockbenchWarning, match="unreadable.*moved it to"):
        again = run_cases(_cases(2), store=store, executor="serial", progress=False)
    assert (store / "_quarantine" / f.name).exists()
    assert list(again["max_abs_phi"]) == list(first["max_abs_phi"])


def test_a_read_only_store_that_holds_every_case_still_answers(tmp_path, monkeypatch):
    from rockbench.sweep import run_cases
    from rockbench.sweep import store as S

    store = tmp_path / "store"
    first = run_cases(_cases(2), store=store, executor="serial", progress=False)

    def refuse(*a, **k):
        raise AssertionError("nothing should be written or locked")

    monkeypatch.setattr(S, "write_row", refuse)
    monkeypatch.setattr(S, "writer_lock", refuse)
    again = run_cases(_cases(2), store=store, executor="serial", progress=False)
    assert list(again["case_id"]) == list(first["case_id"])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups: POSIX")
def test_ctrl_c_is_one_line_exit_130_and_the_store_stays_consistent(tmp_path):
    """Ctrl-C reaches the whole process group (the workers too): one line, exit 130, no
    worker traceback, every stored part complete and a rerun resumes."""
    t = np.arange(2000) * 0.01
    for i in range(6):
        _at2(tmp_path / "recs" / f"R{i}.AT2", _pulse(t, 0.2 + 0.05 * i, 1.0 + 0.1 * i))
    store = tmp_path / "store"
    argv = [sys.executable, "-m", "rockbench", "fragility", "paper-asymmetric", "--records",
            str(tmp_path / "recs"), "--scales", "0.5:2:12", "--engine", "analytic",
            "--store", str(store), "--workers", "2", "--boot", "10"]
    env = dict(os.environ, ROCKBENCH_REQUIRE_ENGINES="")
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True, env=env,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 600          # a cold numba cache on a loaded machine is slow
    while (time.time() < deadline and p.poll() is None
           and not list(store.glob("*/part-*.parquet"))):
        time.sleep(0.2)
    if p.poll() is not None:
        out, err = p.communicate()
        pytest.fail(f"the run ended before the interrupt (exit {p.returncode}): {err[-500:]}")
    os.killpg(p.pid, signal.SIGINT)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().splitlines()[-1] == "rockbench: interrupted"
    assert not list(store.glob("*/.tmp-*"))
    kept = len(load_store(next(store.iterdir())))
    assert kept >= 1

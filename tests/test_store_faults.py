"""Faults of maps and their store (issue 22 section 2): every one ends in one line naming the
file and the remedy (CLI exit 2), or is repaired with a warning; no work is lost beyond the
cells in flight. Analytic backend, tiny grids: seconds."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.errors import RockbenchWarning
from rockbench.cli.main import main
from rockbench.studies.map_agreement import map_agreement, mark_near_boundary
from rockbench.studies.maps import MAP_COLUMNS, load_map, map_cells, run_map

CELLS = dict(grid=(3, 2), amplitude="2:8", frequency="4:8", pulses="symmetric+", tail=0.5)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("rockbench: error:") and "\n" not in err and "Traceback" not in err, err
    return err


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A complete 6-cell analytic store and its map."""
    store = tmp_path_factory.mktemp("good") / "m.parquet"
    return run_map("paper-asymmetric", store=store, progress=False, chunk=2, **CELLS), store


def _copy(store: Path, to: Path) -> Path:
    import shutil

    shutil.copytree(store, to)
    return to


# ------------------------------------------------------------------------------------------
# Part files and _inputs.json
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fault", ["garbage", "truncated", "empty", "foreign"])
def test_a_bad_part_file_is_quarantined_and_its_cells_recomputed(fault, good, tmp_path):
    full, store = good
    copy = _copy(store, tmp_path / "m.parquet")
    (part,) = copy.glob("part-*.parquet")          # the run compacted its parts into one
    if fault == "garbage":
        (copy / "part-zz.parquet").write_bytes(b"PAR1 this is not parquet" * 10)
    elif fault == "truncated":                      # the only part: every cell is lost
        data = part.read_bytes()
        part.write_bytes(data[: len(data) // 2])
    elif fault == "empty":
        (copy / "part-zz.parquet").write_bytes(b"")
    else:
        pd.DataFrame({"x": [1, 2]}).to_parquet(copy / "part-zz.parquet")
    with pytest.warns(RockbenchWarning, match="unreadable"):
        assert len(load_map(copy)) == (0 if fault == "truncated" else 6)   # a reader skips
    with pytest.warns(RockbenchWarning, match="moved it to .*_quarantine"):
        again = run_map("paper-asymmetric", store=copy, progress=False, **CELLS)
    assert again.attrs["cells_run"] == (6 if fault == "truncated" else 0)
    pd.testing.assert_frame_equal(again.drop(columns="cpu_s"), full.drop(columns="cpu_s"))
    assert len(list((copy / "_quarantine").iterdir())) == 1
    assert len(pd.read_parquet(copy)) == 6         # the folder reads as the map, once per cell


@pytest.mark.parametrize("text", ["{", "", "[1, 2]"])
def test_a_broken_inputs_file_is_one_line_naming_it(text, good, tmp_path, capsys):
    _, store = good
    copy = _copy(store, tmp_path / "m.parquet")
    (copy / "_inputs.json").write_text(text)
    with pytest.raises(rb.RockbenchError, match=r"_inputs.json is unreadable.*delete the folder"):
        run_map("paper-asymmetric", store=copy, progress=False, **CELLS)
    args = ["map", "paper-asymmetric", "--grid", "3x2", "--amplitude", "2:8", "--frequency",
            "4:8", "--pulses", "symmetric+", "--store", str(copy)]
    assert main(args) == 2
    assert "_inputs.json" in _one_line_error(capsys)


def test_parts_without_inputs_are_refused(good, tmp_path):
    _, store = good
    copy = _copy(store, tmp_path / "m.parquet")
    (copy / "_inputs.json").unlink()
    with pytest.raises(rb.RockbenchError, match="no _inputs.json"):
        run_map("paper-asymmetric", store=copy, progress=False, **CELLS)


# ------------------------------------------------------------------------------------------
# Folders that cannot be written, no pyarrow
# ------------------------------------------------------------------------------------------
def test_a_store_that_cannot_be_created_is_one_line(tmp_path, capsys, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(rb.RockbenchError, match="cannot create the map store"):
        run_map("paper-asymmetric", store=blocker / "m.parquet", progress=False, **CELLS)
    # a read-only working folder (the default store maps/...): as root nothing is read-only,
    # so the refusal of mkdir is simulated
    monkeypatch.chdir(tmp_path)

    def refuse(self, *a, **k):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", refuse)
    assert main(["map", "paper-asymmetric", "--grid", "2x2"]) == 2
    err = _one_line_error(capsys)
    assert "maps/paper-asymmetric_analytic.parquet" in err and "Permission denied" in err
    assert "--store" in err


def test_no_pyarrow_is_refused_before_any_work_and_leaves_nothing(tmp_path, monkeypatch):
    import rockbench.sweep.store as S

    monkeypatch.setattr(S, "have_pyarrow", lambda: False)
    store = tmp_path / "m.parquet"
    with pytest.raises(rb.RockbenchError, match="pip install pyarrow"):
        run_map("paper-asymmetric", store=store, progress=False, **CELLS)
    assert not store.exists()


def test_a_failed_first_run_leaves_no_store(tmp_path):
    store = tmp_path / "m.parquet"
    with pytest.raises(rb.ParameterError, match="amplitude"):
        run_map("paper-asymmetric", store=store, progress=False,
                **dict(CELLS, amplitude="200:300"))
    assert not store.exists()


# ------------------------------------------------------------------------------------------
# The same limits on every path
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("option,value", [("--amplitude", "200:300"), ("--frequency", "1e-6:1"),
                                          ("--frequency", "1:1e6")])
def test_a_map_has_the_limits_of_run(option, value, tmp_path, capsys):
    assert main(["map", "paper-asymmetric", "--grid", "2x2", option, value, "--store",
                 str(tmp_path / "m.parquet")]) == 2
    err = _one_line_error(capsys)
    assert ("limit A" if option == "--amplitude" else "limit W") in err
    assert not (tmp_path / "m.parquet").exists()


# ------------------------------------------------------------------------------------------
# Engines that fail, schedulers that do not answer, too many workers
# ------------------------------------------------------------------------------------------
def test_a_map_whose_engine_cells_all_fail_is_data_not_a_traceback(tmp_path):
    """Every case errors (an unknown setting): rows with status error, no KeyError."""
    df = run_map("paper-asymmetric", "pymunk", settings={"no_such_setting": 1}, progress=False,
                 workers=1, store=tmp_path / "m.parquet", grid=(2, 1), amplitude="2:8",
                 frequency="4:4", pulses="symmetric+", tail=0.1)
    assert list(df.columns) == list(MAP_COLUMNS) + ["outside"] and len(df) == 2
    assert (df["status"] == "error").all() and df["overturned"].isna().all()
    assert len(load_map(tmp_path / "m.parquet")) == 2


def test_an_engine_that_does_not_import_is_one_line(tmp_path, monkeypatch):
    from rockbench.engines import get_backend

    cls = get_backend("pymunk")
    monkeypatch.setattr(cls, "available", classmethod(lambda c: (False, "no module pymunk")))
    store = tmp_path / "m.parquet"
    with pytest.raises(rb.RockbenchError, match="'pymunk' cannot run here: no module pymunk"):
        run_map("paper-asymmetric", "pymunk", store=store, progress=False, **CELLS)
    assert not store.exists()


def test_a_garbage_scheduler_address_is_refused(tmp_path, capsys):
    assert main(["map", "paper-asymmetric", "--grid", "2x2", "--scheduler", "garbage",
                 "--store", str(tmp_path / "m.parquet")]) == 2
    assert "scheduler" in _one_line_error(capsys)


def test_an_unreachable_scheduler_is_one_line_within_seconds(tmp_path, capsys):
    pytest.importorskip("distributed")
    from rockbench.sweep.executors import DASK_CONNECT_TIMEOUT

    t = time.monotonic()
    assert main(["map", "paper-asymmetric", "--grid", "2x2", "--scheduler",
                 "tcp://127.0.0.1:9", "--store", str(tmp_path / "m.parquet")]) == 2
    assert time.monotonic() - t < DASK_CONNECT_TIMEOUT + 20
    err = _one_line_error(capsys)
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err
    assert not (tmp_path / "m.parquet").exists()


def test_workers_are_capped_at_the_cores():
    from rockbench.sweep.executors import cpu_count, local_workers

    with pytest.warns(RockbenchWarning, match="more than the"):
        assert local_workers(cpu_count() + 62) == cpu_count()
    assert local_workers(1) == 1 and local_workers(None) == cpu_count()


# ------------------------------------------------------------------------------------------
# Two writers, kill -9
# ------------------------------------------------------------------------------------------
def test_a_second_writer_is_refused(good, tmp_path, capsys):
    from rockbench.sweep.store import writer_lock

    _, store = good
    copy = _copy(store, tmp_path / "m.parquet")
    with writer_lock(copy, "map store"):
        with pytest.raises(rb.RockbenchError, match=rf"being written by another process "
                                                     rf"\(pid {os.getpid()}\)"):
            run_map("paper-asymmetric", store=copy, progress=False, **CELLS)
    # released: the store is usable again
    assert run_map("paper-asymmetric", store=copy, progress=False, **CELLS).attrs["reused"] == 6


def _sleep_then_pid(seconds: float) -> int:
    import time
    time.sleep(seconds)
    return os.getpid()


def test_a_lock_is_released_even_with_a_kept_worker_forked_while_it_was_held(tmp_path):
    """A pool worker forked while this process held a store's lock shares the lock's open file
    description; releasing the lock must not wait for that worker to end (a campaign part keeps
    its pools across its sweeps, so the next write of the same store would be refused)."""
    from rockbench.sweep.executors import execute, kept_pools
    from rockbench.sweep.store import writer_lock

    d = tmp_path / "store"
    with kept_pools():
        with writer_lock(d):
            got = []
            execute(_sleep_then_pid, [("a", 0.01)], on_result=lambda k, r: got.append(r),
                    crashed=lambda item, why: None, workers=2, progress=False)
        assert got and got[0] != os.getpid()       # a worker of the kept pool, still alive
        with writer_lock(d):                      # the same store, written again: not refused
            pass


#: 24 solve_ivp cells of 0.05-0.5 s each, one part file per cell (the store keyed by its
#: inputs only, so that the subprocess and this one agree on it whatever the code's hash)
KILLABLE = dict(grid=(6, 4), amplitude="2:8", frequency="2:5", pulses="symmetric+", tail=10.0,
                keyed_by_code=False)
_KILLABLE = textwrap.dedent(f"""
    import sys
    from rockbench.studies.maps import run_map
    KILLABLE = {KILLABLE!r}
    run_map("paper-asymmetric", method="solve_ivp", store=sys.argv[1], progress=False,
            chunk=1, workers=1, **KILLABLE)
""")


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        out += [int(x) for x in text]
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and PDEATHSIG: Linux")
def test_kill_9_mid_map_loses_only_the_cells_in_flight(tmp_path):
    """A map killed with SIGKILL keeps every cell finished before the kill (one part file per
    cell here), its pool worker dies with it, a second writer is refused while it runs, and a
    rerun computes only the missing cells."""
    store = tmp_path / "m.parquet"
    script = tmp_path / "killable.py"
    script.write_text(_KILLABLE)
    proc = subprocess.Popen([sys.executable, str(script), str(store)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and len(list(store.glob("part-*.parquet"))) < 3:
            assert proc.poll() is None, proc.stderr.read().decode()
            time.sleep(0.05)
        seen = len(list(store.glob("part-*.parquet")))
        assert 3 <= seen < 24, seen
        with pytest.raises(rb.RockbenchError, match="being written by another process"):
            run_map("paper-asymmetric", method="solve_ivp", store=store, progress=False,
                    **KILLABLE)
        workers = _children(proc.pid)
        assert workers
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.05)
    assert not any(_alive(w) for w in workers), "pool workers outlived their parent"
    kept = load_map(store)
    assert len(kept) >= seen                         # nothing finished was lost
    again = run_map("paper-asymmetric", method="solve_ivp", store=store, progress=False,
                    **KILLABLE)
    assert again.attrs["reused"] == len(kept) and again.attrs["cells_run"] == 24 - len(kept)
    assert len(again) == 24 and (again["status"] == "ok").all()
    assert len(pd.read_parquet(store)) == 24         # compacted: each cell once


# ------------------------------------------------------------------------------------------
# Comparing maps
# ------------------------------------------------------------------------------------------
def _frame(As, W, over):
    return pd.DataFrame([dict(amplitude=float(A), frequency=float(W), pulse="symmetric",
                              sign=1, overturned=bool(over(A)), exceeded_critical=bool(over(A)),
                              max_abs_phi_over_alpha=1.0, n_impacts=1, fractured=False,
                              status="ok", wall_s=0.0) for A in As])


def test_compare_without_common_cells_is_an_error(tmp_path, capsys):
    a = _frame([1, 2, 3, 4], 2.0, lambda A: A >= 3)
    b = _frame([5, 6, 7, 8], 2.0, lambda A: A >= 5)
    with pytest.raises(rb.RockbenchError, match="no cell in common"):
        map_agreement(a, b)
    for name, df in (("a", a), ("b", b)):
        (tmp_path / f"{name}.parquet").mkdir()
        df.to_parquet(tmp_path / f"{name}.parquet" / "part-0.parquet")
    assert main(["map", "--compare", str(tmp_path / "a.parquet"),
                 str(tmp_path / "b.parquet")]) == 2
    assert "no cell in common" in _one_line_error(capsys)


def test_the_boundary_shift_is_measured_on_common_cells_only():
    """Overlapping A ranges: a overturns from A = 3, b from A = 5; on the common cells A = 3, 4
    b survives both, so b's boundary is not in the common range: no shift is invented."""
    a = _frame([1, 2, 3, 4], 2.0, lambda A: A >= 3)
    b = _frame([3, 4, 5, 6], 2.0, lambda A: A >= 5)
    ag = map_agreement(a, b)
    assert ag["n"] == 2 and ag["fraction"] == 0.0
    (row,) = ag["shift"].to_dict("records")
    assert row["a_min_a"] == 3.0 and np.isnan(row["a_min_b"]) and np.isnan(row["shift"])


# ------------------------------------------------------------------------------------------
# One verdict rule; near the boundary
# ------------------------------------------------------------------------------------------
def test_the_reference_finishes_a_fall_under_way():
    """Issue 24: paper-asymmetric, symmetric pulse -, W = 5.09, A = 7.36 (4.9 % above the
    threshold A = 7.020): the frame is at -8.19 alpha and falling when the map's run (6 T_g
    + 3 s) ends, and falls at 5.73 s. The reference's verdict is overturned, as the engines'
    (their collapse rule)."""
    (cell,) = [c for c in map_cells(grid=(12, 12), amplitude="1:8", frequency="1:10",
                                    pulses="symmetric-")
               if abs(c[2] - 7.3636) < 1e-3 and abs(c[3] - 5.0909) < 1e-3]
    kw = dict(grid=(1, 1), amplitude=(cell[2], cell[2]), frequency=(cell[3], cell[3]),
              pulses="symmetric-", tail=3.0, progress=False)
    for method in ("compiled", "solve_ivp"):
        df = run_map("paper-asymmetric", method=method, **kw)
        assert bool(df["overturned"].iloc[0]), method


def test_cells_near_the_reference_boundary_are_labelled():
    """Symmetric pulse -, W = 5.0909 on paper-asymmetric: threshold A = 7.020 (issue 24).
    Cells within 2 % of it are near the boundary, cells beyond 4 % are not."""
    df = run_map("paper-asymmetric", grid=(13, 1), amplitude="6.5:7.7",
                 frequency=(5.0909, 5.0909), pulses="symmetric-", tail=3.0, progress=False)
    out = mark_near_boundary(df, "paper-asymmetric", tail=3.0)
    rel = (out["amplitude"] - 7.020).abs() / 7.020
    assert out.loc[rel < 0.015, "near_boundary"].all()
    assert not out.loc[rel > 0.04, "near_boundary"].any()
    ag = map_agreement(out, df)
    assert ag["near_boundary"] == int(out["near_boundary"].sum()) > 0
    assert ag["disagree_near_boundary"] == ag["disagree_away"] == 0


def test_analytic_rows_keep_the_order_of_their_cells():
    """Rows come back in the order of the cells given, over several frequencies (what the
    fall extension and the near-boundary marks rely on: they match rows by position)."""
    import random

    from rockbench.studies.maps import _analytic_rows

    cells = map_cells(grid=(4, 3), amplitude="2:8", frequency="3:6", pulses="all")
    random.Random(1).shuffle(cells)
    df = _analytic_rows(rb.load_scene("paper-asymmetric"), cells, "compiled", 3.0)
    assert [(r.pulse, r.sign, r.amplitude, r.frequency) for r in df.itertuples()] == cells


def test_each_engine_cell_is_written_as_it_finishes(tmp_path, monkeypatch):
    """Engine maps write every finished cell (not chunks of 64): each write holds one cell
    before the merge at the end."""
    import rockbench.studies.maps as M

    sizes = []
    real = M.write_part
    monkeypatch.setattr(M, "write_part", lambda path, rows: (sizes.append(len(rows)),
                                                            real(path, rows))[1])
    df = run_map("paper-asymmetric", "pymunk", workers=1, store=tmp_path / "m.parquet",
                 progress=False, grid=(3, 1), amplitude="2:8", frequency="8:8",
                 pulses="symmetric+", tail=0.1)
    assert (df["status"] == "ok").all()
    assert sizes == [1, 1, 1]                    # three cells, three writes (then the merge)
    assert len(list((tmp_path / "m.parquet").glob("part-*.parquet"))) == 1


def test_adaptive_map_of_a_frame_with_tendons():
    """A hybrid frame has no critical angle while its tendons hold (info gives None): the
    adaptive map uses the smallest critical angle there is."""
    df = run_map("paper-asymmetric-hybrid-eps1", adaptive=True, grid=(9, 9), progress=False,
                 pulses="symmetric+", tail=0.5)
    assert len(df) == 81 and df.attrs["cells_run"] + df.attrs["inferred"] == 81


def test_a_measured_map_with_a_broken_inputs_file_is_not_reused(good, tmp_path):
    from rockbench.studies.maps import reuse_map

    _, store = good
    copy = _copy(store, tmp_path / "m.parquet")
    (copy / "_inputs.json").write_text("{")
    df, why = reuse_map(copy, "paper-asymmetric", "pymunk", **CELLS)
    assert df is None and "unreadable _inputs.json" in why

"""Independent parts of a run in lanes (rockbench.sweep.executors.run_parts): the campaign's
parts run two at a time, the second lane in a process of its own."""

from __future__ import annotations

import os

import pytest

from rockbench.sweep.executors import execute, run_parts


def _pid_and(x):
    return os.getpid(), x


def _spin(n: int) -> int:
    s = 0
    for i in range(n):
        s += i * i
    return s


def _pooled(n: int) -> list[int]:
    """A part whose work is in a local pool of two workers."""
    out: dict[str, int] = {}
    execute(_spin, [(str(i), n) for i in range(4)],
            on_result=lambda k, r: out.__setitem__(k, r),
            crashed=lambda item, why: -1, workers=2, progress=False)
    return [out[str(i)] for i in range(4)]


def _fails(x):
    raise ValueError(f"part failed on {x}")


def test_every_part_runs_once_in_its_lane_and_results_keep_the_parts_order():
    timings: dict = {}
    parts = {"a": (_pid_and, (1,)), "b": (_pid_and, (2,)), "c": (_pid_and, (3,))}
    got = run_parts(parts, timings, lanes=[["c"], ["a", "b"]])
    assert list(got) == ["a", "b", "c"]
    assert [v[1] for v in got.values()] == [1, 2, 3]
    assert got["c"][0] == os.getpid()                   # the first lane: this process
    assert got["a"][0] == got["b"][0] != os.getpid()    # the second: one process of its own
    assert set(timings) == {"a", "b", "c"}
    assert all(w >= 0.0 and c >= 0.0 for w, c in timings.values())


def test_a_part_s_cpu_includes_its_pool_workers():
    timings: dict = {}
    got = run_parts({"pooled": (_pooled, (2_000_000,)), "idle": (_pid_and, (0,))}, timings,
                    lanes=[["idle"], ["pooled"]])
    assert got["pooled"] == [_spin(2_000_000)] * 4
    wall, cpu = timings["pooled"]
    # four loops of two million squares each: their CPU is in the part's account, not only
    # the (idle) CPU of the lane's own thread
    one = timings["idle"][1]
    assert cpu > 4 * one and cpu > 0.2


def test_lanes_must_hold_each_part_once():
    with pytest.raises(ValueError, match="once"):
        run_parts({"a": (_pid_and, (1,)), "b": (_pid_and, (2,))}, {}, lanes=[["a"], ["a"]])


@pytest.mark.parametrize("lanes", [[["ok"], ["bad"]], [["bad"], ["ok"]]])
def test_a_failing_part_raises_its_error_whichever_lane_it_is_in(lanes):
    with pytest.raises(ValueError, match="part failed on 7"):
        run_parts({"ok": (_pid_and, (1,)), "bad": (_fails, (7,))}, {}, lanes=lanes)


def _worker_pids_of_two_sweeps(_: int) -> tuple[set[int], set[int]]:
    """Two sweeps of one part: the worker processes that ran each."""
    seen: list[set[int]] = []
    for _ in range(2):
        pids: set[int] = set()
        execute(_pid_and, [(str(i), i) for i in range(6)],
                on_result=lambda k, r: pids.add(r[0]), crashed=lambda item, why: None,
                workers=2, progress=False)
        seen.append(pids)
    return seen[0], seen[1]


def test_a_part_s_sweeps_share_one_pool_of_workers():
    """Within a part the pools are kept: its second sweep runs on the first one's workers
    (their imports and compiled kernels paid once); each part has its own."""
    got = run_parts({"p": (_worker_pids_of_two_sweeps, (0,)),
                     "q": (_worker_pids_of_two_sweeps, (0,))}, {}, lanes=[["p", "q"]])
    first, second = got["p"]
    # which worker takes which item is the scheduler's: a fresh pool for the second sweep
    # would bring new processes, so both sweeps together use at most the pool's two
    assert first and second and os.getpid() not in first | second
    assert len(first | second) <= 2
    assert not ((set(got["q"][0]) | set(got["q"][1])) & (first | second))

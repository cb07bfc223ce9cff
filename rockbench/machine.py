"""The machine a measurement ran on, described once: the tradeoff and advice tables
(``machine``), the report's versions block and the benchmarks' machine lines all read it.

Costs in rockbench are process CPU time; this says which processor they were measured on and
how many cores the process could use.
"""

from __future__ import annotations

import os
import platform
import sys
from typing import Any

__all__ = ["cpu_name", "cores", "describe", "tree_cpu_s", "process_cpu_s"]


def cpu_name() -> str:
    """The processor's model name (``/proc/cpuinfo``'s first ``model name``; elsewhere
    :func:`platform.processor`, or ``"unknown"``)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def cores() -> int:
    """Cores this process may run on (its CPU affinity; ``os.cpu_count()`` where there is
    none)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) so far of the live process ``pid`` (Linux ``/proc``; 0 when
    it has ended or elsewhere)."""
    tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / tick        # utime, stime
    except (OSError, IndexError, ValueError):
        return 0.0


def _live_children_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) of the live descendants of ``pid`` (Linux ``/proc``; 0
    elsewhere): pool workers still running are not in RUSAGE_CHILDREN until reaped."""
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        try:
            kids: list[int] = []
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children", encoding="ascii") as f:
                    kids += [int(k) for k in f.read().split()]
        except OSError:
            continue
        for k in kids:
            total += process_cpu_s(k)
            todo.append(k)
    return total


def tree_cpu_s() -> float:
    """CPU seconds (user + system) spent so far by this process, its ended children and its
    live descendants (pool workers): the cost of a phase of work is the difference of two
    calls. A worker that ended between the calls is counted once it is reaped."""
    import resource

    own = resource.getrusage(resource.RUSAGE_SELF)
    ended = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (own.ru_utime + own.ru_stime + ended.ru_utime + ended.ru_stime
            + _live_children_cpu_s(os.getpid()))


def describe() -> dict[str, Any]:
    """``{"processor", "cores", "python", "platform"}``: where a cost was measured (no engine
    is imported; the callers that know which engines ran add their versions)."""
    return {"processor": cpu_name(), "cores": cores(), "python": sys.version.split()[0],
            "platform": platform.platform()}

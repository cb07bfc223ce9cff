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

__all__ = ["cpu_name", "cores", "describe"]


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


def describe() -> dict[str, Any]:
    """``{"processor", "cores", "python", "platform"}``: where a cost was measured (no engine
    is imported; the callers that know which engines ran add their versions)."""
    return {"processor": cpu_name(), "cores": cores(), "python": sys.version.split()[0],
            "platform": platform.platform()}

"""Progress of long work, on stderr: a tqdm bar on a terminal, one plain line every
:data:`INTERVAL` seconds otherwise (a log file, CI, a pipe), nothing when quiet.

Two kinds of work report here:

* counted work (the cases of a sweep, the cells of a map, the runs of a campaign):
  :func:`bar` ``(total, desc, unit)`` returns an object with tqdm's ``update``,
  ``set_description``, ``set_postfix_str`` and ``close`` (the one executor,
  :func:`rockbench.sweep.executors.execute`, uses it);
* the simulated time of one long run: inside ``with simulated_time(desc):``, the stepping loop
  (:func:`rockbench.engines.loop.step_run`, every ``PROBE_CHUNK`` samples, where the compiled
  loop returns to Python anyway) calls :func:`sim_time` ``(t, t0, t_end)``, which shows the
  simulated seconds done out of the run's window. Outside such a block (worker processes, the
  Python API by default) :func:`sim_time` is a no-op costing one global lookup.

The command line calls :func:`configure` ``(quiet=...)`` once (``--quiet``); off a terminal
the first line comes only after :data:`INTERVAL` seconds, so short commands print nothing.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterator
from typing import Any

__all__ = ["INTERVAL", "configure", "enabled", "bar", "simulated_time", "sim_time"]

#: Seconds between two progress lines when stderr is not a terminal.
INTERVAL = 5.0

_quiet = False
_sim: "_SimTime | None" = None


def configure(*, quiet: bool) -> None:
    """Silence (``quiet=True``) or allow progress for the rest of the process."""
    global _quiet
    _quiet = bool(quiet)


def enabled() -> bool:
    """Whether progress may be shown (not configured quiet)."""
    return not _quiet


def _hms(seconds: float) -> str:
    s = int(round(max(seconds, 0.0)))
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class _Null:
    """A bar that shows nothing (quiet)."""

    n = 0

    def update(self, n: float = 1) -> None:
        self.n += n

    def set_description(self, desc: str, refresh: bool = True) -> None:
        pass

    def set_postfix_str(self, text: str = "", refresh: bool = True) -> None:
        pass

    def close(self) -> None:
        pass


class _Lines(_Null):
    """tqdm's interface, printing ``rockbench: DESC: N/TOTAL UNIT (P %), elapsed, ~left
    [POSTFIX]`` at most every :data:`INTERVAL` seconds, and a last line on close if it printed
    any."""

    def __init__(self, total: float | None, desc: str, unit: str, stream: Any = None,
                 interval: float | None = None):
        self.total, self.desc, self.unit, self.n = total, desc, unit, 0
        self.postfix = ""
        self.stream = stream
        self.interval = INTERVAL if interval is None else interval
        self.t0 = time.monotonic()
        self.last = self.t0
        self.printed = False

    def _line(self) -> str:
        elapsed = time.monotonic() - self.t0
        done = f"{self.n:.4g}" if isinstance(self.n, float) else str(self.n)
        text = f"rockbench: {self.desc}: {done}"
        if self.total:
            total = f"{self.total:.4g}" if isinstance(self.total, float) else str(self.total)
            frac = min(self.n / self.total, 1.0)
            text += f"/{total} {self.unit} ({100 * frac:.0f} %), {_hms(elapsed)} elapsed"
            if 0 < frac < 1:
                text += f", ~{_hms(elapsed * (1 - frac) / frac)} left"
        else:
            text += f" {self.unit}, {_hms(elapsed)} elapsed"
        return text + (f" [{self.postfix}]" if self.postfix else "")

    def _emit(self) -> None:
        try:
            print(self._line(), file=self.stream or sys.stderr, flush=True)
        except (OSError, ValueError):   # stderr closed: progress is never worth an error
            pass
        self.printed = True
        self.last = time.monotonic()

    def _maybe(self) -> None:
        if time.monotonic() - self.last >= self.interval:
            self._emit()

    def update(self, n: float = 1) -> None:
        self.n += n
        self._maybe()

    def set_description(self, desc: str, refresh: bool = True) -> None:
        self.desc = desc

    def set_postfix_str(self, text: str = "", refresh: bool = True) -> None:
        self.postfix = text
        if refresh:
            self._maybe()

    def close(self) -> None:
        if self.printed:
            self._emit()


def bar(total: float | None, desc: str, unit: str = "it", *, show: bool = True):
    """A progress bar for ``total`` items (tqdm's interface): a tqdm bar when stderr is a
    terminal, :class:`_Lines` otherwise, nothing when ``show`` is false or progress is quiet."""
    if not show or _quiet or sys.stderr is None:
        return _Null()
    if sys.stderr.isatty():
        from tqdm.auto import tqdm

        return tqdm(total=total, desc=desc, unit=unit, dynamic_ncols=True)
    return _Lines(total, desc, unit)


class _SimTime:
    """The simulated-time bar of the runs inside one :func:`simulated_time` block (made at the
    first report, when the run's window is known)."""

    def __init__(self, desc: str):
        self.desc = desc
        self.bar: Any = None
        self.window: tuple[float, float] | None = None
        self.done = 0.0

    def report(self, t: float, t0: float, t_end: float) -> None:
        if self.window != (t0, t_end):           # a new run (or the first)
            self.close()
            self.window = (t0, t_end)
            self.bar = bar(round(t_end - t0, 6), self.desc, "s simulated")
            self.done = 0.0
        step = min(t, t_end) - t0 - self.done
        if step > 0:
            self.done += step
            self.bar.update(step)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


@contextlib.contextmanager
def simulated_time(desc: str, *, show: bool = True) -> Iterator[None]:
    """Show the simulated time of the runs inside the block (``desc`` names them); nothing
    when ``show`` is false or progress is quiet."""
    global _sim
    if not show or _quiet:
        yield
        return
    previous, _sim = _sim, _SimTime(desc)
    try:
        yield
    finally:
        _sim.close()
        _sim = previous


def sim_time(t: float, t0: float, t_end: float) -> None:
    """Report that a run of window [t0, t_end] [s] has reached simulated time ``t`` [s]
    (called by the stepping loops; a no-op outside :func:`simulated_time`)."""
    if _sim is not None:
        _sim.report(float(t), float(t0), float(t_end))

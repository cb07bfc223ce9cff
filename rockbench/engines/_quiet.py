"""Keep the engines' own banners off the user's terminal: stderr carries rockbench's words only.

Two engines write to the C-level file descriptors, where ``contextlib.redirect_stderr`` cannot
reach them:

* PyBullet prints ``pybullet build time: ...`` to file descriptor 2 when it is imported;
* OpenSeesPy prints ``Process 0 Terminating`` to file descriptor 2 from a ``Py_AtExit`` hook,
  at the very end of the interpreter's shutdown (after every Python ``atexit`` handler).

:func:`silenced` points file descriptors 1 and 2 at ``/dev/null`` for the duration of a block
(flushing Python's and C's buffers on the way in and out); :func:`quiet_import` imports a module
inside it (only the first import prints anything); ``quiet_import(name, at_exit=True)`` also
registers :func:`_drop_c_stderr_at_exit`, which at interpreter exit moves Python's
``sys.stderr`` to a duplicate of file descriptor 2 and then points file descriptor 2 itself at
``/dev/null``: Python's own messages during shutdown still reach the terminal, the C library's
late writes to descriptor 2 do not. ``tests/test_quiet.py`` checks both in a subprocess.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import importlib
import os
import sys
import threading
from collections.abc import Iterator
from types import ModuleType

__all__ = ["silenced", "quiet_import"]

_lock = threading.RLock()
_exit_hook_registered = False


def _flush_all() -> None:
    """Flush Python's stdout/stderr and every C stdio stream (so that text buffered before a
    redirection lands where it was meant to go)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # pragma: no cover - no C library (not Linux/macOS)
        pass


@contextlib.contextmanager
def silenced(fds: tuple[int, ...] = (1, 2)) -> Iterator[None]:
    """Point the file descriptors ``fds`` at ``/dev/null`` inside the block, then restore
    them. Python-level and C-level writes alike are dropped. Not for long blocks: another
    thread writing to the same descriptors meanwhile is silenced too."""
    with _lock:
        _flush_all()
        saved: list[tuple[int, int]] = []
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            for fd in fds:
                try:
                    saved.append((fd, os.dup(fd)))
                except OSError:          # descriptor not open: nothing to silence
                    continue
                os.dup2(devnull, fd)
            yield
        finally:
            _flush_all()
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)
            os.close(devnull)


def quiet_import(name: str, *, at_exit: bool = False) -> ModuleType:
    """``importlib.import_module(name)`` with file descriptors 1 and 2 silenced during the
    first import; ``at_exit``: the module also writes to descriptor 2 at interpreter exit
    (OpenSeesPy), so drop the C library's writes to it then (:func:`_drop_c_stderr_at_exit`).
    Import errors propagate unchanged."""
    if name in sys.modules:
        # import_module, not sys.modules[name]: a module another thread is still importing
        # is in sys.modules half-initialised; import_module waits for it
        module = importlib.import_module(name)
    else:
        with silenced():
            module = importlib.import_module(name)
    if at_exit:
        _register_exit_hook()
    return module


def _register_exit_hook() -> None:
    global _exit_hook_registered
    if not _exit_hook_registered:
        _exit_hook_registered = True
        atexit.register(_drop_c_stderr_at_exit)


def _drop_c_stderr_at_exit() -> None:
    """At exit: keep ``sys.stderr`` writing to the real stderr (through a duplicate of file
    descriptor 2), then point descriptor 2 at ``/dev/null``, so that what C code prints after
    Python's ``atexit`` handlers (OpenSeesPy's ``Py_AtExit`` hook) is dropped."""
    try:
        _flush_all()
        keep = os.dup(2)
        old = sys.stderr
        sys.stderr = open(keep, "w", buffering=1, encoding=getattr(old, "encoding", None)
                          or "utf-8", errors="backslashreplace", closefd=True)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 2)
        os.close(devnull)
    except (OSError, ValueError):  # pragma: no cover - stderr already closed
        pass

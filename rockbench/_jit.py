"""numba compilation, cached once per installation: the one place that decides where compiled
kernels are stored and when they are stale.

``njit`` is numba's, except that ``cache=True`` stores the machine code in a per-user cache
folder keyed by **rockbench's version and a content hash of every kernel source file**, not in
``__pycache__`` beside the sources:

* a fresh checkout (or a reinstall) of the same code finds the kernels compiled by an earlier
  one, wherever it lives: numba's own in-tree cache is empty in a fresh checkout, and numba's
  ``NUMBA_CACHE_DIR`` keys its folders by the source file's *path*;
* any edit of any kernel file starts a new folder, so a kernel is never loaded with a stale
  copy of another file's kernel inlined into it (numba checks only the kernel's own file);
* inside a folder, numba's index still checks each file's content hash (numba >= 0.61 stamps a
  source by the SHA-256 of its bytes) and keys each entry by signature, CPU and numba version.

The folder: ``$ROCKBENCH_CACHE_DIR`` if set, else the platform's user cache folder
(``$XDG_CACHE_HOME/rockbench`` or ``~/.cache/rockbench`` on Linux), then
``jit/<version>-<hash>``; :func:`cache_dir` names it. Deleting it is always safe (the next run
compiles again). When it cannot be written, numba's default locations are used.

Kernel files are found by reading the package's sources once (every module that applies a
decorator named ``njit``); the compiled code also depends on Python constants the kernels read
from other modules at compile time, which is numba's rule too: change those and delete the cache.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import sys
import time
from pathlib import Path

__all__ = ["NUMBA_AVAILABLE", "NUMBA_ERROR", "njit", "prange", "numba", "cache_dir",
           "kernel_files", "CpuClock"]

_ROOT = Path(__file__).resolve().parent
# numba's parallel kernels (the analytic map cells on threads) run on OpenMP where it exists;
# its threads, waiting for the next loop, spin by default and bill that spinning as CPU time
# (a 100 x 100 map: 12.6 CPU s spinning against 9.1 passive, measured). Passive waiting, unless
# the user chose otherwise; read by the OpenMP runtime when it loads (at the first parallel
# kernel), so it is set here, before any
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
_DECORATED = re.compile(rb"^\s*@njit\b", re.M)

try:  # pragma: no cover - exercised by the environment, not by a test
    import numba
    from numba import prange
    from numba.core.caching import (CompileResultCacheImpl, FunctionCache,
                                    _CacheLocator, _SourceFileBackedLocatorMixin)
    NUMBA_AVAILABLE = True
    NUMBA_ERROR: str | None = None
except Exception as exc:  # noqa: BLE001 - any import failure means "no compiled path"
    numba = None  # type: ignore[assignment]
    NUMBA_AVAILABLE = False
    NUMBA_ERROR = f"numba could not be imported ({type(exc).__name__}: {exc})"
    prange = range  # type: ignore[assignment]


@functools.lru_cache(maxsize=1)
def kernel_files() -> tuple[str, ...]:
    """The package's source files that define compiled kernels (relative paths, sorted)."""
    out = []
    for f in sorted(_ROOT.rglob("*.py")):
        try:
            if _DECORATED.search(f.read_bytes()):
                out.append(f.relative_to(_ROOT).as_posix())
        except OSError:  # pragma: no cover - a file vanished while listing
            continue
    return tuple(out)


@functools.lru_cache(maxsize=1)
def cache_dir() -> Path:
    """The folder of this installation's compiled kernels (see the module docstring)."""
    from . import __version__

    h = hashlib.sha256()
    for rel in kernel_files():
        h.update(rel.encode() + b"\0")
        h.update((_ROOT / rel).read_bytes())
    base = os.environ.get("ROCKBENCH_CACHE_DIR")
    if not base:
        if sys.platform == "darwin":  # pragma: no cover - not tested here
            base = str(Path.home() / "Library" / "Caches" / "rockbench")
        elif os.name == "nt":  # pragma: no cover
            base = str(Path(os.environ.get("LOCALAPPDATA", Path.home())) / "rockbench" / "Cache")
        else:
            xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
            base = str(Path(xdg) / "rockbench")
    return Path(base) / "jit" / f"{__version__}-{h.hexdigest()[:16]}"


if NUMBA_AVAILABLE:
    class _InstallationLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
        """numba cache locator: rockbench's files go to :func:`cache_dir`, one sub-folder per
        module path inside the package (so the same module in two checkouts shares it)."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            rel = Path(py_file).resolve().relative_to(_ROOT).with_suffix("")
            self._cache_path = str(cache_dir() / ".".join(rel.parts))

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                Path(py_file).resolve().relative_to(_ROOT)
            except ValueError:
                return None                      # not a rockbench file: numba's locators
            return super().from_function(py_func, py_file)   # None when not writable

    class _Impl(CompileResultCacheImpl):
        _locator_classes = [_InstallationLocator, *CompileResultCacheImpl._locator_classes]

    class _Cache(FunctionCache):
        _impl_class = _Impl


def njit(*args, **kwargs):
    """``numba.njit`` with ``cache=True`` stored per installation (:func:`cache_dir`); without
    numba, the plain Python function (the callers check :data:`NUMBA_AVAILABLE`)."""
    if not NUMBA_AVAILABLE:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f
    cache = kwargs.pop("cache", False)

    def decorate(fn):
        dispatcher = numba.njit(**kwargs)(fn)
        if cache:
            dispatcher._cache = _Cache(dispatcher.py_func)
        return dispatcher
    if args and callable(args[0]):
        return decorate(args[0])
    return decorate


class CpuClock:
    """Process CPU time [s] of a block, split into the one-off work of numba (loading kernels
    from the cache or compiling them: ``compile_s``) and the rest (``cpu_s``)::

        with CpuClock() as clock:
            ...
        clock.cpu_s, clock.compile_s

    A run's :class:`~rockbench.result.Cost` reports the two apart (``cpu_s``,
    ``compile_cpu_s``): the first run of a kind in a process pays the compilation once, and a
    user comparing engines compares ``cpu_s``, what every later run costs. Compilation is timed
    from numba's ``numba:compiler_lock`` events (held while a dispatcher loads or compiles a
    kernel; nested holds count once). Without numba ``compile_s`` is 0."""

    def __init__(self) -> None:
        self.cpu_s = 0.0
        self.compile_s = 0.0
        self._depth = 0
        self._t0 = self._start = 0.0
        self._scope = None

    def _on_start(self) -> None:
        if self._depth == 0:
            self._start = time.process_time()
        self._depth += 1

    def _on_end(self) -> None:
        self._depth = max(self._depth - 1, 0)
        if self._depth == 0:
            self.compile_s += time.process_time() - self._start

    def __enter__(self) -> "CpuClock":
        if NUMBA_AVAILABLE:
            from numba.core import event as ev

            clock = self

            class _Listener(ev.Listener):
                def on_start(self, event) -> None:
                    clock._on_start()

                def on_end(self, event) -> None:
                    clock._on_end()

            self._scope = ev.install_listener("numba:compiler_lock", _Listener())
            self._scope.__enter__()
        self._t0 = time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        total = time.process_time() - self._t0
        if self._scope is not None:
            self._scope.__exit__(*exc)
            self._scope = None
        self.cpu_s = max(total - self.compile_s, 0.0)

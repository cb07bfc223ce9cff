"""The one executor: run a picklable function over many items, serially, on a process pool or
on a Dask cluster, handing every result to the caller as soon as it finishes.

:func:`execute` is what sweeps (:func:`rockbench.sweep.run_cases`) and the campaign use:

* ``"serial"``: in this process, one after the other (debugging, profiling);
* ``"process"``: ``concurrent.futures.ProcessPoolExecutor`` with at most ``workers`` items in
  flight, so that the progress bar names exactly the running items and a worker that *dies*
  (a segfault in an engine, the out-of-memory killer: ``BrokenProcessPool``) implicates only
  those items: they are run again one by one, each in a fresh process, and the culprit's result
  is ``crashed(item, reason)``;
* ``"dask"``: ``dask.distributed`` (``pip install 'rockbench[dask]'``): a ``Client`` to
  ``dask_address``, or a ``LocalCluster`` of ``workers`` single-threaded processes started and
  closed here; a task that kills its worker gives ``crashed(item, reason)``.

``fn`` must not raise for a failure of the work itself (turn it into a result): an exception
that escapes stops the run. Ctrl-C cancels the queued items at once; results already handed to
``on_result`` (and stored by the caller) are kept.

Local pools never have more workers than cores (:func:`local_workers`: a larger ``workers`` is
capped, with a warning), and their workers die with the process that started them
(:func:`_die_with_parent`: ``PR_SET_PDEATHSIG`` on Linux, so a ``kill -9`` of the parent leaves
no orphan computing on). Inside :func:`kept_pools`, a local pool outlives its :func:`execute`
call and serves the next ones (an adaptive map's rounds), so that its workers' imports and
compiled code are paid once. A Dask scheduler address is checked for its form and connected to
within :data:`DASK_CONNECT_TIMEOUT` seconds; either failure is a one-line
:class:`~rockbench.errors.RockbenchError` naming the address.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import re
import time
import warnings
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ..errors import ParameterError, RockbenchError, RockbenchWarning

__all__ = ["EXECUTORS", "execute", "check_options", "cpu_count", "kept_pools", "local_workers",
           "run_parts", "DASK_CONNECT_TIMEOUT"]

#: Seconds to wait for a Dask scheduler to answer before giving up (Dask's own default is 30).
DASK_CONNECT_TIMEOUT = 5.0

#: Executors accepted by :func:`execute` (and :func:`rockbench.sweep.run_cases`).
EXECUTORS = ("process", "serial", "dask")

Item = tuple[str, Any]


def cpu_count() -> int:
    """Cores this process may run on (affinity), at least 1."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def local_workers(workers: int | None) -> int:
    """Worker processes of a local pool: ``workers`` (default: the cores), capped at the cores
    this process may run on, with a warning when capped (more processes than cores only add
    memory: each worker holds its own engines)."""
    n = cpu_count()
    if workers is None:
        return n
    if workers > n:
        warnings.warn(f"--workers {workers} is more than the {n} cores this process may use: "
                      f"running {n} local worker processes", RockbenchWarning, stacklevel=3)
        return n
    return workers


_ADDRESS = re.compile(r"^(tcp|tls|inproc|ucx|ws|wss)://[^\s/:]+(:\d{1,5})?/?$"
                      r"|^[^\s/:]+:\d{1,5}$")


def check_address(address: str) -> str:
    """``address`` if it has the form of a Dask scheduler address (``tcp://host:port``, or
    ``host:port``); ParameterError otherwise."""
    if not isinstance(address, str) or not _ADDRESS.match(address.strip()):
        raise ParameterError("scheduler", address, "a Dask scheduler address such as "
                             "tcp://127.0.0.1:8786 (protocol://host:port)")
    return address.strip()


def check_options(executor: str, workers: int | None, dask_address: str | None) -> None:
    """ParameterError for an unknown executor, a bad ``workers``, an address without Dask or
    an address that is not of a scheduler's form."""
    if executor not in EXECUTORS:
        raise ParameterError("executor", executor, f"one of {', '.join(EXECUTORS)}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ParameterError("workers", workers, "an integer >= 1 or None")
    if dask_address is not None and executor != "dask":
        raise ParameterError("dask_address", dask_address, "given only with executor='dask'")
    if dask_address is not None:
        check_address(dask_address)


def _die_with_parent(parent: int) -> None:
    """Pool-worker initializer: ask the kernel to kill this worker when its parent dies (Linux
    ``prctl(PR_SET_PDEATHSIG, SIGKILL)``), and exit at once if the parent is already gone.
    Elsewhere nothing is done (the pool's own shutdown still ends the workers)."""
    import signal
    import sys

    # Ctrl-C reaches every process of the terminal's group: the parent stops the work (and
    # these workers) and says so in one line; a worker printing its own KeyboardInterrupt
    # traceback would bury that line
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no libc prctl
            pass
    if os.getppid() != parent:  # the parent died before the request took effect
        os._exit(1)


def _process_pool(workers: int):
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=workers, initializer=_die_with_parent,
                               initargs=(os.getpid(),))


#: The CPU account of the running part of :func:`run_parts` (a one-element list of seconds):
#: each local pool adds its workers' CPU time when it ends; None outside a part.
_CPU_SINK: contextvars.ContextVar[list[float] | None] = contextvars.ContextVar(
    "rockbench_cpu_sink", default=None)


def _account(ex) -> None:
    """Add the CPU seconds of ``ex``'s worker processes to the running part's account."""
    sink = _CPU_SINK.get()
    if sink is None:
        return
    from ..machine import process_cpu_s

    for proc in list((getattr(ex, "_processes", None) or {}).values()):
        sink[0] += process_cpu_s(proc.pid)


Part = tuple[Callable[..., Any], tuple]


def _run_lane(parts: dict[str, Part], quiet: bool = False
              ) -> tuple[dict[str, Any], dict[str, tuple[float, float]]]:
    """Run ``parts`` (name -> (function, args)) one after the other; return their results and
    (wall [s], CPU [s]) each: CPU of this thread plus that of its local pools' workers. Each
    part keeps its local pools (:func:`kept_pools`): its sweeps, maps and fits share workers
    whose imports and compiled kernels are paid once."""
    if quiet:
        from ..progress import configure
        configure(quiet=True)
    results: dict[str, Any] = {}
    timings: dict[str, tuple[float, float]] = {}
    for name, (fn, args) in parts.items():
        sink = [0.0]
        token = _CPU_SINK.set(sink)
        w0, c0 = time.perf_counter(), time.thread_time()
        try:
            with kept_pools():
                results[name] = fn(*args)
        finally:
            timings[name] = (time.perf_counter() - w0, time.thread_time() - c0 + sink[0])
            _CPU_SINK.reset(token)
    return results, timings


def _lane_process_init(parent: int) -> None:
    """Initializer of a lane's process: it dies with its parent (``PR_SET_PDEATHSIG``) but,
    unlike a pool worker, answers Ctrl-C itself, ending its own pools as the parent does."""
    import signal

    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.default_int_handler)


def run_parts(parts: dict[str, Part], timings: dict[str, tuple[float, float]],
              lanes: Sequence[Sequence[str]] | None = None) -> dict[str, Any]:
    """Run independent ``parts`` (name -> (function, args), both picklable) in ``lanes``
    (lists of names; default: one lane of every part, in order); return name -> result.

    The first lane runs in this process; each other lane in a process of its own (started
    fresh: ``spawn``), one part after the other, its own pools forked from it. Lanes keep up
    to lanes x workers processes busy, so one part's last cases, or its work in one process,
    do not leave a core idle. ``timings[name]`` becomes (wall [s], CPU [s]) of the part: CPU
    of the thread that ran it plus that of the workers of its local pools. An exception in a
    lane (Ctrl-C included) ends the other lanes' processes and is raised."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from ..progress import enabled

    lanes = [list(parts)] if lanes is None else [list(lane) for lane in lanes]
    if sorted(n for lane in lanes for n in lane) != sorted(parts):
        raise ValueError(f"lanes {lanes} do not hold each of the parts {list(parts)} once")
    others = []
    try:
        for lane in lanes[1:]:
            ex = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"),
                                     initializer=_lane_process_init, initargs=(os.getpid(),))
            others.append((ex, ex.submit(_run_lane, {n: parts[n] for n in lane},
                                         not enabled())))
        results, times = _run_lane({n: parts[n] for n in lanes[0]})
        for ex, fut in others:
            r, t = fut.result()
            results.update(r)
            times.update(t)
            ex.shutdown(wait=True)
    except BaseException:
        for ex, _ in others:
            _terminate(ex)
        raise
    timings.update(times)
    return {name: results[name] for name in parts}


#: The local pools kept by :func:`kept_pools` (size -> executor), or None outside it.
_KEPT: contextvars.ContextVar[dict[int, Any] | None] = contextvars.ContextVar(
    "rockbench_kept_pools", default=None)


@contextlib.contextmanager
def kept_pools() -> Iterator[None]:
    """Within this block, the local process pool of an :func:`execute` call is kept and
    reused by the next calls with as many workers (their imports, compiled code and caches
    are paid once: an adaptive map runs a few rounds of cells); the pools are shut down, their
    workers joined, when the block ends. Nested blocks share the outer one's pools."""
    if _KEPT.get() is not None:
        yield
        return
    token = _KEPT.set({})
    try:
        yield
    finally:
        pools = _KEPT.get() or {}
        _KEPT.reset(token)
        for ex in pools.values():
            _account(ex)
            ex.shutdown(wait=True, cancel_futures=True)


def _crash_reason(e: BaseException) -> str:
    return f"worker process died while running this case (segfault or out of memory?): {e}"


def execute(fn: Callable[[Any], Any], items: Sequence[Item], *,
            on_result: Callable[[str, Any], None], crashed: Callable[[Any, str], Any],
            label: Callable[[Any], str] = str, is_error: Callable[[Any], bool] | None = None,
            executor: str = "process", workers: int | None = None,
            dask_address: str | None = None, progress: bool = True, desc: str = "sweep",
            unit: str = "case") -> None:
    """Run ``fn(item)`` for every ``(key, item)`` of ``items``; call ``on_result(key, result)``
    in this process as each one finishes (in completion order).

    ``crashed(item, reason)`` is the result of an item whose worker died; ``label(item)`` names
    an item on the tqdm bar (``progress``; its description ``desc`` counts the results for which
    ``is_error(result)`` is true). ``workers`` defaults to the available cores.
    """
    check_options(executor, workers, dask_address)
    items = list(items)
    if not items:
        return
    bar = None
    n_err = [0]
    if progress:
        from ..progress import bar as progress_bar   # tqdm on a terminal, lines otherwise
        bar = progress_bar(len(items), desc, unit)

    def done(k: str, result: Any) -> None:
        on_result(k, result)
        if bar is not None:
            bar.update(1)
            if is_error is not None and is_error(result):
                n_err[0] += 1
                bar.set_description(f"{desc} ({n_err[0]} error{'s' if n_err[0] > 1 else ''})")

    def show(text: str, refresh: bool = True) -> None:
        if bar is not None:
            bar.set_postfix_str(text, refresh=refresh)

    try:
        if executor == "serial":
            for k, item in items:
                show(label(item))
                done(k, fn(item))
        elif executor == "process":
            _pool(fn, items, local_workers(workers), done, show, label, crashed)
        else:
            _dask(fn, items, workers, dask_address, done, show, label, crashed)
    finally:
        if bar is not None:
            bar.close()


def _pool(fn, items: list[Item], size: int, done, show, label, crashed) -> None:
    """A process pool of ``size`` workers (one kept by :func:`kept_pools` when there is one),
    at most ``size`` items in flight; a dead pool makes every item in flight a suspect, rerun
    alone (:func:`_isolated`)."""
    from concurrent.futures import FIRST_COMPLETED, wait
    from concurrent.futures.process import BrokenProcessPool

    kept = _KEPT.get()
    # a pool of its own is never larger than the work; a kept one has the requested size
    workers = size if kept is not None else min(size, len(items))
    queue = deque(items)
    inflight: dict[Any, Item] = {}
    ex = kept.get(workers) if kept is not None else None
    if ex is None:
        ex = _process_pool(workers)
        if kept is not None:
            kept[workers] = ex
    finished_ok = False
    try:
        while queue or inflight:
            while queue and len(inflight) < workers:
                k, item = queue.popleft()
                inflight[ex.submit(fn, item)] = (k, item)
            show(" | ".join(label(item) for _, item in inflight.values()))
            finished, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
            suspects: list[Item] = []
            for f in finished:
                k, item = inflight.pop(f)
                try:
                    result = f.result()
                except BrokenProcessPool:
                    suspects.append((k, item))
                    continue
                done(k, result)
            if suspects:
                # the pool is dead: every item still in flight is a suspect
                suspects.extend(inflight.values())
                inflight.clear()
                ex.shutdown(wait=True, cancel_futures=True)
                for k, item in suspects:
                    show(f"isolating {label(item)}")
                    done(k, _isolated(fn, item, crashed))
                ex = _process_pool(workers)
                if kept is not None:
                    kept[workers] = ex
        finished_ok = True
    finally:
        if kept is None:
            _account(ex)
        if not finished_ok:
            # Ctrl-C, or a result that could not be kept (a full disk): stop now. Finished
            # items are already handed over (and stored); the workers' items in flight are
            # abandoned, their processes ended rather than waited for
            _terminate(ex)
            if kept is not None:
                kept.pop(workers, None)
        elif kept is None:
            ex.shutdown(wait=False, cancel_futures=True)


def _terminate(ex) -> None:
    """Shut a process pool down without waiting for its running items: cancel the queue, end
    the worker processes (SIGTERM; they ignore SIGINT) and join them."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        try:
            p.terminate()
        except (OSError, AttributeError, ValueError):
            pass
    for p in procs:
        try:
            p.join(timeout=5)
        except (OSError, AttributeError, ValueError, AssertionError):
            pass


def _isolated(fn, item: Any, crashed) -> Any:
    """Run one item in a fresh single-worker process pool; a dying worker -> ``crashed``."""
    from concurrent.futures.process import BrokenProcessPool

    with _process_pool(1) as ex:
        try:
            return ex.submit(fn, item).result()
        except BrokenProcessPool as e:
            return crashed(item, _crash_reason(e))


def _dask(fn, items: list[Item], workers: int | None, address: str | None, done, show, label,
          crashed) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise RockbenchError("executor='dask' needs dask.distributed: "
                             "pip install 'rockbench[dask]'") from None
    cluster = None
    if address:
        address = check_address(address)
        try:
            client = Client(address, timeout=DASK_CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError, TypeError) as e:
            why = " ".join(str(e).split()) or type(e).__name__
            raise RockbenchError(
                f"cannot reach the Dask scheduler at {address} within "
                f"{DASK_CONNECT_TIMEOUT:g} s ({why[:200]}); start one (`dask scheduler`) and "
                f"give its address, or leave out --scheduler to run on local processes"
            ) from None
    else:
        cluster = LocalCluster(n_workers=local_workers(workers), threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        futs = {client.submit(fn, item, key=f"rockbench-{k}", pure=False): (k, item)
                for k, item in items}
        for f in as_completed(list(futs)):
            k, item = futs[f]
            try:
                result = f.result()
            except Exception as e:  # e.g. KilledWorker: the item killed its worker
                result = crashed(item, f"{type(e).__name__}: {e}")
            show(f"done {label(item)}", refresh=False)
            done(k, result)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

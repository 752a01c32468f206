"""A process pool that survives its workers, for the plan's simulations: pebble's.

:class:`WorkerPool` is a ``concurrent.futures.Executor`` over ``pebble.ProcessPool``, which
does what ``ProcessPoolExecutor`` cannot:

- a worker that dies (killed by the out-of-memory killer, a signal, a crash) fails only the
  task it was running (pebble's ``ProcessExpired``, raised here as :class:`WorkerLost`), and
  pebble starts a new worker in its place;
- the worker running a task that does not return can be stopped
  (:meth:`WorkerPool.kill`: pebble's cancel of a running task), which
  :func:`placement.pso.evaluate_swarm` uses for ``eval_timeout``.

What pebble leaves to its user is done in each worker's initializer: the worker exits
within a second when the parent dies, even by SIGKILL (no orphans); it ignores Ctrl-C (the
parent handles it); and it limits BLAS to one thread (the pool already has a process per
core). A plain ``ProcessPoolExecutor`` breaks for good when one worker dies
(``BrokenProcessPool``): :func:`run_calls` then raises :class:`ExecutorBroken`.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from concurrent.futures import BrokenExecutor, Executor, Future

from simulation import checks

__all__ = ["ExecutorBroken", "WorkerLost", "WorkerPool", "available_cores"]

#: how often (s) a worker checks that its parent is alive
PARENT_POLL = 0.2


class ExecutorBroken(RuntimeError):
    """The executor cannot run work any more (e.g. a worker process of a
    ``ProcessPoolExecutor`` died: ``BrokenProcessPool``)."""


class WorkerLost(RuntimeError):
    """The worker process running a task died before returning (killed, out of memory)."""


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(PARENT_POLL)
        if os.getppid() != parent:  # the parent died: do not linger as an orphan
            os._exit(1)


def _init_worker(parent: int) -> None:
    """Worker initializer: exit when the parent dies, leave Ctrl-C to the parent, one BLAS
    thread."""
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    # SIGINT goes to the whole process group on Ctrl-C: let the parent handle it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # one BLAS thread per worker: the pool already has a process per core, and BLAS
    # threads on top of it oversubscribe the cores (a long receiver window's small matrix
    # products ran 2.5 times slower so; BENCHMARKS.md, "The receiver")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1, user_api="blas")


def _lost(exc: BaseException, reason: str | None) -> WorkerLost:
    """The :class:`WorkerLost` of a task whose worker died (``exc``: pebble's
    ``ProcessExpired``) or was stopped for ``reason``."""
    pid, code = getattr(exc, "pid", None), getattr(exc, "exitcode", None)
    how = reason or (f"signal {-code}" if code is not None and code < 0 else f"exit code {code}")
    who = f"worker process {pid}" if pid else "a worker process"
    return WorkerLost(f"{who} died while running this task ({how})")


class WorkerPool(Executor):
    """Local worker processes that survive the death of one of them (module docstring):
    a ``concurrent.futures.Executor`` adapter of ``pebble.ProcessPool``.

    max_workers : processes (default: the available cores). mp_context : a
    ``multiprocessing`` context (default: the platform's).

    ``lost`` counts the tasks lost to dead or stopped workers, ``restarts`` the workers
    replaced (pebble replaces each of those).
    """

    def __init__(self, max_workers: int | None = None, *, mp_context=None):
        import multiprocessing

        import pebble

        if max_workers is None:
            max_workers = available_cores()
        self._max_workers = checks.count("max_workers", max_workers, low=1, high=1024)
        self._pool = pebble.ProcessPool(
            max_workers=self._max_workers, initializer=_init_worker,
            initargs=(os.getpid(),), context=mp_context or multiprocessing,
        )  # fmt: skip
        self._lock = threading.Lock()
        self._inner: dict[Future, Future] = {}  # our future -> pebble's
        self._reasons: dict[Future, str] = {}  # why the parent stopped a task's worker
        self._shutdown = False
        self.lost = 0

    def submit(self, fn, /, *args, **kwargs) -> Future:
        """Schedule ``fn(*args, **kwargs)`` on a worker (``concurrent.futures.Executor``);
        the future raises :class:`WorkerLost` if its worker dies."""
        from pebble import ProcessExpired

        if self._shutdown:
            raise RuntimeError("cannot schedule new tasks after shutdown")
        outer: Future = Future()
        outer.set_running_or_notify_cancel()
        inner = self._pool.schedule(fn, args=args, kwargs=kwargs)
        with self._lock:
            self._inner[outer] = inner

        def done(f: Future) -> None:
            with self._lock:
                self._inner.pop(outer, None)
                reason = self._reasons.pop(outer, None)
            exc = None if not f.cancelled() else ProcessExpired("stopped", -signal.SIGTERM)
            exc = exc or f.exception()
            if isinstance(exc, ProcessExpired):
                with self._lock:
                    self.lost += 1
                outer.set_exception(_lost(exc, reason))
            elif exc is not None:
                outer.set_exception(exc)
            else:
                outer.set_result(f.result())

        inner.add_done_callback(done)
        return outer

    @property
    def restarts(self) -> int:
        """Workers replaced: pebble starts a new one for each lost."""
        return self.lost

    def kill(self, future: Future, reason: str = "killed by the parent") -> bool:
        """Stop the worker process running the task of ``future``; the future then raises
        :class:`WorkerLost` with ``reason``. Returns False if it is not running."""
        with self._lock:
            inner = self._inner.get(future)
            if inner is None or future.done() or not inner.running():
                return False
            self._reasons[future] = reason
        return inner.cancel()  # pebble stops the worker of a running task

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop the workers (``concurrent.futures.Executor.shutdown``)."""
        self._shutdown = True
        if cancel_futures:
            with self._lock:
                pending = [f for f in self._inner.values() if not f.running()]
            for f in pending:
                f.cancel()
        self._pool.close()
        if wait:
            self._pool.join()

    def __repr__(self) -> str:
        return f"WorkerPool(max_workers={self._max_workers})"


def run_calls(executor, calls, *, retries: int = 2, progress=None) -> list:
    """``[fn(*args) for fn, args in calls]``, on ``executor`` when given (all submitted at
    once), else one after the other. A call whose worker died (:class:`WorkerLost`) is
    submitted again, at most ``retries`` times, so a deterministic call costs time, not
    the run. ``progress(done, total)`` as calls finish (in order)."""
    calls = list(calls)
    futures = None if executor is None else [executor.submit(fn, *args) for fn, args in calls]
    out = []
    for k, (fn, args) in enumerate(calls):
        if futures is None:
            out.append(fn(*args))
        else:
            out.append(_result(executor, futures[k], fn, args, retries))
        if progress:
            progress(len(out), len(calls))
    return out


def _result(executor, fut, fn, args, retries: int):
    for attempt in range(retries + 1):
        try:
            return fut.result()
        except WorkerLost:
            if attempt == retries:
                raise
            fut = executor.submit(fn, *args)
        except BrokenExecutor as exc:
            raise ExecutorBroken(
                f"the executor broke ({type(exc).__name__}: a worker process died); a "
                "placement.WorkerPool survives dead workers"
            ) from None
    raise AssertionError("unreachable")  # pragma: no cover


def run_jobs(executor, fn, jobs, *, retries: int = 2, progress=None) -> list:
    """``[fn(*job) for job in jobs]`` by :func:`run_calls`."""
    return run_calls(executor, [(fn, tuple(job)) for job in jobs], retries=retries,
                     progress=progress)  # fmt: skip


def executor_workers(executor) -> int:
    """Worker processes of an executor: its ``_max_workers`` when it has one, else the
    machine's cores; 1 without an executor."""
    if executor is None:
        return 1
    n = getattr(executor, "_max_workers", None)
    return int(n) if n else (os.cpu_count() or 2)

"""A process pool that survives its workers, for the swarm's evaluations.

:class:`WorkerPool` is a ``concurrent.futures.Executor`` over local processes
(a ``ProcessPoolExecutor`` inside) that

- loses only the tasks of a worker that dies (killed by the out-of-memory killer, a
  signal, a crash): that task's future raises :class:`WorkerLost`; the tasks that were
  running on the other workers when the pool broke are run again on a fresh pool, and
  later submissions go to the fresh pool;
- leaves no orphans: every worker watches its parent and exits within a second when the
  parent dies, even by SIGKILL;
- can kill the worker running a task that does not return (:meth:`WorkerPool.kill`),
  which :func:`placement.pso.evaluate_swarm` uses for ``eval_timeout``.

A plain ``ProcessPoolExecutor`` cannot do the first two: one dead worker breaks it for
good (``BrokenProcessPool``) and its workers outlive a killed parent.
"""

from __future__ import annotations

import itertools
import os
import shutil
import signal
import tempfile
import threading
import time
import weakref
from concurrent.futures import (
    BrokenExecutor,
    Executor,
    Future,
    InvalidStateError,
    ProcessPoolExecutor,
)
from concurrent.futures.process import BrokenProcessPool

from simulation import checks

__all__ = ["ExecutorBroken", "WorkerLost", "WorkerPool", "available_cores"]

#: how often (s) a worker checks that its parent is alive
PARENT_POLL = 0.2
#: a task is run at most this many times when other workers' deaths interrupt it
MAX_ATTEMPTS = 3


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


def _watch_parent(parent: int, markers: str) -> None:
    while True:
        time.sleep(PARENT_POLL)
        if os.getppid() != parent:  # the parent died: do not linger as an orphan
            shutil.rmtree(markers, ignore_errors=True)
            os._exit(1)


def _init_worker(parent: int, markers: str) -> None:
    """Worker initializer: exit (removing the pool's marker folder) when the parent dies."""
    threading.Thread(target=_watch_parent, args=(parent, markers), daemon=True).start()
    # SIGINT goes to the whole process group on Ctrl-C: let the parent handle it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # one BLAS thread per worker: the pool already has a process per core, and BLAS
    # threads on top of it oversubscribe the cores (a long receiver window's small matrix
    # products ran 2.5 times slower so; BENCHMARKS.md, "The receiver")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1, user_api="blas")


def _run_task(marker: str, fn, args, kwargs):
    """Run ``fn`` in a worker after recording which process runs it."""
    with open(marker, "w") as fh:
        fh.write(str(os.getpid()))
    return fn(*args, **kwargs)


class _Task:
    __slots__ = ("attempts", "args", "fn", "future", "id", "inner", "kwargs", "pool", "reason")

    def __init__(self, task_id, fn, args, kwargs):
        self.id = task_id
        self.fn, self.args, self.kwargs = fn, args, kwargs
        self.future: Future = Future()
        self.attempts = 0
        self.inner: Future | None = None
        self.pool: ProcessPoolExecutor | None = None
        self.reason: str | None = None  # why the parent killed its worker, if it did

    def settle(self, result=None, exc: BaseException | None = None) -> None:
        try:  # the caller may have cancelled the future meanwhile
            if exc is None:
                self.future.set_result(result)
            else:
                self.future.set_exception(exc)
        except InvalidStateError:
            pass


class WorkerPool(Executor):
    """Local worker processes that survive the death of one of them (see module docstring).

    max_workers : processes (default: the available cores). mp_context : a
    ``multiprocessing`` context (default: the platform's).

    Attributes ``lost`` (tasks lost to dead workers) and ``restarts`` (pools replaced)
    count what happened.
    """

    def __init__(self, max_workers: int | None = None, *, mp_context=None):
        if max_workers is None:
            max_workers = available_cores()
        self._max_workers = checks.count("max_workers", max_workers, low=1, high=1024)
        self._mp_context = mp_context
        self._lock = threading.RLock()
        self._pool: ProcessPoolExecutor | None = None
        self._processes: dict = {}
        self._pool_processes: dict[int, dict] = {}
        self._ids = itertools.count()
        self._tasks: dict[int, _Task] = {}
        self._broken: dict[int, list[_Task]] = {}
        self._dir = tempfile.mkdtemp(prefix="anchorplan-pool-")  # which worker runs what
        self._cleanup = weakref.finalize(self, shutil.rmtree, self._dir, True)
        self._shutdown = False
        self.lost = 0
        self.restarts = 0

    # -- the inner pool ----------------------------------------------------------------------
    def _current_pool(self) -> ProcessPoolExecutor:
        with self._lock:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(
                    self._max_workers,
                    mp_context=self._mp_context,
                    initializer=_init_worker,
                    initargs=(os.getpid(), self._dir),
                )
                # the pool's own table of its processes (kept to read exit codes later)
                self._pool_processes[id(self._pool)] = getattr(self._pool, "_processes", {})
            return self._pool

    def _marker(self, task: _Task) -> str:
        return os.path.join(self._dir, f"{task.id}.{task.attempts}")

    def _start(self, task: _Task) -> None:
        for _ in range(MAX_ATTEMPTS):
            pool = self._current_pool()
            task.attempts += 1
            try:
                inner = pool.submit(_run_task, self._marker(task), task.fn, task.args, task.kwargs)
            except BrokenProcessPool:  # broke between two submissions: take a fresh one
                with self._lock:
                    if self._pool is pool:
                        self._pool = None
                        self.restarts += 1
                continue
            except RuntimeError as exc:  # shut down meanwhile
                task.settle(exc=exc)
                return
            task.inner, task.pool = inner, pool
            inner.add_done_callback(lambda f, t=task, p=pool: self._inner_done(t, p, f))
            return
        task.settle(exc=WorkerLost("could not start the task: the pool keeps breaking"))

    def _inner_done(self, task: _Task, pool, inner: Future) -> None:
        # runs in the pool's management thread: never block here
        if inner.cancelled():
            task.future.cancel()
            self._forget(task)
            return
        exc = inner.exception()
        if not isinstance(exc, BrokenProcessPool):
            task.settle(inner.result() if exc is None else None, exc)
            self._forget(task)
            return
        with self._lock:
            first = id(pool) not in self._broken
            self._broken.setdefault(id(pool), []).append(task)
            if self._pool is pool:
                self._pool = None
                self.restarts += 1
        if first:  # once per broken pool: wait for its workers to be reaped, then sort out
            threading.Thread(target=self._repair, args=(pool,), daemon=True).start()

    def _repair(self, pool: ProcessPoolExecutor) -> None:
        pool.shutdown(wait=True)  # joins the management thread, which reaps the workers
        processes = self._pool_processes.pop(id(pool), {})
        exitcodes = {pid: p.exitcode for pid, p in dict(processes).items()}
        with self._lock:
            tasks = self._broken.pop(id(pool), [])
        for task in tasks:
            pid = self._read_pid(task)
            code = exitcodes.get(pid) if pid is not None else None
            # a worker terminated by the pool's own cleanup exits by SIGTERM; one that died
            # by itself (SIGKILL, crash, os._exit) is the culprit; unknown: assume culprit
            collateral = pid is None or code == -signal.SIGTERM
            if not exitcodes:  # cannot tell who died: lose every interrupted task
                collateral = False
            if task.reason is None and collateral and task.attempts < MAX_ATTEMPTS:
                if not self._shutdown:
                    self._start(task)
                    continue
            self.lost += 1
            how = (
                task.reason
                or (f"exit code {code}" if code is not None and code >= 0 else None)
                or (f"signal {-code}" if code is not None else "unknown cause")
            )
            who = f"worker process {pid}" if pid is not None else "a worker process"
            task.settle(exc=WorkerLost(f"{who} died while running this task ({how})"))
            self._forget(task)

    def _read_pid(self, task: _Task) -> int | None:
        try:
            with open(self._marker(task)) as fh:
                return int(fh.read().strip())
        except (OSError, ValueError):
            return None  # never started

    def _forget(self, task: _Task) -> None:
        with self._lock:
            self._tasks.pop(task.id, None)
        for k in range(1, task.attempts + 1):
            try:
                os.unlink(os.path.join(self._dir, f"{task.id}.{k}"))
            except OSError:
                pass

    # -- Executor API ------------------------------------------------------------------------
    def submit(self, fn, /, *args, **kwargs) -> Future:
        """Schedule ``fn(*args, **kwargs)`` on a worker (``concurrent.futures.Executor``)."""
        if self._shutdown:
            raise RuntimeError("cannot schedule new tasks after shutdown")
        task = _Task(next(self._ids), fn, args, kwargs)
        with self._lock:
            self._tasks[task.id] = task
        self._start(task)
        return task.future

    def kill(self, future: Future, reason: str = "killed by the parent") -> bool:
        """Kill the worker process running the task of ``future`` (SIGKILL); the future then
        raises :class:`WorkerLost` with ``reason``. Returns False if it is not running."""
        with self._lock:
            task = next((t for t in self._tasks.values() if t.future is future), None)
        if task is None or future.done():
            return False
        pid = self._read_pid(task)
        if pid is None:
            return False
        task.reason = reason
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            return False
        return True

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop the workers (``concurrent.futures.Executor.shutdown``)."""
        self._shutdown = True
        with self._lock:
            pool = self._pool
            self._pool = None
        if pool is not None:
            pool.shutdown(wait=wait, cancel_futures=cancel_futures)
        if wait:
            self._cleanup()

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

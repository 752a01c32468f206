"""Particle swarm optimization of an anchor layout on the mounting surfaces (paper §III-B).

A particle is a layout of M anchors (M × 3 numbers). Each iteration (paper eqs. 1–2)

    v ← ω v + c1 r1 (pbest − x) + c2 r2 (gbest − x),     x ← P(x + v),

with r1, r2 ~ U(0, 1) per coordinate, |v| clamped per coordinate, and P the projection of
every anchor onto the nearest allowed mounting rectangle (so anchors may jump surfaces;
the anchors are re-aimed at the centroid by construction of the simulator).

Determinism: the swarm dynamics draw from one stream, and the cost of particle i at
iteration t draws its noise from a stream derived from (seed, t, i) only, so a run gives
the same result serially, on a process pool, on Dask, and after a resume.
"""

from __future__ import annotations

import inspect
import json
import logging
import math
import os
import pickle
import signal
import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from analysis.progress import CountingBar, check_progress
from placement import ties
from placement.result import LayoutResult
from placement.serialization import fingerprint, write_json_atomic
from placement.surfaces import MAX_ANCHORS, project, random_layout
from placement.workers import ExecutorBroken, WorkerPool, executor_workers
from simulation import checks, degeneracy, streams
from simulation.room import Room, as_room

logger = logging.getLogger(__name__)

CHECKPOINT_VERSION = 1
#: keys every checkpoint holds
_CHECKPOINT_KEYS = (
    "version", "fingerprint", "seed", "iteration", "x", "v", "pbest", "pcost", "gbest",
    "gcost", "history", "best_anchors_history", "costs", "nfev", "failures", "rng",
    "stopped", "elapsed",
)  # fmt: skip


class EvaluationTimeout(Exception):
    """An evaluation of the cost exceeded ``eval_timeout``."""


#: upper limits of the swarm's size and length
MAX_PARTICLES, MAX_ITERATIONS = 10_000, 100_000


@dataclass(frozen=True)
class PSOOptions:
    """Swarm settings. Defaults: the paper's 15 particles and 40 iterations, Clerc's
    constriction coefficients (ω = 0.7298, c1 = c2 = 1.49618).

    velocity_clamp : max |v| per coordinate as a fraction of the room size on that axis.
    init_velocity : initial velocities are U(−1, 1) × this fraction of the room size.
    init_spread : 0 (paper): the particles besides the seed layouts start at random
        layouts; > 0: they start around the seeds, every coordinate moved by a normal
        offset of this standard deviation (m) (:func:`initial_positions`).
    tol, patience : stop when the best cost improved by less than ``tol`` (relative) over
        the last ``patience`` iterations (paper: "improvement per iteration stays under a
        threshold"); ``tol = 0`` runs all iterations. With a noisy cost, improvements come
        in rare steps, hence a long default patience.

    Allowed: particles 2–10⁴, iterations 1–10⁵, inertia [0, 1], cognitive and social
    [0, 4], velocity_clamp (0, 1], init_velocity and tol [0, 1], patience ≥ 1,
    eval_timeout > 0 s or None.
    """

    particles: int = 15
    iterations: int = 40
    inertia: float = 0.7298
    cognitive: float = 1.49618
    social: float = 1.49618
    velocity_clamp: float = 0.25
    init_velocity: float = 0.1
    tol: float = 1e-3
    patience: int = 20
    init_spread: float = 0.0
    eval_timeout: float | None = None

    def __post_init__(self) -> None:
        checks.count("particles", self.particles, low=2, high=MAX_PARTICLES)
        checks.count("iterations", self.iterations, low=1, high=MAX_ITERATIONS)
        for name, high in (("inertia", 1.0), ("cognitive", 4.0), ("social", 4.0),
                           ("init_velocity", 1.0), ("tol", 1.0)):  # fmt: skip
            checks.real(name, getattr(self, name), low=0.0, high=high)
        checks.real("velocity_clamp", self.velocity_clamp, low=0.0, high=1.0, low_open=True)
        checks.count("patience", self.patience, low=1)
        checks.real("init_spread", self.init_spread, low=0.0, unit="m")
        if self.eval_timeout is not None:
            checks.real("eval_timeout", self.eval_timeout, low=0.0, low_open=True, unit="s")


#: status codes of :class:`PSOResult`
PSO_STATUS = {
    0: "reached the maximum number of iterations",
    1: "the best cost stopped improving (tol, patience)",
    2: "stopped by the callback",
    3: "no particle could be evaluated",
}


@dataclass(frozen=True)
class PSOResult(LayoutResult):
    """Outcome of :func:`pso` (the result convention of :mod:`placement.result`).

    anchors (M, 3) best layout, cost (``fun``) its cost in the cost's unit; history[t] the
    best cost after iteration t (non-increasing); best_anchors_history[t] the best layout
    then; costs (T, K) every evaluated cost in evaluation order; nfev evaluations; nit
    iterations; status a code of :data:`PSO_STATUS`; pbest (K, M, 3) each particle's
    best layout and pcost (K,) its cost.
    """

    FUN: ClassVar[str] = "cost"
    STATUS: ClassVar[dict[int, str]] = PSO_STATUS

    anchors: np.ndarray
    cost: float
    nit: int
    nfev: int
    message: str
    success: bool
    status: int
    history: list[float]
    best_anchors_history: list[np.ndarray]
    costs: np.ndarray
    seed: int
    elapsed: float
    failures: int = 0
    pbest: np.ndarray | None = None
    pcost: np.ndarray | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def nfev_to_reach(self, target: float) -> int | None:
        """Evaluations needed until some evaluated cost is ≤ ``target`` (None if never)."""
        return nfev_to_reach(self.costs, target)

    def to_dict(self) -> dict[str, Any]:
        """The result as plain JSON types (arrays as nested lists)."""
        d = asdict(self)
        d["anchors"] = self.anchors.tolist()
        d["best_anchors_history"] = [np.asarray(a).tolist() for a in self.best_anchors_history]
        d["costs"] = np.asarray(self.costs).tolist()
        for k in ("pbest", "pcost"):
            d[k] = None if d[k] is None else np.asarray(d[k]).tolist()
        d["fun"] = self.cost
        return d


def nfev_to_reach(costs, target: float) -> int | None:
    """Evaluations, in evaluation order, until a cost of ``costs`` (T, K) is ≤ ``target``
    (None if never)."""
    flat = np.asarray(costs, dtype=float).ravel()
    hit = np.flatnonzero(flat <= target)
    return int(hit[0]) + 1 if hit.size else None


def evaluation_rng(seed: int, iteration: int, particle: int) -> np.random.Generator:
    """The noise stream of particle ``particle`` at ``iteration`` for a run seeded ``seed``."""
    return streams.stream(seed, 1, iteration, particle)


def _can_alarm() -> bool:
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


def _timed(fn, timeout: float | None):
    """``fn()``, raising :class:`EvaluationTimeout` after ``timeout`` seconds (SIGALRM, in a
    main thread; elsewhere the caller's deadline applies)."""
    if timeout is None or not _can_alarm():
        return fn()

    def expired(signum, frame):
        raise EvaluationTimeout(f"the evaluation exceeded eval_timeout = {timeout:g} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        return fn()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _evaluate_chunk(
    cost, layouts: np.ndarray, seed: int, iteration: int, ids, eval_timeout: float | None = None
) -> list:
    """Evaluate layouts (k, M, 3) in one worker; a failing evaluation gives (inf, message).

    A layout whose anchors are collinear (or coincident) cannot position in 3D: whatever
    the cost says, it costs inf.
    """
    out = []
    for a, i in zip(layouts, ids, strict=True):
        try:
            rng = evaluation_rng(seed, iteration, int(i))
            c = float(_timed(lambda a=a, rng=rng: cost(a, rng), eval_timeout))
            out.append((c if math.isfinite(c) else math.inf, None))
        except Exception as exc:  # noqa: BLE001 - one bad particle must not stop the run
            out.append((math.inf, f"{type(exc).__name__}: {exc}"))
        if len(a) >= 3 and degeneracy.anchor_rank(a) < 2:
            out[-1] = (math.inf, out[-1][1])
    return out


#: seconds added to the executor's deadline for a chunk under ``eval_timeout``
_DEADLINE_GRACE = 10.0


def _broken(iteration: int, exc: BaseException) -> ExecutorBroken:
    return ExecutorBroken(
        f"the executor broke at iteration {iteration} ({type(exc).__name__}: {exc}); "
        "a placement.WorkerPool replaces dead workers and loses only their particles"
    )


def evaluate_swarm(
    cost,
    layouts: np.ndarray,
    seed: int,
    iteration: int,
    executor: Executor | None = None,
    chunksize: int | None = None,
    *,
    eval_timeout: float | None = None,
    counts: dict[str, int] | None = None,
) -> tuple[np.ndarray, int]:
    """Costs (K,) of layouts (K, M, 3) at ``iteration``, and the number of failures.

    With an executor the particles are submitted in chunks (default: one per worker). A
    failing evaluation costs inf; so does a chunk whose worker process died
    (:class:`~placement.workers.WorkerLost`, with a :class:`~placement.WorkerPool`) and
    an evaluation over ``eval_timeout`` seconds. An executor that can run nothing any
    more (a ``ProcessPoolExecutor`` after a worker died) raises :class:`ExecutorBroken`.
    ``counts`` (optional) receives the numbers of "lost" and "timeouts" evaluations.
    """
    K = len(layouts)
    if executor is None:
        results = _evaluate_chunk(cost, layouts, seed, iteration, np.arange(K), eval_timeout)
    else:
        results = _evaluate_pooled(cost, layouts, seed, iteration, executor, chunksize,
                                   eval_timeout)  # fmt: skip
    costs = np.array([c for c, _ in results], dtype=float)
    failures = 0
    for i, (_, err) in enumerate(results):
        if err is None:
            continue
        failures += 1
        if counts is not None:
            key = None
            if err.startswith("EvaluationTimeout") or "eval_timeout" in err:
                key = "timeouts"
            elif err.startswith("WorkerLost"):
                key = "lost"
            if key is not None:
                counts[key] = counts.get(key, 0) + 1
        logger.warning(
            "iteration %d particle %d: cost failed (%s); cost set to inf", iteration, i, err
        )
    return costs, failures


def _evaluate_pooled(cost, layouts, seed, iteration, executor, chunksize, eval_timeout) -> list:
    """The (cost, error) of every layout, in chunks on ``executor``; a chunk past the
    deadline of ``eval_timeout`` has its worker stopped (or is abandoned) and costs inf."""
    K = len(layouts)
    ids = np.arange(K)
    size = chunksize or max(1, math.ceil(K / executor_workers(executor)))
    starts = {}
    try:
        for i in range(0, K, size):
            fut = executor.submit(_evaluate_chunk, cost, layouts[i : i + size], seed, iteration,
                                  ids[i : i + size], eval_timeout)  # fmt: skip
            starts[fut] = i
    except BrokenProcessPool as exc:
        raise _broken(iteration, exc) from None
    deadline = None
    if eval_timeout is not None:
        rounds = math.ceil(len(starts) / executor_workers(executor))
        deadline = time.monotonic() + rounds * size * eval_timeout + _DEADLINE_GRACE
    results = [None] * K
    pending = set(starts)
    killed = False
    while pending:
        left = None if deadline is None else max(0.0, deadline - time.monotonic())
        done, pending = wait(pending, timeout=left)
        for fut in done:
            results[starts[fut] : starts[fut] + size] = _chunk_result(fut, size, K - starts[fut],
                                                                      iteration)  # fmt: skip
        if pending and deadline is not None and time.monotonic() >= deadline:
            _stop_late(executor, pending, starts, results, size, K, eval_timeout, killed)
            killed = True
            deadline = time.monotonic() + _DEADLINE_GRACE
    return results


def _chunk_result(fut, size: int, left: int, iteration: int) -> list:
    """The results of a finished chunk of ``min(size, left)`` layouts: inf for each when its
    worker was lost; a broken executor raises :class:`ExecutorBroken`."""
    try:
        return fut.result()
    except BrokenProcessPool as exc:
        raise _broken(iteration, exc) from None
    except Exception as exc:  # noqa: BLE001 - a lost worker costs its particles only
        return [(math.inf, f"{type(exc).__name__}: {exc}")] * min(size, left)


def _stop_late(executor, pending, starts, results, size, K, eval_timeout, killed) -> None:
    """Past the deadline: stop the worker of each late chunk (first time, when the executor
    can), which then resolves as WorkerLost; abandon the others at inf (removed from
    ``pending``)."""
    reason = f"no result within the eval_timeout of {eval_timeout:g} s per evaluation"
    kill = getattr(executor, "kill", None)
    for fut in list(pending):
        if not killed and kill is not None and kill(fut, reason):
            continue  # resolves shortly as WorkerLost
        fut.cancel()
        n = min(size, K - starts[fut])
        results[starts[fut] : starts[fut] + n] = [(math.inf, f"EvaluationTimeout: {reason}")] * n
        pending.discard(fut)


def load_checkpoint(path: str | os.PathLike) -> dict | None:
    """The swarm state saved in a checkpoint file, or None if there is no file.

    Raises ``ValueError`` naming the file when it is a directory, unreadable, not JSON
    (e.g. truncated) or not a checkpoint of this version; delete it to start afresh.
    """
    p = Path(path)
    if not p.exists():
        return None
    afresh = "delete it (or choose another --checkpoint) to start afresh"
    if p.is_dir():
        raise ValueError(f"checkpoint {p}: is a directory, expected a file")
    try:
        text = p.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"checkpoint {p}: cannot read it ({exc}); {afresh}") from None
    try:
        state = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"checkpoint {p}: not valid JSON, truncated? ({exc}); {afresh}") from None
    if not isinstance(state, dict):
        raise ValueError(
            f"checkpoint {p}: expected a JSON object, got {checks.describe(state)}; {afresh}"
        )
    missing = [k for k in _CHECKPOINT_KEYS if k not in state]
    if missing and state.get("version") == CHECKPOINT_VERSION:
        raise ValueError(f"checkpoint {p}: not a complete checkpoint (no {missing}); {afresh}")
    if missing:
        raise ValueError(f"checkpoint {p}: not an anchorplan checkpoint; {afresh}")
    try:
        checks.count("iteration", state["iteration"], low=0)
        for key in ("x", "v", "pbest", "gbest"):
            checks.reals(key, state[key])
        np.random.Generator(np.random.PCG64()).bit_generator.state = state["rng"]
    except (ValueError, TypeError, KeyError) as exc:
        raise ValueError(f"checkpoint {p}: damaged ({exc}); {afresh}") from None
    return state


def _check_cost(cost, executor) -> Callable:
    """``cost`` as a ``cost(anchors, rng)`` callable; one-argument costs are wrapped."""
    if not callable(cost):
        raise ValueError(
            f"cost: must be callable as cost(anchors, rng) -> float, got {checks.describe(cost)}"
        )
    try:
        sig = inspect.signature(cost)
    except (TypeError, ValueError):  # builtins without a signature: assume (anchors, rng)
        sig = None
    if sig is not None:
        try:
            sig.bind(None, None)
        except TypeError:
            try:
                sig.bind(None)
            except TypeError:
                raise ValueError(
                    f"cost: must accept (anchors, rng) or (anchors), got signature {sig}"
                ) from None
            from placement.costs import CallableCost

            cost = CallableCost(cost, getattr(cost, "__name__", "callable"))
    if isinstance(executor, ProcessPoolExecutor | WorkerPool):
        try:
            pickle.dumps(cost)
        except Exception as exc:  # noqa: BLE001 - any pickling failure
            raise ValueError(
                f"cost: cannot be sent to worker processes ({type(exc).__name__}: {exc}); "
                "define it at module level, or run without an executor"
            ) from None
    return cost


def _fingerprint(room: Room, M: int, options: PSOOptions, cost_label: str, seed, initial,
                 system=None) -> str:  # fmt: skip
    return fingerprint(
        {
            "room": room.to_dict(),
            "system": None if system is None else system.to_dict(),
            "M": M,
            "options": {k: v for k, v in asdict(options).items() if k != "eval_timeout"},
            "cost": cost_label,
            "seed": seed,
            "initial": None if initial is None else np.asarray(initial).tolist(),
        }
    )


@dataclass
class _Swarm:
    """The swarm's state between iterations: positions x and velocities v (K, M, 3), each
    particle's best pbest (K, M, 3) and its cost pcost (K,), the best gbest and gcost, and
    the run's record. Saved to and restored from a checkpoint as a plain dictionary."""

    seed: int
    iteration: int
    x: np.ndarray
    v: np.ndarray
    pbest: np.ndarray
    pcost: np.ndarray
    gbest: np.ndarray
    gcost: float
    rng: np.random.Generator
    history: list[float]
    best_anchors_history: list[list]
    costs: list[list[float]]
    nfev: int
    failures: int
    counts: dict[str, int]
    stopped: str | None = None
    elapsed: float = 0.0

    @classmethod
    def start(cls, seed: int, x, v, costs, failures: int, counts: dict) -> _Swarm:
        best = ties.argmin(costs)
        return cls(
            seed=seed,
            iteration=0,
            x=x,
            v=v,
            pbest=x.copy(),
            pcost=costs.copy(),
            gbest=x[best].copy(),
            gcost=float(costs[best]),
            rng=streams.stream(seed, 0),
            history=[float(costs[best])],
            best_anchors_history=[x[best].tolist()],
            costs=[costs.tolist()],
            nfev=len(x),
            failures=failures,
            counts=counts,
        )

    def to_state(self, fingerprint: str) -> dict:
        """The checkpoint dictionary (JSON-ready)."""
        return {
            "version": CHECKPOINT_VERSION,
            "fingerprint": fingerprint,
            "seed": self.seed,
            "iteration": self.iteration,
            "x": self.x.tolist(),
            "v": self.v.tolist(),
            "pbest": self.pbest.tolist(),
            "pcost": self.pcost.tolist(),
            "gbest": self.gbest.tolist(),
            "gcost": self.gcost,
            "history": self.history,
            "best_anchors_history": self.best_anchors_history,
            "costs": self.costs,
            "nfev": self.nfev,
            "failures": self.failures,
            "rng": self.rng.bit_generator.state,
            "stopped": self.stopped,
            "elapsed": self.elapsed,
            **self.counts,
        }

    @classmethod
    def from_state(cls, state: dict) -> _Swarm:
        rng = np.random.Generator(np.random.PCG64())
        rng.bit_generator.state = state["rng"]
        return cls(
            seed=int(state["seed"]),
            iteration=int(state["iteration"]),
            x=np.array(state["x"]),
            v=np.array(state["v"]),
            pbest=np.array(state["pbest"]),
            pcost=np.array(state["pcost"], dtype=float),
            gbest=np.array(state["gbest"]),
            gcost=float(state["gcost"]),
            rng=rng,
            history=list(state["history"]),
            best_anchors_history=list(state["best_anchors_history"]),
            costs=list(state["costs"]),
            nfev=int(state["nfev"]),
            failures=int(state["failures"]),
            counts={k: int(state.get(k, 0)) for k in ("lost", "timeouts")},
            stopped=state["stopped"],
            elapsed=float(state["elapsed"]),
        )

    def move(self, room: Room, options: PSOOptions, vmax: np.ndarray) -> None:
        """One velocity and position update (paper eqs. (1)–(2)), projected onto the
        allowed mounting surfaces."""
        r1 = self.rng.random(self.x.shape)
        r2 = self.rng.random(self.x.shape)
        v = (
            options.inertia * self.v
            + options.cognitive * r1 * (self.pbest - self.x)
            + options.social * r2 * (self.gbest - self.x)
        )
        self.v = np.clip(v, -vmax, vmax)
        self.x = project(room, self.x + self.v)

    def record(self, costs: np.ndarray, failures: int, options: PSOOptions) -> None:
        """Update the bests with the costs (K,) of the current positions, and the record."""
        better = np.array([ties.improves(c, p) for c, p in zip(costs, self.pcost, strict=True)])
        self.pbest[better], self.pcost[better] = self.x[better], costs[better]
        i = ties.argmin(self.pcost)
        if ties.improves(self.pcost[i], self.gcost):
            self.gbest, self.gcost = self.pbest[i].copy(), float(self.pcost[i])
        self.iteration += 1
        self.history.append(self.gcost)
        self.best_anchors_history.append(self.gbest.tolist())
        self.costs.append(costs.tolist())
        self.nfev += len(costs)
        self.failures += failures
        self.stopped = _stall(self.history, options)

    def result(self, message: str, success: bool, elapsed: float, resumed_from) -> PSOResult:
        if not success:
            status = 3
        elif self.stopped == "stopped by callback":
            status = 2
        else:
            status = 1 if self.stopped else 0
        return PSOResult(
            anchors=self.gbest.copy(),
            cost=self.gcost,
            nit=self.iteration + 1,
            nfev=self.nfev,
            message=message,
            success=success,
            status=status,
            history=list(self.history),
            best_anchors_history=[np.array(a) for a in self.best_anchors_history],
            costs=np.array(self.costs),
            seed=self.seed,
            elapsed=elapsed,
            failures=self.failures,
            pbest=self.pbest.copy(),
            pcost=self.pcost.copy(),
            extra={**self.counts, "resumed_from": resumed_from},
        )


def _stall(history: list[float], options: PSOOptions) -> str | None:
    """The stopping message when the best cost improved by less than ``tol`` (relative)
    over the last ``patience`` iterations, else None."""
    t, P = len(history) - 1, options.patience
    if options.tol <= 0 or t < P:
        return None
    ref, now = history[t - P], history[t]
    if math.isfinite(ref) and ref - now <= options.tol * abs(ref):
        return f"best cost improved by less than {options.tol:g} (relative) in {P} iterations"
    return None


def initial_positions(
    room: Room, M: int, initial, options: PSOOptions, rng: np.random.Generator
) -> np.ndarray:
    """(K, M, 3) the swarm's first positions: the seed layouts ``initial`` (S, M, 3) first,
    then random area-proportional layouts, or, with ``options.init_spread`` > 0 and
    seeds given, the seeds in turn with every coordinate moved by N(0, init_spread²) m,
    projected onto the mounting surfaces (a swarm that works around its seeds)."""
    K = options.particles
    x = np.stack([random_layout(room, M, rng) for _ in range(K)])
    S = 0 if initial is None else len(initial)
    if S:
        x[:S] = project(room, initial)
        if options.init_spread > 0:
            parents = x[np.arange(K - S) % S]
            x[S:] = project(room, parents + rng.normal(0.0, options.init_spread, parents.shape))
    return x


def pso(
    cost: Callable[[np.ndarray, np.random.Generator], float],
    room: Room,
    M: int,
    *,
    initial: np.ndarray | None = None,
    options: PSOOptions | None = None,
    executor: Executor | None = None,
    chunksize: int | None = None,
    rng=None,
    progress: bool = False,
    callback: Callable[[PSOResult], bool | None] | None = None,
    checkpoint: str | os.PathLike | None = None,
    cost_label: str | None = None,
) -> PSOResult:
    """Minimize ``cost(anchors, rng)`` over layouts of M anchors on the mounting surfaces.

    rng : an int (reproducible; resuming from a checkpoint needs one), a numpy
        ``Generator`` (drawn once for the run's seed) or None.
    initial : (S, M, 3) seed layouts placed first in the swarm (projected onto the
        surfaces), S ≤ particles; the other particles are area-proportional random layouts.
    executor : any ``concurrent.futures.Executor`` (process pool, Dask's
        ``Client.get_executor()``); particles are submitted in chunks of ``chunksize``.
    callback : called with the intermediate :class:`PSOResult` after every iteration;
        returning True stops the run.
    checkpoint : a JSON file written atomically after every iteration; if it exists and
        was written by a run with the same arguments, the run resumes from it and ends
        with exactly the result of an uninterrupted run (``extra["resumed_from"]``: the
        iteration it resumed after). A damaged checkpoint raises ``ValueError``.
    Evaluations lost to a dead worker process of a :class:`~placement.WorkerPool` cost
    inf (``failures``, ``extra["lost"]``); a plain ``ProcessPoolExecutor`` cannot survive
    that and :class:`ExecutorBroken` is raised, the checkpoint holding the last iteration.
    """
    room = as_room(room)
    args = _check_args(
        room, M, cost, options, initial, executor, chunksize, rng, progress, callback,
        cost_label, checkpoint,
    )  # fmt: skip
    swarm, resumed_from = _resume(args["ckpt"], args["fingerprint"])
    t0 = time.perf_counter()
    if swarm is None:
        swarm = _start(room, args)
    elapsed0 = swarm.elapsed

    def elapsed() -> float:
        return elapsed0 + time.perf_counter() - t0

    T = args["options"].iterations
    message = swarm.stopped or f"reached the maximum number of iterations ({T})"
    bar = _progress_bar(args["progress"], T, swarm.iteration + 1)
    try:
        while swarm.stopped is None and swarm.iteration + 1 < T:
            _iterate(room, swarm, args, elapsed, resumed_from, bar)
            message = swarm.stopped or message
    except ExecutorBroken as exc:
        ckpt = args["ckpt"]
        where = (
            f"checkpoint {ckpt} holds iteration {swarm.iteration}: rerun to resume"
            if ckpt is not None
            else "pass a checkpoint to be able to resume"
        )
        raise ExecutorBroken(f"{exc}; {where}") from None
    finally:
        if bar is not None:
            bar.close()
    success = math.isfinite(swarm.gcost)
    if not success:
        message = "no particle could be evaluated (every cost was inf); " + message
    return swarm.result(message, success, elapsed(), resumed_from)


def _check_args(
    room, M, cost, options, initial, executor, chunksize, rng, progress, callback,
    cost_label, checkpoint,
) -> dict[str, Any]:  # fmt: skip
    """Every argument of :func:`pso` checked; returns them resolved (and the fingerprint
    of the run, which a checkpoint must match)."""
    if options is not None and not isinstance(options, PSOOptions):
        raise ValueError(
            f"options: must be a PSOOptions (e.g. PSOOptions(**options)) or None, "
            f"got {checks.describe(options)}"
        )
    options = options or PSOOptions()
    M = checks.count("M", M, low=1, high=MAX_ANCHORS)
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise ValueError(
            f"executor: must be a concurrent.futures.Executor or None, "
            f"got {checks.describe(executor)}"
        )
    cost = _check_cost(cost, executor)
    if chunksize is not None:
        chunksize = checks.count("chunksize", chunksize, low=1)
    seed = None if rng is None else streams.entropy("rng", rng)
    progress = check_progress(progress)
    if callback is not None and not callable(callback):
        raise ValueError(f"callback: must be callable or None, got {checks.describe(callback)}")
    if cost_label is not None and not isinstance(cost_label, str):
        raise ValueError(f"cost_label: must be a string or None, got {checks.describe(cost_label)}")
    eval_timeout = _check_timeout(options.eval_timeout, executor)
    initial = _check_initial(initial, M, options.particles)
    label = cost_label or getattr(cost, "statistic", None) or type(cost).__name__
    return {
        "M": M,
        "cost": cost,
        "options": options,
        "initial": initial,
        "executor": executor,
        "chunksize": chunksize,
        "seed": seed,
        "progress": progress,
        "callback": callback,
        "eval_timeout": eval_timeout,
        "fingerprint": _fingerprint(
            room, M, options, str(label), seed, initial, getattr(cost, "system", None)
        ),
        "ckpt": None if checkpoint is None else checks.output_path("checkpoint", checkpoint),
    }


def _check_timeout(eval_timeout, executor) -> float | None:
    if eval_timeout is not None:
        if executor is None and not _can_alarm():
            raise ValueError(
                "eval_timeout: without an executor it needs the main thread (SIGALRM); "
                "pass executor=placement.WorkerPool(...)"
            )
    return eval_timeout


def _check_initial(initial, M: int, K: int) -> np.ndarray | None:
    if initial is None:
        return None
    initial = checks.reals("initial", initial)
    if initial.ndim not in (2, 3) or initial.shape[-2:] != (M, 3):
        raise ValueError(
            f"initial: expected seed layouts of shape (S, {M}, 3), got {initial.shape}"
        )
    initial = initial.reshape(-1, M, 3)
    if len(initial) > K:
        raise ValueError(f"initial: {len(initial)} seed layouts exceed particles = {K}")
    return initial


def _start(room: Room, args: dict) -> _Swarm:
    """The first iteration: positions, velocities and their costs (checkpointed)."""
    seed, options = args["seed"], args["options"]
    entropy = int(seed) if seed is not None else int(np.random.SeedSequence().entropy % 2**63)
    init_rng = streams.stream(entropy, 2)
    x = initial_positions(room, args["M"], args["initial"], options, init_rng)
    v = init_rng.uniform(-1, 1, size=x.shape) * options.init_velocity * np.array(room.size)
    counts = {"lost": 0, "timeouts": 0}
    costs, failures = evaluate_swarm(
        args["cost"], x, entropy, 0, args["executor"], args["chunksize"],
        eval_timeout=args["eval_timeout"], counts=counts,
    )  # fmt: skip
    swarm = _Swarm.start(entropy, x, v, costs, failures, counts)
    if args["ckpt"] is not None:
        write_json_atomic(args["ckpt"], swarm.to_state(args["fingerprint"]), strict=False)
    return swarm


def _progress_bar(progress, total: int, initial: int):
    if callable(progress):
        return CountingBar(progress, total, initial)
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=initial, desc="PSO", unit="it", leave=False)


def _iterate(room: Room, swarm: _Swarm, args: dict, elapsed, resumed_from, bar) -> None:
    """One iteration: move, evaluate, record, call back, checkpoint, report progress."""
    options = args["options"]
    swarm.move(room, options, options.velocity_clamp * np.array(room.size))
    costs, failures = evaluate_swarm(
        args["cost"], swarm.x, swarm.seed, swarm.iteration + 1, args["executor"],
        args["chunksize"], eval_timeout=args["eval_timeout"], counts=swarm.counts,
    )  # fmt: skip
    swarm.record(costs, failures, options)
    swarm.elapsed = elapsed()
    callback = args["callback"]
    if callback is not None and callback(swarm.result("running", True, elapsed(), resumed_from)):
        swarm.stopped = "stopped by callback"
    if args["ckpt"] is not None:
        write_json_atomic(args["ckpt"], swarm.to_state(args["fingerprint"]), strict=False)
    if bar is not None:
        bar.update(1)
        bar.set_postfix(best=f"{swarm.gcost:.4g}")


def _resume(ckpt: Path | None, fingerprint: str) -> tuple[_Swarm | None, int | None]:
    """The swarm saved in ``ckpt`` by a run with the same fingerprint, and its iteration."""
    saved = None if ckpt is None else load_checkpoint(ckpt)
    if saved is None:
        return None, None
    if saved.get("version") == CHECKPOINT_VERSION and saved.get("fingerprint") == fingerprint:
        logger.info("resuming from %s at iteration %d", ckpt, saved["iteration"])
        return _Swarm.from_state(saved), int(saved["iteration"])
    logger.warning("checkpoint %s was written by a different run; starting afresh", ckpt)
    return None, None

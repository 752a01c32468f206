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

import hashlib
import json
import logging
import math
import os
import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from placement.surfaces import project, random_layout
from simulation.room import Room

logger = logging.getLogger(__name__)

CHECKPOINT_VERSION = 1


@dataclass(frozen=True)
class PSOOptions:
    """Swarm settings. Defaults: the paper's 15 particles and 40 iterations, Clerc's
    constriction coefficients (ω = 0.7298, c1 = c2 = 1.49618).

    velocity_clamp : max |v| per coordinate as a fraction of the room size on that axis.
    init_velocity : initial velocities are U(−1, 1) × this fraction of the room size.
    tol, patience : stop when the best cost improved by less than ``tol`` (relative) over
        the last ``patience`` iterations (paper: "improvement per iteration stays under a
        threshold"); ``tol = 0`` runs all iterations. The single-realization cost is
        noisy and the best cost is a lucky draw, so improvements come in rare steps: with a
        patience of 8, seeded swarms stopped after 14 of 40 iterations (measured), hence 20.
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

    def __post_init__(self) -> None:
        if int(self.particles) != self.particles or self.particles < 2:
            raise ValueError(f"particles: must be an integer >= 2, got {self.particles}")
        if int(self.iterations) != self.iterations or self.iterations < 1:
            raise ValueError(f"iterations: must be an integer >= 1, got {self.iterations}")
        for name in ("inertia", "cognitive", "social", "init_velocity", "tol"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name}: must be finite and >= 0, got {v}")
        if not (math.isfinite(self.velocity_clamp) and self.velocity_clamp > 0):
            raise ValueError(f"velocity_clamp: must be > 0, got {self.velocity_clamp}")
        if int(self.patience) != self.patience or self.patience < 1:
            raise ValueError(f"patience: must be an integer >= 1, got {self.patience}")


@dataclass
class PSOResult:
    """Outcome of :func:`pso`, in the manner of ``scipy.optimize.OptimizeResult``.

    anchors (M, 3) best layout, cost its cost; history[t] the best cost after iteration t
    (non-increasing); best_anchors_history[t] the best layout then; costs (T, K) every
    evaluated cost in evaluation order; nfev evaluations; nit iterations; pbest (K, M, 3)
    each particle's best layout and pcost (K,) its cost.
    """

    anchors: np.ndarray
    cost: float
    nit: int
    nfev: int
    message: str
    success: bool
    history: list[float]
    best_anchors_history: list[np.ndarray]
    costs: np.ndarray
    seed: int
    elapsed: float
    failures: int = 0
    pbest: np.ndarray | None = None
    pcost: np.ndarray | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def x(self) -> np.ndarray:
        """The best layout flattened (3M,), as scipy's ``x``."""
        return self.anchors.ravel()

    @property
    def fun(self) -> float:
        """Alias of ``cost``, as scipy's ``fun``."""
        return self.cost

    def nfev_to_reach(self, target: float) -> int | None:
        """Evaluations needed until some evaluated cost is ≤ ``target`` (None if never)."""
        return nfev_to_reach(self.costs, target)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["anchors"] = self.anchors.tolist()
        d["best_anchors_history"] = [np.asarray(a).tolist() for a in self.best_anchors_history]
        d["costs"] = np.asarray(self.costs).tolist()
        for k in ("pbest", "pcost"):
            d[k] = None if d[k] is None else np.asarray(d[k]).tolist()
        return d


def nfev_to_reach(costs, target: float) -> int | None:
    """Evaluations, in evaluation order, until a cost of ``costs`` (T, K) is ≤ ``target``
    (None if never)."""
    flat = np.asarray(costs, dtype=float).ravel()
    hit = np.flatnonzero(flat <= target)
    return int(hit[0]) + 1 if hit.size else None


def evaluation_rng(seed: int, iteration: int, particle: int) -> np.random.Generator:
    """The noise stream of particle ``particle`` at ``iteration`` for a run seeded ``seed``."""
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(1, iteration, particle)))
    )


def _stream(seed: int, key: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(key,))))


def _evaluate_chunk(cost, layouts: np.ndarray, seed: int, iteration: int, ids) -> list:
    """Evaluate layouts (k, M, 3) in one worker; a failing evaluation gives (inf, message)."""
    out = []
    for a, i in zip(layouts, ids, strict=True):
        try:
            c = float(cost(a, evaluation_rng(seed, iteration, int(i))))
            out.append((c if math.isfinite(c) else math.inf, None))
        except Exception as exc:  # noqa: BLE001 - one bad particle must not stop the run
            out.append((math.inf, f"{type(exc).__name__}: {exc}"))
    return out


def _workers(executor: Executor) -> int:
    n = getattr(executor, "_max_workers", None)
    return int(n) if n else (os.cpu_count() or 2)


def evaluate_swarm(
    cost,
    layouts: np.ndarray,
    seed: int,
    iteration: int,
    executor: Executor | None = None,
    chunksize: int | None = None,
) -> tuple[np.ndarray, int]:
    """Costs (K,) of layouts (K, M, 3) at ``iteration``, and the number of failures.

    With an executor the particles are submitted in chunks (default: one per worker).
    """
    K = len(layouts)
    ids = np.arange(K)
    if executor is None:
        results = _evaluate_chunk(cost, layouts, seed, iteration, ids)
    else:
        size = chunksize or max(1, math.ceil(K / _workers(executor)))
        futures = [
            (
                executor.submit(
                    _evaluate_chunk, cost, layouts[i : i + size], seed, iteration, ids[i : i + size]
                ),
                i,
            )
            for i in range(0, K, size)
        ]
        results = [None] * K
        for fut, start in futures:
            n = min(size, K - start)
            try:
                chunk = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker costs its particles only
                chunk = [(math.inf, f"{type(exc).__name__}: {exc}")] * n
            results[start : start + n] = chunk
    costs = np.array([c for c, _ in results], dtype=float)
    failures = 0
    for i, (_, err) in enumerate(results):
        if err is not None:
            failures += 1
            logger.warning(
                "iteration %d particle %d: cost failed (%s); cost set to inf", iteration, i, err
            )
    return costs, failures


def _fingerprint(room: Room, M: int, options: PSOOptions, cost_label: str, seed, initial) -> str:
    blob = json.dumps(
        {
            "room": room.to_dict(),
            "M": M,
            "options": asdict(options),
            "cost": cost_label,
            "seed": seed,
            "initial": None if initial is None else np.asarray(initial).tolist(),
        },
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _write_atomic(path: Path, state: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as fh:
        json.dump(state, fh)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def pso(
    cost: Callable[[np.ndarray, np.random.Generator], float],
    room: Room,
    M: int,
    *,
    initial: np.ndarray | None = None,
    options: PSOOptions | None = None,
    executor: Executor | None = None,
    chunksize: int | None = None,
    seed: int | None = None,
    progress: bool = False,
    callback: Callable[[PSOResult], bool | None] | None = None,
    checkpoint: str | os.PathLike | None = None,
    cost_label: str | None = None,
) -> PSOResult:
    """Minimize ``cost(anchors, rng)`` over layouts of M anchors on the mounting surfaces.

    initial : (S, M, 3) seed layouts placed first in the swarm (projected onto the
        surfaces), S ≤ particles; the other particles are area-proportional random layouts.
    executor : any ``concurrent.futures.Executor`` (process pool, Dask's
        ``Client.get_executor()``); particles are submitted in chunks of ``chunksize``.
    callback : called with the intermediate :class:`PSOResult` after every iteration;
        returning True stops the run.
    checkpoint : a JSON file written atomically after every iteration; if it exists and
        was written by a run with the same arguments, the run resumes from it and ends
        with exactly the result of an uninterrupted run.
    """
    options = options or PSOOptions()
    if int(M) != M or M < 1:
        raise ValueError(f"M: number of anchors must be an integer >= 1, got {M}")
    M = int(M)
    K, T = int(options.particles), int(options.iterations)
    if initial is not None:
        initial = np.asarray(initial, dtype=float).reshape(-1, M, 3)
        if len(initial) > K:
            raise ValueError(f"initial: {len(initial)} seed layouts exceed particles = {K}")
        if not np.all(np.isfinite(initial)):
            raise ValueError("initial: seed layouts must be finite")
    label = cost_label or getattr(cost, "statistic", None) or type(cost).__name__
    fingerprint = _fingerprint(room, M, options, str(label), seed, initial)
    ckpt = Path(checkpoint) if checkpoint is not None else None

    state = None
    if ckpt is not None and ckpt.exists():
        saved = json.loads(ckpt.read_text())
        if saved.get("version") == CHECKPOINT_VERSION and saved.get("fingerprint") == fingerprint:
            state = saved
            logger.info("resuming from %s at iteration %d", ckpt, saved["iteration"])
        else:
            logger.warning("checkpoint %s was written by a different run; starting afresh", ckpt)

    t0 = time.perf_counter()
    size = np.array(room.size)
    vmax = options.velocity_clamp * size
    if state is None:
        entropy = int(seed) if seed is not None else int(np.random.SeedSequence().entropy % 2**63)
        init_rng = _stream(entropy, 2)
        x = np.stack([random_layout(room, M, init_rng) for _ in range(K)])
        if initial is not None and len(initial):
            x[: len(initial)] = project(room, initial)
        v = init_rng.uniform(-1, 1, size=x.shape) * options.init_velocity * size
        costs, failures = evaluate_swarm(cost, x, entropy, 0, executor, chunksize)
        best = int(np.argmin(costs))
        state = {
            "version": CHECKPOINT_VERSION,
            "fingerprint": fingerprint,
            "seed": entropy,
            "iteration": 0,
            "x": x.tolist(),
            "v": v.tolist(),
            "pbest": x.tolist(),
            "pcost": costs.tolist(),
            "gbest": x[best].tolist(),
            "gcost": float(costs[best]),
            "history": [float(costs[best])],
            "best_anchors_history": [x[best].tolist()],
            "costs": [costs.tolist()],
            "nfev": K,
            "failures": failures,
            "rng": _stream(entropy, 0).bit_generator.state,
            "stopped": None,
            "elapsed": 0.0,
        }
        if ckpt is not None:
            _write_atomic(ckpt, state)

    entropy = int(state["seed"])
    rng = np.random.Generator(np.random.PCG64())
    rng.bit_generator.state = state["rng"]
    x, v = np.array(state["x"]), np.array(state["v"])
    pbest, pcost = np.array(state["pbest"]), np.array(state["pcost"], dtype=float)
    gbest, gcost = np.array(state["gbest"]), float(state["gcost"])
    elapsed0 = float(state["elapsed"])

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=T, initial=state["iteration"] + 1, desc="PSO", unit="it", leave=False)

    def snapshot(message: str, success: bool) -> PSOResult:
        return PSOResult(
            anchors=gbest.copy(),
            cost=gcost,
            nit=state["iteration"] + 1,
            nfev=state["nfev"],
            message=message,
            success=success,
            history=list(state["history"]),
            best_anchors_history=[np.array(a) for a in state["best_anchors_history"]],
            costs=np.array(state["costs"]),
            seed=entropy,
            elapsed=elapsed0 + time.perf_counter() - t0,
            failures=state["failures"],
            pbest=pbest.copy(),
            pcost=pcost.copy(),
        )

    message = state["stopped"] or f"reached the maximum number of iterations ({T})"
    try:
        while state["stopped"] is None and state["iteration"] + 1 < T:
            t = state["iteration"] + 1
            r1 = rng.random(x.shape)
            r2 = rng.random(x.shape)
            v = (
                options.inertia * v
                + options.cognitive * r1 * (pbest - x)
                + options.social * r2 * (gbest - x)
            )
            v = np.clip(v, -vmax, vmax)
            x = project(room, x + v)
            costs, failures = evaluate_swarm(cost, x, entropy, t, executor, chunksize)
            better = costs < pcost
            pbest[better], pcost[better] = x[better], costs[better]
            i = int(np.argmin(pcost))
            if pcost[i] < gcost:
                gbest, gcost = pbest[i].copy(), float(pcost[i])
            history = state["history"] + [gcost]
            stop = None
            P = options.patience
            if options.tol > 0 and t >= P:
                ref = history[t - P]
                if math.isfinite(ref) and ref - gcost <= options.tol * abs(ref):
                    stop = (
                        f"best cost improved by less than {options.tol:g} (relative) "
                        f"in {P} iterations"
                    )
            state.update(
                iteration=t,
                x=x.tolist(),
                v=v.tolist(),
                pbest=pbest.tolist(),
                pcost=pcost.tolist(),
                gbest=gbest.tolist(),
                gcost=gcost,
                history=history,
                best_anchors_history=state["best_anchors_history"] + [gbest.tolist()],
                costs=state["costs"] + [costs.tolist()],
                nfev=state["nfev"] + K,
                failures=state["failures"] + failures,
                rng=rng.bit_generator.state,
                stopped=stop,
                elapsed=elapsed0 + time.perf_counter() - t0,
            )
            if callback is not None and callback(snapshot("running", True)):
                state["stopped"] = "stopped by callback"
            if ckpt is not None:
                _write_atomic(ckpt, state)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(best=f"{gcost:.4g}")
            if state["stopped"]:
                message = state["stopped"]
    finally:
        if bar is not None:
            bar.close()
    success = math.isfinite(gcost)
    if not success:
        message = "no particle could be evaluated (every cost was inf); " + message
    return snapshot(message, success)

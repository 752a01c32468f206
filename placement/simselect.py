"""Simulation-driven selection of M anchors among candidate mounting points.

Anchors transmit one at a time (TDM, paper §II) and each anchor's noise level is set by its
own closest grid node, so the range a node measures from an anchor depends on that
anchor, that node and the noise only, not on the other anchors. Simulating every
candidate point against every node once, for a few noise realizations (the *range
table*), therefore gives the exact simulated ranges of every layout built from the
candidates, and scoring such a layout costs only the least-squares positioning (all
swaps of one anchor are positioned in one batch). A local search on the table (swap one
anchor for one of the 25 nearest unused candidates while the cost falls; with the 10
nearest it stalls in poor local optima) finds layouts that score well in the full
simulation, which the bound-driven selections do not (BENCHMARKS.md): they are the
first seeds of :func:`placement.seed_then_pso`.

The table's noise is fixed (common random numbers), so the search compares layouts on
the same draws; the swarm then re-scores its seeds with fresh noise.
"""

from __future__ import annotations

import logging
import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from placement.costs import SIMULATED_STATISTICS
from placement.surfaces import candidate_grid
from simulation.room import Room

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class RangeTable:
    """Simulated ranges of every candidate anchor at every node.

    candidates (N, 3) and nodes (P, 3) in metres; ranges (R, P, N) estimated ranges in
    metres, realization r of candidate j drawn from its own stream (see
    :func:`range_table`); distances (P, N) the true ranges; region (lo (3,), hi (3,)) the
    room's box, where the positioning starts (as in :func:`simulation.evaluate_layout`).
    """

    candidates: np.ndarray
    nodes: np.ndarray
    ranges: np.ndarray
    distances: np.ndarray
    region: tuple[np.ndarray, np.ndarray]

    @property
    def windows(self) -> int:
        """Received windows simulated to build the table (R · P · N)."""
        return int(self.ranges.size)


def _table_stream(seed: int, candidate: int, realization: int) -> np.random.Generator:
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(0, candidate, realization)))
    )


def _table_chunk(room: Room, candidates, ids, nodes, realizations: int, seed: int, precision):
    """(R, P, n) ranges and (P, n) distances of candidates (n, 3) with global indices ids."""
    from simulation.evaluation import RangingScene

    scene = RangingScene(room, candidates, nodes, precision=precision)
    P, n, N = scene.windows.shape
    out = np.empty((realizations, P, n))
    for r in range(realizations):
        noise = np.stack(
            [
                s * _table_stream(seed, int(j), r).standard_normal((P, N))
                for s, j in zip(scene.noise_sigma, ids, strict=True)
            ],
            axis=1,
        )
        out[r] = scene.dsp.ranges(scene.windows + noise, room.speed_of_sound)
    return out, scene.distances


def range_table(
    room: Room,
    candidates,
    nodes=None,
    *,
    realizations: int = 2,
    seed: int = 0,
    executor: Executor | None = None,
    chunk: int = 24,
    precision: str = "float64",
) -> RangeTable:
    """Simulate ``realizations`` noisy ranges of every candidate (N, 3) at every node.

    Candidate j's realization r draws its noise from ``SeedSequence(seed, spawn_key=(0, j,
    r))``, so the table does not depend on ``chunk`` or on the executor. ``chunk``
    candidates are simulated per task (memory ≈ chunk × P × 192 × 16 bytes).
    """
    cand = room.check_anchors(candidates, min_anchors=1)
    nodes = room.grid() if nodes is None else np.asarray(nodes, dtype=float)
    if int(realizations) != realizations or realizations < 1:
        raise ValueError(f"realizations: must be an integer >= 1, got {realizations}")
    if int(chunk) != chunk or chunk < 1:
        raise ValueError(f"chunk: must be an integer >= 1, got {chunk}")
    starts = range(0, len(cand), int(chunk))
    args = [
        (room, cand[i : i + chunk], np.arange(i, min(i + chunk, len(cand))), nodes) for i in starts
    ]
    extra = (int(realizations), int(seed), precision)
    if executor is None:
        parts = [_table_chunk(*a, *extra) for a in args]
    else:
        parts = [f.result() for f in [executor.submit(_table_chunk, *a, *extra) for a in args]]
    ranges = np.concatenate([p[0] for p in parts], axis=2)
    distances = np.concatenate([p[1] for p in parts], axis=1)
    region = (np.zeros(3), np.asarray(room.size, dtype=float))
    return RangeTable(cand, nodes, ranges, distances, region)


def table_costs(table: RangeTable, layouts, statistic: str = "variance") -> np.ndarray:
    """The simulated ``statistic`` of the Euclidean errors of each layout of candidates
    ``layouts`` (L, M) indices, over all R × P table entries: (L,), +inf for a layout
    where some node fails. The layouts are positioned in one batch."""
    from simulation.positioning import locate

    S = np.asarray(layouts, dtype=int)
    ranges = np.moveaxis(table.ranges[:, :, S], 2, 0)  # (L, R, P, M)
    x = locate(table.candidates[S], ranges, region=table.region)
    e = np.linalg.norm(x - table.nodes, axis=-1)  # (L, R, P)
    stat = SIMULATED_STATISTICS[statistic]
    return np.array([stat(el) if np.all(np.isfinite(el)) else math.inf for el in e])


def table_cost(table: RangeTable, indices, statistic: str = "variance") -> float:
    """:func:`table_costs` of the one layout made of the candidates ``indices`` (M,)."""
    return float(table_costs(table, np.asarray(indices)[None], statistic)[0])


def _local_search(
    table: RangeTable,
    M: int,
    statistic: str,
    neighbours: np.ndarray,
    start: np.ndarray | None,
    random_starts: int,
    max_evaluations: int,
    seed: int,
    key: int,
) -> tuple[np.ndarray, float, int]:
    """One first-improvement swap search; returns (indices (M,), cost, evaluations)."""
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(1, key))))
    N = len(table.candidates)
    nfev = 0

    def costs(layouts):
        nonlocal nfev
        nfev += len(layouts)
        return table_costs(table, np.stack(layouts), statistic)

    if start is None:  # the best of a few random subsets
        tries = [rng.choice(N, M, replace=False) for _ in range(random_starts)]
        values = costs(tries)
        S, f = tries[int(np.argmin(values))].copy(), float(np.min(values))
    else:
        S = np.asarray(start, dtype=int).copy()
        f = float(costs([S])[0])
    improved = True
    while improved and nfev < max_evaluations:
        improved = False
        for i in rng.permutation(M):
            # the swaps of anchor i, scored in one batch; the first that improves is taken
            js = [j for j in rng.permutation(neighbours[S[i]]) if j not in S]
            js = js[: max_evaluations - nfev]
            if not js:
                continue
            swaps = [np.where(np.arange(M) == i, j, S) for j in js]
            g = costs(swaps)
            better = np.flatnonzero(g < f)
            if better.size:
                S, f, improved = swaps[better[0]], float(g[better[0]]), True
                break
    return np.sort(S), f, nfev


@dataclass
class SimulatedSelection:
    """Result of :func:`simulated_select`.

    anchors (M, 3) the best layout found and indices (M,) its candidates; cost its
    statistic on the range table; optima the local optima of all starts as (indices,
    cost), best first; nfev the layouts scored on the table; table_windows the windows
    simulated for the table and equivalent_evaluations that count divided by the windows
    of one full evaluation of an M-anchor layout (P · M); timings in seconds.
    """

    anchors: np.ndarray
    indices: np.ndarray
    cost: float
    statistic: str
    optima: list[tuple[np.ndarray, float]]
    candidates: np.ndarray
    nfev: int
    table_windows: int
    equivalent_evaluations: float
    timings: dict[str, float] = field(default_factory=dict)
    message: str = ""

    @property
    def x(self) -> np.ndarray:
        return self.anchors.ravel()

    @property
    def fun(self) -> float:
        return self.cost

    def layouts(self, k: int | None = None) -> np.ndarray:
        """(k, M, 3) the anchors of the k best local optima."""
        return np.stack([self.candidates[S] for S, _ in self.optima[:k]])

    def to_dict(self) -> dict[str, Any]:
        return {
            "anchors": self.anchors.tolist(),
            "indices": self.indices.tolist(),
            "cost": self.cost,
            "statistic": self.statistic,
            "optima": [{"indices": S.tolist(), "cost": c} for S, c in self.optima],
            "nfev": self.nfev,
            "table_windows": self.table_windows,
            "equivalent_evaluations": self.equivalent_evaluations,
            "timings": self.timings,
            "message": self.message,
        }


def simulated_select(
    room: Room,
    M: int,
    *,
    statistic: str = "variance",
    spacing: float = 0.6,
    candidates=None,
    realizations: int = 3,
    starts: int = 8,
    random_starts: int = 30,
    neighbours: int = 25,
    initial=None,
    max_evaluations: int = 5000,
    seed: int | None = None,
    nodes=None,
    executor: Executor | None = None,
    table: RangeTable | None = None,
) -> SimulatedSelection:
    """Choose M of the candidate points minimizing a simulated error statistic.

    Builds the range table (``realizations`` noise draws of every candidate at every
    node, :func:`range_table`; candidates default to ``candidate_grid(room, spacing)``)
    and runs ``starts`` local searches from the best of ``random_starts`` random subsets,
    plus one from each selection in ``initial`` (k, M) candidate indices. A search swaps
    one anchor for one of its ``neighbours`` nearest unused candidates whenever the cost
    falls, until a full sweep brings no gain or ``max_evaluations`` layouts were scored.
    The searches run on ``executor`` when given; the result does not depend on it.

    statistic : "variance" (the paper's cost), "mean", "p95" or "rms" of the Euclidean
        position errors over all R × P table entries.
    """
    if statistic not in SIMULATED_STATISTICS:
        raise ValueError(f"statistic: unknown {statistic!r}; allowed: {list(SIMULATED_STATISTICS)}")
    if int(M) != M or M < 4:
        raise ValueError(f"M: need an integer number of anchors >= 4, got {M}")
    for name, value, low in (
        ("starts", starts, 0),
        ("random_starts", random_starts, 1),
        ("neighbours", neighbours, 1),
        ("max_evaluations", max_evaluations, 1),
    ):
        if int(value) != value or value < low:
            raise ValueError(f"{name}: must be an integer >= {low}, got {value}")
    seed = int(np.random.SeedSequence().entropy % 2**63) if seed is None else int(seed)
    t0 = time.perf_counter()
    if table is None:
        cand = candidate_grid(room, spacing) if candidates is None else candidates
        table = range_table(
            room, cand, nodes, realizations=realizations, seed=seed, executor=executor
        )
    N = len(table.candidates)
    if N < M:
        raise ValueError(f"candidates: need at least M = {M} points, got {N}")
    inits = [] if initial is None else [np.asarray(s, dtype=int) for s in np.atleast_2d(initial)]
    for s in inits:
        if s.shape != (M,) or s.min() < 0 or s.max() >= N or len(set(s.tolist())) != M:
            raise ValueError(f"initial: each selection must be {M} distinct indices in [0, {N})")
    if not inits and starts == 0:
        raise ValueError("starts: need at least one start (starts >= 1 or initial)")
    t1 = time.perf_counter()

    d = np.linalg.norm(table.candidates[:, None] - table.candidates[None], axis=-1)
    nbr = np.argsort(d, axis=1, kind="stable")[:, 1 : int(neighbours) + 1]

    jobs = [None] * int(starts) + inits
    args = [
        (table, int(M), statistic, nbr, s, int(random_starts), int(max_evaluations), seed, k)
        for k, s in enumerate(jobs)
    ]
    if executor is None:
        found = [_local_search(*a) for a in args]
    else:
        found = [f.result() for f in [executor.submit(_local_search, *a) for a in args]]
    t2 = time.perf_counter()

    optima: list[tuple[np.ndarray, float]] = []
    for S, f, _ in sorted(found, key=lambda t: t[1]):
        if not any(np.array_equal(S, T) for T, _ in optima):
            optima.append((S, float(f)))
    best, cost = optima[0]
    capped = any(n >= max_evaluations for _, _, n in found)
    message = "local optima reached" if not capped else "evaluation budget reached in a search"
    if not math.isfinite(cost):
        message = "no layout with finite cost found"
        logger.warning("simulated_select: %s", message)
    P = len(table.nodes)
    return SimulatedSelection(
        anchors=table.candidates[best],
        indices=best,
        cost=cost,
        statistic=statistic,
        optima=optima,
        candidates=table.candidates,
        nfev=int(sum(n for _, _, n in found)),
        table_windows=table.windows,
        equivalent_evaluations=table.windows / (P * M),
        timings={"table": t1 - t0, "search": t2 - t1},
        message=message,
    )

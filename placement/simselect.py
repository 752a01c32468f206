"""Simulation-driven selection of M anchors among candidate mounting points.

A layout built from candidate points is scored on a range table
(:mod:`placement.rangetable`) by least-squares positioning alone: the simulated ranges
are already in the table, so a layout costs a batch of position fixes, not a
simulation. The search (docs/model.md, "Range-table search"):

1. **Stochastic swap search.** From the best of a few random layouts, one anchor at a
   time: a random sample of ``batch`` of its ``neighbours`` nearest unused candidates is
   scored in one batch and the best swap is taken if it lowers the cost. After
   ``patience`` such steps in a row without a gain, the best layout so far is kicked (two
   anchors moved to random neighbours) and the search goes on from there, until its
   evaluation budget is spent. Several such chains run from different starts (with 4
   anchors two of them from the room's corners layout and a spread layout,
   :func:`spread_starts`).
2. **Descent.** Each chain's best layout is finished by a best-improvement descent on the
   whole table, so every returned layout is a local optimum: no single swap of an anchor
   with one of its ``finish_neighbours`` nearest candidates lowers its cost.

:func:`simulated_select` does both. :func:`refine_on_table` is the multi-resolution step
that follows it in a plan (docs/model.md, "Refinement after the swarm"): given layouts get
table columns for finer candidate points around each of their anchors
(:func:`placement.rangetable.extend_table`) and descend again on the grown table, resolving
them to the fine spacing without simulating a fine grid over whole surfaces.

Every random choice comes from streams derived from ``seed`` and the chain's number;
results do not depend on the executor or the number of workers.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from placement import ties
from placement.rangetable import (
    MAX_TABLE_DRAWS,
    RangeTable,
    check_mount_tolerance,
    extend_table,
    range_table,
    table_costs,
    table_errors,
)
from placement.result import LayoutResult
from placement.surfaces import (
    MAX_ANCHORS,
    allowed_area,
    candidate_grid,
    mounting_surfaces,
    new_points,
    project,
    surface_index,
)
from placement.workers import run_jobs
from simulation import checks, streams
from simulation.room import Room


def nearest(points: np.ndarray, k: int) -> np.ndarray:
    """(N, k') indices of the k' = min(k, N − 1) nearest other points of each point."""
    d = np.linalg.norm(points[:, None] - points[None], axis=-1)
    return np.argsort(d, axis=1, kind="stable")[:, 1 : min(int(k), len(points) - 1) + 1]


class _Scorer:
    """Counts the layouts it scores and stops at a budget."""

    def __init__(self, table: RangeTable, statistic: str, budget: int):
        self.table, self.statistic, self.budget, self.nfev = table, statistic, budget, 0

    @property
    def left(self) -> int:
        return self.budget - self.nfev

    def __call__(self, layouts) -> np.ndarray:
        self.nfev += len(layouts)
        return table_costs(self.table, np.stack(layouts), self.statistic)


def descend(S, f: float, nbr: np.ndarray, score: _Scorer, rng: np.random.Generator):
    """Best-improvement swap descent from layout S (M,) of cost f over the neighbourhoods
    ``nbr`` (N, k); returns (S, f, local), ``local`` True when no single swap of an anchor
    with one of its k neighbours improves S (False when the budget ran out first)."""
    S = np.asarray(S, dtype=int).copy()
    M = len(S)
    stale = 0  # anchors tried in a row without an improvement
    order = rng.permutation(M)
    i = 0
    while stale < M:
        if score.left <= 0:
            return S, f, False
        a = order[i % M]
        i += 1
        js = [j for j in nbr[S[a]] if j not in S][: score.left]
        if not js:
            stale += 1
            continue
        swaps = [np.where(np.arange(M) == a, j, S) for j in js]
        g = score(swaps)
        b = ties.argmin(g)
        if ties.improves(g[b], f):
            S, f, stale = swaps[b], float(g[b]), 1
        else:
            stale += 1
    return S, f, True


def kick(S: np.ndarray, nbr: np.ndarray, rng: np.random.Generator, moves: int = 2):
    """S with ``moves`` random anchors moved to random unused neighbours of theirs."""
    T = np.array(S, copy=True)
    for a in rng.choice(len(S), size=min(moves, len(S)), replace=False):
        free = [j for j in nbr[T[a]] if j not in T]
        if free:
            T[a] = free[int(rng.integers(len(free)))]
    return T


@dataclass
class Chain:
    """One stochastic swap search with kicks (module docstring, step 1), resumable: the
    driver advances it in segments (for progress) with the same result as in one go.

    S, f the current layout and cost; best, fbest the best so far; fails the steps since
    the last gain; step the steps taken; nfev the layouts scored; rng its own stream.
    """

    S: np.ndarray
    f: float
    best: np.ndarray
    fbest: float
    rng: np.random.Generator
    order: np.ndarray
    fails: int = 0
    step: int = 0
    nfev: int = 0

    @classmethod
    def start(cls, table, M: int, statistic: str, tries: int, rng, around=None, nbr=None) -> Chain:
        """The best of ``tries`` random layouts of M candidates; with ``around`` (M,) a
        layout and ``nbr`` the neighbourhoods, random layouts near it instead, each with
        half its anchors moved to random neighbours (:func:`kick`): where the table holds
        a coverage target, random layouts anywhere rarely meet it."""
        N = len(table.candidates)
        if around is None:
            layouts = [rng.choice(N, M, replace=False) for _ in range(tries)]
        else:
            layouts = [kick(around, nbr, rng, max(2, M // 2)) for _ in range(tries)]
        costs = table_costs(table, np.stack(layouts), statistic)
        k = ties.argmin(costs)
        S = np.asarray(layouts[k])
        chain = cls(S, float(costs[k]), S.copy(), float(costs[k]), rng, rng.permutation(M))
        chain.nfev = tries
        return chain

    @classmethod
    def at(cls, table, S, statistic: str, rng) -> Chain:
        """A chain started from the layout S (M,) of candidate indices."""
        S = np.asarray(S, dtype=int)
        f = float(table_costs(table, S[None], statistic)[0])
        chain = cls(S, f, S.copy(), f, rng, rng.permutation(len(S)))
        chain.nfev = 1
        return chain

    def advance(self, table, statistic, nbr, *, batch, patience, until, budget, moves=2):
        """Take steps while fewer than ``until`` layouts were scored; never score more
        than ``budget`` in all. Returns self."""
        M = len(self.S)
        stuck = 0  # anchors in a row whose neighbours are all in the layout
        while self.nfev < min(until, budget) and stuck < M:
            a = self.order[self.step % M]
            self.step += 1
            pool = [j for j in nbr[self.S[a]] if j not in self.S]
            if not pool:  # no swap for this anchor (tiny tables, tiny neighbourhoods)
                stuck += 1
                continue
            stuck = 0
            size = min(batch, len(pool), budget - self.nfev)
            js = self.rng.choice(pool, size=size, replace=False)
            swaps = np.stack([np.where(np.arange(M) == a, j, self.S) for j in js])
            g = table_costs(table, swaps, statistic)
            self.nfev += len(swaps)
            b = ties.argmin(g)
            if ties.improves(g[b], self.f):
                self.S, self.f, self.fails = swaps[b], float(g[b]), 0
                if ties.improves(self.f, self.fbest):
                    self.best, self.fbest = self.S.copy(), self.f
            else:
                self.fails += 1
            if self.fails >= patience and self.nfev < budget:
                self.S = kick(self.best, nbr, self.rng, moves)
                self.f = float(table_costs(table, self.S[None], statistic)[0])
                self.nfev += 1
                self.fails = 0
        return self


def fine_points(room: Room, anchors: np.ndarray, spacing: float, steps: int) -> np.ndarray:
    """(n, 3) points around each anchor (M, 3) in its surface plane: the lattice of
    ``spacing`` (m) with up to ``steps`` steps along each in-plane axis, projected onto
    the mounting surfaces."""
    surfs = mounting_surfaces(room)
    offs = np.arange(-steps, steps + 1) * spacing
    du, dv = np.meshgrid(offs, offs, indexing="ij")
    out = []
    for a, s in zip(anchors, surface_index(room, anchors), strict=True):
        eu, ev = (surfs[int(s)].u_axis, surfs[int(s)].v_axis) if s >= 0 else ((1, 0, 0), (0, 1, 0))
        p = np.repeat(a[None], du.size, axis=0)
        p += du.ravel()[:, None] * np.asarray(eu, float) + dv.ravel()[:, None] * np.asarray(
            ev, float
        )
        out.append(project(room, p))
    return np.concatenate(out)


#: the candidate spacing (m) of the search in a room of ordinary size
DEFAULT_SPACING = 0.4
#: about the most candidate points the default spacing gives (a larger room gets a coarser
#: grid; the refinement's fine lattices then resolve the chosen anchors)
AUTO_CANDIDATES = 1000
#: the finest lattice of the default refinement (m)
FINEST_SPACING = 0.1

#: distinct search optima a plan starts from (the swarm's other particles start at random)
DEFAULT_KEEP = 4
#: the layouts' size up to which a plan starts from more search optima and refines them
#: all: four anchors leave a fix no redundant range, so each anchor shapes the whole field
#: and a layout's refined form can rank far from its form on the coarse candidate grid
#: (docs/model.md, "Refinement after the swarm")
SMALL_M = 4
#: distinct search optima a plan of at most :data:`SMALL_M` anchors starts from: as many as
#: the swarm of ``seed_then_pso`` has particles (:data:`placement.plan.LOCAL_SWARM`)
SMALL_M_KEEP = 5


@dataclass(frozen=True)
class SearchOptions:
    """Settings of the range-table search (:func:`simulated_select`).

    spacing : candidate grid spacing on the mounting surfaces (m); None (the default):
        :data:`DEFAULT_SPACING`, coarser in a large room so that the grid has about
        :data:`AUTO_CANDIDATES` points at most (:meth:`spacing_for`).
    draws, exact_draws, mount_tolerance : the table's draws (:func:`range_table`): how
        many, how many keep the nodes and planned points exactly, and the radius (m) of
        the mounting error in the others.
    chains : independent stochastic searches, each from its own start (the coverage and
        sight selections' where there are any, then at M = 4 :func:`spread_starts`, then
        the best of ``random_starts`` random layouts).
    chain_draws : the first draws the chains score layouts on (fewer is faster; the
        finishing descents and the fine lattices use every draw); None: as many of the
        exact draws as keep a chain's positioning work per layout at that of one draw
        with 8 anchors, ``max(1, min(exact_draws, 8 // M))``.
    random_starts : random layouts scored to pick each chain's start (the best is used).
    neighbours : the swap neighbourhood: this many nearest candidates of an anchor.
    batch : swaps sampled from the neighbourhood and scored together at each step.
    patience : steps without a gain before a kick.
    evaluations : layouts scored per chain (the descent that finishes it comes on top).
    finish_neighbours : the neighbourhood of the finishing descents on the whole table
        (the nearest ``finish_neighbours`` of the ``neighbours``).
    fine_spacings : finer lattices (m) added around the best optima, in turn (empty: off);
        None (the default): the candidate spacing halved, and halved again, down to 0.1 m
        (0.2 and 0.1 m from 0.4 m; :meth:`fine_spacings_for`).
    fine_halvings : with ``fine_spacings`` None, at most this many halvings (None: down to
        0.1 m; 1: the candidate spacing halved once, 0.2 m from 0.4 m, 0.5 m from 1.0 m).
    fine_steps : lattice steps on each side of an anchor along each in-plane axis.
    fine_neighbours : the swap neighbourhood of the descents on a grown table.
    fine_optima : the swarm's best distinct layouts that a plan refines on the fine lattices,
        each on the table grown by its own columns; None (the default): one, or at M = 4
        every distinct layout of the swarm (:meth:`fine_optima_for`).
    keep : distinct optima returned as seeds; None (the default): :data:`DEFAULT_KEEP`, or
        at M = 4 :data:`SMALL_M_KEEP` (:meth:`keep_for`).
    precision : the receiver DSP's precision for the table.
    coverage_k : in a room where walls, obstacles or the signal's reach hide candidates
        from some nodes, the first chain starts from the coverage selection that makes
        the most nodes see this many anchors (:mod:`placement.coverage`; 0: off).
    min_coverage : the share of the nodes every layout must cover with ``coverage_k``
        anchors in line of sight and reach, when the coverage selection shows that M
        anchors can (:class:`placement.coverage.CoverageTarget`: a layout below it costs
        more than any above, in the search, the swarm, the refinement and the finalists);
        0: none; None (the default): none in a plan, the sweep's ``target_coverage`` in
        :func:`placement.sweep`.
    """

    spacing: float | None = None
    draws: int = 3
    exact_draws: int = 2
    mount_tolerance: float = 0.03
    chains: int = 8
    chain_draws: int | None = None
    random_starts: int = 30
    neighbours: int = 48
    batch: int = 24
    patience: int = 16
    evaluations: int = 4500
    finish_neighbours: int = 16
    fine_spacings: tuple[float, ...] | None = None
    fine_halvings: int | None = None
    fine_steps: int = 1
    fine_neighbours: int = 8
    fine_optima: int | None = None
    keep: int | None = None
    precision: str = "float32"
    coverage_k: int = 5
    min_coverage: float | None = None

    def __post_init__(self) -> None:
        if self.spacing is not None:
            checks.real("spacing", self.spacing, low=0.05, high=10.0, unit="m")
        checks.count("draws", self.draws, low=1, high=MAX_TABLE_DRAWS)
        checks.count("exact_draws", self.exact_draws, low=0, high=self.draws)
        check_mount_tolerance(self.mount_tolerance)
        checks.count("chains", self.chains, low=1, high=10_000)
        if self.chain_draws is not None:
            checks.count("chain_draws", self.chain_draws, low=1, high=self.draws)
        checks.count("random_starts", self.random_starts, low=1, high=100_000)
        checks.count("neighbours", self.neighbours, low=1, high=10_000)
        checks.count("batch", self.batch, low=1, high=self.neighbours)
        checks.count("patience", self.patience, low=1, high=100_000)
        checks.count("evaluations", self.evaluations, low=1, high=10**7)
        checks.count("finish_neighbours", self.finish_neighbours, low=1, high=10_000)
        fine = self.fine_spacings
        if fine is not None:
            if isinstance(fine, str | bytes) or not isinstance(fine, Iterable):
                raise ValueError(
                    f"fine_spacings: expected spacings in m, e.g. (0.2, 0.1), got {fine!r}"
                )
            object.__setattr__(self, "fine_spacings", tuple(fine))
            for s in self.fine_spacings:
                checks.real("fine_spacings", s, low=0.01, high=10.0, unit="m")
        if self.fine_halvings is not None:
            checks.count("fine_halvings", self.fine_halvings, low=0, high=10)
        checks.count("fine_steps", self.fine_steps, low=1, high=10)
        checks.count("fine_neighbours", self.fine_neighbours, low=1, high=10_000)
        if self.fine_optima is not None:
            checks.count("fine_optima", self.fine_optima, low=1, high=1000)
        if self.keep is not None:
            checks.count("keep", self.keep, low=1, high=1000)
        checks.choice("precision", self.precision, ("float64", "float32"))
        checks.count("coverage_k", self.coverage_k, low=0, high=MAX_ANCHORS)
        if self.min_coverage is not None:
            checks.real("min_coverage", self.min_coverage, low=0.0, high=1.0)

    def spacing_for(self, room: Room) -> float:
        """The candidate spacing (m) in ``room``: ``spacing`` when given, else
        :data:`DEFAULT_SPACING` or, where the allowed mounting area A (m²) would give more
        than :data:`AUTO_CANDIDATES` points at it, √(A / AUTO_CANDIDATES) rounded up to
        0.1 m (a 24 × 16 × 6 m hall: 1.0 m)."""
        if self.spacing is not None:
            return float(self.spacing)
        area = float(np.sum(allowed_area(room)))
        auto = math.ceil(10 * math.sqrt(area / AUTO_CANDIDATES)) / 10
        return max(DEFAULT_SPACING, auto)

    def keep_for(self, M: int) -> int:
        """The distinct optima a plan of M anchors starts from: ``keep`` when given, else
        :data:`DEFAULT_KEEP`, or :data:`SMALL_M_KEEP` at M = 4 (:data:`SMALL_M`)."""
        if self.keep is not None:
            return self.keep
        return SMALL_M_KEEP if M <= SMALL_M else DEFAULT_KEEP

    def fine_optima_for(self, M: int) -> int | None:
        """The swarm's distinct layouts a plan of M anchors refines: ``fine_optima`` when
        given, else one, or at M = 4 (:data:`SMALL_M`) None: every distinct layout of the
        swarm, whatever its size."""
        if self.fine_optima is not None:
            return self.fine_optima
        return None if M <= SMALL_M else 1

    def fine_spacings_for(self, room: Room) -> tuple[float, ...]:
        """The refinement's lattices (m) in ``room``: ``fine_spacings`` when given, else
        the candidate spacing halved while it stays ≥ :data:`FINEST_SPACING`, at most
        ``fine_halvings`` times."""
        if self.fine_spacings is not None:
            return self.fine_spacings
        out, s = [], self.spacing_for(room) / 2
        limit = math.inf if self.fine_halvings is None else self.fine_halvings
        while s >= FINEST_SPACING - 1e-9 and len(out) < limit:
            out.append(round(s, 6))
            s /= 2
        return tuple(out)


def first_draws(table: RangeTable, n: int) -> RangeTable:
    """A view of the table holding its first ``n`` draws only (all when n ≥ D)."""
    n = min(int(n), table.draws)
    return dataclasses.replace(
        table,
        nodes=table.nodes[:n],
        ranges=table.ranges[:n],
        distances=table.distances[:n],
        line_of_sight=table.line_of_sight[:n],
        exact_draws=min(table.exact_draws, n),
    )


def _advance(table, statistic, nbr, opt, chains, until):
    """Advance each chain (one job) to ``until`` scored layouts; returns them."""
    return [
        c.advance(
            table,
            statistic,
            nbr,
            batch=opt.batch,
            patience=opt.patience,
            until=until,
            budget=opt.evaluations,
        )
        for c in chains
    ]


def _finish(table, statistic, nbr, chains, seed):
    """The finishing descent of each chain's best layout on the whole table;
    [(S, cost, local, n)]."""
    out = []
    for k, c in chains:
        score = _Scorer(table, statistic, 10**9)
        f = float(score([c.best])[0])
        S, f, local = descend(c.best, f, nbr, score, streams.stream(seed, 11, k))
        out.append((np.sort(S), f, local, c.nfev + score.nfev))
    return out


def _descents(table, statistic, nbr, layouts, seed, key):
    """Descent (:func:`descend`) of each (number, layout) of ``layouts`` on ``table``,
    each with the stream of its number; [(S, cost, local, n)]."""
    out = []
    for i, S in layouts:
        rng = streams.stream(seed, key, i)
        score = _Scorer(table, statistic, 10**9)
        S, f, local = descend(S, float(score([S])[0]), nbr, score, rng)
        out.append((np.sort(S), f, local, score.nfev))
    return out


def _split(items: list, parts: int) -> list[list]:
    return [items[i::parts] for i in range(parts) if items[i::parts]]


def _distinct(found) -> list[tuple[np.ndarray, float]]:
    out: list[tuple[np.ndarray, float]] = []
    for i in ties.order([t[1] for t in found]):  # found in chain order: near-ties stable
        S, f = found[i][0], found[i][1]
        if math.isfinite(f) and not any(np.array_equal(S, T) for T, _ in out):
            out.append((S, float(f)))
    return out


#: progress reports per chain: the chains advance in this many segments
SEGMENTS = 8


def _run_chains(table, M, statistic, nbr, opt, seed, executor, workers, progress, starts=()):
    """Start (the first chains from ``starts``, index layouts (M,), the others from random
    layouts, near the first start where the table holds a coverage target), advance (in
    :data:`SEGMENTS` segments) and finish ``opt.chains`` chains as ``workers`` jobs;
    [(S, cost, local, evaluations)] per chain."""
    n = opt.chain_draws or max(1, min(table.exact_draws, 8 // M))
    view = first_draws(table, n)
    # under a target of the nodes' coverage the other chains start near the first start,
    # which meets it (a shadow error alone is no requirement: they start at random)
    target = table.coverage_target
    around = starts[0] if starts and target is not None and target.share > 0 else None
    chains = [
        Chain.start(
            view, M, statistic, opt.random_starts, streams.stream(seed, 10, k), around, nbr
        )  # fmt: skip
        if k >= len(starts)
        else Chain.at(view, starts[k], statistic, streams.stream(seed, 10, k))
        for k in range(opt.chains)
    ]
    parts = _split(list(range(opt.chains)), max(1, workers))
    for seg in range(1, SEGMENTS + 1):
        until = opt.evaluations * seg // SEGMENTS
        jobs = [(view, statistic, nbr, opt, [chains[k] for k in ks], until) for ks in parts]
        for ks, done in zip(parts, run_jobs(executor, _advance, jobs), strict=True):
            for k, c in zip(ks, done, strict=True):
                chains[k] = c
        if progress:
            progress("search", seg, SEGMENTS + 1)
    near = nbr[:, : opt.finish_neighbours]
    jobs = [(table, statistic, near, [(k, chains[k]) for k in ks], seed) for ks in parts]
    found = [r for part in run_jobs(executor, _finish, jobs) for r in part]
    if progress:
        progress("search", SEGMENTS + 1, SEGMENTS + 1)
    return found


def search_table(
    room: Room, options: SearchOptions, nodes=None, rng=0, executor=None, progress=None,
    system=None,
) -> RangeTable:  # fmt: skip
    """The range table of a search: every point of
    ``candidate_grid(room, options.spacing_for(room))`` on ``options.draws`` scene draws of
    ``nodes`` (default ``room.grid()``) with ``system`` (default the paper's).
    ``progress(done, total)`` as its chunks finish."""
    cand = candidate_grid(room, options.spacing_for(room))
    return range_table(
        room,
        cand,
        nodes,
        draws=options.draws,
        exact_draws=options.exact_draws,
        mount_tolerance=options.mount_tolerance,
        rng=rng,
        executor=executor,
        precision=options.precision,
        progress=progress,
        system=system,
    )


def simulated_select(
    room: Room,
    M: int,
    *,
    statistic: str = "variance",
    options: SearchOptions | None = None,
    table: RangeTable | None = None,
    nodes=None,
    rng=0,
    executor: Executor | None = None,
    workers: int = 1,
    progress=None,
    system=None,
) -> SimulatedSelection:
    """Choose M of the candidate points minimizing a simulated error statistic on a range
    table (the module docstring gives the steps), simulated with ``system`` (default the
    paper's) when the table is built here.

    table : a table to search (built from ``options`` and ``nodes`` when None); it is
        returned in the result.
    rng : an int seed of the table and of every chain's stream, a numpy Generator (drawn
        once) or None.
    executor, workers : the chains run as ``workers`` jobs on ``executor``; the result
        does not depend on either.
    progress : an optional callable ``progress(stage, done, total)`` reporting the search
        (stage "search") as it goes.
    """
    opt = options or SearchOptions()
    M = checks.count("M", M, low=4, high=MAX_ANCHORS)
    seed = streams.entropy("rng", rng)
    workers = checks.count("workers", workers, low=1, high=1024)
    t0 = time.perf_counter()
    if table is None:
        table = search_table(room, opt, nodes, seed, executor, system=system)
    if len(table.candidates) < M:
        raise ValueError(f"candidates: need at least M = {M} points, got {len(table.candidates)}")
    t1 = time.perf_counter()
    nbr = nearest(table.candidates, opt.neighbours)
    cover = _coverage_start(table, M, opt.coverage_k)
    seen = _sight_start(table, M, opt.coverage_k)
    shadow = 0.0 if seen is None else shadow_error(table, M, seed)
    target = coverage_target(opt, cover, shadow)
    table = dataclasses.replace(table, coverage_target=target)
    starts = tuple(s.indices for s in (cover, seen) if s is not None)
    starts += spread_starts(table, M)
    found = _run_chains(table, M, statistic, nbr, opt, seed, executor, workers, progress, starts)
    nfev = sum(r[3] for r in found)
    t2 = time.perf_counter()
    sel = _selection(table, statistic, found, nfev, (t0, t1, t2))
    return dataclasses.replace(sel, coverage=cover, sight=seen, coverage_target=target)


def coverage_target(opt: SearchOptions, cover, shadow: float = 0.0):
    """The :class:`placement.coverage.CoverageTarget` the search keeps to: ``opt.min_coverage``
    of the nodes with the coverage selection's k where the selection ``cover`` reaches it,
    and the sight points' ``shadow`` error (m, :func:`shadow_error`; 0: none), counting the
    points whose anchors in sight have a GDOP above :data:`placement.coverage.SHADOW_GDOP`;
    None: neither (no target, or one that M anchors cannot reach, or every node sees every
    candidate, and no shadow)."""
    from placement.coverage import K_FIX, SHADOW_GDOP, CoverageTarget

    share = opt.min_coverage or 0.0
    if share <= 0 or cover is None or not ties.reaches(cover.covered, share):
        share = 0.0
    if share <= 0 and shadow <= 0:
        return None
    limit = SHADOW_GDOP if shadow > 0 else None
    return CoverageTarget(cover.k if cover else K_FIX, share, K_FIX, shadow, limit)


#: the random layouts whose fixes in the shadows measure the shadow error
SHADOW_LAYOUTS = 30


def shadow_error(table: RangeTable, M: int, seed: int) -> float:
    """(m) the RMS error of the fixes, at the table's exact nodes, of the nodes that see
    fewer than 4 anchors in line of sight and reach, over :data:`SHADOW_LAYOUTS` random
    layouts of M candidates (the stream (13,) of ``seed``): what a tag in a shadow gets in
    this room with this system. 0 where no such node has a fix."""
    from placement.coverage import K_FIX, visibility

    rng = streams.stream(seed, 13)
    N = len(table.candidates)
    layouts = np.stack([np.sort(rng.choice(N, M, replace=False)) for _ in range(SHADOW_LAYOUTS)])
    view = first_draws(table, max(table.exact_draws, 1))
    e = table_errors(view, layouts).reshape(len(layouts), view.draws, -1)  # (L, D, P)
    counts = np.stack([np.sum(visibility(view, d, layouts), axis=-1).T for d in range(view.draws)],
                      axis=1)  # fmt: skip  # (L, D, P)
    shadowed = e[(counts < K_FIX) & np.isfinite(e)]
    return float(np.sqrt(np.mean(shadowed**2))) if shadowed.size else 0.0


def _coverage_start(table, M: int, k: int):
    """The coverage selection (:mod:`placement.coverage`) of M of the table's candidates
    for ``min(k, M)`` anchors in line of sight, when some node does not see every candidate
    (else None: in a convex empty room within reach every layout covers every node)."""
    from placement.coverage import plane_groups, select_coverage, visibility

    V = visibility(table)
    if k == 0 or bool(np.all(V)):
        return None
    groups = plane_groups(table.room, table.candidates)
    return select_coverage(V, M, min(k, M), groups=groups)


def _sight_start(table, M: int, k: int):
    """The sight selection: the M of the table's candidates that make the most sight points
    (:func:`placement.rangetable.sight_points`) see 4 anchors in line of sight and reach,
    where the positioning rejects echoes (a robust fix needs 4 direct ranges: a tag that
    sees fewer is fixed on an echo, metres off) and some point does not see every
    candidate; else (or with ``k`` 0, coverage off) None. It starts the second chain."""
    from placement.coverage import K_FIX, plane_groups, select_coverage

    V = table.sight
    if k == 0 or table.system.positioning.method != "robust" or bool(np.all(V)):
        return None
    groups = plane_groups(table.room, table.candidates)
    return select_coverage(V, M, min(K_FIX, M), groups=groups)


def spread_starts(table: RangeTable, M: int) -> tuple[np.ndarray, ...]:
    """Index layouts (M,) that start chains of a plan of at most :data:`SMALL_M` anchors
    after the coverage and sight selections: the room's corners layout
    (:meth:`simulation.Room.corners_layout`, the paper's unoptimized layout, on the nearest
    candidates; where it has M distinct ones) and the spread layout (:func:`spread_layout`).
    With 4 anchors a fix has no redundant range and the search's optima depend more on
    where its chains start; these two starts reach layouts the random starts can miss
    (docs/model.md, "Four anchors"). From M = 5 on, no start (an empty tuple)."""
    if M > SMALL_M:
        return ()
    out = []
    corners = np.sort(_indices(table, table.room.corners_layout()))
    if len(corners) == M and len(np.unique(corners)) == M:
        out.append(corners)
    out.append(spread_layout(table.candidates, M))
    return tuple(out)


def spread_layout(points: np.ndarray, M: int) -> np.ndarray:
    """(M,) sorted indices of M of ``points`` (N, 3) spread by farthest-point sampling: the
    point with the smallest x + y + z first, then each time the point farthest from those
    chosen (near-ties to the lowest index, :mod:`placement.ties`)."""
    p = np.asarray(points, dtype=float)
    chosen = [ties.argmin(p.sum(axis=1))]
    d = np.linalg.norm(p - p[chosen[0]], axis=1)
    while len(chosen) < M:
        d[chosen] = -np.inf  # never a point twice, even where points coincide
        j = ties.argmin(-d)
        chosen.append(j)
        d = np.minimum(d, np.linalg.norm(p - p[j], axis=1))
    return np.sort(np.array(chosen))


def _indices(table: RangeTable, anchors: np.ndarray) -> np.ndarray:
    """(M,) the table columns nearest anchors (M, 3): a layout of the table's candidates
    (near-ties to the lowest column, :mod:`placement.ties`)."""
    d = np.linalg.norm(table.candidates[None] - anchors[:, None], axis=-1)
    return np.array([ties.argmin(row) for row in d], dtype=np.intp)


def refine_on_table(
    room: Room,
    table: RangeTable,
    layouts,
    *,
    statistic: str = "variance",
    options: SearchOptions | None = None,
    rng=0,
    executor: Executor | None = None,
    workers: int = 1,
) -> tuple[list[tuple[np.ndarray, float, bool]], RangeTable, int]:
    """Refine layouts (k, M, 3) on finer lattices (module docstring, step 3): for each
    spacing of ``options.fine_spacings_for(room)`` in turn, the anchors of every layout and the
    lattice points around them become table columns (:func:`extend_table`, same draws)
    and each layout descends over its ``fine_neighbours`` nearest candidates. Returns
    [(anchors (M, 3), table cost, local)] per layout, the grown table and the layouts
    scored."""
    opt = options or SearchOptions()
    seed = streams.entropy("rng", rng)
    current = [room.check_anchors(a) for a in layouts]
    out = [(a, math.inf, False) for a in current]
    nfev = 0
    if not current:
        return out, table, nfev
    for level, spacing in enumerate(opt.fine_spacings_for(room)):
        points = np.concatenate(
            [np.concatenate([a, fine_points(room, a, spacing, opt.fine_steps)]) for a in current]
        )
        table = extend_table(room, table, new_points(table.candidates, points), executor=executor)
        nbr = nearest(table.candidates, opt.fine_neighbours)
        starts = [_indices(table, a) for a in current]
        parts = _split(list(range(len(starts))), max(1, workers))
        jobs = [
            (table, statistic, nbr, [(i, starts[i]) for i in part], seed, 30 + level)
            for part in parts
        ]
        done: list = [None] * len(starts)
        for part, res in zip(parts, run_jobs(executor, _descents, jobs), strict=True):
            for i, r in zip(part, res, strict=True):
                done[i] = r
        out = [(table.candidates[S], f, local) for S, f, local, _ in done]
        nfev += sum(n for *_, n in done)
        current = [a for a, _, _ in out]
    return out, table, nfev


def _selection(table, statistic, found, nfev, t) -> SimulatedSelection:
    optima = _distinct(found)
    if not optima:
        raise ValueError("simulated_select: no layout of the candidates has a finite cost")
    best, cost = optima[0]
    local = next(r[2] for r in found if np.array_equal(r[0], best))
    return SimulatedSelection(
        anchors=table.candidates[best],
        indices=best,
        cost=cost,
        statistic=statistic,
        optima=optima,
        candidates=table.candidates,
        nfev=int(nfev),
        table_windows=table.windows,
        timings={"table": t[1] - t[0], "search": t[2] - t[1]},
        status=0 if local else 1,
        message=SELECTION_STATUS[0 if local else 1],
        table=table,
    )


#: status codes of :class:`SimulatedSelection`
SELECTION_STATUS = {
    0: "a local optimum of the swap neighbourhood",
    1: "the evaluation budget ran out before a local optimum",
}


@dataclass(frozen=True)
class SimulatedSelection(LayoutResult):
    """Result of :func:`simulated_select` (the result convention of
    :mod:`placement.result`).

    anchors (M, 3) the best layout and indices (M,) its candidates in ``candidates``;
    cost (``fun``) its statistic on the table (m² for the variance, m otherwise); optima
    the distinct local optima found, as (indices, cost), best first; nfev the layouts
    scored on the table; table_windows the received windows simulated; timings in
    seconds; status a code of :data:`SELECTION_STATUS`; coverage the coverage selection
    that started the first chain (:class:`placement.coverage.CoverageSelection`, None
    where every node sees every candidate); sight the sight selection that started
    another (:func:`_sight_start`; None: none); coverage_target the target every layout
    was kept to (:func:`coverage_target`; None: none).
    """

    FUN: ClassVar[str] = "cost"
    STATUS: ClassVar[dict[int, str]] = SELECTION_STATUS

    anchors: np.ndarray
    indices: np.ndarray
    cost: float
    statistic: str
    optima: list[tuple[np.ndarray, float]]
    candidates: np.ndarray
    nfev: int
    table_windows: int
    timings: dict[str, float] = field(default_factory=dict)
    success: bool = True
    status: int = 0
    message: str = ""
    table: RangeTable | None = field(default=None, repr=False)
    coverage: Any = None
    sight: Any = None
    coverage_target: Any = None

    def layouts(self, k: int | None = None) -> np.ndarray:
        """(k, M, 3) the anchors of the k best local optima."""
        return np.stack([self.candidates[S] for S, _ in self.optima[:k]])

    def to_dict(self) -> dict[str, Any]:
        """The selection as plain JSON types (the candidates and the table left out)."""
        return {
            "anchors": self.anchors.tolist(),
            "indices": self.indices.tolist(),
            "cost": self.cost,
            "statistic": self.statistic,
            "optima": [{"indices": S.tolist(), "cost": c} for S, c in self.optima],
            "nfev": self.nfev,
            "table_windows": self.table_windows,
            "timings": self.timings,
            "success": self.success,
            "status": self.status,
            "message": self.message,
            "fun": self.cost,
            **({} if self.coverage is None else {"coverage": self.coverage.to_dict()}),
            **({} if self.sight is None else {"sight": self.sight.to_dict()}),
            **({} if self.coverage_target is None
               else {"coverage_target": self.coverage_target.to_dict()}),
        }  # fmt: skip

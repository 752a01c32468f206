"""Range tables: simulated ranges of every candidate mounting point at every node.

Anchors transmit one at a time and each anchor's noise level is set by its own reference
node (docs/model.md, "The noise rule"), so the range that a node measures from an anchor depends on
that anchor, that node and the noise only, never on the other anchors. Simulating every
candidate point against every node once therefore gives the exact simulated ranges of
every layout built from the candidates, and scoring such a layout costs only the
least-squares positioning (docs/model.md, "Range-table search").

A table holds D *draws* of the scene. Draw d has its own node set (P nodes), its own
mounting error of every candidate and its own receiver noise:

- the first ``exact_draws`` draws use the given nodes and the candidates exactly where
  they are planned;
- the other draws move every node uniformly within its grid cell and mount every
  candidate at a random in-plane offset of at most ``mount_tolerance`` from its planned
  point. The position solver still uses the planned points, as an installed system
  would.

Scored over all draws, a layout is good where the tags will be and as it will be
mounted, not only at one fixed set of nodes (docs/model.md, "Range tables and scene draws").

A table also knows which of its *sight points* see each candidate (:func:`sight_points`:
random tag points, many more than the nodes, the same for every table of a room): where a
column's shadow falls between the nodes, a node set would not see that a layout leaves
part of the zone with too few anchors in line of sight.

Randomness: draw d's nodes come from ``SeedSequence(seed, spawn_key=(3, d))``; candidate
j's offset in draw d from ``(2, j, d)`` and its noise from ``(0, j, d)``. The table does
not depend on chunking or on the executor, and :func:`extend_table` adds columns that
are exactly those a bigger table would have had.
"""

from __future__ import annotations

import dataclasses
import math
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from placement.coverage import CoverageTarget, constrain, visibility
from placement.dilution import poor_sight_share_unchecked
from placement.surfaces import mounting_surfaces, project, surface_index
from placement.tags import random_nodes
from placement.workers import run_jobs
from simulation import checks, degeneracy, streams
from simulation.receiver import PRECISIONS
from simulation.room import Room
from simulation.statistics import row_statistics
from simulation.system import System, as_system


@dataclass(frozen=True)
class RangeTable:
    """Simulated ranges of N candidate anchors at the nodes of D draws.

    candidates (N, 3) planned points (m); nodes (D, P, 3) the nodes of each draw (m);
    ranges (D, P, N) estimated ranges (m; NaN where the receiver reported none: the
    candidate beyond the signal's reach, or not heard); distances (D, P, N) true ranges from the
    mounted points (m); room the room and system the system simulated (its positioning
    solves the table's fixes); line_of_sight (D, P, N) bool, nothing blocks the direct
    path. seed, mount_tolerance (m), exact_draws and precision describe how it was drawn.
    sight (Q, N) bool: sight point q of ``sight_points`` (Q, 3) (:func:`sight_points`) sees
    candidate j in line of sight and reach (:func:`sight`). coverage_target: a
    :class:`placement.coverage.CoverageTarget` the costs of its layouts enforce
    (:func:`table_costs`; None: none).
    """

    candidates: np.ndarray
    nodes: np.ndarray
    ranges: np.ndarray
    distances: np.ndarray
    room: Room
    system: System
    line_of_sight: np.ndarray
    seed: int
    mount_tolerance: float
    exact_draws: int
    precision: str
    sight: np.ndarray
    sight_points: np.ndarray
    coverage_target: CoverageTarget | None = None

    @property
    def draws(self) -> int:
        """D, the number of draws."""
        return int(self.nodes.shape[0])

    @property
    def windows(self) -> int:
        """Received windows simulated for the table (D · P · N)."""
        return int(self.ranges.size)


def cell_size(nodes: np.ndarray) -> np.ndarray:
    """(3,) the spacing of a node grid along each axis (0 where all nodes share a value)."""
    out = np.zeros(3)
    for k in range(3):
        u = np.unique(np.round(nodes[:, k], 9))
        if len(u) > 1:
            out[k] = float(np.min(np.diff(u)))
    return out


def node_region(room: Room, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) lower and upper bounds each node may move within: the room less its node
    margin, intersected with the tag zone holding the node when the room has zones."""
    lo = np.broadcast_to(np.full(3, room.node_margin), nodes.shape).copy()
    hi = np.broadcast_to(np.asarray(room.size) - room.node_margin, nodes.shape).copy()
    if room.zones:
        owner = np.full(len(nodes), -1)
        for k, (zlo, zhi) in enumerate(room.zones):
            inside = np.all(
                (nodes >= np.asarray(zlo) - 1e-9) & (nodes <= np.asarray(zhi) + 1e-9), 1
            )
            owner[(owner < 0) & inside] = k
        for k, (zlo, zhi) in enumerate(room.zones):
            rows = owner == k
            lo[rows] = np.maximum(lo[rows], zlo)
            hi[rows] = np.minimum(hi[rows], zhi)
    return lo, hi


#: the sight points of a room (:func:`sight_points`)
SIGHT_POINTS = 2000
#: the key of the sight points' stream (of seed 0: they depend on the room only)
SIGHT_STREAM = 12


def sight_points(room: Room) -> np.ndarray:
    """(Q, 3) the room's sight points: :data:`SIGHT_POINTS` uniform random tag points
    (:func:`placement.tags.random_nodes`) from a stream of the room's own, so that every
    table and cost of a room counts the same points."""
    return random_nodes(room, SIGHT_POINTS, streams.stream(0, SIGHT_STREAM))


def sight(room: Room, system: System, anchors, points) -> np.ndarray:
    """(Q, n) bool: point q (points (Q, 3)) sees anchor j (anchors (n, 3)): nothing blocks
    the direct path, and it lies within the signal's reach and beyond its near limit (as
    :func:`placement.coverage.visibility`)."""
    from simulation.polyhedral import line_of_sight

    a = np.asarray(anchors, dtype=float)
    d = np.linalg.norm(points[:, None, :] - a[None], axis=-1)
    return line_of_sight(room, a, points) & system.within_reach(d, room.speed_of_sound)


def node_draws(room: Room, nodes, draws: int, exact_draws: int, rng=0) -> np.ndarray:
    """(D, P, 3) node sets: the first ``exact_draws`` are ``nodes`` (P, 3); in the others
    every node moves uniformly within ±½ grid cell on each axis (:func:`cell_size`),
    staying in its region (:func:`node_region`; a node whose move would leave a polygonal
    floor plan or enter an obstacle stays where it is). Draw d moves by the stream (3, d) of the
    int seed ``rng`` (a Generator is drawn once)."""
    seed = streams.entropy("rng", rng)
    p = np.asarray(nodes, dtype=float)
    half = cell_size(p) / 2
    lo, hi = node_region(room, p)
    out = np.empty((draws, *p.shape))
    plain = room.is_shoebox and not room.obstacles
    for d in range(draws):
        if d < exact_draws:
            out[d] = p
        else:
            move = streams.stream(seed, 3, d).uniform(-1.0, 1.0, p.shape) * half
            out[d] = np.clip(p + move, lo, hi)
            if not plain:  # a node that would leave the floor plan or enter an obstacle stays
                stay = ~room.contains(out[d], margin=max(room.node_margin - 1e-9, 0.0))
                out[d][stay] = p[stay]
    return out


_X, _Y = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)

#: the most draws a range table holds
MAX_TABLE_DRAWS = 1000

#: the largest mounting error (m) a plan, a table or a validation accepts
MAX_MOUNT_TOLERANCE = 1.0


def check_mount_tolerance(value) -> float:
    """The radius (m) of the in-plane mounting error, checked: in [0, MAX_MOUNT_TOLERANCE]."""
    return checks.real("mount_tolerance", value, low=0.0, high=MAX_MOUNT_TOLERANCE, unit="m")


def mounted_points(
    room: Room, candidates, ids, draw: int, tolerance: float, exact: bool, rng=0
) -> np.ndarray:
    """(n, 3) where candidates (n, 3) with table indices ``ids`` end up in ``draw``: the
    planned point moved in its surface plane by a uniform offset within a disc of radius
    ``tolerance`` (m), projected back onto the mounting surfaces; unchanged when ``exact``.
    Candidate j's offset comes from the stream (2, j, draw) of the int seed ``rng``."""
    seed = streams.entropy("rng", rng)
    c = np.asarray(candidates, dtype=float)
    if exact or tolerance == 0:
        return c.copy()
    surfs = mounting_surfaces(room)
    index = surface_index(room, c)
    out = c.copy()
    for row, (j, s) in enumerate(zip(ids, index, strict=True)):
        u1, u2 = streams.stream(seed, 2, int(j), draw).random(2)
        radius, angle = tolerance * np.sqrt(u1), 2 * np.pi * u2
        eu, ev = (surfs[int(s)].u_axis, surfs[int(s)].v_axis) if s >= 0 else (_X, _Y)
        out[row] += radius * np.cos(angle) * np.asarray(eu) + radius * np.sin(angle) * np.asarray(
            ev
        )
    return project(room, out)


def _columns(room: Room, candidates, ids, nodes, spec: dict):
    """(D, P, n) ranges, true distances and lines of sight of candidates (n, 3), indices
    ids."""
    from simulation.evaluation import RangingScene

    D, P, _ = nodes.shape
    ranges = np.empty((D, P, len(ids)))
    dist = np.empty((D, P, len(ids)))
    los = np.empty((D, P, len(ids)), dtype=bool)
    exact_scene = None  # exact draws share nodes and points: one noise-free scene
    for d in range(D):
        exact = d < spec["exact_draws"]
        mounted = mounted_points(
            room, candidates, ids, d, spec["mount_tolerance"], exact, spec["seed"]
        )
        if exact and exact_scene is not None:
            scene = exact_scene
        else:
            scene = RangingScene(room, mounted, nodes[d], system=spec["system"],
                                 precision=spec["precision"])  # fmt: skip
            exact_scene = scene if exact else None
        dtype = scene.windows.dtype  # single precision for a long window's FFT DSP
        noise = np.stack(
            [
                dtype.type(s)
                * streams.stream(spec["seed"], 0, int(j), d).standard_normal(
                    scene.windows.shape[::2], dtype=dtype
                )
                for s, j in zip(scene.noise_sigma, ids, strict=True)
            ],
            axis=1,
        )
        ranges[d] = scene.detect(scene.windows + noise)[0]  # NaN: no range
        dist[d] = np.linalg.norm(nodes[d][:, None, :] - mounted[None], axis=-1)
        los[d] = scene.line_of_sight
    return ranges, dist, los


def _simulate(room, candidates, first_id: int, nodes, spec, executor, chunk, progress=None):
    ids = np.arange(first_id, first_id + len(candidates))
    args = [
        (room, candidates[i : i + chunk], ids[i : i + chunk], nodes, spec)
        for i in range(0, len(candidates), chunk)
    ]
    parts = run_jobs(executor, _columns, args, progress=progress)
    return tuple(np.concatenate([p[k] for p in parts], axis=2) for k in range(3))


def range_table(
    room: Room,
    candidates,
    nodes=None,
    *,
    draws: int = 1,
    exact_draws: int = 1,
    mount_tolerance: float = 0.0,
    rng=0,
    executor: Executor | None = None,
    chunk: int = 16,
    precision: str = "float32",
    progress=None,
    system=None,
) -> RangeTable:
    """Simulate every candidate (N, 3) at the nodes of ``draws`` draws (see the module)
    with ``system`` (a :class:`simulation.System`; default the paper's).

    nodes : (P, 3) the nodes of the exact draws (default ``room.grid()``), or (D, P, 3)
        explicit node sets (then ``draws`` is D).
    exact_draws : how many draws keep the nodes and the planned points exactly.
    mount_tolerance : radius (m) of the in-plane mounting error in the other draws.
    rng : an int seed of every stream of the table (see the module), a numpy Generator
        (drawn once) or None.
    chunk : candidates simulated per task (memory ≈ chunk · P · 192 · 16 bytes).
    precision : the receiver DSP's precision (see :class:`simulation.receiver.Dsp`).
    progress : an optional callable ``progress(done, total)`` called as chunks finish.
    """
    cand = room.check_anchors(candidates, min_anchors=1)
    seed = streams.entropy("rng", rng)
    nodes = room.grid() if nodes is None else checks.reals("nodes", nodes)
    if nodes.ndim == 3 and len(nodes):  # explicit node sets: they set the draws
        nodes = np.stack([room.check_nodes(n) for n in nodes])
        draws = len(nodes)
    elif nodes.ndim == 2:
        nodes = room.check_nodes(nodes)
    else:
        raise ValueError(f"nodes: expected (P, 3) or (D, P, 3) with D >= 1, got {nodes.shape}")
    draws = checks.count("draws", draws, low=1, high=MAX_TABLE_DRAWS)
    spec = {
        "exact_draws": checks.count("exact_draws", exact_draws, low=0, high=draws),
        "mount_tolerance": check_mount_tolerance(mount_tolerance),
        "seed": seed,
        "precision": checks.choice("precision", precision, PRECISIONS),
        "system": as_system(system),
    }
    spec["system"].check_room(room)
    chunk = checks.count("chunk", chunk, low=1)
    if nodes.ndim == 2:
        nodes = node_draws(room, nodes, draws, spec["exact_draws"], seed)
    ranges, dist, los = _simulate(room, cand, 0, nodes, spec, executor, chunk, progress)
    pts = sight_points(room)
    seen = sight(room, spec["system"], cand, pts)
    return RangeTable(
        cand, nodes, ranges, dist, room, line_of_sight=los, sight=seen, sight_points=pts, **spec
    )


def extend_table(
    room: Room,
    table: RangeTable,
    candidates,
    *,
    executor: Executor | None = None,
    chunk: int = 16,
) -> RangeTable:
    """The table with columns for more candidates (n, 3) appended (indices N … N + n − 1),
    simulated on the same draws: equal to building the bigger table at once."""
    new = room.check_anchors(candidates, min_anchors=1)
    chunk = checks.count("chunk", chunk, low=1)
    spec = {
        "exact_draws": table.exact_draws,
        "mount_tolerance": table.mount_tolerance,
        "seed": table.seed,
        "precision": table.precision,
        "system": table.system,
    }
    ranges, dist, los = _simulate(
        room, new, len(table.candidates), table.nodes, spec, executor, int(chunk)
    )
    return dataclasses.replace(
        table,
        candidates=np.concatenate([table.candidates, new]),
        ranges=np.concatenate([table.ranges, ranges], axis=2),
        distances=np.concatenate([table.distances, dist], axis=2),
        line_of_sight=np.concatenate([table.line_of_sight, los], axis=2),
        sight=np.concatenate(
            [table.sight, sight(room, table.system, new, table.sight_points)], axis=1
        ),  # fmt: skip
    )


def _layout_indices(table: RangeTable, layouts) -> np.ndarray:
    """layouts as (L, M) integer indices of the table's candidates, or ValueError."""
    S = np.asarray(layouts)
    N = len(table.candidates)
    if S.ndim != 2 or (S.size and not np.issubdtype(S.dtype, np.integer)):
        raise ValueError(
            f"layouts: expected (L, M) integer indices of the table's candidates, got "
            f"{checks.describe(layouts)}"
        )
    if S.size and (S.min() < 0 or S.max() >= N):
        raise ValueError(
            f"layouts: candidate indices must be in [0, {N - 1}], got {S.min()} … {S.max()}"
        )
    return S.astype(int, copy=False)


def _positions(table: RangeTable, layouts) -> tuple[np.ndarray, np.ndarray]:
    """(x (L, D, P, 3), fixed (L,)): the positions of layouts (L, M) of candidates over every
    draw and node of the table, positioned in one batch (positions only: a score needs no
    fix's quality), and whether each layout's anchors determine a position (not collinear
    or coincident: ``locate``'s status −1)."""
    S = _layout_indices(table, layouts)
    ranges = np.moveaxis(table.ranges[:, :, S], 2, 0)  # (L, D, P, M)
    anchors = table.candidates[S]
    x = table.system.positioning.locate(table.room, anchors, ranges)
    return x, np.asarray(degeneracy.anchor_rank(anchors) >= 2).reshape(len(S))


def _errors(table: RangeTable, x) -> np.ndarray:
    """(L, D·P) Euclidean errors (m) of the positions x (L, D, P, 3) at the table's nodes."""
    e = np.linalg.norm(x - table.nodes, axis=-1)  # (L, D, P)
    return e.reshape(len(e), math.prod(e.shape[1:]))  # explicit: L may be 0


def table_errors(table: RangeTable, layouts) -> np.ndarray:
    """(L, D·P) Euclidean position errors (m) of layouts of candidates ``layouts`` (L, M)
    indices over every draw and node of the table, positioned in one batch."""
    return _errors(table, _positions(table, layouts)[0])


def table_costs(table: RangeTable, layouts, statistic: str = "variance") -> np.ndarray:
    """(L,) the simulated ``statistic`` of each layout's errors over all D · P table
    entries (:func:`table_errors`), availability first (a layout with a node realization
    without a fix costs more than any with none: :data:`simulation.statistics.NO_FIX_COST`),
    and before that the table's coverage target (:func:`placement.coverage.constrain`);
    +inf for a layout whose anchors are collinear (``locate``'s status −1)."""
    x, fixed = _positions(table, layouts)
    e = _errors(table, x)
    # collinear or coincident anchors leave the position undetermined: never a solution
    costs = np.where(fixed, _shadowed_statistics(table, layouts, statistic, e), math.inf)
    return _kept_to_target(table, layouts, costs)


def _shadowed_statistics(table: RangeTable, layouts, statistic: str, errors) -> np.ndarray:
    """(L,) the ``statistic`` of each layout's errors (L, n); under a coverage target with a
    shadow error E, the share of the sight points that see fewer than its ``sight_k``
    anchors (or, with its ``gdop_limit``, see them in a poorer geometry:
    :func:`placement.dilution.poor_sight_share`) counts as tags fixed E m off
    (:class:`placement.coverage.CoverageTarget`)."""
    target = table.coverage_target
    if target is None or target.shadow_error <= 0:
        return row_statistics(statistic, errors)
    S = _layout_indices(table, layouts)
    h = poor_sight_share_unchecked(
        table.sight_points, table.candidates, table.sight, S, target.sight_k, target.gdop_limit
    )
    return row_statistics(statistic, errors, shadow=(h, target.shadow_error))


def _kept_to_target(table: RangeTable, layouts, costs) -> np.ndarray:
    """(L,) the costs (L,) of the layouts (L, M) of candidates with the table's coverage
    target of the nodes applied (:func:`placement.coverage.constrain`; unchanged without
    one)."""
    if table.coverage_target is None:
        return np.asarray(costs, dtype=float)
    return constrain(costs, sight_counts(table, layouts), table.coverage_target)


def sight_counts(table: RangeTable, layouts, points: bool = False) -> np.ndarray:
    """(L, P) the anchors of each layout (L, M) of candidates that each node of the table's
    first draw sees in line of sight and reach (:func:`placement.coverage.visibility`);
    with ``points``, (L, Q): those each sight point sees (:attr:`RangeTable.sight`)."""
    S = _layout_indices(table, layouts)
    V = table.sight[:, S] if points else visibility(table, columns=S)
    return np.sum(V, axis=-1).T  # the layouts' columns only


def table_cost(table: RangeTable, indices, statistic: str = "variance") -> float:
    """:func:`table_costs` of the one layout made of the candidates ``indices`` (M,)."""
    return float(table_costs(table, np.asarray(indices)[None], statistic)[0])

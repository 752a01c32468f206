"""Layouts planned for line of sight: every zone node seeing k anchors (docs/model.md,
"Coverage selection").

Where an obstacle blocks the direct path the receiver locks onto an echo; a positioning
that rejects echoes (:mod:`simulation.robust`) needs k = 5 anchors in line of sight and
within reach to tell one echo from the rest. A range table knows, per candidate point and
node, whether the direct path is blocked and whether it lies within the signal's reach
(:func:`visibility`). The coverage selection chooses M candidates so that as many nodes as
possible see at least k of them: the integer program

    maximize Σ_p z_p   over y ∈ {0, 1}^N, z ∈ {0, 1}^P
    subject to Σ_j y_j = M,   k·z_p ≤ Σ_j V_pj y_j   for every node p,
               Σ_{j ∈ G} y_j ≤ M − 1   for every group G,

V_pj = 1 where node p sees candidate j, and the groups the candidates of one mounting
surface and those at one height: anchors all in one plane leave the position
mirror-ambiguous, and the points that see most (the top of the walls, the ceiling) would
otherwise all lie in one. It is declared with cvxpy and solved by HiGHS
within a time limit; the solver's dual bound bounds the share any M candidates can cover.
When every node can be covered the optimum covers all of them; when not, it covers the
largest share. The layouts start the range-table search, which then scores them on
simulated ranges (:func:`placement.simselect.simulated_select`).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from simulation import checks
from simulation.statistics import BELOW_TARGET_COST  # the penalty, beside the no-fix one

#: the anchors in line of sight a node needs for the robust positioning to find one echo
K_LINE_OF_SIGHT = 5
#: the anchors a least-squares fix needs
K_FIX = 4
#: the GDOP of the anchors in sight above which a robust plan counts a tag as in a shadow
#: (:class:`CoverageTarget`): ten times the range error, decimetres where ranges are good to
#: a centimetre
SHADOW_GDOP = 10.0


def coverage_k(system) -> int:
    """The anchors in line of sight a node needs with ``system``: 5 where its positioning
    rejects echoes (enough to find one), 4 otherwise (a fix)."""
    return K_LINE_OF_SIGHT if system.positioning.method == "robust" else K_FIX


#: seconds the integer program may take
TIME_LIMIT = 20.0


@dataclass(frozen=True)
class CoverageSelection:
    """A coverage selection: the candidate ``indices`` (M,) chosen, the share of nodes
    seeing at least ``k`` of them (``covered``), an upper ``bound`` on the share any M
    candidates can cover (equal to ``covered`` when the program was solved to optimality),
    ``status`` ("optimal", "time limit" or "greedy": the solver gave nothing better than
    the greedy start) and the greedy pick's share (``greedy``)."""

    indices: np.ndarray
    covered: float
    bound: float
    k: int
    status: str
    greedy: float

    def to_dict(self) -> dict:
        return {"indices": self.indices.tolist(), "covered": self.covered, "bound": self.bound,
                "k": self.k, "status": self.status, "greedy": self.greedy}  # fmt: skip


def plane_groups(room, candidates) -> list[np.ndarray]:
    """The candidates (N, 3) by mounting surface and by height (to the centimetre): each a
    plane that must not hold every anchor (module docstring)."""
    from placement.surfaces import surface_index

    c = np.asarray(candidates, dtype=float)
    out = []
    for key in (surface_index(room, c), np.round(c[:, 2], 2)):
        out += [np.flatnonzero(key == v) for v in np.unique(key)]
    return out


@dataclass(frozen=True)
class CoverageTarget:
    """A requirement on the layouts of a search: at least ``share`` of the nodes see ``k``
    anchors in line of sight and reach (:func:`visibility`, at the exact nodes of the
    table's first draw); a layout below it costs more than any that meets it
    (:func:`constrain`): the search keeps to the layouts that meet it, as a constrained
    swarm ranks the feasible first (Deb's rule). With ``shadow_error`` E > 0 (m), the
    share h of the table's sight points (:func:`placement.rangetable.sight_points`) that
    see fewer than ``sight_k`` anchors counts as tags fixed E m off
    (:func:`simulation.statistics.mixed_statistic`): the shadow of a column between the
    nodes costs what its tags' fixes on echoes cost. With a ``gdop_limit``, a sight point
    whose anchors in sight have a GDOP above it, or lie in one plane with it, counts as a
    shadow too (:func:`placement.dilution.poor_sight_share`): the tags between the nodes of an
    aisle seen along the aisle."""

    k: int
    share: float
    sight_k: int = K_FIX
    shadow_error: float = 0.0
    gdop_limit: float | None = None

    def __post_init__(self) -> None:
        checks.count("k", self.k, low=1, high=10_000)
        checks.real("share", self.share, low=0.0, high=1.0)
        checks.count("sight_k", self.sight_k, low=1, high=10_000)
        checks.real("shadow_error", self.shadow_error, low=0.0, unit="m")
        if self.gdop_limit is not None:
            checks.real("gdop_limit", self.gdop_limit, low=0.0, low_open=True)

    def needed(self, P: int) -> int:
        """The nodes of P that must be covered: ⌈share · P⌉, a product within a tie of
        an integer counting as that integer."""
        return int(math.ceil(self.share * P - 1e-9))

    def to_dict(self) -> dict:
        return {"k": self.k, "share": self.share, "sight_k": self.sight_k,
                "shadow_error": self.shadow_error, "gdop_limit": self.gdop_limit}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict) -> CoverageTarget:
        """The target of :meth:`to_dict` (one written before the sight points or their
        geometry: none there)."""
        limit = d.get("gdop_limit")
        return cls(int(d["k"]), float(d["share"]), int(d.get("sight_k", K_FIX)),
                   float(d.get("shadow_error", 0.0)),
                   None if limit is None else float(limit))  # fmt: skip


def constrain(costs, counts, target: CoverageTarget | None) -> np.ndarray:
    """(L,) the costs (L,) of layouts whose nodes see ``counts`` (L, P) anchors in line of
    sight and reach, with :data:`BELOW_TARGET_COST` added below ``target`` (None: the costs
    unchanged)."""
    costs = np.asarray(costs, dtype=float)
    if target is None:
        return costs
    counts = np.asarray(counts)
    P = counts.shape[-1]
    short = np.maximum(target.needed(P) - np.sum(counts >= target.k, axis=-1), 0)
    return np.where(short > 0, BELOW_TARGET_COST * (1.0 + short / P) + costs, costs)


def visibility(table, draw: int = 0, columns=None) -> np.ndarray:
    """(P, N) bool: node p of the table's draw ``draw`` sees candidate j: nothing blocks the
    direct path, and it lies within the signal's reach and beyond its near limit. With
    ``columns`` (an index array of shape S), (P, *S): those candidates only."""
    cols = slice(None) if columns is None else columns
    reach = table.system.within_reach(table.distances[draw][:, cols], table.room.speed_of_sound)
    return table.line_of_sight[draw][:, cols] & reach


def covered_share(V: np.ndarray, indices, k: int) -> float:
    """The share of the nodes (rows of V (P, N)) that see at least k of ``indices``."""
    return float(np.mean(np.sum(V[:, np.asarray(indices, dtype=int)], axis=1) >= k))


def greedy(V: np.ndarray, M: int, k: int, groups=()) -> np.ndarray:
    """(M,) candidates picked one at a time, each the one that most raises Σ_p min(count_p,
    k) (the nodes' progress towards k; ties to the lowest index), the last one from
    outside any group that holds all the others."""
    V = np.asarray(V, dtype=bool)
    count = np.zeros(V.shape[0], dtype=int)
    chosen: list[int] = []
    for _ in range(M):
        gain = np.sum(V & (count < k)[:, None], axis=0).astype(float)
        gain[chosen] = -1.0
        for g in groups:  # a group may not take all M
            if np.sum(np.isin(chosen, g)) == M - 1:
                gain[g] = -1.0
        j = int(np.argmax(gain))
        chosen.append(j)
        count += V[:, j]
    return np.sort(np.asarray(chosen))


def select_coverage(V, M: int, k: int = K_LINE_OF_SIGHT, time_limit: float = TIME_LIMIT, groups=()):
    """The coverage selection (module docstring) of M candidates on the visibility V (P, N)
    bool, no group of ``groups`` (index arrays) holding all M: a
    :class:`CoverageSelection`, never worse than :func:`greedy`."""
    V = np.asarray(V, dtype=bool)
    if V.ndim != 2 or V.shape[1] < 1:
        raise ValueError(f"V: expected a (nodes, candidates) boolean array, got {V.shape}")
    P, N = V.shape
    M = checks.count("M", M, low=1, high=N)
    k = checks.count("k", k, low=1, high=M)
    time_limit = checks.real("time_limit", time_limit, low=0.0, low_open=True, unit="s")
    groups = [np.asarray(g, dtype=int) for g in groups if len(g) >= M]
    start = greedy(V, M, k, groups)
    start_share = covered_share(V, start, k)
    picked, bound, status = _solve(V, M, k, time_limit, groups)
    if picked is None or covered_share(V, picked, k) <= start_share:
        picked, status = start, ("greedy" if picked is None else status)
    share = covered_share(V, picked, k)
    if status == "optimal":
        bound = share
    return CoverageSelection(np.sort(picked), share, max(bound, share), k, status, start_share)


@contextlib.contextmanager
def _quiet_stdout():
    """The process's standard output sent to the null device: HiGHS prints its banner
    there from C++ whenever a solver object is built, whatever its options say, and a
    library does not print."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _solve(V, M: int, k: int, time_limit: float, groups):
    """(indices or None, bound on the share, status) of the integer program by HiGHS."""
    import cvxpy as cp

    P, N = V.shape
    y, z = cp.Variable(N, boolean=True), cp.Variable(P, boolean=True)
    constraints = [cp.sum(y) == M, k * z <= V.astype(float) @ y]
    constraints += [cp.sum(y[g]) <= M - 1 for g in groups]
    problem = cp.Problem(cp.Maximize(cp.sum(z)), constraints)
    try:
        with warnings.catch_warnings(), _quiet_stdout():
            warnings.simplefilter("ignore")  # "inaccurate" at the time limit: we say so
            problem.solve(solver="HIGHS", time_limit=time_limit, output_flag=False)
    except (cp.error.SolverError, ValueError):
        return None, 1.0, "greedy"
    if y.value is None:
        return None, 1.0, "greedy"
    picked = np.argsort(-y.value, kind="stable")[:M]
    info = problem.solver_stats.extra_stats if problem.solver_stats else None
    dual = getattr(info, "mip_dual_bound", math.nan)
    bound = min(1.0, -float(dual) / P) if dual is not None and math.isfinite(dual) else 1.0
    status = "optimal" if problem.status == cp.OPTIMAL else "time limit"
    return picked, bound, status

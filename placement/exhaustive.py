"""Exhaustive search over all M-subsets of N candidate mounting points (paper §III-A).

The exact answer to the selection problem that :func:`placement.relax_select` bounds and
rounds: every M-subset of the candidates is scored with the same criterion, so for small
N and M the optimum is proved by enumeration (the tests use it to check the relaxation).

The problem (design inputs, the FIM table, the criteria "A", "D", "minimax" in m²) is
that of :mod:`placement.selection`, shared with the relaxation.

Subsets are enumerated as a prefix of M − 2 candidates (a Python loop) times every pair of
later candidates (vectorized, in cache-sized blocks) on the tabulated FIM entries: the same
numbers as ``analysis.crlb_trace`` on an (L, M, 3) batch of layouts (the tests check it),
without recomputing the unit vectors for every subset.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analysis.fim import DEFAULT_SIGMA
from placement.result import LayoutResult
from placement.selection import DEFAULT_SPACING, criterion_values, design_inputs
from simulation import checks
from simulation.room import Room

#: subsets per vectorized block (keeps the (6, block, P) temporaries in cache)
_BLOCK = 256


# -- exhaustive search ------------------------------------------------------------------------
@dataclass(frozen=True)
class ExhaustiveResult(LayoutResult):
    """The best subset(s) of an exhaustive search (:mod:`placement.result` convention).

    ``anchors`` (M, 3) m and ``indices`` (M,) into the candidates of the best subset;
    ``cost_m2`` (= ``fun``) its criterion value in m² (:mod:`placement.selection`);
    ``top_indices`` (k, M) and ``top_costs_m2`` (k,) the k best subsets in increasing cost;
    ``nfev`` the number of subsets scored; ``solve_time`` the wall time in s. ``status``:
    see :attr:`STATUS`; ``success`` is True when the best subset has a finite cost.
    """

    FUN: ClassVar[str] = "cost_m2"
    STATUS: ClassVar[dict[int, str]] = {
        0: "optimal: the best subset of all C(N, M) was found",
        1: "singular: every subset has a singular FIM at some node (cost +inf)",
    }

    anchors: np.ndarray
    indices: np.ndarray
    cost_m2: float
    criterion: str
    top_indices: np.ndarray
    top_costs_m2: np.ndarray
    success: bool
    status: int
    message: str
    nfev: int
    solve_time: float


def exhaustive_search(
    room: Room,
    M: int,
    *,
    candidates=None,
    criterion: str = "A",
    sigma=DEFAULT_SIGMA,
    nodes=None,
    top_k: int = 1,
    max_subsets: int = 10_000_000,
    spacing: float = DEFAULT_SPACING,
) -> ExhaustiveResult:
    """Score every M-subset of the candidates and return the best (ties: first in order).

    Same arguments and criteria as :func:`placement.relax_select`. ``max_subsets`` guards
    against C(N, M) being too large (time grows linearly with it: docs/implementation.md);
    ``top_k`` ≥ 1 best subsets are kept. Raises ``ValueError`` on bad input.
    """
    inp = design_inputs(room, M, candidates, criterion, sigma, nodes, spacing)
    max_subsets = checks.count("max_subsets", max_subsets, low=1)
    top_k = checks.count("top_k", top_k, low=1)
    N, M = inp.candidates.shape[0], inp.M
    n_total = math.comb(N, M)
    if n_total > max_subsets:
        raise ValueError(
            f"M: C({N}, {M}) = {n_total} subsets exceeds max_subsets = {max_subsets}; "
            "use fewer candidates or relax_select"
        )
    top_k = min(top_k, n_total)
    t0 = time.perf_counter()
    G = np.ascontiguousarray(inp.table())  # (6, N, P)
    ia, ib = np.triu_indices(N, 1)  # all pairs, lexicographic: pairs with a >= k are a tail
    H = np.ascontiguousarray(G[:, ia] + G[:, ib])  # (6, N(N-1)/2, P)
    first_pair = np.searchsorted(ia, np.arange(N + 1))
    best_v = np.full(top_k, np.inf)
    best_s = np.zeros((top_k, M), dtype=np.intp)
    filled = 0
    for prefix in itertools.combinations(range(N - 2), M - 2):
        lo0 = first_pair[prefix[-1] + 1]
        if lo0 >= ia.size:
            continue
        Jp = G[:, list(prefix)].sum(axis=1)[:, None, :]  # (6, 1, P)
        for lo in range(lo0, ia.size, _BLOCK):
            hi = min(lo + _BLOCK, ia.size)
            v = criterion_values(Jp + H[:, lo:hi], criterion)
            # keep the k best (strictly better than the current k-th; ties keep the first)
            if filled == top_k and not np.any(v < best_v[-1]):
                continue
            cand = np.flatnonzero(v < best_v[-1]) if filled == top_k else np.arange(v.size)
            cand = cand[np.argsort(v[cand], kind="stable")[:top_k]]
            subs = np.empty((cand.size, M), dtype=np.intp)
            subs[:, : M - 2] = prefix
            subs[:, M - 2] = ia[lo + cand]
            subs[:, M - 1] = ib[lo + cand]
            allv = np.concatenate([best_v[:filled], v[cand]])
            alls = np.concatenate([best_s[:filled], subs])
            order = np.argsort(allv, kind="stable")[:top_k]
            filled = order.size
            best_v[:filled], best_s[:filled] = allv[order], alls[order]
    idx = best_s[0].copy()
    status = 0 if math.isfinite(best_v[0]) else 1
    return ExhaustiveResult(
        anchors=inp.candidates[idx].copy(),
        indices=idx,
        cost_m2=float(inp.scale(best_v[0])),
        criterion=criterion,
        top_indices=best_s[:filled].copy(),
        top_costs_m2=np.atleast_1d(inp.scale(best_v[:filled])),
        success=status == 0,
        status=status,
        message=ExhaustiveResult.STATUS[status],
        nfev=n_total,
        solve_time=time.perf_counter() - t0,
    )

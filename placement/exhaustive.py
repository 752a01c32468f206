"""Exhaustive search over all M-subsets of N candidate mounting points (paper §III-A).

The exact answer to the selection problem that :func:`placement.relax_select` bounds and
rounds: every M-subset of the candidates is scored with the same criterion, so for small
N and M the optimum is proved by enumeration (the tests use it to check the relaxation).

Criteria (σ the range standard deviation, J_p the FIM of paper eq. 6 at node p):

* ``"A"``: mean over the nodes of tr J_p⁻¹ (m², the paper's "PEB" without the root);
* ``"minimax"``: max over the nodes of tr J_p⁻¹ (m²);
* ``"D"``: the geometric mean over the nodes of det(J_p)^(−1/3) (m²), i.e.
  exp(−Σ_p log det J_p / (3P)). Minimizing it is maximizing Σ_p log det J_p; it is the
  per-axis variance of a sphere with the volume of the mean CRLB ellipsoid.

All three are minimized and are +inf for a subset whose J_p is singular at any node.

Speed: the FIM is linear in the selection, J_p(S) = Σ_{n∈S} G_pn with G_pn = u uᵀ/σ_n²,
so the six unique entries of every G_pn are tabulated once, (6, N, P). Subsets are
enumerated as a prefix of M − 2 candidates (a Python loop) times every pair of later
candidates (vectorized, in cache-sized blocks), and tr J⁻¹ / det J follow from the
closed-form 3×3 adjugate, as in :func:`analysis.crlb_trace`. Calling
``analysis.crlb_trace`` on an (L, M, 3) batch of layouts gives the same numbers (the
tests check it) but recomputes the unit vectors for every subset and is ~50× slower.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

from analysis.fim import SINGULAR_RTOL
from placement.surfaces import allowed, candidate_grid
from simulation import checks
from simulation.room import Room, as_room

CRITERIA = ("A", "D", "minimax")

#: weights of the six unique entries (xx, yy, zz, xy, xz, yz) in a Frobenius inner product
ENTRY_WEIGHTS = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])

#: default candidate spacing (m) when ``candidates`` is None: ~200 points in techtile
DEFAULT_SPACING = 0.75

#: subsets per vectorized block (keeps the (6, block, P) temporaries in cache)
_BLOCK = 256


# -- inputs shared with the relaxation -------------------------------------------------------
@dataclass(frozen=True)
class DesignInputs:
    """Validated inputs of a selection problem.

    ``candidates`` (N, 3) m, ``nodes`` (P, 3) m, ``sigma`` (N,) m per candidate or (N, P)
    per candidate and node, and
    ``sigma_ref`` (m, their geometric mean): the solvers work with σ_n/σ_ref (σ
    normalized to 1) and rescale the results.
    """

    candidates: np.ndarray
    nodes: np.ndarray
    sigma: np.ndarray
    sigma_ref: float
    M: int
    criterion: str

    def table(self) -> np.ndarray:
        """(6, N, P) normalized FIM entries of every candidate at every node."""
        return fim_table(self.candidates, self.nodes, self.sigma / self.sigma_ref)

    def scale(self, objective):
        """Normalized objective (see :func:`criterion_values`) → criterion value in m²."""
        return to_value(objective, self.criterion, self.sigma_ref)


def design_inputs(
    room: Room,
    M,
    candidates=None,
    criterion: str = "A",
    sigma=0.04,
    nodes=None,
    spacing: float = DEFAULT_SPACING,
) -> DesignInputs:
    """Check the arguments of a selection problem; raise ``ValueError`` naming the problem."""
    room = as_room(room)
    checks.choice("criterion", criterion, CRITERIA)
    if candidates is None:
        cand = candidate_grid(room, spacing)
    else:
        cand = checks.reals("candidates", candidates)
        if cand.ndim != 2 or cand.shape[1] != 3 or cand.shape[0] == 0:
            raise ValueError(f"candidates: expected shape (N, 3) with N >= 1, got {cand.shape}")
        if not np.all(np.isfinite(cand)):
            raise ValueError("candidates: must be finite (no NaN or inf)")
        off = np.flatnonzero(~allowed(room, cand, tol=1e-6))
        if off.size:
            raise ValueError(
                f"candidates: {off.size} point(s) are not on an allowed mounting surface "
                f"{list(room.mounting)} or lie in a keep-out "
                f"(first: index {off[0]}, {cand[off[0]].tolist()}); "
                "use placement.project or placement.candidate_grid"
            )
    N = cand.shape[0]
    if isinstance(M, bool) or not isinstance(M, int | np.integer) or not 4 <= M <= N:
        raise ValueError(
            f"M: number of anchors must be an integer in [4, {N}] (4 for 3D positioning, "
            f"at most the {N} candidates), got {M!r}"
        )
    if nodes is None:
        p = room.grid()
    else:
        p = checks.points("nodes", nodes)
        checks.inside("nodes", p, room.size)
    s = checks.reals("sigma", sigma)
    if s.ndim == 0:
        s = np.full(N, float(s))
    if s.shape == (p.shape[0], N):
        s = s.T  # per (node, candidate) pair, stored (N, P) like the FIM table
    elif s.shape != (N,):
        raise ValueError(
            f"sigma: expected a scalar, shape ({N},) (one per candidate) or "
            f"({p.shape[0]}, {N}) (one per node and candidate), got {s.shape}"
        )
    if not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise ValueError("sigma: range standard deviations must be finite and > 0 m")
    checks.check_size(
        "candidates x nodes", 6 * N * p.shape[0] * 8 * 4, value=(N, p.shape[0]),
        hint="use fewer candidates (a larger spacing) or nodes",
    )  # fmt: skip
    return DesignInputs(cand, p, s, float(np.exp(np.mean(np.log(s)))), int(M), criterion)


# -- the FIM table and the criteria -----------------------------------------------------------
def fim_table(candidates, nodes, sigma=1.0) -> np.ndarray:
    """(6, N, P) entries (xx, yy, zz, xy, xz, yz) of G_pn = u uᵀ/σ_pn² (paper eq. 6).

    ``sigma`` is a scalar, per candidate (N,), or per candidate and node (N, P).

    u is the unit vector from candidate n to node p; a node on a candidate carries no
    information (G = 0), as in :func:`analysis.fim`.
    """
    a = np.asarray(candidates, dtype=float)
    p = np.asarray(nodes, dtype=float)
    d = p[None, :, :] - a[:, None, :]  # (N, P, 3)
    d2 = np.einsum("npk,npk->np", d, d)
    w = 1.0 / np.asarray(sigma, dtype=float) ** 2
    w = w[:, None] if w.ndim == 1 else np.broadcast_to(w, d2.shape)  # (N,) or (N, P)
    s = np.divide(w, d2, out=np.zeros_like(d2), where=d2 > 0)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([s * x * x, s * y * y, s * z * z, s * x * y, s * x * z, s * y * z])


def _minors_det(J):
    """Principal-minor sum (= tr adj J) and det J of symmetric 3×3 given as 6 entries."""
    xx, yy, zz, xy, xz, yz = J
    mx = yy * zz
    mx -= yz * yz
    my = xx * zz
    my -= xz * xz
    mz = xx * yy
    mz -= xy * xy
    t1 = xy * zz
    t1 -= yz * xz
    t2 = xy * yz
    t2 -= yy * xz
    det = xx * mx
    det -= xy * t1
    det += xz * t2
    minors = mx + my
    minors += mz
    return minors, det


def _nonsingular(J, minors, det):
    """The singularity rule of :mod:`analysis.fim`: λ_min ≈ det/minors ≤ rtol · tr J."""
    tr = J[0] + J[1]
    tr += J[2]
    tr *= minors
    tr *= SINGULAR_RTOL
    return (minors > 0) & (det > tr)


def node_values(J, criterion: str) -> np.ndarray:
    """Per-node objective from FIM entries J (6, ..., P): tr J⁻¹ ("A", "minimax") or
    −log det J ("D"); +inf where J is singular."""
    minors, det = _minors_det(J)
    ok = _nonsingular(J, minors, det)
    out = np.full(det.shape, np.inf)
    if criterion == "D":
        np.log(det, out=out, where=ok)
        np.negative(out, out=out, where=ok)
    else:
        np.divide(minors, det, out=out, where=ok)
    return out


def criterion_values(J, criterion: str) -> np.ndarray:
    """Normalized objective of FIM entries J (6, ..., P) → (...): mean tr J⁻¹ ("A"),
    max tr J⁻¹ ("minimax") or −mean log det J ("D"); +inf if any node is singular."""
    v = node_values(J, criterion)
    return v.max(axis=-1) if criterion == "minimax" else v.mean(axis=-1)


def to_value(objective, criterion: str, sigma_ref: float):
    """Rescale a normalized objective (σ_ref = 1) to the criterion's value in m²."""
    objective = np.asarray(objective, dtype=float)
    if criterion == "D":
        # −mean log det J_norm = g  →  det J = det J_norm · σ_ref⁻⁶
        with np.errstate(over="ignore"):
            out = np.exp(objective / 3.0) * sigma_ref**2
    else:
        out = objective * sigma_ref**2
    return out.item() if out.ndim == 0 else out


# -- exhaustive search ------------------------------------------------------------------------
@dataclass(frozen=True)
class ExhaustiveResult:
    """The best subset(s) of an exhaustive search.

    ``anchors`` (M, 3) m and ``indices`` (M,) into ``candidates`` of the best subset,
    ``value`` its criterion value (m², see the module docstring), ``top_indices`` (k, M)
    and ``top_values`` (k,) the k best subsets in increasing value, ``n_subsets`` the
    number of subsets scored, ``solve_time`` the wall time in s.
    """

    anchors: np.ndarray
    indices: np.ndarray
    value: float
    criterion: str
    top_indices: np.ndarray
    top_values: np.ndarray
    n_subsets: int
    solve_time: float

    def to_dict(self) -> dict:
        return {
            "anchors": self.anchors.tolist(),
            "indices": self.indices.tolist(),
            "value": self.value,
            "criterion": self.criterion,
            "top_indices": self.top_indices.tolist(),
            "top_values": self.top_values.tolist(),
            "n_subsets": self.n_subsets,
            "solve_time": self.solve_time,
        }


def exhaustive_search(
    room: Room,
    M: int,
    *,
    candidates=None,
    criterion: str = "A",
    sigma=0.04,
    nodes=None,
    top_k: int = 1,
    max_subsets: int = 10_000_000,
    spacing: float = DEFAULT_SPACING,
) -> ExhaustiveResult:
    """Score every M-subset of the candidates and return the best (ties: first in order).

    Same arguments and criteria as :func:`placement.relax_select`. ``max_subsets`` guards
    against C(N, M) being too large (≈ 5 µs per subset on 270 nodes); ``top_k`` ≥ 1 best
    subsets are kept. Raises ``ValueError`` on bad input.
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
    return ExhaustiveResult(
        anchors=inp.candidates[idx].copy(),
        indices=idx,
        value=float(inp.scale(best_v[0])),
        criterion=criterion,
        top_indices=best_s[:filled].copy(),
        top_values=np.atleast_1d(inp.scale(best_v[:filled])),
        n_subsets=n_total,
        solve_time=time.perf_counter() - t0,
    )

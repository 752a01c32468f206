"""Convex-relaxation selection of M anchors out of N candidates, with a certificate.

Selecting anchors is a Boolean design problem: w ∈ {0, 1}^N, Σ w = M, with the FIM at
node p affine in w, J_p(w) = Σ_n w_n u_pn u_pnᵀ/σ_n² (paper eq. 6). Relaxing w to [0, 1]^N
gives a convex problem (cvxpy, solved by Clarabel) whose optimum lower-bounds every
selection. Criteria, all *minimized* (see :mod:`placement.selection` for the units):

* ``"A"``: mean over the nodes of tr J_p⁻¹ (m²). Each tr J_p⁻¹ is written with the Schur
  complement LMI [[X_p, I], [I, J_p(w)]] ⪰ 0 ⇔ X_p ⪰ J_p⁻¹, minimizing Σ tr X_p / P.
* ``"minimax"``: max over the nodes of tr J_p⁻¹ (m²): the same LMIs and tr X_p ≤ t.
* ``"D"``: maximize Σ_p log det J_p(w), with log det J ≥ Σ log Z_ii for
  [[J, Z], [Zᵀ, Diag(Z)]] ⪰ 0, Z lower triangular. Reported as the equivalent minimized
  value exp(−Σ_p log det J_p / (3P)) in m² (geometric mean of det^(−1/3)); the bound and
  the gap refer to that value (a gap g means Σ log det is 3P·log(1 + g) below the optimum).
  ``Selection.details`` also carries Σ_p log det J_p and its upper bound (log 1/m⁶).

All P LMIs are one batched (P, 6, 6) PSD constraint built from a single sparse matrix,
which keeps cvxpy's canonicalization short. σ is normalized to 1 inside the solver
(σ_n/σ_ref with σ_ref the geometric mean) and the results are rescaled, because Clarabel
fails on the unnormalized data (J ~ 10³/m²); docs/implementation.md.

Certificate. The lower bound is not the solver's number: it is recomputed in numpy from the
relaxed weights w* by convexity (the Frank–Wolfe / Lagrangian bound). For a convex f and
any w with every J_p(w) ≻ 0,

    min_{w' ∈ Ω} f(w') ≥ f(w) + ∇f(w)·w − max_{w' ∈ Ω} (−∇f(w))·w',

and over Ω = {0 ≤ w' ≤ 1, Σ w' = M} the last term is the sum of the M largest entries of
−∇f (∂/∂w_n tr J⁻¹ = −tr(J⁻¹ G_n J⁻¹), ∂/∂w_n log det J = tr(J⁻¹ G_n)). For minimax, f is
replaced by Σ_p λ_p tr J_p⁻¹ ≤ max_p tr J_p⁻¹ with λ the solver's dual multipliers
(any λ in the simplex is valid). The bound equals the relaxed optimum when w* is optimal
and is valid whatever the solver's accuracy; a solver that stops inaccurately only makes
it looser, and that is reported in ``status`` (1, "inaccurate"). If the bound cannot be
computed (no solution, singular J) or exceeds the returned cost, no certificate is
returned: ``lower_bound_m2 = 0`` (trivially true), ``gap = inf`` and ``success`` False,
with the reason in ``status`` and ``message``.

Rounding. Subsets are drawn without replacement with probabilities proportional to the
weights (Gumbel-top-M, seeded), together with the top-M weights (random tie break); the
``starts`` best are improved by swap local search (each selected candidate in turn is
replaced by the unselected one that lowers the value most, until a pass changes nothing).
Top-M alone fails on symmetric rooms, where the relaxed weights tie (an example in
docs/implementation.md). Singular subsets count as +inf.
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from analysis.fim import DEFAULT_SIGMA
from placement import ties
from placement.result import LayoutResult
from placement.selection import (
    DEFAULT_SPACING,
    ENTRIES,
    ENTRY_WEIGHTS,
    design_inputs,
    node_values,
    subset_values,
)
from simulation import checks, streams
from simulation.room import Room

log = logging.getLogger(__name__)

#: most candidate points of a relaxation (the problem has N weights and 36·P LMI entries)
MAX_CANDIDATES = 5000

#: (row, col) of the six entries of a lower-triangular 3×3 Z (D criterion)
_IL = ((0, 0), (1, 1), (2, 2), (1, 0), (2, 0), (2, 1))
#: relative slack: a bound above cost·(1 + this) is rejected as not verified
_BOUND_RTOL = 1e-9
#: Clarabel settings (``solver_opts`` overrides them): no chordal decomposition (it only
#: splits the 6×6 LMIs) and tolerances 10–100× looser than Clarabel's 1e-8, which the
#: certificate allows because the bound is recomputed from w* (docs/implementation.md).
_CLARABEL_DEFAULTS = {
    "chordal_decomposition_enable": False,
    "tol_gap_rel": 1e-6,
    "tol_gap_abs": 1e-7,
    "tol_feas": 1e-7,
    "tol_ktratio": 1e-5,
}


@dataclass(frozen=True)
class Selection(LayoutResult):
    """Result of :func:`relax_select` (:mod:`placement.result` convention).

    anchors : (M, 3) selected mounting points (m); indices : (M,) into ``candidates``.
    weights : (N,) relaxed weights in [0, 1] summing to M (NaN-free; zeros if the solver
        failed). candidates : (N, 3) the candidate set (m).
    cost_m2 (= ``fun``) : criterion value of the selection (m², see the module docstring).
    lower_bound_m2 : certified lower bound on the best possible cost over all M-subsets of
        the candidates (m²); 0 when not certified. gap : (cost − lower_bound)/lower_bound,
        so cost ≤ (1 + gap)·optimum; inf when not certified.
    relaxed_cost_m2 : criterion value of the fractional w* (≥ relaxed optimum ≥ bound).
    success : whether ``lower_bound_m2`` is a verified bound (status 0 or 1).
    status, message : the code of :attr:`STATUS` and its text ("optimal", "inaccurate",
        "bound_above_value", "singular_relaxation", "solver_failed: …").
    solver_status : cvxpy's status string (or the exception). nit : Clarabel's iterations
        (0 if unknown).
    compile_time, solve_time, rounding_time, total_time : wall-clock seconds (cvxpy
        problem build + canonicalization; Clarabel; rounding + local search; all).
    sigma : the reference σ (m, geometric mean of the given σ) the solver normalized by.
    details : the solver's own objective ``solver_value`` (m²), ``relaxation_gap`` =
        relaxed_cost/lower_bound − 1 (how accurately the relaxation was solved; ~1e-6), and
        for "D" ``logdet_sum`` = Σ_p log det J_p of the selection and ``logdet_upper_bound``
        (log 1/m⁶).
    """

    FUN: ClassVar[str] = "cost_m2"
    STATUS: ClassVar[dict[int, str]] = {
        0: "optimal: solved, certificate verified",
        1: "inaccurate: Clarabel stopped inaccurate; the bound is still verified by "
        "convexity, possibly loose",
        2: "bound_above_value: the recomputed bound exceeds the cost; no certificate",
        3: "singular_relaxation: a node's FIM is singular at w*; no certificate",
        4: "solver_failed: no relaxed solution; rounding from uniform weights, no certificate",
    }

    anchors: np.ndarray
    indices: np.ndarray
    weights: np.ndarray
    cost_m2: float
    lower_bound_m2: float
    gap: float
    success: bool
    status: int
    message: str
    nit: int
    solve_time: float
    criterion: str
    relaxed_cost_m2: float
    solver_status: str
    compile_time: float
    rounding_time: float
    total_time: float
    sigma: float
    candidates: np.ndarray
    details: dict = field(default_factory=dict)

    @property
    def M(self) -> int:
        """The number of chosen anchors."""
        return int(self.indices.size)


# -- the convex problem -----------------------------------------------------------------------
def _lmi_maps(G: np.ndarray, criterion: str):
    """Sparse maps of the batched LMI: vec L = Aw w + Az z + c, L (P, 6, 6) row-major.

    "A"/"minimax": L_p = [[X_p, I], [I, J_p(w)]]; "D": L_p = [[J_p(w), Z_p], [Z_pᵀ,
    Diag(Z_p)]]. ``z`` holds six numbers per node, z[6p + k]: the entries of X_p in the
    order of ``ENTRIES`` or of the lower-triangular Z_p in the order of ``_IL``.
    """
    import scipy.sparse as sp

    _, N, P = G.shape
    base = np.arange(P) * 36  # first entry of node p's 6×6 block
    J0 = 3 if criterion != "D" else 0  # J_p(w) block offset

    def pos(r, c):
        return base + r * 6 + c

    rows_w, vals_w = [], []
    for k, (i, j) in enumerate(ENTRIES):  # J_p(w) entries, both triangles: dense in w
        for r, c in {(i, j), (j, i)}:
            rows_w.append(np.repeat(pos(J0 + r, J0 + c), N))
            vals_w.append(G[k].T.ravel())  # (P, N) row-major, matches np.repeat
    cols_w = np.tile(np.arange(N), P * len(rows_w))
    rows_z, cols_z = [], []
    for k, (i, j) in enumerate(ENTRIES if criterion != "D" else _IL):
        if criterion != "D":  # X_p, symmetric, top-left block
            cells = {(i, j), (j, i)}
        else:  # Z_p top-right, Z_pᵀ bottom-left, diag(Z_p) bottom-right
            cells = {(i, 3 + j), (3 + j, i)} | ({(3 + i, 3 + i)} if i == j else set())
        for r, c in cells:
            rows_z.append(pos(r, c))
            cols_z.append(np.arange(P) * 6 + k)
    Aw = sp.csr_matrix(
        (np.concatenate(vals_w), (np.concatenate(rows_w), cols_w)), shape=(36 * P, N)
    )
    rz = np.concatenate(rows_z)
    Az = sp.csr_matrix((np.ones(rz.size), (rz, np.concatenate(cols_z))), shape=(36 * P, 6 * P))
    c = np.zeros((P, 6, 6))
    if criterion != "D":  # the identity blocks of [[X, I], [I, J]]
        c[:, :3, 3:] = np.eye(3)
        c[:, 3:, :3] = np.eye(3)
    return Aw, Az, c.ravel()


def _build(G: np.ndarray, M: int, criterion: str):
    """The relaxed problem in cvxpy: returns (problem, w, dual-carrying constraint or None)."""
    import cvxpy as cp
    import scipy.sparse as sp

    _, N, P = G.shape
    Aw, Az, c = _lmi_maps(G, criterion)
    w = cp.Variable(N, name="w")
    z = cp.Variable(6 * P, name="z")
    L = cp.reshape(Aw @ w + Az @ z + c, (P, 6, 6), order="C")
    cons = [cp.constraints.PSD(L), w >= 0, w <= 1, cp.sum(w) == M]
    diag = sp.csr_matrix(  # (P, 6P): sums the three diagonal entries of node p
        (
            np.ones(3 * P),
            (np.repeat(np.arange(P), 3), (np.arange(P)[:, None] * 6 + np.arange(3)).ravel()),
        ),
        shape=(P, 6 * P),
    )
    dual = None
    if criterion == "A":
        obj = cp.Minimize(cp.sum(diag @ z) / P)
    elif criterion == "minimax":
        t = cp.Variable(name="t")
        dual = diag @ z <= t
        cons.append(dual)
        obj = cp.Minimize(t)
    else:
        zd = sp.csr_matrix(
            (
                np.ones(3 * P),
                (np.arange(3 * P), (np.arange(P)[:, None] * 6 + np.arange(3)).ravel()),
            ),
            shape=(3 * P, 6 * P),
        )
        obj = cp.Minimize(-cp.sum(cp.log(zd @ z)) / P)
    return cp.Problem(obj, cons), w, dual


def _solver_keys() -> list[str]:
    """The keywords ``solver_opts`` may hold: Clarabel's settings and cvxpy's verbose."""
    import clarabel

    settings = [k for k in dir(clarabel.DefaultSettings()) if not k.startswith("_")]
    return [k for k in settings if k != "default"] + ["verbose"]


def _solve(G: np.ndarray, M: int, criterion: str, solver_opts: dict | None):
    """Build and solve; returns (w or None, λ or None, cvxpy status, solver value, times, info)."""
    import cvxpy as cp

    t0 = time.perf_counter()
    prob, w, dual = _build(G, M, criterion)
    t1 = time.perf_counter()
    info = {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "solution may be inaccurate": we report status
            opts = {**_CLARABEL_DEFAULTS, **(solver_opts or {})}
            try:
                prob.solve(solver=cp.CLARABEL, **opts)
            except TypeError as exc:  # a setting of the wrong type: the caller's input
                raise ValueError(f"solver_opts: Clarabel refused {solver_opts}: {exc}") from None
        status = str(prob.status)
    except (cp.error.SolverError, ArithmeticError, np.linalg.LinAlgError) as exc:
        log.warning("relax_select: Clarabel failed: %s", exc)
        status = f"error: {exc}"
    wall = time.perf_counter() - t1
    stats = prob.solver_stats if prob.status is not None else None
    solve = float(stats.solve_time) if stats is not None and stats.solve_time else wall
    if stats is not None:
        info["iterations"] = stats.num_iters
    compile_time = (t1 - t0) + max(0.0, wall - solve)
    ok = status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) and w.value is not None
    wv = np.clip(np.asarray(w.value, dtype=float), 0.0, 1.0) if ok else None
    if wv is not None and not np.all(np.isfinite(wv)):
        wv = None
    lam = None
    if ok and dual is not None and dual.dual_value is not None:
        lam = np.clip(np.asarray(dual.dual_value, dtype=float).ravel(), 0.0, None)
    value = float(prob.value) if ok and prob.value is not None else float("nan")
    return wv, lam, status, value, compile_time, solve, info


# -- certificate ------------------------------------------------------------------------------
def _certified_bound(G: np.ndarray, w: np.ndarray, M: int, criterion: str, lam=None):
    """Normalized convexity lower bound at w (see the module docstring), or None.

    Returns (bound, objective f(w)) with f the criterion's normalized objective.
    """
    J6 = np.einsum("knp,n->kp", G, w)  # (6, P)
    f_nodes = node_values(J6, criterion)
    if not np.all(np.isfinite(f_nodes)):
        return None
    P = J6.shape[1]
    J = np.empty((P, 3, 3))
    for k, (i, j) in enumerate(ENTRIES):
        J[:, i, j] = J[:, j, i] = J6[k]
    Jinv = np.linalg.inv(J)
    if criterion == "D":
        Y = Jinv / P
        f_lin = f_nodes.mean()
    else:
        Y = Jinv @ Jinv
        if criterion == "A":
            Y /= P
            f_lin = f_nodes.mean()
        else:
            if lam is None or lam.shape != (P,) or not lam.sum() > 0:
                lam = (f_nodes == f_nodes.max()).astype(float)  # valid, if weak
            lam = lam / lam.sum()
            Y *= lam[:, None, None]
            f_lin = float(lam @ f_nodes)
    Y6 = np.stack([Y[:, i, j] for i, j in ENTRIES]) * ENTRY_WEIGHTS[:, None]  # (6, P)
    c = np.einsum("knp,kp->n", G, Y6)  # −∂f/∂w_n ≥ 0
    top = np.sort(c)[::-1][:M].sum()
    bound = f_lin + float(c @ w) - top
    if not np.isfinite(bound):
        return None
    f = float(f_nodes.max() if criterion == "minimax" else f_nodes.mean())
    return bound, f


# -- rounding ---------------------------------------------------------------------------------
def _lowered(x: float) -> float:
    """x minus a relative 1e-12 (x itself if not finite): the bar for a strict improvement."""
    return x - 1e-12 * abs(x) if np.isfinite(x) else x


def _local_search(G: np.ndarray, S: np.ndarray, criterion: str, max_passes: int = 100):
    """1-swap local search from subset S (M,); returns (sorted S, value).

    Each position in turn is swapped for the unselected candidate that lowers the value
    most (if any); passes repeat until one makes no change. Minimax compares (max, mean)
    lexicographically so that swaps that keep the worst node but improve the others are
    taken (the max alone is flat over most swaps).
    """
    S = np.sort(S)
    J = G[:, S].sum(axis=1)

    def score(J):
        v = node_values(J, criterion)
        if criterion == "minimax":
            return v.max(axis=-1), v.mean(axis=-1)
        return v.mean(axis=-1), np.zeros(v.shape[:-1])

    cur = tuple(float(x) for x in score(J))
    for _ in range(max_passes):
        changed = False
        for pos in range(S.size):
            # all N candidates (no gather: cheaper than indexing the unselected ones)
            v, tie = score((J - G[:, S[pos]])[:, None, :] + G)
            v[S] = np.inf  # selected ones are not swap targets
            # strict relative improvement: ties (symmetric rooms) must not cycle
            better = v < _lowered(cur[0])
            better |= (v <= cur[0]) & (tie < _lowered(cur[1]))
            if not np.any(better):
                continue
            cand = np.flatnonzero(better)
            j = cand[np.lexsort((tie[cand], v[cand]))[0]]
            S = S.copy()
            S[pos] = j
            J = G[:, S].sum(axis=1)  # from scratch: no drift
            cur = tuple(float(x) for x in score(J))
            changed = True
        if not changed:
            break
    order = np.argsort(S)
    return S[order], cur[0]


def _round(G, w, M, criterion, rng, samples: int, starts: int):
    """Sampling ∝ weights (Gumbel-top-M) + top-M, then swap local search of the best few."""
    N = G.shape[1]
    p = np.clip(w, 0.0, 1.0) if w is not None else np.full(N, M / N)
    if not p.sum() > 0:
        p = np.full(N, M / N)
    logp = np.full(N, -np.inf)
    np.log(p, out=logp, where=p > 0)
    keys = logp[None, :] + rng.gumbel(size=(samples, N))
    drawn = np.argpartition(-keys, M - 1, axis=1)[:, :M]
    top = np.argsort(-(p + 1e-9 * rng.random(N)), kind="stable")[:M]
    S = np.unique(np.sort(np.vstack([top[None], drawn]), axis=1), axis=0)
    v = subset_values(G, S, criterion)
    order = ties.order(v)[:starts]
    best_S, best_v = S[order[0]], float(v[order[0]])
    for k in order:
        Sk, vk = _local_search(G, S[k], criterion)
        if ties.improves(vk, best_v):
            best_S, best_v = Sk, vk
    return np.sort(best_S), best_v


# -- public API -------------------------------------------------------------------------------
def _certify(G, wv, lam, M, criterion, inp, cost_m2, obj, solver_status, details):
    """(status, message, lower bound m², gap, relaxed cost m²) from the relaxed weights
    (see "Certificate" in the module docstring); adds the D criterion's log-det figures and
    the relaxation gap to ``details``."""
    nan, inf = float("nan"), float("inf")
    if wv is None:
        return 4, f"solver_failed: {solver_status}", 0.0, inf, nan
    cert = _certified_bound(G, wv, M, criterion, lam)
    if cert is None:
        return 3, "singular_relaxation", 0.0, inf, nan
    lb_norm, f_norm = cert
    relaxed = float(inp.scale(f_norm))
    lb = float(inp.scale(lb_norm)) if criterion == "D" or lb_norm > 0 else 0.0
    # how well Clarabel solved the relaxation: f(w*) against the bound certified at w*
    details["relaxation_gap"] = relaxed / lb - 1 if lb > 0 else inf
    if criterion == "D":
        P = G.shape[2]
        details["logdet_sum"] = float(-P * obj - 6 * P * np.log(inp.sigma_ref))
        details["logdet_upper_bound"] = float(-P * lb_norm - 6 * P * np.log(inp.sigma_ref))
    if lb > cost_m2 * (1 + _BOUND_RTOL):
        log.warning("relax_select: bound %g above cost %g, not certified", lb, cost_m2)
        return 2, "bound_above_value", 0.0, inf, relaxed
    lower = min(lb, cost_m2)
    gap = (cost_m2 - lower) / lower if lower > 0 else inf
    if solver_status == "optimal":
        return 0, "optimal", lower, gap, relaxed
    return 1, "inaccurate", lower, gap, relaxed


def _check_settings(inp, samples, starts, solver_opts) -> tuple[int, int]:
    """The rounding's ``samples`` and ``starts``, checked with the candidates' count and
    the Clarabel settings ``solver_opts``."""
    if len(inp.candidates) > MAX_CANDIDATES:
        raise ValueError(
            f"candidates: {len(inp.candidates)} points, more than the {MAX_CANDIDATES} the "
            "relaxation handles; use a larger spacing"
        )
    samples = checks.count("samples", samples, low=1, high=100_000)
    starts = checks.count("starts", starts, low=1, high=10_000)
    if solver_opts is not None:
        checks.mapping("solver_opts", solver_opts, "a dict of Clarabel settings or None")
        checks.known_keys("solver_opts", solver_opts, _solver_keys())
    return samples, starts


def relax_select(
    room: Room,
    M: int,
    *,
    candidates=None,
    criterion: str = "A",
    sigma=DEFAULT_SIGMA,
    nodes=None,
    rng=None,
    spacing: float = DEFAULT_SPACING,
    samples: int = 64,
    starts: int = 8,
    solver_opts: dict | None = None,
) -> Selection:
    """Choose M of N candidate mounting points by convex relaxation + rounding.

    Parameters
    ----------
    room : the room (mounting surfaces, default nodes ``room.grid()``).
    M : number of anchors, 4 ≤ M ≤ N.
    candidates : (N, 3) points on the allowed surfaces (m); default
        ``candidate_grid(room, spacing)`` (``spacing`` = 0.75 m: 204 points in techtile).
    criterion : "A" (mean tr J⁻¹), "D" (Σ log det J, maximized) or "minimax" (worst tr J⁻¹).
    sigma : range standard deviation (m), scalar, per candidate (N,) or per node and
        candidate (P, N) (e.g. :class:`analysis.MultipathRangeNoise`).
    nodes : (P, 3) evaluation nodes (m); default ``room.grid()`` (270 nodes).
    rng : an int seed, a ``numpy.random.Generator`` or None (fresh entropy) for the
        rounding.
    samples, starts : subsets drawn ∝ weights; how many of the best get local search.
    solver_opts : extra keyword arguments for Clarabel (through ``cvxpy.Problem.solve``).

    Returns a :class:`Selection`. Bad input raises ``ValueError``; solver failures are
    reported in ``Selection.status`` (the rounding then starts from uniform weights).
    """
    t_start = time.perf_counter()
    inp = design_inputs(room, M, candidates, criterion, sigma, nodes, spacing)
    samples, starts = _check_settings(inp, samples, starts, solver_opts)
    rng = streams.rng("rng", rng)
    G = inp.table()
    N, M = G.shape[1], inp.M
    wv, lam, solver_status, solver_value, compile_time, solve_time, info = _solve(
        G, M, criterion, solver_opts
    )

    t_round = time.perf_counter()
    S, obj = _round(G, wv, M, criterion, rng, int(samples), int(starts))
    rounding_time = time.perf_counter() - t_round
    cost_m2 = float(inp.scale(obj))

    details = {}
    if np.isfinite(solver_value):
        details["solver_value"] = float(inp.scale(solver_value))
    status, message, lower, gap, relaxed = _certify(
        G, wv, lam, M, criterion, inp, cost_m2, obj, solver_status, details
    )
    return Selection(
        anchors=inp.candidates[S].copy(),
        indices=S,
        weights=np.zeros(N) if wv is None else wv,
        cost_m2=cost_m2,
        lower_bound_m2=lower,
        gap=float(gap),
        success=status in (0, 1),
        status=status,
        message=message,
        nit=int(info.get("iterations") or 0),
        solve_time=solve_time,
        criterion=criterion,
        relaxed_cost_m2=relaxed,
        solver_status=solver_status,
        compile_time=compile_time,
        rounding_time=rounding_time,
        total_time=time.perf_counter() - t_start,
        sigma=inp.sigma_ref,
        candidates=inp.candidates,
        details=details,
    )

"""Gradient refinement of an anchor layout on its mounting surfaces (CasADi + IPOPT).

Each anchor keeps its surface and moves in that rectangle's in-plane coordinates (u, v)
(:func:`placement.to_uv`); the rectangle is the variable bound, so every iterate stays on
an allowed surface. With keep-outs the bound is one allowed rectangle of that surface
(:func:`placement.allowed_rectangles`): the largest one containing the start (or the
nearest one), so no iterate enters a keep-out. The objective is built from one CasADi SX
function of a single node,

    PEB_p(x) = σ_ref · √tr J_p(x)⁻¹    (metres, paper eq. 7 with the root; adjugate formula),

mapped over the P nodes (``Function.map``), and is either

* ``"mean"``: the mean over the nodes of PEB_p = √tr J_p⁻¹ (the root is taken per node:
  the quantity minimized is mean PEB in metres, not mean tr J⁻¹), or
* ``"smoothmax"``: a smooth worst case, the log-mean-exp τ·log((1/P) Σ_p exp(PEB_p/τ)),
  which lies between the mean and the max PEB and tends to the max as τ → 0
  (``temperature`` τ in metres; default 5 % of the initial mean PEB).

Gradients are exact (reverse-mode AD through the map). IPOPT's default here is its
limited-memory quasi-Newton Hessian (history 20; docs/implementation.md compares it with
the exact one on this small, dense problem); ``hessian="exact"`` gives
IPOPT the exact Hessian, from the per-node SX Hessian mapped and summed over the nodes
(plus the log-mean-exp curvature term for "smoothmax").

σ is normalized to 1 inside (σ_j/σ_ref, σ_ref their geometric mean) and rescaled. The
refinement is local: ``multistart`` adds random starts (uniform on each anchor's own
rectangle) and keeps the best. IPOPT output is silenced unless ``verbose``. A failed solve,
a singular start (a node with PEB = inf) or a result no better than the start is reported
in ``status`` (:attr:`RefineResult.STATUS`) and ``message``, and the input layout is
returned unchanged.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analysis.fim import DEFAULT_SIGMA, peb
from placement import ties
from placement.result import LayoutResult
from placement.surfaces import allowed, allowed_rectangles, from_uv, mounting_surfaces, to_uv
from simulation import checks, streams
from simulation.room import Room, as_room

log = logging.getLogger(__name__)

OBJECTIVES = ("mean", "smoothmax")
#: IPOPT statuses accepted as converged
_SUCCESS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: statuses whose final iterate is still accepted when it improves on the start
_STOPPED = ("Maximum_Iterations_Exceeded", "Maximum_CpuTime_Exceeded")


@dataclass(frozen=True)
class RefineResult(LayoutResult):
    """Outcome of :func:`refine_peb` (:mod:`placement.result` convention).

    anchors : (M, 3) refined layout (m), or the input when not ``accepted``.
    initial_anchors : (M, 3) the input layout.
    objective : "mean" or "smoothmax"; objective_m (= ``fun``) / initial_objective_m: that
        objective (m) at the returned and at the input layout (PEB = √tr J⁻¹ per node).
    mean_peb_m, max_peb_m, initial_mean_peb_m, initial_max_peb_m : mean and max over the
        nodes of PEB (m) after and before.
    success : IPOPT converged for the kept start. accepted : the returned anchors differ
        from the input (status 0 or 1).
    status, message : the code of :attr:`STATUS`, and IPOPT's return status of the kept
        start or the reason ("singular_start", "no_improvement", "error: …").
    nit : IPOPT iterations of the kept start; nfev : objective evaluations over all starts.
    starts : number of starts; solve_time : wall-clock seconds of the whole call.
    """

    FUN: ClassVar[str] = "objective_m"
    STATUS: ClassVar[dict[int, str]] = {
        0: "converged: IPOPT converged and the layout improved",
        1: "stopped: IPOPT hit its iteration or time limit; the layout improved",
        2: "no_improvement: no start improved on the input, which is returned",
        3: "singular_start: a node has PEB = inf at the input; nothing to refine",
        4: "duplicate_anchors: the refined anchors coincide; the input is returned",
        5: "failed: CasADi or IPOPT failed for every start; the input is returned",
    }

    anchors: np.ndarray
    initial_anchors: np.ndarray
    objective: str
    objective_m: float
    initial_objective_m: float
    mean_peb_m: float
    max_peb_m: float
    initial_mean_peb_m: float
    initial_max_peb_m: float
    success: bool
    accepted: bool
    status: int
    message: str
    nit: int
    nfev: int
    starts: int
    solve_time: float


def _objective_value(pebs: np.ndarray, objective: str, tau: float) -> float:
    """The objective (m) from per-node PEB (P,) in metres."""
    if not np.all(np.isfinite(pebs)):
        return float("inf")
    if objective == "mean":
        return float(pebs.mean())
    z = pebs / tau
    zmax = z.max()
    return float(tau * (zmax + np.log(np.mean(np.exp(z - zmax)))))


def _node_function(M: int, C: np.ndarray, c0: np.ndarray, w: np.ndarray, hessian: bool):
    """SX function of one node: (x (2M), p (3)) → normalized PEB, gradient[, Hessian]."""
    import casadi as ca

    x = ca.SX.sym("x", 2 * M)
    p = ca.SX.sym("p", 3)
    a = ca.reshape(ca.mtimes(ca.DM(C), x) + ca.DM(c0), 3, M)  # anchors on their planes
    d = ca.repmat(p, 1, M) - a
    s = ca.DM(w).T / ca.sum1(d * d)  # (1/σ_j²)/‖d_j‖²: u uᵀ/σ² = s d dᵀ
    dx, dy, dz = d[0, :], d[1, :], d[2, :]
    xx, yy, zz = ca.sum2(s * dx * dx), ca.sum2(s * dy * dy), ca.sum2(s * dz * dz)
    xy, xz, yz = ca.sum2(s * dx * dy), ca.sum2(s * dx * dz), ca.sum2(s * dy * dz)
    # adjugate: tr J⁻¹ = (sum of principal 2×2 minors) / det J (as analysis.fim)
    mx, my, mz = yy * zz - yz * yz, xx * zz - xz * xz, xx * yy - xy * xy
    det = xx * mx - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz)
    g = ca.sqrt((mx + my + mz) / det)
    val = ca.Function("node_peb", [x, p], [g])
    if not hessian:
        return val, None
    # separate functions: IPOPT evaluates the value far more often than derivatives
    w_ = ca.SX.sym("w")
    H = ca.hessian(g, x)[0]
    return val, ca.Function("node_peb_derivs", [x, p, w_], [ca.gradient(g, x), w_ * H])


def _build_solver(node, derivs, nodes, M, objective, tau_n, opts):
    """IPOPT solver over x (2M) for the mapped node function; tau_n in normalized units.

    ``derivs`` (per-node gradient and weighted Hessian) is given for the exact Hessian.
    """
    import casadi as ca

    P = nodes.shape[0]
    X = ca.DM(nodes.T)
    x = ca.MX.sym("x", 2 * M)
    g = node.map("nodes_peb", "serial", P, [0], [])(x, X)  # (1, P) normalized PEB
    if objective == "mean":
        f = ca.sum2(g) / P
        s = ca.DM.ones(P, 1) / P
    else:
        z = g.T / tau_n
        zmax = ca.mmax(z)
        e = ca.exp(z - zmax)
        f = tau_n * (zmax + ca.log(ca.sum1(e) / P))
        s = e / ca.sum1(e)  # softmax weights = ∂f/∂g_p
    nlp_opts = dict(opts)
    if derivs is not None:
        # Σ_p s_p ∇²g_p from the per-node SX Hessians (summed by the map), plus for the
        # log-mean-exp its own curvature (G diag(s) Gᵀ − ḡ ḡᵀ)/τ, G the node gradients
        G, H = derivs.map("nodes_derivs", "serial", P, [0], [1])(x, X, s.T)
        if objective == "smoothmax":
            gbar = ca.mtimes(G, s)
            H = H + (ca.mtimes(G * ca.repmat(s.T, 2 * M, 1), G.T) - ca.mtimes(gbar, gbar.T)) / tau_n
        lam_f = ca.MX.sym("lam_f")
        nlp_opts["hess_lag"] = ca.Function(
            "hess_lag",
            [x, ca.MX.sym("p", 0), lam_f, ca.MX.sym("lam_g", 0)],
            [ca.triu(lam_f * H)],
        )
    else:
        nlp_opts["ipopt.hessian_approximation"] = "limited-memory"
        nlp_opts["ipopt.limited_memory_max_history"] = 20  # = 2M for M = 10: fewer iterations
    return ca.nlpsol("refine_peb", "ipopt", {"x": x, "f": f}, nlp_opts)


@dataclass(frozen=True)
class _Problem:
    """The checked inputs of :func:`refine_peb`."""

    room: Room
    a0: np.ndarray
    nodes: np.ndarray
    sigma: np.ndarray
    objective: str
    tau: float | None
    peb0: np.ndarray
    f0: float

    @property
    def M(self) -> int:
        return self.a0.shape[0]

    def result(self, anchors, code, message, success, nit=0, nfev=0, starts=0, t0=0.0):
        """The :class:`RefineResult` of returning ``anchors``."""
        pe = peb(anchors, self.nodes, self.sigma)
        return RefineResult(
            anchors=np.array(anchors, dtype=float),
            initial_anchors=self.a0.copy(),
            objective=self.objective,
            objective_m=_objective_value(pe, self.objective, self.tau),
            initial_objective_m=self.f0,
            mean_peb_m=float(pe.mean()),
            max_peb_m=float(pe.max()),
            initial_mean_peb_m=float(self.peb0.mean()),
            initial_max_peb_m=float(self.peb0.max()),
            success=success,
            accepted=code in (0, 1),
            status=code,
            message=message,
            nit=nit,
            nfev=nfev,
            starts=starts,
            solve_time=time.perf_counter() - t0,
        )


def _problem(room, anchors, sigma, objective, nodes, temperature) -> _Problem:
    """Check the layout, nodes, σ and objective; PEB and objective at the start."""
    room = as_room(room)
    a0 = room.check_anchors(checks.reals("anchors", anchors), min_anchors=4)
    checks.distinct("anchors", a0)
    M = a0.shape[0]
    if not np.all(allowed(room, a0, tol=1e-6)):
        raise ValueError(
            f"anchors: every anchor must lie on an allowed mounting surface {list(room.mounting)}"
            " outside the keep-outs (use placement.project)"
        )
    checks.choice("objective", objective, OBJECTIVES)
    p = room.grid() if nodes is None else room.check_nodes(nodes)
    s = checks.reals("sigma", sigma)
    s = np.full(M, float(s)) if s.ndim == 0 else s
    if s.shape != (M,) or not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise ValueError(f"sigma: expected finite values > 0 m, scalar or shape ({M},)")
    peb0 = peb(a0, p, s)
    tau = None
    if objective == "smoothmax":
        if temperature is None:
            tau = 0.05 * float(peb0.mean()) if np.all(np.isfinite(peb0)) else 1.0
        else:
            tau = checks.real("temperature", temperature, low=0.0, low_open=True, unit="m")
    f0 = _objective_value(peb0, objective, tau)
    return _Problem(room, a0, p, s, objective, tau, peb0, f0)


def _variables(room: Room, a0: np.ndarray):
    """The (u, v) variables of every anchor on its own allowed rectangle, a = C x + c0:
    (surface index (M,), C (3M, 2M), c0 (3M,), lower (2M,), upper (2M,), start x0 (2M,))."""
    M = a0.shape[0]
    idx, uv = to_uv(room, a0, tol=1e-6)
    surfs = mounting_surfaces(room)
    rlo, rhi, ridx = allowed_rectangles(room)
    C = np.zeros((3 * M, 2 * M))
    c0 = np.zeros(3 * M)
    lbx, ubx = np.empty(2 * M), np.empty(2 * M)
    for j, k in enumerate(idx):
        o, eu, ev = surfs[k].frame
        c0[3 * j : 3 * j + 3] = o
        C[3 * j : 3 * j + 3, 2 * j] = eu
        C[3 * j : 3 * j + 3, 2 * j + 1] = ev
        # the largest allowed rectangle of its surface holding the start, else the nearest
        lo, hi = rlo[ridx == k], rhi[ridx == k]
        gap = np.linalg.norm(np.clip(uv[j], lo, hi) - uv[j], axis=-1)
        r = int(np.argmax(gap <= 1e-6)) if np.any(gap <= 1e-6) else int(np.argmin(gap))
        lbx[2 * j : 2 * j + 2], ubx[2 * j : 2 * j + 2] = lo[r], hi[r]
    return idx, C, c0, lbx, ubx, np.clip(uv.ravel(), lbx, ubx)


def _solve_starts(solver, starts, lbx, ubx, layout, prob: _Problem):
    """Run IPOPT from every start; (best or None, last status, nfev) with best =
    (objective m, anchors, IPOPT status, converged, iterations)."""
    best, last_status, nfev = None, "no_start", 0
    for xs in starts:
        try:
            sol = solver(x0=xs, lbx=lbx, ubx=ubx)
            stats = solver.stats()
            status = str(stats.get("return_status", "unknown"))
            iters = int(stats.get("iter_count", 0))
            nfev += int(stats.get("n_call_nlp_f", 0))
            x = np.clip(np.asarray(sol["x"], dtype=float).ravel(), lbx, ubx)
        except RuntimeError as exc:
            log.warning("refine_peb: IPOPT failed: %s", exc)
            last_status = f"error: {exc}"
            continue
        last_status = status
        success = status in _SUCCESS
        if not (success or status in _STOPPED) or not np.all(np.isfinite(x)):
            continue
        cand = layout(x)
        val = _objective_value(peb(cand, prob.nodes, prob.sigma), prob.objective, prob.tau)
        if np.isfinite(val) and (best is None or ties.improves(val, best[0])):
            best = (val, cand, status, success, iters)
    return best, last_status, nfev


def refine_peb(
    room: Room,
    anchors,
    *,
    sigma=DEFAULT_SIGMA,
    objective: str = "mean",
    nodes=None,
    multistart: int = 0,
    rng=None,
    verbose: bool = False,
    hessian: str = "limited-memory",
    temperature: float | None = None,
    max_iter: int = 500,
    tol: float = 1e-6,
    return_info: bool = False,
):
    """Move the anchors on their surfaces to minimize mean PEB or a smooth worst case.

    Parameters
    ----------
    room : the room; anchors must lie on its allowed mounting surfaces.
    anchors : (M, 3) layout in metres, M ≥ 4, on the surfaces (each keeps its own).
    sigma : range standard deviation (m), scalar or per anchor (M,).
    objective : "mean" (mean over nodes of PEB = √tr J⁻¹) or "smoothmax" (log-mean-exp).
    nodes : (P, 3) evaluation nodes (m); default ``room.grid()``.
    multistart : extra random starts (each anchor uniform on its own allowed rectangle).
    rng : an int seed, a ``numpy.random.Generator`` or None (fresh entropy) for the extra
        starts.
    verbose : let IPOPT print its log.
    hessian : "limited-memory" (default, faster) or "exact" (AD Hessian).
    temperature : τ (m) of "smoothmax"; default 5 % of the initial mean PEB.
    max_iter, tol : IPOPT iteration limit and tolerance (normalized objective).
    return_info : return a :class:`RefineResult` instead of the (M, 3) anchors.

    Returns the refined (M, 3) anchors (the input unchanged on failure), or a
    :class:`RefineResult` when ``return_info``. Bad input raises ``ValueError``.
    """
    t0 = time.perf_counter()
    prob = _problem(room, anchors, sigma, objective, nodes, temperature)
    checks.choice("hessian", hessian, ("limited-memory", "exact"))
    multistart = checks.count("multistart", multistart, low=0, high=10_000)
    max_iter = checks.count("max_iter", max_iter, low=1, high=1_000_000)
    tol = checks.real("tol", tol, low=0.0, low_open=True)
    verbose = checks.flag("verbose", verbose)
    return_info = checks.flag("return_info", return_info)
    rng = streams.rng("rng", rng)
    res = _refine(prob, multistart, rng, verbose, hessian, max_iter, tol, t0)
    return res if return_info else res.anchors


def _refine(prob: _Problem, multistart, rng, verbose, hessian, max_iter, tol, t0):
    """Build the CasADi problem, run IPOPT from every start, keep the best improvement."""
    a0, M = prob.a0, prob.M
    if not np.isfinite(prob.f0):
        return prob.result(a0, 3, "singular_start", False, t0=t0)
    idx, C, c0, lbx, ubx, x0 = _variables(prob.room, a0)
    s_ref = float(np.exp(np.mean(np.log(prob.sigma))))
    opts = {
        "ipopt.print_level": 5 if verbose else 0,
        "print_time": bool(verbose),
        "ipopt.sb": "yes",
        "ipopt.max_iter": int(max_iter),
        "ipopt.tol": float(tol),
        "error_on_fail": False,
    }
    tau_n = None if prob.tau is None else prob.tau / s_ref
    try:
        node, derivs = _node_function(M, C, c0, (s_ref / prob.sigma) ** 2, hessian == "exact")
        solver = _build_solver(node, derivs, prob.nodes, M, prob.objective, tau_n, opts)
    except RuntimeError as exc:  # CasADi reports its failures as RuntimeError
        log.warning("refine_peb: could not build the CasADi problem: %s", exc)
        return prob.result(a0, 5, f"error: {exc}", False, t0=t0)
    starts = [x0] + [rng.uniform(lbx, ubx) for _ in range(int(multistart))]
    n = len(starts)
    best, last_status, nfev = _solve_starts(
        solver, starts, lbx, ubx, lambda x: from_uv(prob.room, idx, x.reshape(M, 2)), prob
    )
    if best is None:
        return prob.result(a0, 5, last_status, False, nfev=nfev, starts=n, t0=t0)
    val, cand, status, success, iters = best
    try:  # anchors moved onto each other: not a valid layout
        checks.distinct("anchors", cand)
    except ValueError as exc:
        message = f"duplicate_anchors: {exc}"
        return prob.result(a0, 4, message, False, iters, nfev, n, t0)
    if not val < prob.f0:
        return prob.result(a0, 2, "no_improvement", success, iters, nfev, n, t0)
    return prob.result(cand, 0 if success else 1, status, success, iters, nfev, n, t0)

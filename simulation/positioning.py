"""Least-squares positioning from ranges, batched over nodes and realizations (paper §II).

For each node, minimize F(x) = ½ Σ_j (‖x − a_j‖ − ρ_j)² over x ∈ ℝ³ with a damped
Gauss–Newton method (Levenberg–Marquardt with Nielsen's damping update, per-node damping,
a fixed maximum number of iterations, explicit 3 × 3 solves), all nodes at once in numpy.
An undamped Gauss–Newton diverges on the outlier ranges of a reverberant room.

Start: the linear least-squares solution of the squared-range differences (subtracting
the mean equation, ‖x‖² cancels: 2(a_j − ā)ᵀx = (‖a_j‖² − mean‖a‖²) − (ρ_j² − mean ρ²))
when the anchors are not coplanar and that point lies inside ``region``, else the centre
of ``region``. Unbounded by default; ``bounded=True`` keeps every iterate in ``region``
(projected steps).

Every node gets a status (modelled on scipy ``least_squares``): 1 gradient small, 2 cost
change small, 3 step small, 4 zero residual, 0 iteration limit (not converged: the best
iterate is returned and flagged, never silently).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from simulation import checks

logger = logging.getLogger(__name__)

STATUS_MESSAGES = {
    0: "iteration limit reached",
    1: "gradient norm below gtol",
    2: "relative cost change below ftol",
    3: "step below xtol",
    4: "zero residual",
    -1: "anchors collinear or coincident: the position is not determined",
}
#: ranges below this (m) are not measurements; the receiver's noisy ranges reach -0.34 m
RANGE_FLOOR = -1.0


@dataclass(frozen=True)
class PositionFix:
    """Positions from :func:`locate` with per-node solver diagnostics.

    x : (..., P, 3) estimates in metres. converged : (..., P) bool. status : (..., P) int
    (see :data:`STATUS_MESSAGES`). nit : (..., P) iterations used. cost : (..., P)
    F(x) = ½ Σ residual² in m². start : (..., P, 3) starting points.
    """

    x: np.ndarray
    converged: np.ndarray
    status: np.ndarray
    nit: np.ndarray
    cost: np.ndarray
    start: np.ndarray

    @property
    def success(self) -> bool:
        """True when every node converged."""
        return bool(np.all(self.converged))

    def to_dict(self) -> dict:
        return {
            "x": self.x.tolist(),
            "converged": self.converged.tolist(),
            "status": self.status.tolist(),
            "nit": self.nit.tolist(),
            "cost": self.cost.tolist(),
        }


def _region(anchors: np.ndarray, region) -> tuple[np.ndarray, np.ndarray]:
    if region is None:
        return anchors.min(axis=0), anchors.max(axis=0)
    try:
        lo, hi = (checks.reals("region", v, shape=(3,)) for v in region)
    except (TypeError, ValueError):
        raise ValueError(
            f"region: expected (lo (3,), hi (3,)) in metres, got {checks.describe(region)}"
        ) from None
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi >= lo)):
        raise ValueError(f"region: expected finite (lo (3,), hi (3,)) with hi >= lo, got {region}")
    return lo, hi


def _linear_solution(a: np.ndarray, ranges: np.ndarray, owner: np.ndarray | None = None):
    """Linear LS solutions (B, 3) of the squared-range differences for ranges (B, M), and
    whether the anchors are not coplanar (a bool, or (B,) when ``owner`` maps each row to
    its layout of anchors a (L, M, 3))."""
    if owner is not None:  # layout by layout: the same arithmetic as for one layout alone
        lin, ok = np.empty((len(ranges), 3)), np.empty(len(ranges), dtype=bool)
        for layout in range(len(a)):
            rows = owner == layout
            lin[rows], ok[rows] = _linear_solution(a[layout], ranges[rows])
        return lin, ok
    A = 2.0 * (a - a.mean(axis=0))  # (M, 3)
    sv = np.linalg.svd(A, compute_uv=False)
    a2 = np.sum(a * a, axis=1)
    b = (a2 - a2.mean()) - (ranges * ranges - np.mean(ranges * ranges, axis=-1, keepdims=True))
    return b @ np.linalg.pinv(A).T, bool(sv[-1] > 1e-9 * max(sv[0], 1e-300))


def linear_start(anchors: np.ndarray, ranges: np.ndarray) -> np.ndarray | None:
    """Linear LS solution (B, 3) of the squared-range differences, None if anchors coplanar."""
    lin, ok = _linear_solution(anchors, ranges)
    return lin if ok else None


def _geometry(x, a, rho):
    """Residuals (B, M) and unit vectors [3 × (B, M)] from anchors to points x [3 × (B,)];
    anchor coordinates a [3 × (B or 1, M)]. Component arrays keep the loop memory-light."""
    d = [x[k][:, None] - a[k] for k in range(3)]
    dist = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    inv = 1.0 / np.where(dist > 0, dist, 1.0)
    return dist - rho, [dk * inv for dk in d]


def _solve_sym3(s00, s01, s02, s11, s12, s22, b0, b1, b2):
    """Solve symmetric positive-definite 3 × 3 systems, given by their six distinct
    entries (B,), for right-hand sides (b0, b1, b2) (B,) by cofactors."""
    c00 = s11 * s22 - s12 * s12
    c01 = s02 * s12 - s01 * s22
    c02 = s01 * s12 - s02 * s11
    c11 = s00 * s22 - s02 * s02
    c12 = s01 * s02 - s00 * s12
    c22 = s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    det = np.where(det != 0, det, np.finfo(float).tiny)
    return [
        (c00 * b0 + c01 * b1 + c02 * b2) / det,
        (c01 * b0 + c11 * b1 + c12 * b2) / det,
        (c02 * b0 + c12 * b1 + c22 * b2) / det,
    ]


def locate(
    anchors,
    ranges,
    *,
    region=None,
    bounded: bool = False,
    x0=None,
    max_iter: int = 100,
    xtol: float = 1e-10,
    ftol: float = 1e-12,
    gtol: float = 1e-12,
    full_output: bool = False,
):
    """Least-squares positions from ranges: anchors (M, 3), ranges (..., P, M) in metres.

    Several layouts at once: anchors (L, M, 3) and ranges (L, ..., P, M), layout l's
    ranges in ``ranges[l]``; each node is solved as it would be alone (up to rounding).

    Parameters
    ----------
    region : (lo (3,), hi (3,)) box the nodes are known to be in (e.g. ``(0, room.size)``);
        sets the start (box centre, or the linear solution when inside) and the bounds.
        Default: the anchors' bounding box.
    bounded : keep the iterates inside ``region``.
    x0 : optional (..., P, 3) or (3,) starting points (overrides the start rule).
    max_iter, xtol, ftol, gtol : iteration limit and tolerances (see module docstring).
    full_output : return a :class:`PositionFix` instead of the (..., P, 3) array.

    Returns (..., P, 3) estimates, or a :class:`PositionFix`. Nodes that hit ``max_iter``
    return their best iterate and ``converged = False`` (logged at DEBUG). With collinear
    or coincident anchors (closer than 1 mm to a line) the position is not determined:
    every node of that layout gets status −1 and ``converged = False``. Ranges below
    −1 m (a noisy range may be slightly negative) raise ``ValueError``.
    """
    a, rho, max_iter = _check_input(
        anchors,
        ranges,
        max_iter,
        (xtol, ftol, gtol),
        {"bounded": bounded, "full_output": full_output},
    )
    M = a.shape[-2]
    lead = rho.shape[:-1]
    R = rho.reshape(-1, M)
    owner, lo, hi, anc = _rows(a, len(R), region)
    x = _start(a, R, owner, lo, hi, x0, lead)
    if bounded:
        x = np.clip(x, lo, hi)
    start = x.copy()
    x, cost, status, nit = _levenberg_marquardt(
        anc, R, x, lo, hi, bounded, int(max_iter), (xtol, ftol, gtol)
    )
    rank = np.asarray(checks.anchor_rank(a))
    if np.any(rank < 2):  # collinear: rotation about the anchor line leaves ranges unchanged
        bad = (rank < 2) if owner is None else (rank < 2)[owner]
        status[np.broadcast_to(bad, status.shape)] = -1
    converged = status > 0
    if not np.all(converged):
        logger.debug(
            "locate: %d of %d nodes not converged (max_iter=%d)",
            int(np.sum(~converged)),
            len(R),
            max_iter,
        )
    out = x.reshape(*lead, 3)
    if not full_output:
        return out
    return PositionFix(
        x=out,
        converged=converged.reshape(lead),
        status=status.astype(int).reshape(lead),
        nit=nit.reshape(lead),
        cost=cost.reshape(lead),
        start=start.reshape(*lead, 3),
    )


def _check_input(anchors, ranges, max_iter, tols, flags) -> tuple[np.ndarray, np.ndarray, int]:
    a = checks.reals("anchors", anchors)
    if a.ndim not in (2, 3) or a.shape[-1] != 3 or a.shape[-2] < 3:
        raise ValueError(f"anchors: expected shape (M, 3) or (L, M, 3) with M >= 3, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("anchors: must be finite")
    rho = checks.reals("ranges", ranges)
    M = a.shape[-2]
    if rho.ndim < 1 or rho.shape[-1] != M:
        raise ValueError(f"ranges: expected shape (..., P, {M}), got {rho.shape}")
    if a.ndim == 3 and (rho.ndim < 2 or rho.shape[0] != a.shape[0]):
        raise ValueError(
            f"ranges: with {a.shape[0]} layouts expected shape ({a.shape[0]}, ..., P, {M}), "
            f"got {rho.shape}"
        )
    if not np.all(np.isfinite(rho)):
        raise ValueError("ranges: must be finite (no NaN or inf)")
    if rho.size and rho.min() < RANGE_FLOOR:
        raise ValueError(
            f"ranges: must be distances >= {RANGE_FLOOR:g} m (noisy ranges may be slightly "
            f"negative), got {rho.min():g} m"
        )
    max_iter = checks.count("max_iter", max_iter, low=1)
    for name, tol in zip(("xtol", "ftol", "gtol"), tols, strict=True):
        checks.real(name, tol, low=0.0)
    for name, flag in flags.items():
        checks.flag(name, flag)
    return a, rho, max_iter


def _rows(a: np.ndarray, B: int, region):
    """Per-row layout owner (B,) or None, the region's bounds (per row when several
    layouts share no region) and the anchor coordinates as [3 × (B or 1, M)]."""
    if a.ndim == 2:
        lo, hi = _region(a, region)
        return None, lo, hi, [a[None, :, k] for k in range(3)]
    owner = np.repeat(np.arange(a.shape[0]), B // a.shape[0])
    if region is None:
        lo, hi = a.min(axis=1)[owner], a.max(axis=1)[owner]
    else:
        lo, hi = _region(a[0], region)
    return owner, lo, hi, [np.ascontiguousarray(a[owner, :, k]) for k in range(3)]


def _start(a, R, owner, lo, hi, x0, lead) -> np.ndarray:
    """(B, 3) starting points: ``x0``, else the linear solution when inside the region,
    else the region's centre."""
    B = len(R)
    if x0 is not None:
        x0 = checks.reals("x0", x0)
        try:
            x = np.broadcast_to(x0, (*lead, 3)).reshape(B, 3).copy()
        except ValueError:
            raise ValueError(f"x0: expected shape (3,) or (..., P, 3), got {x0.shape}") from None
        if not np.all(np.isfinite(x)):
            raise ValueError("x0: must be finite")
        return x
    x = np.broadcast_to((lo + hi) / 2, (B, 3)).copy()
    lin, ok = _linear_solution(a, R, owner)
    inside = ok & np.all((lin >= lo) & (lin <= hi), axis=1)
    x[inside] = lin[inside]
    return x


def _levenberg_marquardt(anc, R, x, lo, hi, bounded, max_iter, tols):
    """Damped Gauss–Newton (Levenberg–Marquardt, Nielsen's damping update) on every row
    at once: ranges R (B, M), anchors [3 × (B or 1, M)], starts x (B, 3). Returns the
    positions (B, 3), costs ½Σr² (B,), statuses (B,) and iterations (B,). Finished rows
    leave the working set, so the loop runs on the still-active rows only."""
    xtol, ftol, gtol = tols
    B = len(R)
    per_row = anc[0].shape[0] == B and B > 1
    xs = [x[:, k].copy() for k in range(3)]
    r, _ = _geometry(xs, anc, R)
    cost = 0.5 * np.sum(r * r, axis=1)
    status = np.zeros(B, dtype=np.int8)
    nit = np.zeros(B, dtype=np.int32)
    status[cost == 0] = 4
    idx = np.flatnonzero(status == 0)
    s = _State(
        [v[idx] for v in xs], *_geometry([v[idx] for v in xs], _take(anc, idx, per_row), R[idx])
    )
    s.cost, s.rho = cost[idx], R[idx]
    s.anc = _take(anc, idx, per_row)
    s.lo, s.hi = (lo[idx], hi[idx]) if lo.ndim == 2 else (lo, hi)
    s.lam, s.nu = np.full(idx.size, 1e-3), np.full(idx.size, 2.0)
    for it in range(1, max_iter + 1):
        if idx.size == 0:
            break
        st = _lm_iteration(s, bounded, xtol, ftol, gtol)
        fin = (st > 0) | (it == max_iter)
        if np.any(fin):
            j = idx[fin]
            for k in range(3):
                xs[k][j] = s.x[k][fin]
            cost[j], status[j], nit[j] = s.cost[fin], st[fin], it
            idx = idx[~fin]
            s.keep(~fin, per_row, lo.ndim == 2)
    return np.stack(xs, axis=-1), cost, status, nit


def _take(anc, idx, per_row):
    return [v[idx] for v in anc] if per_row else anc


class _State:
    """The active rows of the Levenberg–Marquardt loop."""

    def __init__(self, x, r, u):
        self.x, self.r, self.u = x, r, u

    def keep(self, mask, per_row: bool, row_bounds: bool) -> None:
        self.x = [v[mask] for v in self.x]
        self.u = [v[mask] for v in self.u]
        self.r, self.cost, self.rho = self.r[mask], self.cost[mask], self.rho[mask]
        self.lam, self.nu = self.lam[mask], self.nu[mask]
        if per_row:
            self.anc = [v[mask] for v in self.anc]
        if row_bounds:
            self.lo, self.hi = self.lo[mask], self.hi[mask]


def _lm_iteration(s: _State, bounded: bool, xtol, ftol, gtol) -> np.ndarray:
    """One damped step on every active row; updates ``s`` and returns each row's status
    (0 still running, else the convergence code of :data:`STATUS_MESSAGES`)."""
    u, lam = s.u, s.lam
    g = [np.sum(s.r * uk, axis=1) for uk in u]  # Jᵀr
    small_g = np.maximum(np.maximum(np.abs(g[0]), np.abs(g[1])), np.abs(g[2])) <= gtol
    step = _solve_sym3(
        np.sum(u[0] * u[0], axis=1) + lam,
        np.sum(u[0] * u[1], axis=1),
        np.sum(u[0] * u[2], axis=1),
        np.sum(u[1] * u[1], axis=1) + lam,
        np.sum(u[1] * u[2], axis=1),
        np.sum(u[2] * u[2], axis=1) + lam,
        -g[0],
        -g[1],
        -g[2],
    )
    xn = [s.x[k] + step[k] for k in range(3)]
    if bounded:
        xn = [np.clip(xn[k], s.lo[..., k], s.hi[..., k]) for k in range(3)]
        step = [xn[k] - s.x[k] for k in range(3)]
    rn, un = _geometry(xn, s.anc, s.rho)
    cn = 0.5 * np.sum(rn * rn, axis=1)
    # predicted reduction of the damped model: ½ δᵀ(λδ − g)
    pred = 0.5 * sum(step[k] * (lam * step[k] - g[k]) for k in range(3))
    actual = s.cost - cn
    ratio = np.where(pred > 0, actual / np.where(pred > 0, pred, 1.0), -1.0)
    ok = (ratio > 0) & np.isfinite(cn)
    # convergence tests (gradient before the step; step, cost change after it)
    snorm = np.sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2])
    xnorm = np.sqrt(s.x[0] * s.x[0] + s.x[1] * s.x[1] + s.x[2] * s.x[2])
    small_x = snorm <= xtol * (xnorm + xtol)
    small_f = ok & (actual <= ftol * s.cost) & (pred <= ftol * s.cost)
    zero = ok & (cn == 0)
    # accept / reject with Nielsen's damping update
    s.x = [np.where(ok, xn[k], s.x[k]) for k in range(3)]
    s.r = np.where(ok[:, None], rn, s.r)
    s.u = [np.where(ok[:, None], un[k], u[k]) for k in range(3)]
    s.cost = np.where(ok, cn, s.cost)
    fac = np.maximum(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3)
    s.lam = np.where(ok, lam * fac, lam * s.nu)
    s.nu = np.where(ok, 2.0, 2.0 * s.nu)
    st = np.zeros(len(ok), dtype=np.int8)
    st[small_g] = 1
    st[small_f & (st == 0)] = 2
    st[small_x & (st == 0)] = 3
    st[zero] = 4
    # a damping that overflows means no descent direction is left: stationary point
    st[(st == 0) & ~np.isfinite(s.lam * 1e3)] = 1
    return st

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


def _residuals(x, anchors, rho):
    diff = x[:, None, :] - anchors  # (B, M, 3); anchors (M, 3) or one layout per row (B, M, 3)
    dist = np.sqrt(np.einsum("bmk,bmk->bm", diff, diff))
    r = dist - rho
    unit = diff / np.where(dist > 0, dist, 1.0)[..., None]
    return r, unit


def _solve_sym3(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve symmetric positive-definite 3 × 3 systems A (B, 3, 3) x = b (B, 3) by cofactors."""
    a00, a01, a02 = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    a11, a12, a22 = A[:, 1, 1], A[:, 1, 2], A[:, 2, 2]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    det = np.where(det != 0, det, np.finfo(float).tiny)
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return (
        np.stack(
            [
                c00 * b0 + c01 * b1 + c02 * b2,
                c01 * b0 + c11 * b1 + c12 * b2,
                c02 * b0 + c12 * b1 + c22 * b2,
            ],
            axis=-1,
        )
        / det[:, None]
    )


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
    for name, tol in (("xtol", xtol), ("ftol", ftol), ("gtol", gtol)):
        checks.real(name, tol, low=0.0)
    checks.flag("bounded", bounded)
    checks.flag("full_output", full_output)
    lead = rho.shape[:-1]
    R = rho.reshape(-1, M)
    B = R.shape[0]
    owner = None  # row -> layout, when there are several layouts
    if a.ndim == 3:
        owner = np.repeat(np.arange(a.shape[0]), B // a.shape[0])
        if region is None:
            lo, hi = a.min(axis=1)[owner], a.max(axis=1)[owner]
        else:
            lo, hi = _region(a[0], region)
        anc = a[owner]  # (B, M, 3)
    else:
        lo, hi = _region(a, region)
        anc = a

    if x0 is not None:
        x0 = checks.reals("x0", x0)
        try:
            x = np.broadcast_to(x0, (*lead, 3)).reshape(B, 3).copy()
        except ValueError:
            raise ValueError(f"x0: expected shape (3,) or (..., P, 3), got {x0.shape}") from None
        if not np.all(np.isfinite(x)):
            raise ValueError("x0: must be finite")
    else:
        x = np.broadcast_to((lo + hi) / 2, (B, 3)).copy()
        lin, ok = _linear_solution(a, R, owner)
        inside = ok & np.all((lin >= lo) & (lin <= hi), axis=1)
        x[inside] = lin[inside]
    if bounded:
        x = np.clip(x, lo, hi)
    start = x.copy()

    r, unit = _residuals(x, anc, R)
    cost = 0.5 * np.sum(r * r, axis=1)
    status = np.zeros(B, dtype=np.int8)
    nit = np.zeros(B, dtype=np.int32)
    status[cost == 0] = 4
    # iterate on compact copies of the still-active nodes; finished nodes are written back
    idx = np.flatnonzero(status == 0)
    xa, ra, ua, ca, Ra = x[idx], r[idx], unit[idx], cost[idx], R[idx]
    per_row = owner is not None
    Aa = anc[idx] if per_row else anc
    la, ha = (lo[idx], hi[idx]) if lo.ndim == 2 else (lo, hi)
    lam = np.full(idx.size, 1e-3)  # Nielsen's τ·max diag(JᵀJ); the diagonal is O(1) here
    nu = np.full(idx.size, 2.0)
    eye = np.eye(3)
    for it in range(1, int(max_iter) + 1):
        if idx.size == 0:
            break
        g = np.einsum("bm,bmk->bk", ra, ua)  # Jᵀr
        JtJ = np.einsum("bmi,bmj->bij", ua, ua)
        small_g = np.max(np.abs(g), axis=1) <= gtol
        step = _solve_sym3(JtJ + lam[:, None, None] * eye, -g)
        xn = xa + step
        if bounded:
            xn = np.clip(xn, la, ha)
            step = xn - xa
        rn, un = _residuals(xn, Aa, Ra)
        cn = 0.5 * np.einsum("bm,bm->b", rn, rn)
        # predicted reduction of the damped model: ½ δᵀ(λδ − g)
        pred = 0.5 * np.einsum("bk,bk->b", step, lam[:, None] * step - g)
        actual = ca - cn
        rho_ratio = np.where(pred > 0, actual / np.where(pred > 0, pred, 1.0), -1.0)
        ok = (rho_ratio > 0) & np.isfinite(cn)
        # convergence tests (gradient before the step; step, cost change after it)
        snorm = np.sqrt(np.einsum("bk,bk->b", step, step))
        small_x = snorm <= xtol * (np.sqrt(np.einsum("bk,bk->b", xa, xa)) + xtol)
        small_f = ok & (actual <= ftol * ca) & (pred <= ftol * ca)
        zero = ok & (cn == 0)
        # accept / reject with Nielsen's damping update
        xa = np.where(ok[:, None], xn, xa)
        ra = np.where(ok[:, None], rn, ra)
        ua = np.where(ok[:, None, None], un, ua)
        ca = np.where(ok, cn, ca)
        fac = np.maximum(1.0 / 3.0, 1.0 - (2.0 * rho_ratio - 1.0) ** 3)
        lam = np.where(ok, lam * fac, lam * nu)
        nu = np.where(ok, 2.0, 2.0 * nu)
        st = np.zeros(idx.size, dtype=np.int8)
        st[small_g] = 1
        st[small_f & (st == 0)] = 2
        st[small_x & (st == 0)] = 3
        st[zero] = 4
        # a damping that overflows means no descent direction is left: stationary point
        st[(st == 0) & ~np.isfinite(lam * 1e3)] = 1
        done = st > 0
        if np.any(done) or it == max_iter:
            fin = done | (it == max_iter)
            j = idx[fin]
            x[j], cost[j], status[j], nit[j] = xa[fin], ca[fin], st[fin], it
            keep = ~fin
            idx, xa, ra, ua, ca, Ra = idx[keep], xa[keep], ra[keep], ua[keep], ca[keep], Ra[keep]
            lam, nu = lam[keep], nu[keep]
            if per_row:
                Aa = Aa[keep]
            if lo.ndim == 2:
                la, ha = la[keep], ha[keep]

    rank = np.asarray(checks.anchor_rank(a))
    if np.any(rank < 2):  # collinear: rotation about the anchor line leaves ranges unchanged
        bad = (rank < 2) if owner is None else (rank < 2)[owner]
        status[np.broadcast_to(bad, status.shape)] = -1
    converged = status > 0
    if not np.all(converged):
        logger.debug("locate: %d of %d nodes hit max_iter=%d", int(np.sum(~converged)), B, max_iter)
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

"""Positioning that rejects echoes: least squares on the consistent anchors (docs/model.md,
"Positioning that rejects echoes").

Where an obstacle blocks the direct path, the receiver locks onto an echo and reports a
range metres too long; least squares trusts it and the fix moves by metres. The ranges of
the anchors that do see the tag agree with each other to the receiver's range σ. This is
the residual test of Chan et al. (IEEE TVT 2006), solved greedily as in least-median
schemes (Casas et al., 2006):

1. solve least squares on every heard anchor (:mod:`simulation.least_squares`);
2. test the normalized residual T = Σ r_j² / σ² against the χ² quantile with n − 3
   degrees of freedom at the false-alarm probability α (n heard anchors, σ the range σ of
   the receiver);
3. while the test fails and more than 4 anchors remain, drop one: the two anchors with the
   largest deleted residuals r_j² / (1 − h_jj) (h_jj the leverage of anchor j in the
   linearized fit) are each left out and the position solved again from the current one
   (at most :data:`SUBSET_ITER` iterations); the one whose removal leaves the smaller T is
   dropped;
4. when that ends without 5 consistent anchors (two or more echoes can pull the first fit
   so far that the deleted residuals point at good anchors), search the subsets of the
   heard anchors exhaustively, the largest first, each solved from the linear solution of
   its own squared-range differences, down to 5 anchors; the first size with a subset that
   passes the test gives the fix (the subset with the smallest T), within a budget of
   :data:`SUBSET_BUDGET` solves per fix; a subset still above :data:`SCREEN_FACTOR` times
   the threshold after :data:`SUBSET_SCREEN` iterations is not solved on;
5. the fix is the least-squares position on the anchors kept.

Every fix gets a quality: **verified** (:data:`VERIFIED`) when 5 or more anchors pass the
test, so that one echo among them would have shown; **unverified** (:data:`UNVERIFIED`)
when only 4 remain (no redundancy to tell an echo) or no subset passes; **no fix**
(:data:`NO_FIX`) with fewer than 4 heard anchors.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from simulation.least_squares import linear_fix, lm_solve, residuals, scratch

#: the quality of a fix (:class:`simulation.positioning.PositionFix` ``quality``)
NO_FIX, UNVERIFIED, VERIFIED = 0, 1, 2
QUALITY = {
    NO_FIX: "no fix: fewer than 4 anchors heard",
    UNVERIFIED: "unverified: 4 consistent anchors (no redundancy), or none consistent",
    VERIFIED: "verified: 5 or more anchors consistent to the range sigma",
}
#: anchors left out and solved again per dropping step (the largest deleted residuals)
CANDIDATES = 2
#: the most subsets the exhaustive search of step 4 solves for one fix (8 anchors: every
#: subset of 7 and 6, and 60 of the 56 + … of 5 before it gives up)
SUBSET_BUDGET = 96
#: det(S) ≤ COPLANAR · tr(S)³ of the linear normal equations S: the subset's anchors are
#: (nearly) coplanar and its linear solution is not used
COPLANAR = 1e-12
#: the iterations of one subset's solve: from its linear solution a consistent subset
#: converges in a few; one that does not is not consistent
SUBSET_ITER = 30
#: a subset's first iterations: one whose normalized residual is then still above
#: SCREEN_FACTOR times the test's threshold is far from consistent and is not solved on
SUBSET_SCREEN, SCREEN_FACTOR = 5, 100.0


def thresholds(false_alarm: float, M: int) -> np.ndarray:
    """(M + 1,) the χ² quantiles q[k] with P(χ²_k > q[k]) = ``false_alarm`` (q[0] = 0)."""
    from scipy.stats import chi2

    return np.concatenate([[0.0], chi2.isf(false_alarm, np.arange(1, M + 1))])


@numba.njit(cache=True)
def robust_rows(
    a,
    owner,
    R,
    xs,
    costs,
    status,
    nit,
    lo,
    hi,
    bounded,
    poly,
    max_iter,
    xtol,
    ftol,
    gtol,
    sigma,
    thr,
    used,
    quality,
):  # pragma: no cover - compiled
    """Steps 2–4 of the module docstring for every row whose least-squares fix is in xs
    (B, 3), costs (B,), status (B,) (rows with status < 0 have no fix and are left); the
    anchors kept are written into used (B, M) and the quality into quality (B,)."""
    M = R.shape[1]
    work = scratch(M)
    rho, trial = np.empty(M), np.empty(M)
    x, xt, xb = np.empty(3), np.empty(3), np.empty(3)
    score = np.empty(M)
    drop_iter = min(max_iter, SUBSET_ITER)  # from a converged fix: few when consistent
    for b in range(R.shape[0]):
        for j in range(M):
            used[b, j] = R[b, j] == R[b, j]
        if status[b] < 0:
            quality[b] = NO_FIX
            continue
        ab = a[owner[b]]
        rho[:] = R[b]
        x[:] = xs[b]
        n = 0
        for j in range(M):
            n += rho[j] == rho[j]
        T = 2.0 * costs[b] / (sigma * sigma)
        iters = nit[b]
        while T > thr[n - 3] and n > 4:
            _deleted_residuals(x, ab, rho, score, work[0], work[1])
            best_T, best_j, best_st = math.inf, -1, 0
            for _ in range(CANDIDATES):
                j = _argmax_finite(score)
                if j < 0:
                    break
                score[j] = -math.inf
                trial[:] = rho
                trial[j] = np.nan
                xt[:] = x
                c, st, it = lm_solve(ab, trial, xt, lo[b], hi[b], bounded, poly, drop_iter,
                                     xtol, ftol, gtol, *work)  # fmt: skip
                iters += it
                Tj = 2.0 * c / (sigma * sigma)
                if Tj < best_T:
                    best_T, best_j, best_st = Tj, j, st
                    xb[:] = xt
            if best_j < 0:
                break
            rho[best_j] = np.nan
            used[b, best_j] = False
            x[:] = xb
            T, n = best_T, n - 1
            status[b] = best_st
        if not (T <= thr[n - 3] and n >= 5):  # step 4
            T, n, iters = _subsets(
                ab, R[b], x, T, n, iters, lo[b], hi[b], bounded, poly, max_iter, xtol, ftol,
                gtol, sigma, thr, used[b], work,
            )  # fmt: skip
        xs[b] = x
        costs[b] = 0.5 * T * sigma * sigma
        nit[b] = iters
        quality[b] = VERIFIED if (T <= thr[n - 3] and n >= 5) else UNVERIFIED


@numba.njit(cache=True)
def _subsets(ab, rho0, x, T, n, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
             sigma, thr, used, work):  # fmt: skip  # pragma: no cover - compiled
    """Step 4 of the module docstring: the largest subset of the heard anchors of rho0 (M,)
    that passes the test, from size (heard − 1) down to 5. On success x (3,) and used (M,)
    hold its fix and anchors; returns (T, n, iterations)."""
    M = rho0.shape[0]
    heard = np.zeros(M, dtype=np.int64)
    h = 0
    for j in range(M):
        if rho0[j] == rho0[j]:
            heard[h] = j
            h += 1
    trial, xt, best_x = np.empty(M), np.empty(3), np.empty(3)
    mask = np.zeros(h, dtype=np.bool_)
    best_mask = np.zeros(h, dtype=np.bool_)
    solves = 0
    for size in range(h - 1, 4, -1):
        best_T = math.inf
        _first_combination(mask, size)
        while True:
            trial[:] = np.nan
            for i in range(h):
                if mask[i]:
                    trial[heard[i]] = rho0[heard[i]]
            if not linear_fix(ab, trial, xt, COPLANAR):  # coplanar anchors: from the first fit
                xt[:] = x
            for k in range(3):
                xt[k] = min(max(xt[k], lo[k]), hi[k])
            c, st, it = lm_solve(ab, trial, xt, lo, hi, bounded, poly,
                                 min(max_iter, SUBSET_SCREEN), xtol, ftol, gtol, *work)  # fmt: skip
            iters += it
            Tk = 2.0 * c / (sigma * sigma)
            if st == 0 and Tk <= SCREEN_FACTOR * thr[size - 3] and max_iter > SUBSET_SCREEN:
                c, st, it = lm_solve(ab, trial, xt, lo, hi, bounded, poly,
                                     min(max_iter, SUBSET_ITER) - SUBSET_SCREEN, xtol, ftol,
                                     gtol, *work)  # fmt: skip
                iters += it
                Tk = 2.0 * c / (sigma * sigma)
            if Tk < best_T:
                best_T = Tk
                best_x[:] = xt
                best_mask[:] = mask
            solves += 1
            if solves >= SUBSET_BUDGET or not _next_combination(mask):
                break
        if best_T <= thr[size - 3]:
            x[:] = best_x
            used[:] = False
            for i in range(h):
                used[heard[i]] = best_mask[i]
            return best_T, size, iters
        if solves >= SUBSET_BUDGET:
            break
    return T, n, iters


@numba.njit(cache=True)
def _first_combination(mask, size) -> None:  # pragma: no cover - compiled
    """mask (h,) set to the first combination of ``size`` (the first ``size`` entries)."""
    mask[:] = False
    mask[:size] = True


@numba.njit(cache=True)
def _next_combination(mask) -> bool:  # pragma: no cover - compiled
    """In place: the next combination of the same size in lexicographic order of the set
    bits' positions (a set bit moves right); False after the last one."""
    h = mask.shape[0]
    # the rightmost set bit that can move right
    ones = 0
    for i in range(h - 1, -1, -1):
        if mask[i]:
            if i < h - 1 - ones:
                mask[i] = False
                for k in range(i + 1, h):
                    mask[k] = k <= i + 1 + ones
                return True
            ones += 1
    return False


@numba.njit(cache=True)
def _deleted_residuals(x, ab, rho, score, r, u):  # pragma: no cover - compiled
    """score (M,): r_j² / (1 − h_jj) of every heard anchor at x (−inf for the others), h_jj
    the leverage u_jᵀ (UᵀU)⁻¹ u_j of the unit vectors u_j from the anchors to x."""
    residuals(x, ab, rho, r, u)
    s00 = s01 = s02 = s11 = s12 = s22 = 0.0
    for j in range(ab.shape[0]):
        s00 += u[j, 0] * u[j, 0]
        s01 += u[j, 0] * u[j, 1]
        s02 += u[j, 0] * u[j, 2]
        s11 += u[j, 1] * u[j, 1]
        s12 += u[j, 1] * u[j, 2]
        s22 += u[j, 2] * u[j, 2]
    c00, c01, c02 = s11 * s22 - s12 * s12, s02 * s12 - s01 * s22, s01 * s12 - s02 * s11
    c11, c12, c22 = s00 * s22 - s02 * s02, s01 * s02 - s00 * s12, s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    for j in range(ab.shape[0]):
        if rho[j] != rho[j]:
            score[j] = -math.inf
            continue
        u0, u1, u2 = u[j, 0], u[j, 1], u[j, 2]
        h = 0.0
        if det > 0:
            h = (u0 * (c00 * u0 + c01 * u1 + c02 * u2) + u1 * (c01 * u0 + c11 * u1 + c12 * u2)
                 + u2 * (c02 * u0 + c12 * u1 + c22 * u2)) / det  # fmt: skip
        score[j] = r[j] * r[j] / max(1.0 - h, 1e-9)


@numba.njit(cache=True)
def _argmax_finite(v) -> int:  # pragma: no cover - compiled
    """The index of the largest finite entry of v, −1 when there is none."""
    best, k = -math.inf, -1
    for j in range(v.shape[0]):
        if v[j] > best:
            best, k = v[j], j
    return k

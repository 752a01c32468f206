"""Positioning that rejects echoes: least squares on the consistent anchors (docs/model.md,
"Positioning that rejects echoes").

Where an obstacle blocks the direct path, the receiver locks onto an echo and reports a
range metres too long; least squares trusts it and the fix moves by metres. The ranges of
the anchors that do see the tag agree with each other to the receiver's range σ. This is
the residual test of Chan et al. (IEEE TVT 2006), solved greedily as in least-median
schemes (Casas et al., 2006):

1. solve least squares on every heard anchor (:mod:`simulation.least_squares`) but those
   whose range is proved an echo (:func:`proved_echoes`: an echo only lengthens a range,
   so r_j − r_k − |a_j − a_k| bounds the excess of range j over its distance from below
   for every heard k; above :data:`PROVED` it is no direct range), where 5 or more
   remain: the dropping steps would leave them out one at a time; the later steps still
   see every range;
2. test the normalized residual T = Σ r_j² / σ² against the χ² quantile with n − 3
   degrees of freedom at the false-alarm probability α (n heard anchors, σ the range σ of
   the receiver);
3. while the test fails and more than 4 anchors remain, drop one: the two anchors with the
   largest deleted residuals r_j² / (1 − h_jj) (h_jj the leverage of anchor j in the
   linearized fit) are each left out in that order and the position solved again from
   the current one (at most :data:`SUBSET_ITER` iterations); the first whose removal
   passes the test is dropped (the second is then not solved), else the one whose removal
   leaves the smaller T;
   when the test passes but the room's map (below) hides some of the anchors kept from
   the fix (a range bent round an obstacle's edge can be only centimetres long, so the
   test passes with it), those anchors are left out and the fix solved again
   (:func:`_drop_hidden`); it stands when 6 or more anchors remain, pass the test and
   nothing contradicts it (with 5, one range of redundancy, the set to keep is step 4's
   choice);
4. when that ends without 5 consistent anchors (two or more echoes can pull the first fit
   so far that the deleted residuals point at good anchors), or with a contradiction
   (below), search for consensus as RANSAC does (Fischler and Bolles, 1981),
   deterministically: minimal sets of 4 heard anchors, in the order of their ranges (a
   near anchor is more often in sight) except that a range proved an echo comes after
   all the others (its excess bounded as in step 1 above :data:`SHORT`), each
   solved from the linear solution of its squared-range differences (:func:`_minimal_fix`:
   coplanar anchors fix two mirror images in their plane, the better is taken; nearly
   coplanar ones, :data:`FLAT`, a solution polished by :data:`POLISH_ITER` iterations of
   least squares); a hypothesis is scored by its contradictions (ranges shorter than its
   distance by more than :data:`SHORT`) and its inliers (ranges within :data:`LOOSE`); one
   better than the best so far is refined by least squares on its inliers, then on those
   within 3σ of the refined fix; the first refined set of 5 or more that passes the test
   with no contradiction ends the search (at most :data:`HYPOTHESES` minimal sets, up to
   :data:`FOUR_HYPOTHESES` while only a minimal set agrees uncontradicted and passes the
   test unpenalized (below), and up to :data:`MORE_HYPOTHESES` while every set so far is
   contradicted or penalized: in a hall of racks the few direct ranges may be among the
   longest), else the best one is kept; where no 5 anchors agree without a contradiction,
   the least contradicted minimal set whose 4 ranges agree (T at most :data:`MINIMAL_T`)
   is the fix when it is less contradicted than the fix so far, or as little and with a
   smaller penalized T. With one degree of freedom, T cannot tell the direct set from a
   wrong one that agrees by chance: T is penalized by :data:`MISS_PENALTY` for each miss
   the contradictions forgive (below) and by :data:`HELD_PENALTY` for a fix held at the
   room's boundary (:func:`_ranked`). The minimal sets are solved for this only once the
   search has found no such set of 5. Where the fix is still contradicted, the tag may
   see only 3 anchors: their ranges fix two mirror images, and the least contradicted
   image of any 3 heard anchors, then the less penalized, is the fix when it is less
   contradicted (:func:`_triples`: a column hides all but 3 anchors from a sliver behind
   it, and the echoes of the others are then long ranges to anchors that do not see it);
5. the fix grows (:func:`_grow`): each heard anchor left out whose range is within
   :data:`LOOSE` of its distance from the fix, the nearest first, joins it when the fix on
   the larger set still passes the test with no contradiction (a dropping step or the
   tight refinement can leave out a direct range that mounting error put a few
   centimetres off); the growing stops after :data:`GROW_TRIES` refusals; a fix on 4
   anchors that the room's bounds hold at its boundary is then moved to the interior
   candidate that fits its ranges best, within :data:`INTERIOR` and no more contradicted
   (:func:`_off_the_boundary`): a tag close to its 4 anchors' plane fits its mirror image
   across that plane about as well, and least squares started on the image's side runs
   into the wall and stops there;
6. the fix is the least-squares position on the anchors kept.

A fix's contradictions are its ranges shorter than their distance by more than
:data:`SHORT` (no path is shorter than the direct one) and, where the positioning knows the
room's map (walls of a floor plan that is not convex, obstacles;
:func:`simulation.polyhedral.blocking_map`), two more. A fix that rests on an anchor that
does not see it (from the fix or from any point :data:`GRAZE` from it along the axes, but
those across a face from it, in a wall or an obstacle) rests on an echo: the echoes off one
face agree with each other at the mirror image of the tag, as direct ranges would. And an
anchor that surely sees the fix (from it and from all those points) hears its direct path:
beyond the first :data:`MISSES`, each such anchor whose range is longer than its distance
by more than :data:`LOOSE` contradicts the fix (a mirror image above the racks is seen by
every anchor, with echo ranges). A short range outweighs
any number of what the map says (:func:`_contradictions`): it is physics, the map may be
coarse.

Every fix gets a quality: **verified** (:data:`VERIFIED`) when 5 or more anchors pass the
test, so that one echo among them would have shown, their directions fix the position
(dilution of precision at most :data:`DOP_MAX`: five collinear anchors agree with each
other on a whole circle), and its protection level is within the alert limit: the largest
move of the fix that one echo the test misses (with probability :data:`MISSED_DETECTION`)
can cause, as receiver integrity monitoring bounds it (the slope method of Brown and Chin,
1998): an echo of excess b on anchor j raises T by b²(1 − h_jj)/σ² and moves the fix by
b‖k_j‖, k_j the column j of (UᵀU)⁻¹Uᵀ, so the protection level is
σ √λ max_j ‖k_j‖/√(1 − h_jj), λ the non-centrality the test misses (:func:`bias_scales`).
With a range σ of centimetres that is centimetres where 5 anchors surround the tag; with
the decimetres of a peak-pick receiver, metres: its fixes cannot be vouched for.
**Unverified** (:data:`UNVERIFIED`) when only 4 remain (no redundancy to tell an echo), or
3 (step 4's last resort), no subset passes, or the bound is not met; **no fix**
(:data:`NO_FIX`) with fewer than 4 heard anchors.
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

from simulation.least_squares import (
    NO_REFCOUNT,
    adjugate_times,
    cofactors,
    fill,
    flatness,
    gram_gradient,
    inside_floor_plan,
    into_floor_plan,
    lm_solve,
    lm_solve_inline,
    mirrors,
    nearest_on_boundary,
    normal_equations,
    put,
    residuals,
    scratch,
)
from simulation.polyhedral import sees_near

#: the quality of a fix (:class:`simulation.positioning.PositionFix` ``quality``)
NO_FIX, UNVERIFIED, VERIFIED = 0, 1, 2
QUALITY = {
    NO_FIX: "no fix: fewer than 4 anchors heard",
    UNVERIFIED: "unverified: 4 consistent anchors (no redundancy), 3 that nothing "
    "contradicts, none consistent, or an echo the test misses could move the fix beyond the "
    "alert limit",
    VERIFIED: "verified: 5 or more anchors consistent to the range sigma, the fix within "
    "the alert limit of any echo the test misses",
}
#: anchors left out and solved again per dropping step (the largest deleted residuals)
CANDIDATES = 2
#: the most minimal sets (4 anchors) step 4 tries for one fix (8 anchors: all 70)
HYPOTHESES = 300
#: the most minimal sets step 4 tries for a fix that every set so far contradicts: in a
#: hall of racks 4 or 5 of 18 heard anchors may see the tag, and their sets come late
MORE_HYPOTHESES = 3000
#: the most minimal sets step 4 tries for a fix while only a minimal set agrees with
#: nothing contradicting it and passes the test with no penalty (:func:`_ranked`): 4 ranges
#: agree by chance more often than 5; past it, up to :data:`MORE_HYPOTHESES`
FOUR_HYPOTHESES = 700
#: (m, range σs): a range within the larger of the two of a hypothesis' distance is its
#: inlier before refinement (a minimal set's fix is only roughly right)
LOOSE = (0.2, 5.0)
#: (m, range σs): a range shorter than the distance by more than the larger of the two
#: contradicts the position (an echo makes a range longer, never shorter)
SHORT = (0.1, 3.0)
#: (m) an anchor hides a position only if it hides every point this close to it along the
#: axes: a fix is centimetres off, and a direct path may graze an obstacle's edge
GRAZE = 0.05
#: (m, range σs): a range whose proved excess (:func:`proved_echoes`) is above the larger of
#: the two is left out before the first fit (four times :data:`SHORT`: an anchor mounted a
#: few centimetres off the plan, or a noisy range, proves nothing)
PROVED = (0.4, 12.0)
#: the anchors that surely see a position with a range longer than its distance (their
#: direct path missed) before each further one contradicts it (on a room's map)
MISSES = 2
#: the largest normalized residual T of a minimal set taken where no 5 anchors agree: its 4
#: ranges agree to about 7 cm (anchors are mounted within centimetres of the plan)
MINIMAL_T = 200.0
#: the most sets of 3 anchors step 4's last resort tries (:func:`_triples`; 10 heard: all)
TRIPLES = 120
#: the anchors step 5 may try to add to a fix and refuse before it stops
GROW_TRIES = 2
#: a bound no count of contradictions reaches
INFINITE = 1 << 30
#: the largest position dilution of precision of the anchors of a verified fix: 5 nearly
#: collinear anchors agree with each other at many positions
DOP_MAX = 10.0
#: the probability that the test misses the echo whose move of the fix is the protection
#: level of a verified fix (its missed-detection probability)
MISSED_DETECTION = 1e-3
#: det(S) ≤ COPLANAR · tr(S)³ of the linear normal equations S: the subset's anchors are
#: (nearly) coplanar and its linear solution is not used
COPLANAR = 1e-12
#: det(S) ≤ FLAT · tr(S)³ of a minimal set's linear normal equations: its anchors are so
#: nearly coplanar (three on the ceiling, one a little below) that the linear solution
#: can be decimetres off; it is polished by least squares on the set's ranges
FLAT = 1e-3
#: the least distance of a coplanar minimal set's mirror images from the anchors' plane
#: (:func:`simulation.least_squares.mirror_fixes`): a fit polished from there reaches the
#: side's least-squares fix; from the plane itself it cannot leave the plane
OFF_PLANE = 0.1
#: a fix within HELD m of the room's boundary is held there by the bounds (:func:`_held`)
HELD = 1e-6
#: what a forgiven miss adds to the T of a minimal set's fix in their ranking: −2 ln of the
#: share of tags (about 4 % in the warehouse) where an anchor that the map says sees the tag
#: has a range longer than :data:`LOOSE` (its direct path missed), as a likelihood would
MISS_PENALTY = 6.4
#: what a fix held at the room's boundary adds to its T in the ranking of minimal sets: the
#: χ² quantile of one degree of freedom at 10⁻³ (a tag is not at the walls, a mirror image is)
HELD_PENALTY = 10.8
#: (m, range σs): the largest RMS range residual of a fix on 4 anchors moved off the room's
#: boundary by step 5's end (:func:`_off_the_boundary`): the larger of the two; anchors are
#: mounted within centimetres of the plan
INTERIOR = (0.02, 2.0)
#: the iterations of one dropping step's or one refinement's solve: from a good start a
#: consistent set converges in a few; one that does not is not consistent
SUBSET_ITER = 30
#: the iterations that polish a nearly coplanar minimal set's linear solution
#: (:data:`FLAT`) before it is scored: its inliers and short ranges need it within
#: decimetres, not converged; a set that is ranked is solved in full (:func:`_minimal`)
POLISH_ITER = 2


@functools.lru_cache(maxsize=64)
def thresholds(false_alarm: float, M: int) -> np.ndarray:
    """(M + 1,) the χ² quantiles q[k] with P(χ²_k > q[k]) = ``false_alarm`` (q[0] = 0).
    Read-only (cached)."""
    from scipy.stats import chi2

    q = np.concatenate([[0.0], chi2.isf(false_alarm, np.arange(1, M + 1))])
    q.flags.writeable = False
    return q


@functools.lru_cache(maxsize=64)
def bias_scales(false_alarm: float, M: int) -> np.ndarray:
    """(M + 1,) √λ[k] (s[0] = 0): the non-centrality λ[k] of a χ²_k that the test at
    ``false_alarm`` (:func:`thresholds`) misses with probability :data:`MISSED_DETECTION`;
    an echo on anchor j passes unseen that often while its excess is below
    σ √λ[k] / √(1 − h_jj) (module docstring). Read-only (cached)."""
    from scipy.optimize import brentq
    from scipy.stats import ncx2

    q = thresholds(false_alarm, M)
    s = np.zeros(M + 1)
    for k in range(1, M + 1):
        # the cdf at the threshold falls from 1 − α (λ → 0) to 0 as λ grows
        s[k] = math.sqrt(brentq(lambda lam, k=k: ncx2.cdf(q[k], k, lam) - MISSED_DETECTION,
                                1e-9, 1e4))  # fmt: skip
    s.flags.writeable = False
    return s


@numba.njit(cache=True)
def robust_rows(
    a,
    owner,
    R,
    F,
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
    bias,
    alert,
    used,
    quality,
    geo,
    front,
):  # pragma: no cover - compiled
    """Steps 2–5 of the module docstring for every row of ranges R (B, M) whose
    least-squares fix on the ranges F (B, M) (R without its proved echoes,
    :func:`proved_echoes`) is in xs (B, 3), costs (B,), status (B,) (rows with status < 0
    have no fix and are left); the
    anchors kept are written into used (B, M) and the quality into quality (B,) (``bias``
    (M + 1,) :func:`bias_scales`, ``alert`` the alert limit in m); ``geo``
    the room's map (:func:`simulation.polyhedral.blocking_map`; empty: nothing hides an
    anchor) and ``front`` (L, M, F) the faces of the map each anchor faces
    (:func:`simulation.polyhedral.facing`)."""
    M = R.shape[1]
    work = scratch(M)
    rho, trial = np.empty(M), np.empty(M)
    x, xt, xb = np.empty(3), np.empty(3), np.empty(3)
    score = np.empty(M)
    fst = np.zeros(1, dtype=np.int64)  # the status of the solve that gave the fix
    loose, short = max(LOOSE[0], LOOSE[1] * sigma), max(SHORT[0], SHORT[1] * sigma)
    for b in range(R.shape[0]):
        if status[b] < 0:
            for j in range(M):
                used[b, j] = R[b, j] == R[b, j]
            quality[b] = NO_FIX
            continue
        ab = a[owner[b]]
        gr = row_map(geo, front[owner[b]])
        put(rho, F[b])
        for j in range(M):
            used[b, j] = F[b, j] == F[b, j]
        put(x, xs[b])
        fst[0] = status[b]
        T, n, iters = _one_fix(ab, R[b], rho, x, 2.0 * costs[b] / (sigma * sigma), nit[b],
                               lo[b], hi[b], bounded, poly, max_iter, xtol, ftol, gtol, sigma,
                               thr, loose, short, used[b], work, gr, score, trial, xt, xb,
                               fst)  # fmt: skip
        status[b] = fst[0]
        xs[b] = x
        costs[b] = 0.5 * T * sigma * sigma
        nit[b] = iters
        quality[b] = _quality(ab, R[b], used[b], x, T, n, thr, sigma * bias[n - 3], alert,
                              rho, work)  # fmt: skip


@numba.njit(cache=True)
def _one_fix(ab, rho0, rho, x, T, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
             sigma, thr, loose, short, used, work, geo, score, trial, xt, xb,
             fst):  # fmt: skip  # pragma: no cover - compiled
    """Steps 3–5 of the module docstring for one row: the heard ranges rho0 (M,) of anchors
    ab (M, 3), the ranges of its first fit in rho (M,) (rho0 without its proved echoes;
    NaN: left out, as ``used`` (M,) is False), that fit in x (3,) with its normalized
    residual T and iterations; in place on x, rho and used, the status of the solve that
    gave the fix into fst (1,) (``geo`` the row's map, :func:`row_map`; ``work``,
    ``score``, ``trial``, ``xt``, ``xb``: scratch). Returns (T, n, iterations) of the fix."""
    drop_iter = min(max_iter, SUBSET_ITER)  # from a converged fix: few when consistent
    T, n, iters = _drop_failing(ab, rho, x, T, iters, lo, hi, bounded, poly, drop_iter, xtol,
                                ftol, gtol, sigma, thr, used, work, score, trial, xt, xb,
                                fst)  # fmt: skip  # step 3
    clean = T <= thr[n - 3] and n >= 5
    if clean and _contradictions(ab, rho0, rho, x, short, loose, geo, 0) > 0:
        clean, T, n, iters = _drop_hidden(ab, rho0, rho, x, T, n, iters, lo, hi,
                                          bounded, poly, drop_iter, xtol, ftol, gtol, sigma,
                                          thr, loose, short, used, work, geo, trial, xt,
                                          fst)  # fmt: skip  # step 3's end
    if not clean:
        T, n, iters = _consensus(
            ab, rho0, x, T, n, iters, lo, hi, bounded, poly, max_iter, xtol, ftol,
            gtol, sigma, thr, loose, short, used, work, geo, fst,
        )  # fmt: skip  # step 4
    T, n, iters = _grow(ab, rho0, x, T, n, iters, lo, hi, bounded, poly, drop_iter,
                        xtol, ftol, gtol, sigma, thr, loose, short, used, work, geo,
                        trial, xt, score, fst)  # fmt: skip  # step 5 (n ≥ 3 here)
    if bounded and n == 4 and _held(x, lo, hi, poly):
        T, iters = _off_the_boundary(ab, rho0, x, T, iters, lo, hi, poly, drop_iter,
                                     xtol, ftol, gtol, sigma, loose, short, used, work,
                                     geo, trial, xt, xb, fst)  # fmt: skip  # step 5's end
    return T, n, iters


@numba.njit(cache=True)
def proved_echoes(a, owner, R, sigma):  # pragma: no cover - compiled
    """(B, M) the ranges R (B, M) of the layouts a (L, M, 3) (row b's ``owner[b]``) with
    every range proved an echo left out (NaN) where 5 or more heard ranges remain (enough
    to test them)
    (step 1 of the module docstring): an echo only lengthens a range, so
    r_j − r_k − |a_j − a_k| bounds the excess of range j over its distance from below for
    every heard k (the triangle inequality); above :data:`PROVED` (``sigma`` the range σ,
    m), range j is no direct range, and least squares need not be pulled by it first."""
    B, M = R.shape
    F = R.copy()
    proved = max(PROVED[0], PROVED[1] * sigma)
    echo = np.zeros(M, dtype=np.bool_)
    for b in range(B):
        ab, rho, n, m = a[owner[b]], R[b], 0, 0
        for j in range(M):
            echo[j] = rho[j] == rho[j] and _proved_echo(ab, rho, j, proved)
            n += rho[j] == rho[j]
            m += echo[j]
        if m and n - m >= 5:
            for j in range(M):
                if echo[j]:
                    F[b, j] = np.nan
    return F


@numba.njit(**NO_REFCOUNT)
def _drop_failing(ab, rho, x, T, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
                  sigma, thr, used, work, score, trial, xt, xb, fst):  # fmt: skip
    # pragma: no cover - compiled
    """Step 3 of the module docstring, in place on the fix x (3,) of the heard ranges rho
    (M,) with normalized residual T: while the test (``thr``) fails and more than 4 remain,
    :func:`_drop_one` leaves one out (NaN in rho, False in ``used`` (M,)) and its status
    goes into fst (1,) (``score``, ``trial``, ``xt``, ``xb``: scratch). Returns (T, n,
    iterations)."""
    n = 0
    for j in range(rho.shape[0]):
        n += rho[j] == rho[j]
    while T > thr[n - 3] and n > 4:
        best_T, best_j, best_st, it = _drop_one(ab, rho, x, score, trial, xt, xb, lo, hi,
                                                bounded, poly, max_iter, xtol, ftol, gtol,
                                                sigma, thr[n - 4], work)  # fmt: skip
        iters += it
        if best_j < 0:
            break
        rho[best_j] = np.nan
        used[best_j] = False
        put(x, xb)
        T, n = best_T, n - 1
        fst[0] = best_st
    return T, n, iters


@numba.njit(**NO_REFCOUNT)
def _drop_hidden(ab, rho0, rho, x, T, n, iters, lo, hi, bounded, poly, max_iter, xtol, ftol,
                 gtol, sigma, thr, loose, short, used, work, geo, trial, xt, fst):  # fmt: skip
    # pragma: no cover - compiled
    """The end of step 3 of the module docstring, on the fix x (3,) that passes the test
    on the n anchors of rho (M,) (NaN: left out) but that the map ``geo`` contradicts: the
    kept anchors that do not see x are left out and the fix solved again; when at least 6
    remain, the new fix passes the test and nothing contradicts it, x, rho, ``used`` (M,)
    and fst (1,) (its solve's status) take it (``trial`` (M,), ``xt`` (3,): scratch).
    Returns (clean, T, n, iterations): clean False leaves x, rho, used and fst as they
    were."""
    M = rho0.shape[0]
    m = 0
    for j in range(M):
        trial[j] = rho[j]
        if rho[j] == rho[j]:
            if _sees(geo, x, ab, j, False):
                m += 1
            else:
                trial[j] = np.nan
    if m < 6 or m == n:
        return False, T, n, iters
    put(xt, x)
    c, st, it = lm_solve(ab, trial, xt, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
                         *work)  # fmt: skip
    iters += it
    Tm = 2.0 * c / (sigma * sigma)
    if Tm > thr[m - 3] or _contradictions(ab, rho0, trial, xt, short, loose, geo, 0) > 0:
        return False, T, n, iters
    put(x, xt)
    fst[0] = st
    for j in range(M):
        rho[j] = trial[j]
        used[j] = trial[j] == trial[j]
    return True, Tm, m, iters


@numba.njit(**NO_REFCOUNT)
def _grow(ab, rho0, x, T, n, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma,
          thr, loose, short, used, work, geo, trial, xt, seen,
          fst):  # fmt: skip  # pragma: no cover
    """Step 5 of the module docstring, in place on the fix x (3,) with the normalized
    residual T of its n anchors ``used`` (M,): each heard anchor left out whose range in
    rho0 (M,) is within ``loose`` m of its distance from x, the nearest first, is added
    when the fix on the larger set still passes the test (``thr``) with nothing
    contradicting it (``short``, ``geo``: :func:`_contradictions`); it stops after
    :data:`GROW_TRIES` refusals (``trial`` (M,), ``xt`` (3,), ``seen`` (M,): scratch; the
    status of the solve that gave the fix into fst (1,)). Returns (T, n, iterations)."""
    M = rho0.shape[0]
    for j in range(M):
        seen[j] = 1.0 if used[j] or rho0[j] != rho0[j] else 0.0
    refused = 0
    while refused < GROW_TRIES:
        k, best = -1, loose
        for j in range(M):
            e = abs(_distance(x, ab[j]) - rho0[j]) if seen[j] == 0.0 else math.inf
            if e <= best:
                k, best = j, e
        if k < 0:
            break
        seen[k] = 1.0
        for j in range(M):
            trial[j] = rho0[j] if used[j] or j == k else np.nan
        put(xt, x)
        c, st, it = lm_solve(ab, trial, xt, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
                             *work)  # fmt: skip
        iters += it
        Tk = 2.0 * c / (sigma * sigma)
        if Tk <= thr[n - 2] and _contradictions(ab, rho0, trial, xt, short, loose, geo,
                                                0) == 0:  # fmt: skip
            used[k] = True
            put(x, xt)
            T, n = Tk, n + 1
            fst[0] = st
        else:
            refused += 1
    return T, n, iters


@numba.njit(cache=True)
def _off_the_boundary(ab, rho0, x, T, iters, lo, hi, poly, max_iter, xtol, ftol, gtol, sigma,
                      loose, short, used, work, geo, trial, xt, xf, fst):  # fmt: skip
    # pragma: no cover - compiled
    """The end of step 5 of the module docstring, in place on a fix x (3,) on the 4 anchors
    ``used`` (M,) that the bounds hold at the room's boundary (box [lo, hi], floor plan
    ``poly``). Where a tag lies close to the plane of its 4 anchors, its ranges fit two
    mirror images across that plane about equally; least squares started on the wrong side
    runs into the wall and stops there, fitting neither. The candidates: the fit without
    bounds (into xf (3,)) where it ends strictly inside the room, and the bounded fits
    started from the mirror images of that fit and of x across the anchors' best-fitting
    plane that end strictly inside (:func:`_inside`). The one with the smallest misfit
    replaces x when its RMS range residual is within :data:`INTERIOR` and nothing
    contradicts it more than x (:func:`_contradictions`); the status of its solve goes
    into fst (1,) (``trial`` (M,), ``xt`` (3,): scratch). Returns (T, iterations)."""
    M = rho0.shape[0]
    for j in range(M):
        trial[j] = rho0[j] if used[j] else np.nan
    now = _contradictions(ab, rho0, trial, x, short, loose, geo, INFINITE)
    tol = max(INTERIOR[0], INTERIOR[1] * sigma)
    best_c, best_st, best = 2.0 * tol * tol, 0, np.empty(3)  # ½Σr² of 4 ranges at RMS tol
    found = False
    put(xf, x)
    c, st, it = lm_solve(ab, trial, xf, lo, hi, False, poly, max_iter, xtol, ftol, gtol, *work)
    iters += it
    if c <= best_c and _admissible(ab, rho0, trial, xf, now, short, loose, geo, lo, hi, poly):
        best_c, best_st, found = c, st, True
        put(best, xf)
    centre, normal = _best_plane(ab, used)
    for start in (xf, x):
        _reflect(start, centre, normal, xt)
        _outside(xt, lo, hi, poly)
        c, st, it = lm_solve(ab, trial, xt, lo, hi, True, poly, max_iter, xtol, ftol, gtol,
                             *work)  # fmt: skip
        iters += it
        if c < best_c and _admissible(ab, rho0, trial, xt, now, short, loose, geo, lo, hi,
                                      poly):  # fmt: skip
            best_c, best_st, found = c, st, True
            put(best, xt)
    if not found:
        return T, iters
    put(x, best)
    fst[0] = best_st
    return 2.0 * best_c / (sigma * sigma), iters


@numba.njit(**NO_REFCOUNT)
def _admissible(ab, rho0, kept, p, now, short, loose, geo, lo, hi, poly) -> bool:
    # pragma: no cover - compiled
    """Whether the candidate p (3,) of :func:`_off_the_boundary` (on the ranges kept (M,))
    lies strictly inside the room (:func:`_inside`) and nothing contradicts it more than
    the ``now`` contradictions of the fix it would replace (:func:`_contradictions`)."""
    return _inside(p, lo, hi, poly) and _contradictions(ab, rho0, kept, p, short, loose, geo,
                                                        now) <= now  # fmt: skip


@numba.njit(cache=True)
def _best_plane(ab, used):  # pragma: no cover - compiled
    """(centroid (3,), unit normal (3,)) of the plane that fits the anchors ``used`` (M,)
    of ab (M, 3) best in least squares: the normal is the eigenvector of the smallest
    eigenvalue of their scatter matrix."""
    n, centre = 0, np.zeros(3)
    for j in range(ab.shape[0]):
        if used[j]:
            n += 1
            centre += ab[j]
    centre /= n
    scatter = np.zeros((3, 3))
    for j in range(ab.shape[0]):
        if used[j]:
            d = ab[j] - centre
            scatter += np.outer(d, d)
    return centre, np.linalg.eigh(scatter)[1][:, 0].copy()


@numba.njit(cache=True, inline="always")
def _reflect(p, centre, normal, out) -> None:  # pragma: no cover - compiled
    """out (3,): the mirror image of p (3,) across the plane through ``centre`` (3,) with
    the unit ``normal`` (3,)."""
    d = 2.0 * ((p[0] - centre[0]) * normal[0] + (p[1] - centre[1]) * normal[1]
               + (p[2] - centre[2]) * normal[2])  # fmt: skip
    for k in range(3):
        out[k] = p[k] - d * normal[k]


@numba.njit(**NO_REFCOUNT)
def _inside(x, lo, hi, poly) -> bool:  # pragma: no cover - compiled
    """Whether x (3,) lies strictly inside the box [lo, hi] and the floor plan ``poly``
    (K, 2) (none with K = 0): farther than :data:`HELD` from their boundaries."""
    for k in range(3):
        if not (x[k] - lo[k] > HELD and hi[k] - x[k] > HELD):
            return False
    if poly.shape[0] < 3:
        return True
    return inside_floor_plan(x[0], x[1], poly) and nearest_on_boundary(
        x[0], x[1], poly)[0] > HELD * HELD  # fmt: skip


@numba.njit(**NO_REFCOUNT)
def _drop_one(ab, rho, x, score, trial, xt, xb, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
              sigma, passes, work):  # fmt: skip  # pragma: no cover - compiled
    """Step 3 of the module docstring once, from the fix x (3,) on the ranges rho (M,): the
    :data:`CANDIDATES` anchors of the largest deleted residuals each left out and solved
    again, the largest first, until one leaves a T within ``passes`` (the test's threshold
    with one anchor fewer) (``score``, ``trial``, ``xt``: scratch); returns (T, anchor,
    status, iterations)
    of the best, its fix in xb (3,) (anchor −1: none to leave out)."""
    _deleted_residuals(x, ab, rho, score, work[0], work[1])
    best_T, best_j, best_st, iters = math.inf, -1, 0, 0
    for _ in range(CANDIDATES):
        j = _argmax_finite(score)
        if j < 0:
            break
        score[j] = -math.inf
        put(trial, rho)
        trial[j] = np.nan
        put(xt, x)
        c, st, it = _solve(ab, trial, xt, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, work)
        iters += it
        Tj = 2.0 * c / (sigma * sigma)
        if Tj < best_T:
            best_T, best_j, best_st = Tj, j, st
            put(xb, xt)
        if best_T <= passes:  # the test passes without it: the next candidates are not tried
            break
    return best_T, best_j, best_st, iters


@numba.njit(cache=True)
def _consensus(ab, rho0, x, T, n, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
               sigma, thr, loose, short, used, work, geo, fst):  # fmt: skip  # pragma: no cover
    """Step 4 of the module docstring for the ranges rho0 (M,) of anchors ab (M, 3): the
    minimal sets of 4 heard anchors in the order of :func:`_order_key`, each a hypothesis
    scored by its short ranges and its inliers (:func:`_score`); a promising one is refined
    (:func:`_refine`) and checked on the map ``geo`` (:func:`_contradictions`), and the
    first refined set that passes the test with no contradiction ends the search
    (``loose``, ``short``: :data:`LOOSE`, :data:`SHORT` in metres). On success x (3,) and
    used (M,) hold the best refined fix and its anchors, fst (1,) the status of the solve
    that gave it; returns (T, n, iterations)."""
    M = rho0.shape[0]
    h = 0
    for j in range(M):
        h += rho0[j] == rho0[j]
    if h < 5:
        return T, n, iters
    order = np.argsort(_order_key(ab, rho0, short))
    c = np.arange(4)
    trial, xt, xm, best_x = np.empty(M), np.empty(3), np.empty(3), np.empty(3)
    best_short, best_in, best_T, best_st = INFINITE, 0, T, 0
    four = np.empty(M)  # the best minimal set's fix, contradictions, T, status and ranges
    four_x, four_short, four_ev, four_T, four_st = np.empty(3), INFINITE, 0.0, math.inf, 0
    # minimal sets met before any uncontradicted set of 5: solved only if none is found
    # (their anchors, linear fixes and short ranges; :func:`_settle`)
    cap = min(HYPOTHESES, h * (h - 1) * (h - 2) * (h - 3) // 24)
    pend, pend_x = np.empty((cap, 4), np.int64), np.empty((cap, 3))
    pend_short, npend = np.empty(cap, np.int64), 0
    for t in range(MORE_HYPOTHESES):
        if t == HYPOTHESES:  # the rule below reads the best minimal set: settle it now
            four_short, four_ev, four_T, iters, four_st = _settle(
                ab, rho0, pend, pend_x, pend_short, npend, xt, xm, trial, four, four_x,
                four_short, four_ev, four_T, four_st, iters, lo, hi, bounded, poly, max_iter, xtol,
                ftol, gtol, sigma, short, loose, work, geo,
            )  # fmt: skip
            npend = 0
        if t >= HYPOTHESES and (best_short == 0 or (t >= FOUR_HYPOTHESES and four_short == 0
                                                    and four_T + four_ev <= thr[1])):  # fmt: skip
            break  # something uncontradicted: search no further
        fill(trial, np.nan)
        for i in range(4):
            trial[order[c[i]]] = rho0[order[c[i]]]
        iters += _minimal_fix(ab, rho0, trial, x, xt, xm, lo, hi, bounded, poly, max_iter,
                              xtol, ftol, gtol, loose, short, work)  # fmt: skip
        inl, nshort = _score(ab, rho0, xt, loose, max(loose, short))
        nshort *= M + 1  # as _contradictions counts them
        if best_short > 0 and t < HYPOTHESES:  # no uncontradicted set of 5 yet: for later
            npend = _put_off(pend, pend_x, pend_short, npend, order, c, xt, nshort)
        elif best_short > 0 and nshort <= four_short:
            four_short, four_ev, four_T, iters, four_st = _minimal(
                ab, rho0, xt, xm, trial, four, four_x, four_short, four_ev, four_T, four_st, iters,
                lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma, short, loose, work,
                geo,
            )  # fmt: skip
        if inl >= 5 and _better(nshort, inl, best_short, best_in):
            best_short, best_in, best_T, best_st, iters, done = _promising(
                ab, rho0, xt, trial, best_x, used, best_short, best_in, best_T, best_st, iters,
                lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma, thr, loose, short,
                work, geo,
            )  # fmt: skip
            if done:
                break
        if not _next_colex(c, h):
            break
    if best_in >= 5 and best_short == 0:
        put(x, best_x)
        fst[0] = best_st
        return best_T, best_in, iters
    four_short, four_ev, four_T, iters, four_st = _settle(
        ab, rho0, pend, pend_x, pend_short, npend, xt, xm, trial, four, four_x, four_short,
        four_ev, four_T, four_st, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma,
        short, loose, work, geo,
    )  # fmt: skip
    T, n, iters, now = _fallback(ab, rho0, x, T, n, iters, best_x, best_short, best_in, best_T,
                                 best_st, four, four_x, four_short, four_ev, four_T, four_st,
                                 used, fst, trial, short, loose, geo, lo, hi, poly)  # fmt: skip
    if now > 0 and _triples(ab, rho0, x, now, order, h, trial, xt, xm, best_x, short, loose,
                            geo, lo, hi, poly):  # fmt: skip
        return _on_three(ab, trial, x, used, fst, iters, lo, hi, bounded, poly, max_iter, xtol,
                         ftol, gtol, sigma, work)  # fmt: skip
    return T, n, iters


@numba.njit(**NO_REFCOUNT)
def _on_three(ab, trial, x, used, fst, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
              sigma, work):  # fmt: skip  # pragma: no cover - compiled
    """The fix x (3,) solved by least squares on the 3 ranges in trial (M,) that
    :func:`_triples` chose (used (M,) their anchors, fst (1,) the solve's status); returns
    (T, 3, iterations)."""
    for j in range(used.shape[0]):
        used[j] = trial[j] == trial[j]
    c3, fst[0], it = lm_solve(ab, trial, x, lo, hi, bounded, poly, min(max_iter, SUBSET_ITER),
                              xtol, ftol, gtol, *work)  # fmt: skip
    return 2.0 * c3 / (sigma * sigma), 3, iters + it


@numba.njit(cache=True, inline="always")
def _clamp(x, lo, hi) -> None:  # pragma: no cover - compiled
    """In place: x (3,) into the box [lo, hi]."""
    for k in range(3):
        x[k] = min(max(x[k], lo[k]), hi[k])


@numba.njit(**NO_REFCOUNT)
def _minimal_fix(ab, rho0, trial, x, xt, xm, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
                 loose, short, work) -> int:  # fmt: skip  # pragma: no cover - compiled
    """xt (3,) the fix of a minimal set (its ranges in trial (M,)) in the box [lo, hi]: the
    linear solution of its squared-range differences; where its anchors are nearly
    coplanar (:data:`FLAT`), that solution polished by :data:`POLISH_ITER` iterations of
    least squares on the set's ranges (off their plane it is ill-conditioned); where they
    are coplanar, the better of the two mirror images (:func:`_mirror_fix`); where they are
    collinear, solved from the fit so far x (3,) (xm (3,): scratch). Returns the
    iterations of the solves."""
    iters = 0
    eq = normal_equations(ab, trial)  # built once: a coplanar set's mirror images need it too
    flat = flatness(eq, xt, COPLANAR)
    if flat > COPLANAR:
        if flat <= FLAT:  # nearly coplanar: polished
            _outside(xt, lo, hi, poly)
            iters = lm_solve(ab, trial, xt, lo, hi, bounded, poly, min(max_iter, POLISH_ITER),
                             xtol, ftol, gtol, *work)[2]  # fmt: skip
    elif not _mirror_fix(eq, ab, rho0, trial, xt, xm, lo, hi, poly, loose, short):
        put(xt, x)  # collinear: from the fit so far
        iters = lm_solve(ab, trial, xt, lo, hi, bounded, poly, min(max_iter, SUBSET_ITER), xtol,
                         ftol, gtol, *work)[2]  # fmt: skip
    _clamp(xt, lo, hi)
    return iters


@numba.njit(**NO_REFCOUNT)
def _mirror_fix(eq, ab, rho0, trial, xt, xm, lo, hi, poly, loose, short) -> bool:
    # pragma: no cover - compiled
    """xt (3,) the fix of a minimal set of coplanar anchors (its ranges in trial (M,), its
    normal equations ``eq``), which have no linear solution off their plane: of the two
    mirror images in their plane (:func:`simulation.least_squares.mirror_fixes`), each
    moved into the box [lo, hi] and the floor plan ``poly``, the one that fewer ranges of
    rho0 (M,) contradict, then not moved by more than
    ``loose`` m (anchors on a ceiling or a wall put one image outside the room, and moved
    into it that image fits its ranges no more), then with more inliers (:func:`_score`),
    then that moved less (xm (3,): scratch). False: the anchors are collinear."""
    if not mirrors(eq, ab, trial, xt, xm, OFF_PLANE):
        return False
    out_t, out_m = _outside(xt, lo, hi, poly), _outside(xm, lo, hi, poly)
    in_t, short_t = _score(ab, rho0, xt, loose, max(loose, short))
    in_m, short_m = _score(ab, rho0, xm, loose, max(loose, short))
    # an image moved into the room by more than ``loose`` no longer fits the set's ranges
    if (short_m, out_m > loose, -in_m, out_m) < (short_t, out_t > loose, -in_t, out_t):
        put(xt, xm)
    return True


@numba.njit(**NO_REFCOUNT)
def _outside(x, lo, hi, poly) -> float:  # pragma: no cover - compiled
    """In place: x (3,) moved into the box [lo, hi] and the floor plan ``poly`` (K, 2)
    (none with K = 0); returns how far it moved (m)."""
    x0, x1, x2 = x[0], x[1], x[2]
    _clamp(x, lo, hi)
    if poly.shape[0] >= 3:
        into_floor_plan(x, poly)
    return math.sqrt((x[0] - x0) ** 2 + (x[1] - x1) ** 2 + (x[2] - x2) ** 2)


@numba.njit(**NO_REFCOUNT)
def _fallback(ab, rho0, x, T, n, iters, best_x, best_short, best_in, best_T, best_st, four,
              four_x, four_short, four_ev, four_T, four_st, used, fst, trial, short, loose,
              geo, lo, hi, poly):  # fmt: skip  # pragma: no cover - compiled
    """The end of step 4 where no 5 anchors agree without a contradiction: the fix is the
    best refined set of 5 that something contradicts (best_x (3,), its contradictions,
    anchors, T and status), else the fix so far x (3,) (its T, n anchors ``used`` (M,));
    the best minimal set (its ranges in four (M,), fix four_x (3,), contradictions,
    penalty, T and status) replaces it when its 4 ranges agree and it is less contradicted,
    or as little and with a smaller T plus penalty (:func:`_ranked`, in the box [lo, hi] and
    the floor plan ``poly``; ``trial`` (M,): scratch). Returns (T, n, iterations, the
    contradictions of the fix)."""
    if best_in >= 5:
        now, T, n, ev = best_short, best_T, best_in, 0.0  # a set of 5 that something contradicts
        put(x, best_x)
        fst[0] = best_st
    else:
        for j in range(used.shape[0]):
            trial[j] = rho0[j] if used[j] else np.nan
        now, ev = _ranked(ab, rho0, trial, x, short, loose, geo, INFINITE, lo, hi, poly)
    rests = four_short < now or (four_short == now == 0 and four_T + four_ev < T + ev)
    if four_T <= MINIMAL_T and rests:
        put(x, four_x)  # no consistent set of 5: a consistent minimal set less contradicted
        fst[0] = four_st
        for j in range(used.shape[0]):
            used[j] = four[j] == four[j]
        return four_T, 4, iters, four_short
    return T, n, iters, now


@numba.njit(cache=True)
def _triples(ab, rho0, x, now, order, h, trial, xt, xm, xb, short, loose, geo, lo, hi, poly):
    # pragma: no cover - compiled
    """Step 4's last resort, where every fix of 4 or more anchors is contradicted (the fix
    so far x (3,), ``now`` contradictions): the tag may see only 3 anchors, which fix two
    mirror images in their plane (:func:`simulation.least_squares.mirror_fixes`), the
    others' ranges echoes. Of the images of every 3 heard anchors (the first h of
    ``order``, nearest ranges first), each moved into the box [lo, hi] and the floor plan
    ``poly``, the one least contradicted (:func:`_ranked`: an echo range shorter than its
    distance, one of the 3 hidden from it on the map, an anchor that surely sees it with
    an echo range), then with the smaller penalty, replaces x when it is less contradicted
    than x; its 3 ranges are then in trial (M,) (xt, xm, xb (3,): scratch). Returns
    whether it did."""
    # a short range counts M + 1 and the map at most M: only the images with the fewest
    # short ranges can rank first, and the map is read for those alone
    M = ab.shape[0]
    c, chosen = np.arange(3), np.empty(3, np.int64)
    fewest = INFINITE
    for _ in range(TRIPLES):
        if _images(ab, rho0, order, c, trial, xt, xm, lo, hi, poly):
            fewest = min(fewest, _score(ab, rho0, xt, 0.0, short)[1],
                         _score(ab, rho0, xm, 0.0, short)[1])  # fmt: skip
        if not _next_colex(c, h):
            break
    if fewest * (M + 1) >= now:
        return False
    best, best_ev, found = now, math.inf, False
    c[:] = np.arange(3)
    for _ in range(TRIPLES):
        if _images(ab, rho0, order, c, trial, xt, xm, lo, hi, poly):
            for image in range(2):
                p = xt if image == 0 else xm
                if _score(ab, rho0, p, 0.0, short)[1] > fewest:
                    continue
                nshort, ev = _ranked(ab, rho0, trial, p, short, loose, geo, best, lo, hi, poly)
                if nshort < best or (nshort == best and found and ev < best_ev):
                    best, best_ev, found = nshort, ev, True
                    put(xb, p)
                    for i in range(3):
                        chosen[i] = order[c[i]]
        if not _next_colex(c, h):
            break
    if not found:
        return False
    fill(trial, np.nan)
    for i in range(3):
        trial[chosen[i]] = rho0[chosen[i]]
    put(x, xb)
    return True


@numba.njit(**NO_REFCOUNT)
def _images(ab, rho0, order, c, trial, xt, xm, lo, hi, poly) -> bool:
    # pragma: no cover - compiled
    """trial (M,) the ranges of rho0 (M,) of the anchors order[c] (c (3,)) and xt, xm (3,)
    the two mirror images they fix (:func:`simulation.least_squares.mirror_fixes`), each
    moved into the box [lo, hi] and the floor plan ``poly``; False: the 3 are collinear."""
    fill(trial, np.nan)
    for i in range(3):
        trial[order[c[i]]] = rho0[order[c[i]]]
    if not mirrors(normal_equations(ab, trial), ab, trial, xt, xm, 0.0):
        return False
    _outside(xt, lo, hi, poly)
    _outside(xm, lo, hi, poly)
    return True


@numba.njit(cache=True)
def _order_key(ab, rho0, short):  # pragma: no cover - compiled
    """(M,) the order of the anchors in the minimal sets: their ranges, those proved
    echoes by more than ``short`` m (:func:`_proved_echo`) after all the others (inf for
    the unheard)."""
    M = rho0.shape[0]
    key = np.full(M, np.inf)
    top = 0.0
    for j in range(M):
        if rho0[j] == rho0[j]:
            top = max(top, rho0[j])
    for j in range(M):
        if rho0[j] != rho0[j]:
            continue
        key[j] = rho0[j]
        if _proved_echo(ab, rho0, j, short):
            key[j] += top + 1.0  # after every range not known to be an echo
    return key


@numba.njit(**NO_REFCOUNT)
def _proved_echo(ab, rho, j, margin) -> bool:  # pragma: no cover - compiled
    """Whether the heard range rho[j] is proved an echo: an echo only lengthens a range, so
    r_j − r_k − |a_j − a_k| bounds its excess over the distance from below for every heard
    k (the triangle inequality); true when that bound exceeds ``margin`` (m) for some k."""
    for k in range(rho.shape[0]):
        if rho[k] == rho[k] and rho[j] - rho[k] - _distance(ab[j], ab[k]) > margin:
            return True
    return False


@numba.njit(cache=True, inline="always")
def _put_off(pend, pend_x, pend_short, npend, order, c, xt, nshort) -> int:
    # pragma: no cover - compiled
    """Row ``npend`` of pend, pend_x, pend_short (:func:`_settle`): the minimal set's
    anchors order[c] (4,), its linear fix xt (3,) and its short ranges; returns npend + 1."""
    for i in range(4):
        pend[npend, i] = order[c[i]]
    pend_x[npend] = xt
    pend_short[npend] = nshort
    return npend + 1


@numba.njit(**NO_REFCOUNT)
def _promising(ab, rho0, xt, trial, best_x, used, best_short, best_in, best_T, best_st, iters,
               lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma, thr, loose, short,
               work, geo):  # fmt: skip  # pragma: no cover - compiled
    """A promising hypothesis of :func:`_consensus` (its linear fix in xt (3,), its ranges
    in trial (M,)) refined (:func:`_refine`) and checked on the map; when it beats the best
    refined set so far (fewer contradictions, then more anchors), best_x (3,) and ``used``
    (M,) take it. Returns the best's (contradictions, anchors, T, status), the iterations
    and whether it ends the search (5 or more anchors pass the test, nothing contradicts)."""
    Tk, m, it, st = _refine(ab, rho0, xt, trial, loose, 3.0 * sigma, lo, hi, bounded, poly,
                            max_iter, xtol, ftol, gtol, sigma, work)  # fmt: skip
    iters += it
    # with no more anchors than the best's, only fewer contradictions win
    bound = best_short if m > best_in else best_short - 1
    nshort = _contradictions(ab, rho0, trial, xt, short, loose, geo, bound)
    if not (m >= 5 and _better(nshort, m, best_short, best_in)):
        return best_short, best_in, best_T, best_st, iters, False
    put(best_x, xt)
    for j in range(used.shape[0]):
        used[j] = trial[j] == trial[j]
    return nshort, m, Tk, st, iters, nshort == 0 and Tk <= thr[m - 3]


@numba.njit(**NO_REFCOUNT)
def _settle(ab, rho0, pend, pend_x, pend_short, npend, xt, xm, trial, four, four_x, four_short,
            four_ev, four_T, four_st, iters, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol,
            sigma, short, loose, work, geo):  # fmt: skip  # pragma: no cover - compiled
    """The minimal sets put off by :func:`_consensus` (their anchors pend (K, 4), linear
    fixes pend_x (K, 3) and short-range counts pend_short (K,), the first ``npend``), each
    passed to :func:`_minimal` in the order they were met when its short ranges are no more
    than the best's so far, as the search would have done on meeting them (``xt``,
    ``trial``: scratch); returns the best's (contradictions, penalty, T, iterations,
    status)."""
    for p in range(npend):
        if pend_short[p] > four_short:
            continue
        fill(trial, np.nan)
        for i in range(4):
            trial[pend[p, i]] = rho0[pend[p, i]]
        put(xt, pend_x[p])
        four_short, four_ev, four_T, iters, four_st = _minimal(
            ab, rho0, xt, xm, trial, four, four_x, four_short, four_ev, four_T, four_st, iters, lo,
            hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma, short, loose, work, geo,
        )  # fmt: skip
    return four_short, four_ev, four_T, iters, four_st


@numba.njit(**NO_REFCOUNT)
def _minimal(ab, rho0, xt, xm, trial, four, four_x, four_short, four_ev, four_T, four_st, iters,
             lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, sigma, short, loose, work,
             geo):  # fmt: skip  # pragma: no cover
    """A minimal set (its ranges in trial (M,), its linear fix in xt (3,)) solved by least
    squares from xt into the scratch xm (3,); kept in four (M,) and four_x (3,) when it has
    fewer contradictions than the best minimal set so far, or as few and a smaller T plus
    penalty (:func:`_ranked`); returns the best's (contradictions, penalty, T, iterations,
    the status of its solve)."""
    put(xm, xt)
    c, st, it = lm_solve(ab, trial, xm, lo, hi, bounded, poly, min(max_iter, SUBSET_ITER),
                         xtol, ftol, gtol, *work)  # fmt: skip
    Tm = 2.0 * c / (sigma * sigma)
    if four_short == 0 and Tm >= four_T + four_ev:
        # the best so far is uncontradicted and its T plus penalty no larger: contradictions
        # and penalty only add, so this set cannot rank before it (the map is not read)
        return four_short, four_ev, four_T, iters + it, four_st
    nshort, ev = _ranked(ab, rho0, trial, xm, short, loose, geo, four_short, lo, hi, poly)
    if (nshort, Tm + ev) < (four_short, four_T + four_ev):
        put(four, trial)
        put(four_x, xm)
        return nshort, ev, Tm, iters + it, st
    return four_short, four_ev, four_T, iters + it, four_st


@numba.njit(**NO_REFCOUNT)
def _ranked(ab, rho0, kept, x, short, long, geo, bound, lo, hi, poly):  # pragma: no cover
    """(contradictions, penalty) of the fix x (3,) on the ranges kept (M,)
    (:func:`_contradictions`, counting stopped above ``bound``): as contradicted fixes rank
    by T plus the penalty, :data:`MISS_PENALTY` for each miss forgiven (an anchor that
    the map says sees x with a long range) and :data:`HELD_PENALTY` for a fix held at the
    room's boundary (as a mirror image is)."""
    n, miss = _map_evidence(ab, rho0, kept, x, short, long, geo, bound + MISSES)
    penalty = MISS_PENALTY * min(miss, MISSES) + HELD_PENALTY * _held(x, lo, hi, poly)
    return n + max(miss - MISSES, 0), penalty


@numba.njit(**NO_REFCOUNT)
def _held(x, lo, hi, poly) -> int:  # pragma: no cover - compiled
    """1 when x (3,) lies on the boundary of the box [lo, hi] or of the floor plan ``poly``
    (K, 2) (within :data:`HELD`), else 0."""
    for k in range(3):
        if x[k] - lo[k] <= HELD or hi[k] - x[k] <= HELD:
            return 1
    if poly.shape[0] >= 3 and nearest_on_boundary(x[0], x[1], poly)[0] <= HELD * HELD:
        return 1
    return 0


@numba.njit(cache=True, inline="always")
def _solve(ab, rho, x, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, work):
    # pragma: no cover - compiled
    """:func:`simulation.least_squares.lm_solve` compiled into its caller, the scratch
    ``work`` (:func:`simulation.least_squares.scratch`) unpacked there: the same results,
    faster. Used by the step made most often (dropping an anchor); the other steps call
    ``lm_solve``, which keeps the search quick to compile."""
    r, u, rn, un, xn, step, free = work
    return lm_solve_inline(ab, rho, x, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, r, u,
                           rn, un, xn, step, free)  # fmt: skip


@numba.njit(cache=True, inline="always")
def _better(nshort, inl, best_short, best_in) -> bool:  # pragma: no cover - compiled
    """Fewer contradictions, then more inliers."""
    return nshort < best_short or (nshort == best_short and inl > best_in)


@numba.njit(**NO_REFCOUNT)
def _refine(ab, rho0, x, trial, loose, tight, lo, hi, bounded, poly, max_iter, xtol, ftol,
            gtol, sigma, work):  # fmt: skip  # pragma: no cover - compiled
    """In place on x (3,): the least-squares fix on the anchors whose range is within
    ``loose`` m of x's distance, then on those within ``tight`` m of the new fix (trial
    (M,) ends holding their ranges, NaN elsewhere); returns (T, anchors, iterations, the
    status of the last solve)."""
    iters, T, st = 0, math.inf, 0
    for tol in (loose, tight):
        m = _inliers(ab, rho0, x, tol, trial)
        if m < 5:
            return T, m, iters, st
        c, st, it = lm_solve(ab, trial, x, lo, hi, bounded, poly, min(max_iter, SUBSET_ITER),
                             xtol, ftol, gtol, *work)  # fmt: skip
        iters += it
        T = 2.0 * c / (sigma * sigma)
    return T, m, iters, st


@numba.njit(**NO_REFCOUNT)
def _score(ab, rho0, x, tol, short) -> tuple[int, int]:  # pragma: no cover - compiled
    """(inliers, contradictions) of the position x (3,): the heard anchors whose range is
    within ``tol`` m of their distance, and those whose range is shorter than their
    distance by more than ``short`` m (no path is shorter than the direct one)."""
    inl = nshort = 0
    for j in range(ab.shape[0]):
        if rho0[j] == rho0[j]:
            e = _distance(x, ab[j]) - rho0[j]
            inl += abs(e) <= tol
            nshort += e > short
    return inl, nshort


@numba.njit(**NO_REFCOUNT)
def _contradictions(ab, rho0, kept, x, short, long, geo, bound) -> int:  # pragma: no cover
    """How much contradicts the fix x (3,) that rests on the ranges kept (M,) (NaN: not
    kept; module docstring): each range of rho0 (M,) shorter than its distance by more
    than ``short`` m counts M + 1 (no path is shorter than the direct one: it outweighs
    whatever the map says), and on the map ``geo`` each kept anchor that does not see x
    and each anchor beyond the first :data:`MISSES` that surely sees x with a range longer
    than its distance by more than ``long`` m counts 1 (:func:`_map_evidence`). Counting
    stops above ``bound``."""
    n, miss = _map_evidence(ab, rho0, kept, x, short, long, geo, bound)
    return n + max(miss - MISSES, 0)


@numba.njit(**NO_REFCOUNT)
def _map_evidence(ab, rho0, kept, x, short, long, geo, bound):  # pragma: no cover - compiled
    """(contradictions before the misses, misses) of the fix x (3,) on the ranges kept
    (M,): the first counts the short ranges (M + 1 each) and the kept anchors that do not
    see x on the map ``geo``; the second, the anchors not kept that surely see x with a
    range longer than its distance by more than ``long`` m (:func:`_contradictions` forgives
    the first :data:`MISSES`). Counting stops once their sum less MISSES exceeds
    ``bound``."""
    M = ab.shape[0]
    n = _score(ab, rho0, x, 0.0, short)[1] * (M + 1)
    if n > bound or geo[0].shape[0] == 0:
        return n, 0
    for j in range(M):
        if kept[j] == kept[j] and not _sees(geo, x, ab, j, False):
            n += 1
            if n > bound:
                return n, 0
    miss = 0
    for j in range(M):
        if (kept[j] != kept[j] and rho0[j] - _distance(x, ab[j]) > long
                and _sees(geo, x, ab, j, True)):  # fmt: skip
            miss += 1
            if n + miss - MISSES > bound:
                break
    return n, miss


@numba.njit(cache=True, inline="always")
def row_map(geo, front):  # pragma: no cover - compiled
    """The map of one layout's rows: the room's map ``geo``
    (:func:`simulation.polyhedral.blocking_map`) and, after it, the faces each anchor
    faces, front (M, F) (:func:`simulation.polyhedral.facing`)."""
    return (geo[0], geo[1], geo[2], geo[3], geo[4], geo[5], front)


@numba.njit(cache=True, inline="always")
def _sees(geo, x, ab, j, every) -> bool:  # pragma: no cover - compiled
    """Anchor j of ab (M, 3) sees the position x (3,) from one of the points :data:`GRAZE`
    from it (``every`` False) or from all (True) (:func:`simulation.polyhedral.sees_near`);
    ``geo`` the row's map (:func:`row_map`)."""
    return sees_near(geo, x, ab[j], geo[6][j], GRAZE, every)


@numba.njit(**NO_REFCOUNT)
def _inliers(ab, rho0, x, tol, trial) -> int:  # pragma: no cover - compiled
    """trial (M,): the ranges of rho0 (M,) within ``tol`` m of their anchor's distance from
    x (3,), NaN elsewhere; returns how many."""
    m = 0
    for j in range(ab.shape[0]):
        trial[j] = np.nan
        if rho0[j] == rho0[j] and abs(_distance(x, ab[j]) - rho0[j]) <= tol:
            trial[j] = rho0[j]
            m += 1
    return m


@numba.njit(cache=True, inline="always")
def _distance(x, a) -> float:  # pragma: no cover - compiled
    return math.sqrt((x[0] - a[0]) ** 2 + (x[1] - a[1]) ** 2 + (x[2] - a[2]) ** 2)


@numba.njit(**NO_REFCOUNT)
def _next_colex(c, h) -> bool:  # pragma: no cover - compiled
    """In place: the next k-subset c (k,) (increasing indices into 0..h−1) in colexicographic
    order, the subsets of the first indices before any that needs a later one; False after
    the last."""
    k = c.shape[0]
    for i in range(k):
        top = c[i + 1] if i + 1 < k else h
        if c[i] + 1 < top:
            c[i] += 1
            for m in range(i):
                c[m] = m
            return True
    return False


@numba.njit(**NO_REFCOUNT)
def _quality(ab, rho0, used, x, T, n, thr, bias, alert, rho, work) -> int:  # pragma: no cover
    """:data:`VERIFIED` when the n anchors ``used`` (M,) pass the test (T ≤ thr[n − 3],
    n ≥ 5), fix x (3,) (position dilution of precision ≤ :data:`DOP_MAX`) and keep the echo
    the test misses within ``alert`` m (:func:`_largest_slope` times ``bias`` = σ √λ, m),
    else :data:`UNVERIFIED`; rho (M,) is scratch."""
    if not (T <= thr[n - 3] and n >= 5):
        return UNVERIFIED
    for j in range(rho0.shape[0]):
        rho[j] = rho0[j] if used[j] else np.nan
    u = work[1]
    residuals(x, ab, rho, work[0], u)  # the unit vectors U from the anchors kept to x
    c, det = cofactors(gram_gradient(work[0], u)[0])
    # √tr((UᵀU)⁻¹): inf when the anchors do not fix x (collinear)
    dop = math.sqrt((c[0] + c[3] + c[5]) / det) if det > 0 else math.inf
    if dop > DOP_MAX:
        return UNVERIFIED
    return VERIFIED if bias * _largest_slope(rho, u, c, det) <= alert else UNVERIFIED


@numba.njit(**NO_REFCOUNT)
def _largest_slope(rho, u, c, det) -> float:  # pragma: no cover - compiled
    """max_j ‖k_j‖ / √(1 − h_jj) over the anchors whose range in rho (M,) is not NaN: the
    move of the fix per unit of test statistic √ΔT·σ that a bias on range j causes
    (k_j = (UᵀU)⁻¹u_j, h_jj = u_jᵀk_j; u (M, 3) the unit vectors U to the fix, c and det
    the cofactors and determinant of UᵀU, :func:`simulation.least_squares.cofactors`); inf
    when they do not fix it."""
    if not det > 0:
        return math.inf
    worst = 0.0
    for j in range(u.shape[0]):
        if rho[j] != rho[j]:
            continue
        a0, a1, a2 = adjugate_times(c, u[j, 0], u[j, 1], u[j, 2])
        k0, k1, k2 = a0 / det, a1 / det, a2 / det
        free = 1.0 - (u[j, 0] * k0 + u[j, 1] * k1 + u[j, 2] * k2)
        if not free > 1e-12:  # the anchor alone fixes a direction: no echo on it shows
            return math.inf
        worst = max(worst, math.sqrt((k0 * k0 + k1 * k1 + k2 * k2) / free))
    return worst


@numba.njit(**NO_REFCOUNT)
def _deleted_residuals(x, ab, rho, score, r, u):  # pragma: no cover - compiled
    """score (M,): r_j² / (1 − h_jj) of every heard anchor at x (−inf for the others), h_jj
    the leverage u_jᵀ (UᵀU)⁻¹ u_j of the unit vectors u_j from the anchors to x."""
    residuals(x, ab, rho, r, u)
    c, det = cofactors(gram_gradient(r, u)[0])
    for j in range(ab.shape[0]):
        if rho[j] != rho[j]:
            score[j] = -math.inf
            continue
        u0, u1, u2 = u[j, 0], u[j, 1], u[j, 2]
        h = 0.0
        if det > 0:
            a0, a1, a2 = adjugate_times(c, u0, u1, u2)
            h = (u0 * a0 + u1 * a1 + u2 * a2) / det
        score[j] = r[j] * r[j] / max(1.0 - h, 1e-9)


@numba.njit(**NO_REFCOUNT)
def _argmax_finite(v) -> int:  # pragma: no cover - compiled
    """The index of the largest finite entry of v, −1 when there is none."""
    best, k = -math.inf, -1
    for j in range(v.shape[0]):
        if v[j] > best:
            best, k = v[j], j
    return k

"""The compiled damped Gauss–Newton (Levenberg–Marquardt) solve of one position from
ranges, shared by the least-squares and the robust positioning (docs/model.md,
"Positioning").

For ranges ρ (M,) of anchors a (M, 3) (NaN: not heard, left out of the sums), minimize
F(x) = ½ Σ_j (‖x − a_j‖ − ρ_j)² with Nielsen's damping update, explicit 3 × 3 solves and
a fixed iteration limit. Bounded (``bounded``): a coordinate at a face of the box [lo, hi]
whose descent direction points out of it is held there while the others take the damped
step of their own block (an active set); every step is projected onto the box and, with a
floor plan (``poly`` (K, 2), K ≥ 3 corners, counter-clockwise), onto the floor plan: a
position in a cut-out corner of an L-shaped room is not in the room.

Statuses (modelled on scipy ``least_squares``): 1 gradient small, 2 cost change small,
3 step small, 4 zero residual, 0 iteration limit.

The solve's helpers are compiled into it, and the solve into :func:`lm_rows` and the robust
search's dropping step (:func:`lm_solve_inline`, numba's ``inline="always"``; an inlined
function takes its arguments one by one, no ``*args``): the loop then knows the scratch
arrays apart and runs faster, with the same floating-point operations in the same order
(the same results, bit for bit).
"""

from __future__ import annotations

import math

import numba
import numpy as np


def _without_refcounts() -> dict:
    """numba's options of a compiled function that creates no array: compiled without
    numba's reference counting (its option ``_nrt``, which numba documents only for its own
    use), where this numba knows that option; else with it (the same results, slower).

    With reference counts, every call of a compiled function counts each array it is passed
    up on entry and down on exit, atomically: across the robust search's many small calls,
    that counting was the largest part of a fix that was not arithmetic (BENCHMARKS.md,
    "Positioning that rejects echoes without reference counts"). Such a function neither
    creates an array nor assigns a slice (:func:`put`, :func:`fill`); the arrays it is
    passed are its callers'."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:  # numba moved its options: keep the reference counts
        CPUTargetOptions = None
    return {"cache": True, "_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {"cache": True}


#: the options of :func:`_without_refcounts`
NO_REFCOUNT = _without_refcounts()


@numba.njit(cache=True, inline="always")
def put(dst, src) -> None:  # pragma: no cover - compiled
    """dst[:] = src (1-D), element by element: a function compiled with
    :data:`NO_REFCOUNT` assigns no slice."""
    for k in range(dst.shape[0]):
        dst[k] = src[k]


@numba.njit(cache=True, inline="always")
def fill(dst, v) -> None:  # pragma: no cover - compiled
    """dst[:] = v (1-D), element by element (:func:`put`)."""
    for k in range(dst.shape[0]):
        dst[k] = v


@numba.njit(cache=True, inline="always")
def residuals(x, a, rho, r, u):  # pragma: no cover - compiled
    """Residuals r (M,) and unit vectors u (M, 3) from the anchors a (M, 3) to the point
    x (3,) for ranges rho (M,); returns ½Σr²."""
    cost = 0.0
    for j in range(a.shape[0]):
        if rho[j] != rho[j]:  # NaN: not heard, no residual
            r[j] = 0.0
            u[j, 0] = u[j, 1] = u[j, 2] = 0.0
            continue
        d0, d1, d2 = x[0] - a[j, 0], x[1] - a[j, 1], x[2] - a[j, 2]
        dist = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        inv = 1.0 / dist if dist > 0 else 1.0
        r[j] = dist - rho[j]
        u[j, 0], u[j, 1], u[j, 2] = d0 * inv, d1 * inv, d2 * inv
        cost += r[j] * r[j]
    return 0.5 * cost


@numba.njit(cache=True, inline="always")
def gram_gradient(r, u):  # pragma: no cover - compiled
    """JᵀJ as (s00, s01, s02, s11, s12, s22) and Jᵀr as (g0, g1, g2) for the residuals r
    (M,) and their unit vectors u (M, 3) (the Jacobian's rows), in one pass."""
    s00 = s01 = s02 = s11 = s12 = s22 = g0 = g1 = g2 = 0.0
    for j in range(r.shape[0]):
        u0, u1, u2 = u[j, 0], u[j, 1], u[j, 2]
        s00 += u0 * u0
        s01 += u0 * u1
        s02 += u0 * u2
        s11 += u1 * u1
        s12 += u1 * u2
        s22 += u2 * u2
        g0 += r[j] * u0
        g1 += r[j] * u1
        g2 += r[j] * u2
    return (s00, s01, s02, s11, s12, s22), (g0, g1, g2)


@numba.njit(cache=True, inline="always")
def _free_coordinates(x, g, lo, hi, free):  # pragma: no cover - compiled
    """In place: free (3,) False for each coordinate of x held at a bound of [lo, hi]
    because the descent direction −Jᵀr (g = Jᵀr) points out of the box there."""
    for k in range(3):
        free[k] = not ((x[k] <= lo[k] and g[k] > 0) or (x[k] >= hi[k] and g[k] < 0))


@numba.njit(cache=True, inline="always")
def _damped_step(S, g, lam, step, free):  # pragma: no cover - compiled
    """The step (3,) solving (JᵀJ + λI) δ = −Jᵀr by cofactors over the free coordinates
    (a held one, ``free[k]`` False, gets δ_k = 0), from S = JᵀJ and g = Jᵀr
    (:func:`gram_gradient`); returns (g0, g1, g2) = Jᵀr with the held coordinates'
    entries zero (the projected gradient)."""
    s00, s01, s02, s11, s12, s22 = S
    g0, g1, g2 = g
    # a held coordinate leaves the system: its row and column become the identity's
    if not free[0]:
        s00, s01, s02, g0 = 1.0, 0.0, 0.0, 0.0
    if not free[1]:
        s11, s01, s12, g1 = 1.0, 0.0, 0.0, 0.0
    if not free[2]:
        s22, s02, s12, g2 = 1.0, 0.0, 0.0, 0.0
    s00 += lam
    s11 += lam
    s22 += lam
    c00 = s11 * s22 - s12 * s12
    c01 = s02 * s12 - s01 * s22
    c02 = s01 * s12 - s02 * s11
    c11 = s00 * s22 - s02 * s02
    c12 = s01 * s02 - s00 * s12
    c22 = s00 * s11 - s01 * s01
    det = s00 * c00 + s01 * c01 + s02 * c02
    if det == 0:
        det = 2.2250738585072014e-308
    step[0] = -(c00 * g0 + c01 * g1 + c02 * g2) / det
    step[1] = -(c01 * g0 + c11 * g1 + c12 * g2) / det
    step[2] = -(c02 * g0 + c12 * g1 + c22 * g2) / det
    return g0, g1, g2


@numba.njit(cache=True)
def lm_rows(
    a, owner, R, x0, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, xs, costs, status, nit
):  # pragma: no cover - compiled
    """The Levenberg–Marquardt solve (:func:`lm_solve`) of every row: ranges R (B, M),
    layouts a (L, M, 3) with row b's ``owner[b]``, starts x0 (B, 3), bounds lo, hi (B, 3);
    written into xs (B, 3), costs (B,), status (B,) and nit (B,)."""
    x = np.empty(3)
    r, u, rn, un, xn, step, free = scratch(R.shape[1])
    for b in range(R.shape[0]):
        put(x, x0[b])
        cost, st, it = lm_solve_inline(a[owner[b]], R[b], x, lo[b], hi[b], bounded, poly,
                                       max_iter, xtol, ftol, gtol, r, u, rn, un, xn, step,
                                       free)  # fmt: skip
        xs[b] = x
        costs[b], status[b], nit[b] = cost, st, it


@numba.njit(cache=True, inline="always")
def scratch(M):  # pragma: no cover - compiled
    """The scratch arrays of :func:`lm_solve` for M anchors: r, u, rn, un, xn, step, free
    (r, u and rn, un swap roles in a solve: none holds a result after it)."""
    return (np.empty(M), np.empty((M, 3)), np.empty(M), np.empty((M, 3)), np.empty(3),
            np.empty(3), np.ones(3, dtype=np.bool_))  # fmt: skip


@numba.njit(**NO_REFCOUNT)
def lm_solve(
    ab, rho, x, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, r, u, rn, un, xn, step, free
):  # pragma: no cover - compiled
    """Solve one position in place in x (3,) from ranges rho (M,) of anchors ab (M, 3)
    (module docstring; r … free: :func:`scratch`); returns (cost ½Σr², status,
    iterations)."""
    return lm_solve_inline(ab, rho, x, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, r, u,
                           rn, un, xn, step, free)  # fmt: skip


@numba.njit(cache=True, inline="always")
def lm_solve_inline(
    ab, rho, x, lo, hi, bounded, poly, max_iter, xtol, ftol, gtol, r, u, rn, un, xn, step, free
):  # pragma: no cover - compiled
    """:func:`lm_solve`, compiled into its caller: :func:`lm_rows` and the robust search's
    dropping step (their loops then know the scratch arrays apart) and :func:`lm_solve`
    itself (one compiled solve for the other callers, which compile faster calling it than
    holding its loop)."""
    fill(free, True)
    if bounded and poly.shape[0] >= 3:
        into_floor_plan(x, poly)
    cost = residuals(x, ab, rho, r, u)
    st, it = np.int8(4 if cost == 0 else 0), 0
    lam, nu = 1e-3, 2.0
    S, g = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    moved = True  # x moved since JᵀJ and Jᵀr were formed: a rejected step keeps them
    while st == 0 and it < max_iter:
        it += 1
        if moved:
            S, g = gram_gradient(r, u)
            if bounded:  # the held coordinates depend on x and Jᵀr only
                _free_coordinates(x, g, lo, hi, free)
            moved = False
        g0, g1, g2 = _damped_step(S, g, lam, step, free)
        small_g = max(abs(g0), abs(g1), abs(g2)) <= gtol
        for k in range(3):
            xn[k] = x[k] + step[k]
            if bounded:
                xn[k] = min(max(xn[k], lo[k]), hi[k])
        if bounded and poly.shape[0] >= 3:
            into_floor_plan(xn, poly)
        if bounded:
            for k in range(3):
                step[k] = xn[k] - x[k]
        cn = residuals(xn, ab, rho, rn, un)
        # predicted reduction of the damped model: ½ δᵀ(λδ − g)
        pred = 0.5 * (
            step[0] * (lam * step[0] - g0)
            + step[1] * (lam * step[1] - g1)
            + step[2] * (lam * step[2] - g2)
        )
        actual = cost - cn
        ratio = actual / pred if pred > 0 else -1.0
        ok = ratio > 0 and math.isfinite(cn)
        snorm = math.sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2])
        xnorm = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        small_x = snorm <= xtol * (xnorm + xtol)
        small_f = ok and actual <= ftol * cost and pred <= ftol * cost
        # accept / reject with Nielsen's damping update
        if ok:
            put(x, xn)
            r, rn, u, un = rn, r, un, u  # the scratch arrays swap roles
            cost = cn
            moved = True
            lam *= max(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3)
            nu = 2.0
        else:
            lam *= nu
            nu *= 2.0
        if small_g:
            st = 1
        elif small_f:
            st = 2
        elif small_x:
            st = 3
        if ok and cn == 0:
            st = 4
        # a damping that overflows means no descent direction is left: stationary point
        if st == 0 and not math.isfinite(lam * 1e3):
            st = 1
    return cost, st, it


@numba.njit(**NO_REFCOUNT)
def inside_floor_plan(x, y, poly) -> bool:  # pragma: no cover - compiled
    """Whether (x, y) lies inside the polygon ``poly`` (K, 2) (even-odd rule; a point on
    an edge counts as inside)."""
    K = poly.shape[0]
    inside = False
    x0, y0 = poly[K - 1, 0], poly[K - 1, 1]
    for i in range(K):  # the edge from corner i − 1 to corner i
        x1, y1 = poly[i, 0], poly[i, 1]
        # an edge whose span of y misses y is neither under the point nor crossed
        if min(y0, y1) - 1e-12 <= y <= max(y0, y1) + 1e-12:
            dx, dy = x1 - x0, y1 - y0
            cross = (x - x0) * dy - (y - y0) * dx
            if abs(cross) <= 1e-12 * (abs(dx) + abs(dy)) and (
                min(x0, x1) - 1e-12 <= x <= max(x0, x1) + 1e-12
            ):
                return True  # on the edge: inside
            if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * dx / dy:
                inside = not inside
        x0, y0 = x1, y1
    return inside


@numba.njit(**NO_REFCOUNT)
def into_floor_plan(p, poly) -> None:  # pragma: no cover - compiled
    """In place: a point p (3,) whose (x, y) lies outside the floor plan ``poly`` (K, 2)
    moves to the nearest point of its boundary (z unchanged)."""
    if inside_floor_plan(p[0], p[1], poly):
        return
    p[0], p[1] = nearest_on_boundary(p[0], p[1], poly)[1:]


@numba.njit(**NO_REFCOUNT)
def nearest_on_boundary(x, y, poly):  # pragma: no cover - compiled
    """(squared distance, x, y) of the point of the boundary of the polygon ``poly``
    (K, 2) nearest to (x, y)."""
    K = poly.shape[0]
    best, bx, by = math.inf, x, y
    for i in range(K):
        x0, y0 = poly[i, 0], poly[i, 1]
        k = i + 1 if i + 1 < K else 0
        dx, dy = poly[k, 0] - x0, poly[k, 1] - y0
        L2 = dx * dx + dy * dy
        t = 0.0 if L2 == 0 else min(max(((x - x0) * dx + (y - y0) * dy) / L2, 0.0), 1.0)
        qx, qy = x0 + t * dx, y0 + t * dy
        d = (x - qx) ** 2 + (y - qy) ** 2
        if d < best:
            best, bx, by = d, qx, qy
    return best, bx, by


@numba.njit(cache=True, inline="always")
def normal_equations(ab, rho):  # pragma: no cover - compiled
    """The normal equations S x = g of the heard anchors' squared-range differences
    (:func:`linear_fix`) for anchors ab (M, 3) and ranges rho (M,) (NaN: not heard):
    (n heard, S as (s00, s01, s02, s11, s12, s22), g (3,), the anchors' centroid (3,),
    the mean squared range), in tuples: the robust search solves one for every minimal
    set, and arrays would be allocated each time."""
    n = 0
    m0 = m1 = m2 = ma2 = mr2 = 0.0
    for j in range(ab.shape[0]):
        if rho[j] == rho[j]:
            n += 1
            m0 += ab[j, 0]
            m1 += ab[j, 1]
            m2 += ab[j, 2]
            ma2 += ab[j, 0] ** 2 + ab[j, 1] ** 2 + ab[j, 2] ** 2
            mr2 += rho[j] * rho[j]
    s00 = s01 = s02 = s11 = s12 = s22 = g0 = g1 = g2 = 0.0
    if n > 0:
        m0, m1, m2, ma2, mr2 = m0 / n, m1 / n, m2 / n, ma2 / n, mr2 / n
    for j in range(ab.shape[0]):
        if rho[j] == rho[j]:
            c0, c1, c2 = 2 * (ab[j, 0] - m0), 2 * (ab[j, 1] - m1), 2 * (ab[j, 2] - m2)
            rhs = (ab[j, 0] ** 2 + ab[j, 1] ** 2 + ab[j, 2] ** 2 - ma2) - (rho[j] * rho[j] - mr2)
            s00 += c0 * c0
            s01 += c0 * c1
            s02 += c0 * c2
            s11 += c1 * c1
            s12 += c1 * c2
            s22 += c2 * c2
            g0 += c0 * rhs
            g1 += c1 * rhs
            g2 += c2 * rhs
    return n, (s00, s01, s02, s11, s12, s22), (g0, g1, g2), (m0, m1, m2), mr2


@numba.njit(cache=True, inline="always")
def cofactors(S):  # pragma: no cover - compiled
    """The cofactors (c00, c01, c02, c11, c12, c22) of the symmetric 3 × 3 matrix S
    (s00, s01, s02, s11, s12, s22) and its determinant."""
    s00, s01, s02, s11, s12, s22 = S
    c = (s11 * s22 - s12 * s12, s02 * s12 - s01 * s22, s01 * s12 - s02 * s11,
         s00 * s22 - s02 * s02, s01 * s02 - s00 * s12, s00 * s11 - s01 * s01)  # fmt: skip
    return c, s00 * c[0] + s01 * c[1] + s02 * c[2]


@numba.njit(cache=True, inline="always")
def adjugate_times(c, u0, u1, u2):  # pragma: no cover - compiled
    """adj(S) u for the cofactors c (:func:`cofactors`) of the symmetric S and
    u = (u0, u1, u2)."""
    return (c[0] * u0 + c[1] * u1 + c[2] * u2, c[1] * u0 + c[3] * u1 + c[4] * u2,
            c[2] * u0 + c[4] * u1 + c[5] * u2)  # fmt: skip


@numba.njit(cache=True, inline="always")
def _cofactor_solve(c, det, g, x) -> None:  # pragma: no cover - compiled
    """x (3,) = S⁻¹ g from the cofactors c and determinant of S (:func:`cofactors`)."""
    a0, a1, a2 = adjugate_times(c, g[0], g[1], g[2])
    x[0], x[1], x[2] = a0 / det, a1 / det, a2 / det


@numba.njit(**NO_REFCOUNT)
def linear_fix(ab, rho, x, coplanar) -> bool:  # pragma: no cover - compiled
    """x (3,) the linear solution of the heard anchors' squared-range differences (the
    normal equations S x = g, solved by cofactors) for anchors ab (M, 3) and ranges rho
    (M,) (NaN: not heard); False, x untouched, with fewer than 4 heard or when they are
    coplanar (det S ≤ ``coplanar`` · (tr S)³)."""
    return flatness(normal_equations(ab, rho), x, coplanar) > coplanar


@numba.njit(**NO_REFCOUNT)
def flatness(eq, x, coplanar) -> float:  # pragma: no cover - compiled
    """det S / (tr S)³ of the normal equations ``eq`` (:func:`normal_equations`; 0 for
    anchors in a plane, −1 with fewer than 4 heard), x (3,) their solution where it exceeds
    ``coplanar`` (else x untouched)."""
    n, S, g, _, _ = eq
    if n < 4:
        return -1.0
    c, det = cofactors(S)
    tr = S[0] + S[3] + S[5]
    flat = det / (tr * tr * tr) if tr > 0.0 else 0.0
    if flat > coplanar:
        _cofactor_solve(c, det, g, x)
    return flat


@numba.njit(**NO_REFCOUNT)
def mirror_fixes(ab, rho, x, y, least) -> bool:  # pragma: no cover - compiled
    """x (3,) and y (3,) the two positions that the ranges rho (M,) of coplanar anchors ab
    (M, 3) (NaN: not heard; at least 3 heard, not collinear) fix, mirror images of each
    other in the anchors' plane (docs/model.md, "Positioning that rejects echoes"): the
    squared-range differences fix the position's projection onto the plane (the normal
    equations S p = g of :func:`linear_fix` with the component along the plane's normal n,
    the null direction of S, held at the plane), and the mean squared range its distance h
    from the plane, x = p + h n, y = p − h n, h at least ``least`` (m): where the ranges
    barely reach off the plane (noise, or anchors mounted off their plan), the images are
    put that far off it, since a least-squares fit started on the plane cannot leave it
    (the plane is a symmetry of the fit). False, x and y untouched, with fewer than 3 heard
    or collinear anchors."""
    return mirrors(normal_equations(ab, rho), ab, rho, x, y, least)


@numba.njit(**NO_REFCOUNT)
def mirrors(eq, ab, rho, x, y, least) -> bool:  # pragma: no cover - compiled
    """:func:`mirror_fixes` from the normal equations ``eq`` of ab (M, 3) and rho (M,)
    (:func:`normal_equations`), which the caller may have built already."""
    k, S, g, m, mr2 = eq
    if k < 3:
        return False
    c, _ = cofactors(S)
    # the null direction of a rank-2 S: its adjugate's largest row
    rows = ((c[0], c[1], c[2]), (c[1], c[3], c[4]), (c[2], c[4], c[5]))
    n0, n1, n2, best = 0.0, 0.0, 0.0, 0.0
    for r in rows:
        size = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
        if size > best:
            n0, n1, n2, best = r[0], r[1], r[2], size
    tr = S[0] + S[3] + S[5]
    if not best > 1e-24 * tr**4:  # rank 1 or less: collinear anchors fix no plane
        return False
    size = math.sqrt(best)
    n0, n1, n2 = n0 / size, n1 / size, n2 / size
    # (S + tr n nᵀ) p = g + tr n (n · m): p on the plane through the centroid m
    off = tr * (n0 * m[0] + n1 * m[1] + n2 * m[2])
    T = (S[0] + tr * n0 * n0, S[1] + tr * n0 * n1, S[2] + tr * n0 * n2,
         S[3] + tr * n1 * n1, S[4] + tr * n1 * n2, S[5] + tr * n2 * n2)  # fmt: skip
    cT, det = cofactors(T)
    if not det > 0.0:
        return False
    # p is solved into y, which holds it only until the images are written below
    _cofactor_solve(cT, det, (g[0] + off * n0, g[1] + off * n1, g[2] + off * n2), y)
    p0, p1, p2 = y[0], y[1], y[2]
    q = 0.0  # the mean squared distance of p from the anchors heard
    for j in range(ab.shape[0]):
        if rho[j] == rho[j]:
            q += (p0 - ab[j, 0]) ** 2 + (p1 - ab[j, 1]) ** 2 + (p2 - ab[j, 2]) ** 2
    h = math.sqrt(max(mr2 - q / k, least * least))
    x[0], x[1], x[2] = p0 + h * n0, p1 + h * n1, p2 + h * n2
    y[0], y[1], y[2] = p0 - h * n0, p1 - h * n1, p2 - h * n2
    return True

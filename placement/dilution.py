"""Tags whose anchors in sight cannot fix them well: too few, or in a poor geometry
(docs/model.md, "Shadows and poor geometry").

A robust fix uses the anchors a tag sees in line of sight and reach. Where it sees fewer
than k (4 for a fix), its fix rests on an echo. Where it sees enough but they lie nearly in
one plane with it (the aisle of a warehouse, seen from anchors along that aisle), the
direct ranges pin the tag along some directions only: the geometric dilution of precision

    GDOP = √tr (Hᵀ H)⁻¹,   H the (n, 3) unit vectors from the tag to the n anchors it sees,

(paper §IV: the position error bound at σ = 1 m, :func:`analysis.fim.gdop`) grows without
bound, and with it the error of a tag between the planner's nodes. The planner counts such
points of the room as shadows (:class:`placement.coverage.CoverageTarget`).

:func:`poor_sight_share` is compiled (numba): it runs for every layout the search scores,
over the room's sight points (thousands) and the layout's anchors; numpy would build an
(L, Q, M, 3) array per batch. :func:`analysis.fim.gdop` is the reference it is tested
against.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from simulation import checks


@numba.njit(cache=True)
def _poor_rows(points, candidates, seen, layouts, k, limit2):  # pragma: no cover - compiled
    L, M = layouts.shape
    Q = points.shape[0]
    out = np.empty(L)
    for i in range(L):
        poor = 0
        for q in range(Q):
            a = b = c = d = e = f = 0.0  # HᵀH: a b c on the diagonal, d e f off it
            n = 0
            for m in range(M):
                j = layouts[i, m]
                if not seen[q, j]:
                    continue
                ux = candidates[j, 0] - points[q, 0]
                uy = candidates[j, 1] - points[q, 1]
                uz = candidates[j, 2] - points[q, 2]
                r2 = ux * ux + uy * uy + uz * uz
                if r2 <= 0.0:
                    continue  # an anchor at the tag gives no direction
                a += ux * ux / r2
                b += uy * uy / r2
                c += uz * uz / r2
                d += ux * uy / r2
                e += ux * uz / r2
                f += uy * uz / r2
                n += 1
            if n < k:
                poor += 1
                continue
            if limit2 == math.inf:
                continue
            c00, c11, c22 = b * c - f * f, a * c - e * e, a * b - d * d
            det = a * c00 - d * (d * c - e * f) + e * (d * f - b * e)
            # tr (HᵀH)⁻¹ = (c00 + c11 + c22) / det; a singular HᵀH (det ≤ 0) is poor too
            if not (det > 0.0 and c00 + c11 + c22 <= limit2 * det):
                poor += 1
        out[i] = poor / Q
    return out


def poor_sight_share(points, candidates, seen, layouts, k: int, gdop_limit=None) -> np.ndarray:
    """(L,) the share of the points (Q, 3) that each layout (L, M) of candidate indices
    leaves poorly fixed: the point sees (``seen`` (Q, N) bool) fewer than ``k`` of the
    layout's anchors (candidates (N, 3), m), or, with a ``gdop_limit``, the anchors it sees
    have a GDOP above it or a singular geometry (module docstring). Without a limit: the
    share seeing fewer than k."""
    P = checks.reals("points", points, shape=(None, 3), unit="m")
    C = checks.reals("candidates", candidates, shape=(None, 3), unit="m")
    V = np.ascontiguousarray(seen, dtype=np.bool_)
    S = np.ascontiguousarray(layouts, dtype=np.int64)
    if V.shape != (len(P), len(C)) or S.ndim != 2:
        raise ValueError(
            f"poor_sight_share: expected seen (Q, N) = ({len(P)}, {len(C)}) and layouts "
            f"(L, M), got {V.shape} and {S.shape}"
        )
    if S.size and (S.min() < 0 or S.max() >= len(C)):
        raise ValueError(
            f"layouts: candidate indices must be in [0, {len(C) - 1}], got {S.min()} … {S.max()}"
        )
    k = checks.count("k", k, low=1, high=10_000)
    if gdop_limit is not None:
        gdop_limit = checks.real("gdop_limit", gdop_limit, low=0.0, low_open=True)
    return poor_sight_share_unchecked(P, C, V, S, k, gdop_limit)


def poor_sight_share_unchecked(points, candidates, seen, layouts, k: int, gdop_limit=None):
    """:func:`poor_sight_share` of arguments already checked (a range table's sight points,
    candidates and sight, the layouts' candidate indices, the target's k and limit): the
    planner's cost calls it for every batch of layouts it scores."""
    S = np.ascontiguousarray(layouts, dtype=np.int64)
    if len(S) == 0 or len(points) == 0:
        return np.zeros(len(S))
    limit = math.inf if gdop_limit is None else float(gdop_limit)
    return _poor_rows(np.ascontiguousarray(points, dtype=float),
                      np.ascontiguousarray(candidates, dtype=float),
                      np.ascontiguousarray(seen, dtype=np.bool_), S, int(k),
                      limit * limit)  # fmt: skip

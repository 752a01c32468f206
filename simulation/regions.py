"""Keep-out geometry: the allowed part of a mounting rectangle as a union of rectangles.

A keep-out is a closed axis-aligned box [min, max] in room coordinates (m); a point p is
forbidden iff min ≤ p ≤ max on every axis (faces included). On a mounting surface (a
rectangle in the plane ``axis = offset``) a box matters iff the plane cuts it,
min[axis] ≤ offset ≤ max[axis]; its footprint is then the closed rectangle of its two
in-plane extents. The allowed region of the surface is the rectangle minus the
footprints. Because the footprints are closed, the allowed region is not closed (the
nearest allowed point to a point inside a box does not exist), so every footprint is
grown by :data:`EPS` (1 µm) on each side before it is removed: the allowed rectangles
returned here stop ``EPS`` outside every box and never touch one.

The rectangle minus the grown footprints is cut along every footprint edge into a grid
of cells; a cell is free iff its centre lies in no grown footprint. :func:`free_cells`
returns the free cells (disjoint, for areas and uniform sampling) and
:func:`maximal_rectangles` the maximal rectangles of their union (overlapping, for
projection and for keeping an anchor in one rectangle during refinement). Without
footprints both are the rectangle itself, bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: keep-out footprints are grown by this much (m) before they are removed
EPS = 1e-6

Box = tuple[tuple[float, float, float], tuple[float, float, float]]


def footprints(
    boxes: Sequence[Box], axis: int, offset: float, uv_axes: tuple[int, int]
) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The (lower uv, upper uv) footprints of the boxes that the plane ``axis = offset`` cuts."""
    out = []
    for lo, hi in boxes:
        if lo[axis] <= offset <= hi[axis]:
            out.append(((lo[uv_axes[0]], lo[uv_axes[1]]), (hi[uv_axes[0]], hi[uv_axes[1]])))
    return out


def _cells(lower, upper, blocks, eps: float):
    """Breakpoints (u (nu+1,), v (nv+1,)) and the free mask (nu, nv) of the cell grid."""
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    if not blocks:
        return [np.array([lower[k], upper[k]]) for k in range(2)], np.ones((1, 1), bool)
    blo = np.array([b[0] for b in blocks], dtype=float) - eps  # (B, 2) grown footprints
    bhi = np.array([b[1] for b in blocks], dtype=float) + eps
    edges = []
    for k in range(2):
        cuts = np.concatenate([[lower[k], upper[k]], blo[:, k], bhi[:, k]])
        cuts = np.unique(np.clip(cuts, lower[k], upper[k]))
        edges.append(cuts)
    cu = (edges[0][1:] + edges[0][:-1]) / 2
    cv = (edges[1][1:] + edges[1][:-1]) / 2
    inside = (
        (cu[:, None, None] > blo[None, None, :, 0])
        & (cu[:, None, None] < bhi[None, None, :, 0])
        & (cv[None, :, None] > blo[None, None, :, 1])
        & (cv[None, :, None] < bhi[None, None, :, 1])
    )  # (nu, nv, B)
    return edges, ~inside.any(axis=-1)


def free_cells(lower, upper, blocks, eps: float = EPS) -> tuple[np.ndarray, np.ndarray]:
    """Disjoint free cells (lower (C, 2), upper (C, 2)) of the rectangle minus the blocks.

    ``blocks`` are closed footprints ((u0, v0), (u1, v1)); each is grown by ``eps``.
    Ordered u slowest. C = 0 when the blocks cover the whole rectangle.
    """
    (eu, ev), free = _cells(lower, upper, blocks, eps)
    i, j = np.nonzero(free)
    lo = np.stack([eu[i], ev[j]], axis=-1).reshape(-1, 2)
    hi = np.stack([eu[i + 1], ev[j + 1]], axis=-1).reshape(-1, 2)
    return lo, hi


def maximal_rectangles(lower, upper, blocks, eps: float = EPS) -> tuple[np.ndarray, np.ndarray]:
    """Maximal rectangles (lower (R, 2), upper (R, 2)) of the union of the free cells.

    Their union is the allowed region (less the ``eps`` margins); they may overlap.
    Ordered by decreasing area (ties: u, then v of the lower corner).
    """
    (eu, ev), free = _cells(lower, upper, blocks, eps)
    nu, nv = free.shape
    keep = []
    for i0 in range(nu):
        ok = np.ones(nv, bool)
        for i1 in range(i0, nu):
            ok &= free[i1]
            if not ok.any():
                break
            j = 0
            while j < nv:  # maximal runs of rows free over columns i0..i1
                if not ok[j]:
                    j += 1
                    continue
                j1 = j
                while j1 + 1 < nv and ok[j1 + 1]:
                    j1 += 1
                # maximal in v by construction; keep it if it cannot grow in u either
                left = i0 > 0 and free[i0 - 1, j : j1 + 1].all()
                right = i1 + 1 < nu and free[i1 + 1, j : j1 + 1].all()
                if not (left or right):
                    keep.append((i0, i1, j, j1))
                j = j1 + 1
    if not keep:
        return np.empty((0, 2)), np.empty((0, 2))
    lo = np.array([[eu[i0], ev[j0]] for i0, _, j0, _ in keep])
    hi = np.array([[eu[i1 + 1], ev[j1 + 1]] for _, i1, _, j1 in keep])
    area = np.prod(hi - lo, axis=-1)
    order = np.lexsort((lo[:, 1], lo[:, 0], -area))
    return lo[order], hi[order]


def in_boxes(boxes: Sequence[Box], points) -> np.ndarray:
    """(..., B) bool: point (..., 3) lies in closed box b (faces included)."""
    p = np.asarray(points, dtype=float)
    if not boxes:
        return np.zeros((*p.shape[:-1], 0), bool)
    lo = np.array([b[0] for b in boxes], dtype=float)
    hi = np.array([b[1] for b in boxes], dtype=float)
    q = p[..., None, :]
    return np.all((q >= lo) & (q <= hi), axis=-1)

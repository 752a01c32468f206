"""Degenerate anchor layouts: the affine rank of a layout and its name.

A layout whose anchors are collinear or coincident cannot position in 3D; a coplanar one
has a mirror ambiguity that the room's box resolves.
"""

from __future__ import annotations

import math

import numpy as np

from simulation.checks import MIN_ANCHOR_DISTANCE

__all__ = ["GEOMETRY", "anchor_rank", "geometry", "rank_of_spread"]

#: the name of a layout's affine rank
GEOMETRY = {0: "coincident", 1: "collinear", 2: "coplanar", 3: "3d"}


def anchor_rank(anchors, tol: float = MIN_ANCHOR_DISTANCE) -> np.ndarray | int:
    """Affine rank of anchors (M, 3) or of each layout (..., M, 3): 3 spans space, 2
    coplanar, 1 collinear, 0 coincident; directions with an RMS spread under ``tol`` m
    do not count."""
    a = np.asarray(anchors, dtype=float)
    c = a - a.mean(axis=-2, keepdims=True)
    return rank_of_spread(np.linalg.svd(c, compute_uv=False), a.shape[-2], tol)


def rank_of_spread(s, M: int, tol: float = MIN_ANCHOR_DISTANCE) -> np.ndarray | int:
    """:func:`anchor_rank` from the singular values s (..., 3) of M anchors' coordinates
    about their mean."""
    r = np.sum(np.asarray(s) / math.sqrt(max(M, 1)) > tol, axis=-1)
    return int(r) if np.ndim(r) == 0 else r


def geometry(anchors, tol: float = MIN_ANCHOR_DISTANCE) -> str:
    """ "3d", "coplanar", "collinear" or "coincident" for one layout (M, 3)."""
    return GEOMETRY[int(anchor_rank(anchors, tol))]

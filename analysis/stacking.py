"""Anchors that a drawing puts on one spot: the groups whose labels a figure, the
planning page or the mounting sheet writes once ("2,3,4")."""

from __future__ import annotations

import numpy as np

#: (m) projected anchors closer than this share a label: their marks cover each other
STACKED = 0.05


def stacks(points, tol: float = STACKED) -> list[list[int]]:
    """The groups of the points (M, D) m (anchors projected onto a view, D = 1 or 2) that lie
    within ``tol`` of each other, linked in chains (:func:`groups`)."""
    if len(points) == 0:
        return []
    p = np.asarray(points, dtype=float).reshape(len(points), -1)
    return groups(np.linalg.norm(p[:, None] - p[None], axis=-1) <= tol)


def groups(near) -> list[list[int]]:
    """The connected groups of the symmetric relation near (n, n) bool (i and j in one
    group when a chain of near pairs links them), each in index order, ordered by its
    first index."""
    near = np.asarray(near, dtype=bool)
    group = np.arange(len(near))
    for _ in range(len(near)):  # a chain of n is joined within n passes
        group = np.min(np.where(near, group[None], group[:, None]), axis=1)
    return [np.flatnonzero(group == g).tolist() for g in np.unique(group)]

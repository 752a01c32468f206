"""Fixes checked against the room's map: a robust fix must be one the room allows
(docs/model.md, "Positioning that rejects echoes").

The residual test alone cannot tell a true position from a mirror image: when one face of
an obstacle reflects the chirps of several anchors towards the tag, their echo ranges agree
with each other, as if the tag stood at its mirror image behind the face, and 5 of them
pass the test as readily as 5 direct ranges. The room's geometry tells them apart: a range
the fix rests on is a direct path only if the straight segment from the fix to that anchor
is free (:func:`simulation.polyhedral.line_of_sight`). The robust search counts such a
range as a contradiction (:mod:`simulation.robust`), and it keeps a contradicted fix only
where no set without one agrees.

This check is what the system vouches for: a fix that rests on a hidden anchor, or lies
outside the room or inside an obstacle, is not verified. It stays where the search put it,
unverified.

The check needs the room's map: the positioning must know its room (``keep_in_room``) and
the room must have something that blocks a path (obstacles, or a floor plan that is not
convex).
"""

from __future__ import annotations

import numpy as np

from simulation.polyhedral import hidden_anchors
from simulation.robust import UNVERIFIED, VERIFIED


def needs_check(room) -> bool:
    """Whether anything in ``room`` can block a direct path (obstacles, a floor plan that
    is not convex): only then can a fix rest on a hidden anchor."""
    return bool(room.obstacles) or not room.is_convex


def contradictions(room, layouts, owner, x, used) -> tuple[np.ndarray, np.ndarray]:
    """(hidden (N, M) bool: anchor j is used by fix i but the segment from the fix to it is
    blocked; outside (N,) bool: fix i lies outside the room or inside an obstacle) for
    fixes ``x`` (N, 3) m of the layouts (L, M, 3), fix i of layout ``owner[i]``, resting on
    the anchors ``used`` (N, M). Fixes without a position (NaN) contradict nothing."""
    N, M = used.shape
    hidden = np.zeros((N, M), dtype=bool)
    outside = np.zeros(N, dtype=bool)
    rows = np.flatnonzero(np.all(np.isfinite(x), axis=1))
    hidden[rows] = hidden_anchors(room, layouts, owner[rows], x[rows], used[rows])
    outside[rows] = ~room.contains(x[rows])
    return hidden, outside


def map_check(room, layouts, owner, fix: dict) -> dict:
    """The fixes of ``fix`` (a dict of flat arrays: ``x`` (N, 3), ``used`` (N, M),
    ``quality`` (N,) and any other per-fix arrays) checked against the room (module
    docstring), ``layouts`` (L, M, 3) and ``owner`` (N,) as in :func:`contradictions`: the
    same dict with ``quality`` no better than unverified where a fix rests on a hidden anchor
    or lies outside the room."""
    # only a verified fix can lose its quality: the others are not checked
    rows = np.flatnonzero(fix["quality"] == VERIFIED)
    hidden, outside = contradictions(room, layouts, owner[rows], fix["x"][rows],
                                     fix["used"][rows])  # fmt: skip
    bad = rows[hidden.any(axis=1) | outside]
    if not bad.size:
        return fix
    quality = fix["quality"].copy()
    quality[bad] = UNVERIFIED
    return {**fix, "quality": quality}

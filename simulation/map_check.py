"""Fixes checked against the room's map: a robust fix must be one the room allows
(docs/model.md, "Positioning that rejects echoes").

The residual test (:mod:`simulation.robust`) cannot tell a true position from a mirror
image: when one face of an obstacle reflects the chirps of several anchors towards the
tag, their echo ranges agree with each other, as if the tag stood at its mirror image
behind the face, and 5 of them pass the test as readily as 5 direct ranges. The room's
geometry tells them apart. A range the fix rests on is a direct path only if the straight
segment from the fix to that anchor is free (:func:`simulation.polyhedral.line_of_sight`);
a fix rests on a hidden anchor, or lies inside an obstacle, only if it is wrong.

So, for each fix that rests on a hidden anchor or lies outside the room:

1. the hidden anchors' ranges are dropped (they are echoes where the fix stands, or the fix
   is wrong) and the remaining ranges are solved again by the same positioning;
2. the new fix replaces the old one if it is verified and rests on anchors it sees, inside
   the room;
3. otherwise the old fix stays, unverified: the system cannot vouch for it.

The check needs the room's map: the positioning must know its room (``keep_in_room``) and
the room must have something that blocks a path (obstacles, or a floor plan that is not
convex).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from simulation.polyhedral import line_of_sight
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
    found = np.all(np.isfinite(x), axis=1)
    for layout in np.unique(owner[found]):
        rows = np.flatnonzero(found & (owner == layout))
        los = line_of_sight(room, layouts[layout], x[rows])
        hidden[rows] = used[rows] & ~los
        outside[rows] = ~room.contains(x[rows])
    return hidden, outside


def map_check(room, layouts, owner, ranges, fix: dict, solve: Callable) -> dict:
    """The fixes of ``fix`` (a dict of flat arrays: ``x`` (N, 3), ``used`` (N, M),
    ``quality`` (N,) and any other per-fix arrays) checked against the room (module
    docstring); ``ranges`` (N, M) m the fixes were solved from, ``layouts`` (L, M, 3) and
    ``owner`` (N,) as in :func:`contradictions`; ``solve(anchors (n, M, 3), ranges (n, M))``
    solves rows again and returns the same dict for them. Returns the checked dict."""
    hidden, outside = contradictions(room, layouts, owner, fix["x"], fix["used"])
    bad = np.flatnonzero(hidden.any(axis=1) | outside)
    if not len(bad):
        return fix
    out = {k: v.copy() for k, v in fix.items()}
    again = solve(layouts[owner[bad]], np.where(hidden[bad], np.nan, ranges[bad]))
    h2, out2 = contradictions(room, layouts, owner[bad], again["x"], again["used"])
    good = (again["quality"] == VERIFIED) & ~h2.any(axis=1) & ~out2
    for k in out:
        out[k][bad[good]] = again[k][good]
    q = out["quality"]
    q[bad[~good]] = np.minimum(q[bad[~good]], UNVERIFIED)
    return out

"""Random tag points: where a user's tags may be, drawn uniformly in the node region (the
room less its node margin, or its tag zones), inside the floor plan and outside obstacles.
The field check places its tags there (:mod:`placement.validation`), and the range table's
sight points are drawn so (:func:`placement.rangetable.sight_points`)."""

from __future__ import annotations

import numpy as np

from simulation.room import Room


def random_nodes(room: Room, n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) uniform random points in the node region: the room less its node margin, or
    the tag zones (chosen in proportion to their volume) within it; in a polygonal room or
    one with obstacles, inside the floor plan and outside the obstacles."""
    if room.is_shoebox and not room.obstacles:
        return _uniform_nodes(room, n, rng)
    # a polygonal room or obstacles: draw until n points lie in the room (rejection)
    margin = max(room.node_margin - 1e-9, 0.0)
    out = np.empty((0, 3))
    while len(out) < n:
        p = _uniform_nodes(room, 2 * (n - len(out)) + 8, rng)
        out = np.concatenate([out, p[room.contains(p, margin=margin)]])
    return out[:n]


def _uniform_nodes(room: Room, n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, 3) uniform points in the node region of the bounding box, or in its zones."""
    lo = np.full(3, room.node_margin)
    hi = np.asarray(room.size) - room.node_margin
    if not room.zones:
        return rng.uniform(lo, hi, (n, 3))
    boxes = [(np.maximum(lo, z0), np.minimum(hi, z1)) for z0, z1 in room.zones]
    vol = np.array([np.prod(np.maximum(b - a, 0)) for a, b in boxes])
    pick = rng.choice(len(boxes), n, p=vol / vol.sum() if vol.sum() > 0 else None)
    out = np.empty((n, 3))
    for k, (a, b) in enumerate(boxes):
        rows = pick == k
        out[rows] = rng.uniform(a, b, (int(rows.sum()), 3))
    return out

"""Floor plans: a room as a simple polygon extruded to a height, and obstacles in it.

A polygonal room (``Room.from_corners``) is the prism over a simple polygon (convex or
not: L, T, U shapes) from the floor z = 0 to the ceiling z = height. Its corners are
normalized to counter-clockwise order; wall i is the vertical rectangle over the edge from
corner i to corner i + 1 (in the corners' own order, names ``wall-0`` … ``wall-{n-1}``
unless given), and every wall's normal points into the room. The shoebox is the rectangle
with the compass walls south (y = 0), east, north and west, in that order.

An obstacle is an axis-aligned box standing in the room (a column, a shelf, a cabinet):
sound does not pass it, its faces reflect like walls, no node or anchor lies inside it,
and the faces of a ``mountable`` one (a column) carry anchors. A face that lies on the
room's boundary (a box on the floor, against a wall or up to the ceiling) is not a
reflector: the boundary is.

2-D polygon operations (validation, orientation, insets, point in polygon) are shapely's.
Module docs: docs/model.md, "Polygonal rooms and obstacles".
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from simulation import checks

#: energy absorption of a polygonal room's walls, floor and ceiling and of an obstacle's
#: faces when none is given (the techtile room's wood surfaces)
DEFAULT_ABSORPTION = 0.45
#: the fewest and the most corners of a floor plan
MIN_CORNERS, MAX_CORNERS = 3, 200
#: a corner closer than this (m) to another is a repeat
CORNER_TOL = 1e-6

#: the shoebox's walls in corner order (0, 0) → (Lx, 0) → (Lx, Ly) → (0, Ly)
SHOEBOX_WALLS = ("south", "east", "north", "west")


def _polygon(corners: np.ndarray):
    from shapely import Polygon

    return Polygon(corners)


def normalize_corners(corners, wall_names=()) -> tuple[np.ndarray, tuple[str, ...]]:
    """The corners (n, 2) in counter-clockwise order and the wall names in the same order,
    checked: 3 to 200 finite corners with x, y ≥ 0, no repeats, a simple polygon of
    positive area. ``wall_names`` (one per edge, corner i to i + 1 as given; default
    ``wall-i``) follow the edges when the order is reversed."""
    c = checks.reals("corners", corners, finite=False)
    if c.ndim != 2 or c.shape[1] != 2 or not (MIN_CORNERS <= len(c) <= MAX_CORNERS):
        raise ValueError(
            f"corners: expected {MIN_CORNERS}–{MAX_CORNERS} corners [[x, y], ...] in metres, "
            f"got {checks.describe(corners)}"
        )
    if not np.all(np.isfinite(c)):
        raise ValueError("corners: every coordinate must be finite (no NaN or inf)")
    if np.any(c < 0):
        k = int(np.argwhere(c < 0)[0, 0])
        raise ValueError(
            f"corners: corner {k} {c[k].tolist()} has a negative coordinate; allowed: x, y >= 0 "
            "(shift the plan so that the room lies in the positive quadrant)"
        )
    d = np.linalg.norm(c[:, None] - c[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    if np.any(d < CORNER_TOL):
        i, j = (int(v) for v in np.argwhere(d < CORNER_TOL)[0])
        raise ValueError(
            f"corners: corners {i} and {j} repeat {c[i].tolist()}; allowed: distinct corners "
            "(do not close the polygon by repeating the first corner)"
        )
    names = _wall_names(wall_names, len(c))
    poly = _polygon(c)
    area = abs(float(np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])))
    if area <= 2e-9 and np.linalg.matrix_rank(c[1:] - c[0], tol=1e-9) < 2:
        raise ValueError(
            f"corners: the polygon has zero area (collinear corners {c.tolist()}); allowed: "
            "a simple polygon enclosing the floor"
        )
    split = straight_corners(c, CORNER_TOL)
    if split.size:
        k = int(split[0])
        raise ValueError(
            f"corners: corner {k} {c[k].tolist()} lies on the straight line between its "
            "neighbours (one wall drawn as two); allowed: corners where the walls turn "
            "(remove it)"
        )
    if not poly.exterior.is_simple or not poly.is_valid or poly.area <= 1e-9:
        raise ValueError(
            "corners: the polygon intersects itself; allowed: a simple polygon, corners in "
            f"order around the floor (got {c.tolist()})"
        )
    if not poly.exterior.is_ccw:
        # reversed order: the wall from corner i to i + 1 becomes the edge n − 2 − i
        c = c[::-1].copy()
        n = len(c)
        names = tuple(names[(n - 2 - j) % n] for j in range(n))
    return c, names


def straight_corners(c: np.ndarray, tol: float) -> np.ndarray:
    """The indices of the corners of the closed polygon c (n, 2) m that lie within ``tol``
    m of the segment between their two neighbours: not a turn of the walls."""
    prev, nxt = np.roll(c, 1, axis=0), np.roll(c, -1, axis=0)
    e, r = nxt - prev, c - prev
    length2 = np.einsum("ij,ij->i", e, e)
    off = np.abs(e[:, 0] * r[:, 1] - e[:, 1] * r[:, 0]) / np.sqrt(np.maximum(length2, 1e-300))
    along = np.einsum("ij,ij->i", r, e) / np.maximum(length2, 1e-300)
    return np.flatnonzero((off < tol) & (along > 0) & (along < 1))


def _wall_names(given, n: int) -> tuple[str, ...]:
    if isinstance(given, str):
        given = (given,)
    given = tuple(given or ())
    if not given:
        return tuple(f"wall-{i}" for i in range(n))
    if len(given) != n:
        raise ValueError(f"wall_names: expected one name per wall ({n}), got {len(given)}")
    bad = [g for g in given if not isinstance(g, str) or not g or g in ("floor", "ceiling")]
    if bad:
        raise ValueError(
            f"wall_names: names must be non-empty strings other than 'floor' and 'ceiling', "
            f"got {bad}"
        )
    if len(set(given)) != n:
        raise ValueError(f"wall_names: each wall needs its own name, got {list(given)}")
    return given


@dataclass(frozen=True)
class Wall:
    """A vertical wall over the edge from ``start`` to ``end`` (m, (2,) each) up to
    ``height``: its inward unit normal ``normal`` (3,) and its length (m)."""

    name: str
    start: np.ndarray
    end: np.ndarray
    height: float

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def direction(self) -> np.ndarray:
        """(3,) unit vector along the wall, from start to end (horizontal)."""
        d = (self.end - self.start) / self.length
        return np.array([d[0], d[1], 0.0])

    @property
    def normal(self) -> np.ndarray:
        """(3,) unit normal pointing into the room (left of start → end for CCW corners)."""
        d = self.direction
        return np.array([-d[1], d[0], 0.0])


def walls(corners: np.ndarray, names: Sequence[str], height: float) -> list[Wall]:
    """The walls of CCW corners (n, 2), edge i from corner i to corner i + 1."""
    c = np.asarray(corners, dtype=float)
    n = len(c)
    return [Wall(names[i], c[i].copy(), c[(i + 1) % n].copy(), float(height)) for i in range(n)]


def contains_xy(corners: np.ndarray, xy: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(...,) bool: 2-D points (..., 2) inside the polygon, at least ``margin`` m from its
    boundary (boundary included when ``margin`` is 0)."""
    import shapely

    poly = _polygon(corners)
    p = np.asarray(xy, dtype=float)
    flat = p.reshape(-1, 2)
    if margin > 0:
        inner = poly.buffer(-margin, join_style="mitre")
        ok = (
            shapely.intersects_xy(inner, flat[:, 0], flat[:, 1])
            if not inner.is_empty
            else (np.zeros(len(flat), bool))
        )
    else:
        ok = shapely.intersects_xy(poly, flat[:, 0], flat[:, 1])
    return np.asarray(ok, dtype=bool).reshape(p.shape[:-1])


def centroid(corners: np.ndarray) -> np.ndarray:
    """(2,) the polygon's area centroid (m)."""
    c = _polygon(corners).centroid
    return np.array([c.x, c.y])


def inset(corners: np.ndarray, distance: float) -> np.ndarray:
    """(k, 2) the corners of the polygon moved ``distance`` m inwards (mitred), CCW."""
    poly = _polygon(corners).buffer(-distance, join_style="mitre")
    if poly.is_empty or poly.geom_type != "Polygon":
        raise ValueError(f"distance: {distance:g} m leaves no single polygon inside the floor plan")
    xy = np.asarray(poly.exterior.coords)[:-1]
    return xy if _polygon(xy).exterior.is_ccw else xy[::-1].copy()


# -- obstacles -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Obstacle:
    """An axis-aligned box standing in the room (m): ``lo`` (3,) and ``hi`` (3,) corners,
    a ``name``, the energy ``absorption`` α of its faces and whether its faces are mounting
    surfaces (``mountable``)."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    name: str = ""
    absorption: float = DEFAULT_ABSORPTION
    mountable: bool = False

    def to_dict(self) -> dict[str, Any]:
        """``{"min", "max", "name"?, "absorption", "mountable"}`` (the TOML/JSON form)."""
        d: dict[str, Any] = {"min": list(self.lo), "max": list(self.hi)}
        if self.name:
            d["name"] = self.name
        d["absorption"] = self.absorption
        d["mountable"] = self.mountable
        return d

    def contains(self, points, margin: float = 0.0) -> np.ndarray:
        """(...,) bool: points (..., 3) inside the box grown by ``margin`` m (faces included)."""
        p = np.asarray(points, dtype=float)
        lo = np.asarray(self.lo) - margin
        hi = np.asarray(self.hi) + margin
        return np.all((p >= lo) & (p <= hi), axis=-1)


OBSTACLE_KEYS = ("min", "max", "name", "absorption", "mountable")


def obstacles_from(items, size, corners=None) -> tuple[Obstacle, ...]:
    """Obstacles from a list of ``{"min": [x, y, z], "max": [...], "name", "absorption",
    "mountable"}`` mappings (or :class:`Obstacle`), checked against the room: each box has
    min < max on every axis, stands in the room (inside the floor plan, between the floor
    and the ceiling; touching the boundary is allowed, cutting a wall is not), and no two
    overlap (:func:`_check_apart`)."""
    if items is None:
        return ()
    if isinstance(items, Mapping | str | bytes) or not isinstance(items, Iterable):
        raise ValueError(
            f"obstacles: expected a list of boxes {{'min': [x, y, z], 'max': [x, y, z]}}, "
            f"got {checks.describe(items)}"
        )
    out = []
    for k, item in enumerate(items):
        what = f"obstacles[{k}]"
        if isinstance(item, Obstacle):
            item = item.to_dict()
        if not isinstance(item, Mapping):
            raise ValueError(
                f"{what}: expected {{'min': [x, y, z], 'max': [x, y, z], ...}}, "
                f"got {checks.describe(item)}"
            )
        extra = set(item) - set(OBSTACLE_KEYS)
        if extra or not {"min", "max"} <= set(item):
            raise ValueError(
                f"{what}: expected keys 'min', 'max' and optionally 'name', 'absorption', "
                f"'mountable', got {sorted(item)}"
            )
        lo = tuple(float(v) for v in checks.reals(f"{what} min", item["min"], shape=(3,)))
        hi = tuple(float(v) for v in checks.reals(f"{what} max", item["max"], shape=(3,)))
        if any(a >= b for a, b in zip(lo, hi, strict=True)):
            raise ValueError(
                f"{what}: min {list(lo)} must be below max {list(hi)} on every axis (a box "
                "with volume)"
            )
        name = item.get("name", "")
        if not isinstance(name, str):
            raise ValueError(f"{what}: name must be a string, got {name!r}")
        alpha = checks.real(f"{what} absorption", item.get("absorption", DEFAULT_ABSORPTION),
                            low=0.0, high=1.0)  # fmt: skip
        mountable = checks.flag(f"{what} mountable", item.get("mountable", False))
        _check_inside(what, lo, hi, size, corners)
        out.append(Obstacle(lo, hi, name, alpha, mountable))
    _check_apart(out)
    return tuple(out)


def _check_apart(obstacles: list[Obstacle]) -> None:
    """Refuse two boxes that share a volume. Each box reflects on all six faces, so where
    two overlap, the faces of one inside the other and the faces they share would reflect
    twice: the same solid would sound different from the same solid made of boxes that
    only touch (their common faces lie inside it and reflect nothing)."""
    if len(obstacles) < 2:
        return
    lo = np.array([o.lo for o in obstacles])
    hi = np.array([o.hi for o in obstacles])
    common = np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None])
    i, j = np.nonzero(np.triu(np.all(common > 1e-9, axis=-1), k=1))
    if i.size == 0:
        return
    a, b = int(i[0]), int(j[0])
    c_lo, c_hi = np.maximum(lo[a], lo[b]), np.minimum(hi[a], hi[b])

    def named(k: int) -> str:
        return f"obstacles[{k}]" + (f" ({obstacles[k].name!r})" if obstacles[k].name else "")

    span = ", ".join(f"{ax} {u:g}–{v:g}" for ax, u, v in zip("xyz", c_lo, c_hi, strict=True))
    raise ValueError(
        f"{named(b)}: overlaps {named(a)} in {span} m; allowed: boxes that touch at most "
        "(describe a solid of another shape as boxes that meet face to face: an overlap "
        "would reflect twice where the boxes share a face)"
    )


def _check_inside(what: str, lo, hi, size, corners) -> None:
    tol = 1e-9
    if lo[2] < -tol or hi[2] > size[2] + tol:
        raise ValueError(
            f"{what}: z from {lo[2]:g} to {hi[2]:g} m leaves the room (floor 0, ceiling "
            f"{size[2]:g} m); allowed: 0 <= min z < max z <= {size[2]:g}"
        )
    if corners is None:
        ok = all(lo[k] >= -tol and hi[k] <= size[k] + tol for k in range(2))
    else:
        from shapely import box

        ok = _polygon(corners).buffer(tol).covers(box(lo[0], lo[1], hi[0], hi[1]))
    if not ok:
        raise ValueError(
            f"{what}: the footprint x {lo[0]:g}–{hi[0]:g}, y {lo[1]:g}–{hi[1]:g} m is not "
            "inside the floor plan (outside the room or cutting a wall); allowed: a box "
            "standing in the room, touching its walls at most"
        )


def face_rectangles(ob: Obstacle) -> list[tuple[int, int, np.ndarray, np.ndarray]]:
    """The six faces of a box as (axis, side, lo (3,), hi (3,)): side 0 the face at
    ``lo[axis]`` (outward normal −axis), side 1 at ``hi[axis]`` (outward +axis)."""
    lo, hi = np.asarray(ob.lo, dtype=float), np.asarray(ob.hi, dtype=float)
    out = []
    for axis in range(3):
        for side, at in ((0, lo[axis]), (1, hi[axis])):
            flo, fhi = lo.copy(), hi.copy()
            flo[axis] = fhi[axis] = at
            out.append((axis, side, flo, fhi))
    return out


def on_boundary(axis: int, at: float, lo: np.ndarray, hi: np.ndarray, size, corners) -> bool:
    """Whether the face rectangle [lo, hi] (its ``axis`` fixed at ``at``) lies on the room's
    boundary: the floor, the ceiling, or a wall's plane covering the face."""
    if axis == 2:
        return math.isclose(at, 0.0, abs_tol=1e-9) or math.isclose(at, size[2], abs_tol=1e-9)
    if corners is None:
        return math.isclose(at, 0.0, abs_tol=1e-9) or math.isclose(at, size[axis], abs_tol=1e-9)
    from shapely import LineString

    other = 1 - axis
    seg = [(0.0, 0.0), (0.0, 0.0)]
    for i, v in enumerate((lo[other], hi[other])):
        xy = [0.0, 0.0]
        xy[axis], xy[other] = at, v
        seg[i] = tuple(xy)
    return _polygon(corners).exterior.buffer(1e-9).covers(LineString(seg))

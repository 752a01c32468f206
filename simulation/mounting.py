"""Mounting surfaces: the planes anchors may be mounted on, and their allowed regions.

Each surface is a plane ``anchor_offset`` off a room surface, in the room, described by a
frame: an origin and two orthonormal in-plane axes, so that a point is
origin + u·e_u + v·e_v; (u, v) are its in-plane coordinates and the surface's outer
rectangle is [lower, upper] in them. The surfaces of a room, in the order of
``room.mounting`` followed by the faces of its mountable obstacles:

- a shoebox wall or its ceiling or floor: the axis-aligned rectangle ``anchor_offset`` off
  its plane and at least that far from the neighbouring planes (ceiling: u = x, v = y;
  south/north: u = x, v = z; west/east: u = y, v = z);
- a wall of a polygonal room: the plane ``anchor_offset`` in from the wall, u the distance
  along it from the start of its edge in the inset floor plan, v = z;
- the ceiling or floor of a polygonal room: u = x, v = y over the bounding box of the floor
  plan inset by ``anchor_offset``;
- a face of a ``mountable`` obstacle (not its bottom, nor one on the room's boundary):
  ``anchor_offset`` off the face, at least that far in from its edges.

The **allowed region** of a surface is its rectangle minus what no anchor may occupy:
keep-out boxes and obstacles that its plane cuts, and (ceiling and floor of a polygonal
room) the part of the rectangle outside the inset floor plan. Everything removed is a
rectangle in (u, v): the footprint of a box on a vertical or horizontal plane is one, and
the outside of the floor plan is cut into horizontal slabs at its corners (exact for
rectilinear plans: L, T, U shapes; a slanted edge is followed in slabs of at most
:data:`SLAB` m, the region then inscribed). The region is kept as rectangles
(:mod:`simulation.regions`), which the projection clips to and the gradient refinement
bounds an anchor by. 2-D polygon operations (the inset plan, clipping it into slabs) are
shapely's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simulation.floorplan import face_rectangles, inset, on_boundary
from simulation.regions import free_cells, maximal_rectangles

#: the tallest horizontal slab (m) that follows a slanted edge of a floor plan
SLAB = 0.1

#: the shoebox planes: name -> (axis, side), side 0 is the plane at 0, 1 at L
SHOEBOX_PLANES: dict[str, tuple[int, int]] = {
    "floor": (2, 0),
    "ceiling": (2, 1),
    "south": (1, 0),
    "north": (1, 1),
    "west": (0, 0),
    "east": (0, 1),
}

_EYE = np.eye(3)


@dataclass(frozen=True)
class MountingSurface:
    """A mounting plane as a frame: ``origin`` (3,), unit in-plane axes ``u_axis`` and
    ``v_axis`` (3,), the unit ``normal`` (3,) into the room, and its outer rectangle
    ``lower`` ≤ (u, v) ≤ ``upper`` (m). ``axis``, ``offset`` and ``uv_axes`` describe an
    axis-aligned surface (the plane ``axis = offset``, in-plane axes ``uv_axes``); None for
    a slanted wall."""

    name: str
    origin: tuple[float, float, float]
    u_axis: tuple[float, float, float]
    v_axis: tuple[float, float, float]
    normal: tuple[float, float, float]
    lower: tuple[float, float]
    upper: tuple[float, float]
    axis: int | None = None
    offset: float | None = None
    uv_axes: tuple[int, int] | None = None

    @property
    def area(self) -> float:
        """Area of the outer rectangle in m²."""
        return (self.upper[0] - self.lower[0]) * (self.upper[1] - self.lower[1])

    @property
    def frame(self) -> np.ndarray:
        """(3, 3) rows origin, e_u, e_v."""
        return np.array([self.origin, self.u_axis, self.v_axis], dtype=float)

    def point(self, uv) -> np.ndarray:
        """(..., 3) points from in-plane coordinates (..., 2)."""
        uv = np.asarray(uv, dtype=float)
        o, eu, ev = self.frame
        return o + uv[..., 0, None] * eu + uv[..., 1, None] * ev

    def uv(self, points) -> np.ndarray:
        """(..., 2) in-plane coordinates of points (..., 3) (projected onto the plane)."""
        d = np.asarray(points, dtype=float) - np.asarray(self.origin)
        return np.stack([d @ np.asarray(self.u_axis), d @ np.asarray(self.v_axis)], axis=-1)

    def height(self, points) -> np.ndarray:
        """(...,) signed distance (m) of points (..., 3) from the plane along the normal."""
        d = np.asarray(points, dtype=float) - np.asarray(self.origin)
        return d @ np.asarray(self.normal)


def _aligned(name, axis: int, at: float, normal_sign: float, lower, upper) -> MountingSurface:
    uv = tuple(k for k in range(3) if k != axis)
    origin = np.zeros(3)
    origin[axis] = at
    return MountingSurface(
        name=name,
        origin=tuple(origin),
        u_axis=tuple(_EYE[uv[0]]),
        v_axis=tuple(_EYE[uv[1]]),
        normal=tuple(normal_sign * _EYE[axis]),
        lower=tuple(float(x) for x in lower),
        upper=tuple(float(x) for x in upper),
        axis=axis,
        offset=float(at),
        uv_axes=uv,
    )


def _shoebox_surface(room, name: str) -> MountingSurface:
    axis, side = SHOEBOX_PLANES[name]
    o, L = room.anchor_offset, room.size
    uv = tuple(k for k in range(3) if k != axis)
    at = o if side == 0 else L[axis] - o
    return _aligned(
        name, axis, at, 1.0 if side == 0 else -1.0, (o, o), (L[uv[0]] - o, L[uv[1]] - o)
    )


def _polygon_surface(room, name: str, inner: np.ndarray) -> MountingSurface:
    o, h = room.anchor_offset, room.size[2]
    if name in ("ceiling", "floor"):
        lo, hi = inner.min(axis=0), inner.max(axis=0)
        at = h - o if name == "ceiling" else o
        return _aligned(name, 2, at, -1.0 if name == "ceiling" else 1.0, lo, hi)
    i = room.wall_names.index(name)
    n = len(inner)
    a, b = inner[i], inner[(i + 1) % n]  # the inset edge of wall i
    length = float(np.linalg.norm(b - a))
    d = (b - a) / length
    normal = np.array([-d[1], d[0], 0.0])
    for axis in (0, 1):  # an axis-aligned wall: the exact frame of the shoebox's walls
        if abs(d[1 - axis]) < 1e-12:
            # along axis ``axis``, fixed coordinate on the other: u = the coordinate itself
            lo_u, hi_u = sorted((float(a[axis]), float(b[axis])))
            sign = float(np.sign(normal[1 - axis]))
            return _aligned(name, 1 - axis, float(a[1 - axis]), sign, (lo_u, o), (hi_u, h - o))
    origin = (float(a[0]), float(a[1]), 0.0)
    return MountingSurface(name, origin, (float(d[0]), float(d[1]), 0.0), (0.0, 0.0, 1.0),
                           tuple(normal), (0.0, o), (length, h - o))  # fmt: skip


def _obstacle_surfaces(room) -> list[tuple[MountingSurface, int]]:
    """The mountable obstacles' faces (not bottoms, not on the room's boundary), each with
    its obstacle's index."""
    out = []
    o = room.anchor_offset
    corners = None if room.is_shoebox else np.asarray(room.corners)
    labels = {(0, 0): "-x", (0, 1): "+x", (1, 0): "-y", (1, 1): "+y", (2, 1): "top"}
    for k, ob in enumerate(room.obstacles):
        if not ob.mountable:
            continue
        for axis, side, flo, fhi in face_rectangles(ob):
            if (axis, side) == (2, 0) or on_boundary(axis, flo[axis], flo, fhi, room.size, corners):
                continue
            uv = tuple(j for j in range(3) if j != axis)
            lower = (flo[uv[0]] + o, max(flo[uv[1]], 0.0) + o)
            upper = (fhi[uv[0]] - o, min(fhi[uv[1]], room.size[2]) - o)
            if axis == 2:
                lower = (flo[0] + o, flo[1] + o)
                upper = (fhi[0] - o, fhi[1] - o)
            if upper[0] <= lower[0] or upper[1] <= lower[1]:
                continue  # narrower than two offsets: no room for an anchor
            at = flo[axis] - o if side == 0 else flo[axis] + o
            sign = -1.0 if side == 0 else 1.0  # out of the box, into the room
            name = f"{ob.name or f'obstacle-{k}'}:{labels[(axis, side)]}"
            out.append((_aligned(name, axis, at, sign, lower, upper), k))
    return out


def _check_room(room) -> None:
    """ValueError unless ``room`` is a room (this module serves :mod:`simulation.room`, so
    it does not import it)."""
    if type(room).__name__ != "Room" or not hasattr(room, "mounting"):
        raise ValueError(
            f"room: must be a simulation.Room (e.g. Room.techtile(), Room.from_toml(path)), "
            f"got {type(room).__name__}"
        )


def face_obstacles(room) -> dict:
    """{surface name: the obstacle it is a face of} for the faces of the room's mountable
    obstacles among :func:`mounting_surfaces`."""
    _check_room(room)
    return {s.name: room.obstacles[k] for s, k in _obstacle_surfaces(room)}


def mounting_surfaces(room) -> tuple[MountingSurface, ...]:
    """The room's mounting surfaces: ``room.mounting`` in its order, then the faces of its
    mountable obstacles (module docstring)."""
    _check_room(room)
    if room.is_shoebox:
        base = [_shoebox_surface(room, n) for n in room.mounting]
    else:
        inner = inset(np.asarray(room.corners), room.anchor_offset)
        inner = _match_walls(inner, np.asarray(room.corners), room.anchor_offset)
        base = [_polygon_surface(room, n, inner) for n in room.mounting]
    return tuple(base + [s for s, _ in _obstacle_surfaces(room)])


def _match_walls(inner: np.ndarray, corners: np.ndarray, offset: float) -> np.ndarray:
    """The inset corners in the order of the walls: inset edge i parallel to wall i, in the
    same direction, ``offset`` m inside it."""
    n = len(corners)
    if len(inner) != n:
        raise ValueError(
            "anchor_offset: insetting the floor plan by it drops a wall (a wall shorter than "
            "about two offsets); allowed: a smaller anchor_offset or longer walls"
        )
    wd = np.roll(corners, -1, axis=0) - corners
    wd /= np.linalg.norm(wd, axis=1, keepdims=True)
    wn = np.stack([-wd[:, 1], wd[:, 0]], axis=1)  # inward normals (CCW corners)
    for shift in range(n):
        e = np.roll(inner, -shift, axis=0)
        ed = np.roll(e, -1, axis=0) - e
        ed /= np.linalg.norm(ed, axis=1, keepdims=True)
        depth = np.sum((e - corners) * wn, axis=1)
        if np.allclose(np.sum(ed * wd, axis=1), 1.0, atol=1e-9) and np.allclose(
            depth, offset, atol=1e-9
        ):
            return e
    raise ValueError("anchor_offset: the inset floor plan does not match its walls")


# -- allowed regions -------------------------------------------------------------------------
def _box_footprint(s: MountingSurface, lo, hi):
    """The (lower uv, upper uv) of a box [lo, hi] that the surface's plane cuts, or None."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if s.axis is not None:
        if not (lo[s.axis] <= s.offset <= hi[s.axis]):
            return None
        u, v = s.uv_axes
        return (lo[u], lo[v]), (hi[u], hi[v])
    # a slanted vertical plane: clip its horizontal line by the box's xy rectangle
    o, d = np.asarray(s.origin[:2]), np.asarray(s.u_axis[:2])
    t0, t1 = -math.inf, math.inf
    for k in range(2):
        if abs(d[k]) < 1e-15:
            if not (lo[k] <= o[k] <= hi[k]):
                return None
            continue
        a, b = (lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    if t0 > t1:
        return None
    return (t0, lo[2]), (t1, hi[2])


def _outside_plan(s: MountingSurface, room) -> list:
    """Rectangles (uv) of the ceiling's or floor's outer rectangle outside the inset floor
    plan (module docstring): horizontal slabs at its corners, slabs of at most SLAB m
    where an edge is slanted, each slab keeping the x-range inside the plan throughout."""
    from shapely import Polygon, box

    plan = Polygon(inset(np.asarray(room.corners), room.anchor_offset))
    x0, x1 = s.lower[0], s.upper[0]
    ys = np.unique(np.round(np.asarray(plan.exterior.coords)[:, 1], 12))
    cuts = [ys[0]]
    for a, b in zip(ys[:-1], ys[1:], strict=True):
        piece = plan.intersection(box(x0 - 1, a, x1 + 1, b))
        parts = [g for g in getattr(piece, "geoms", [piece]) if g.geom_type == "Polygon"]
        rectilinear = all(_rectilinear(np.asarray(g.exterior.coords)) for g in parts)
        steps = 1 if rectilinear else max(1, math.ceil((b - a) / SLAB))
        cuts += list(np.linspace(a, b, steps + 1)[1:])
    blocks = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        slab = plan.intersection(box(x0 - 1, a, x1 + 1, b))
        inside = []  # x-intervals inside the plan at every y of the slab
        for part in getattr(slab, "geoms", [slab]):
            if part.is_empty or part.area <= 0:
                continue
            left, right = _inscribed_x(np.asarray(part.exterior.coords), a, b)
            if right > left:
                inside.append((left, right))
        edges = [x0, *sorted(v for iv in sorted(inside) for v in iv), x1]
        for lo_x, hi_x in zip(edges[0::2], edges[1::2], strict=False):
            if hi_x > lo_x:
                blocks.append(((lo_x, a), (hi_x, b)))
    return blocks


def _rectilinear(xy: np.ndarray) -> bool:
    """Whether every edge of the closed ring ``xy`` is horizontal or vertical."""
    d = np.diff(xy, axis=0)
    return bool(np.all((np.abs(d[:, 0]) < 1e-12) | (np.abs(d[:, 1]) < 1e-12)))


def _inscribed_x(xy: np.ndarray, a: float, b: float) -> tuple[float, float]:
    """The x-range a slab piece (its exterior ring ``xy``, all corners at y = a or y = b)
    holds at every height between a and b: its left boundary is one segment from the
    leftmost corner at a to the leftmost at b, its right boundary likewise."""
    at_a = xy[np.abs(xy[:, 1] - a) < 1e-9, 0]
    at_b = xy[np.abs(xy[:, 1] - b) < 1e-9, 0]
    if not (at_a.size and at_b.size):  # a sliver pinched to a point at one end
        return 0.0, 0.0
    return float(max(at_a.min(), at_b.min())), float(min(at_a.max(), at_b.max()))


def surface_blocks(room, s: MountingSurface) -> list:
    """Everything removed from the surface's rectangle, as uv rectangles: keep-outs and
    obstacles its plane cuts, and the outside of the inset floor plan."""
    boxes = list(room.keepouts) + [(ob.lo, ob.hi) for ob in room.obstacles]
    blocks = [fp for lo, hi in boxes if (fp := _box_footprint(s, lo, hi)) is not None]
    if not room.is_shoebox and s.name in ("ceiling", "floor"):
        blocks += _outside_plan(s, room)
    return blocks


def regions(room):
    """((cells lower (n, 2), upper (n, 2), surface (n,)), (rectangles lower, upper,
    surface)) in uv: the disjoint free cells and the maximal rectangles of every surface's
    allowed region (:mod:`simulation.regions`)."""
    out = {"cells": ([], [], []), "rects": ([], [], [])}
    for i, s in enumerate(mounting_surfaces(room)):
        blocks = surface_blocks(room, s)
        for key, fn in (("cells", free_cells), ("rects", maximal_rectangles)):
            lo2, hi2 = fn(s.lower, s.upper, blocks)
            out[key][0].append(np.asarray(lo2, dtype=float).reshape(-1, 2))
            out[key][1].append(np.asarray(hi2, dtype=float).reshape(-1, 2))
            out[key][2].append(np.full(len(lo2), i))
    res = []
    for key in ("cells", "rects"):
        arrays = tuple(np.concatenate(a) for a in out[key])
        for a in arrays:
            a.setflags(write=False)
        res.append(arrays)
    return tuple(res)


def check_mounting_area(room) -> None:
    """ValueError naming the surface when keep-outs, obstacles or the floor plan leave a
    mounting surface no allowed area."""
    cells = regions(room)[0]
    lo, hi, idx = cells
    area = np.prod(hi - lo, axis=-1)
    for i, s in enumerate(mounting_surfaces(room)):
        if not np.any(area[idx == i] > 0):
            cut = [k for k, (a, b) in enumerate(room.keepouts) if _box_footprint(s, a, b)]
            obs = [k for k, ob in enumerate(room.obstacles) if _box_footprint(s, ob.lo, ob.hi)]
            feet = [[[round(float(v), 6) for v in f[0]], [round(float(v), 6) for v in f[1]]]
                    for a, b in room.keepouts if (f := _box_footprint(s, a, b))]  # fmt: skip
            raise ValueError(
                f"keepouts: boxes {cut} ({feet} in the plane)"
                + (f" and obstacles {obs}" if obs else "")
                + f" cover the whole mounting area of surface {s.name!r} (anchors "
                f"{room.anchor_offset:g} m off the plane, at least that far from its edges); "
                f"allowed: boxes that leave part of it free, or remove {s.name!r} from mounting"
            )

"""Mounting surfaces: where anchors may go, and the projection back onto them (paper §II).

The surfaces themselves (frames, outer rectangles, allowed regions) are
:mod:`simulation.mounting`'s: planes ``anchor_offset`` off the walls, the ceiling (or floor)
and the faces of mountable obstacles, each with in-plane coordinates (u, v). A point on a
surface is written (surface index, u, v); for a shoebox u, v are the two in-plane
coordinates in increasing axis order (ceiling: u = x, v = y; south/north: u = x, v = z;
west/east: u = y, v = z), for a polygonal room's wall u runs along it.

Keep-outs (``room.keepouts``) and obstacles: an anchor at p is forbidden iff p lies in a
keep-out box (faces included) or outside the room (:func:`allowed`). The allowed region of
a surface is its rectangle minus what its plane cuts of those boxes (and, on the ceiling
of a polygonal room, the part outside the floor plan), written as a union of allowed
rectangles (:func:`allowed_rectangles`) that stop 1 µm
(:data:`simulation.regions.EPS`) outside every box; :func:`project`,
:func:`candidate_grid` and :func:`random_layout` only return points of those rectangles
or, for the grid, points outside every box. ``surface_index``, ``on_surfaces``, ``to_uv``
and ``from_uv`` describe the whole rectangles (geometry only).
"""

from __future__ import annotations

import math

import numpy as np

from simulation import checks, streams
from simulation.directivity import aim_vectors
from simulation.mounting import MountingSurface, mounting_surfaces, regions
from simulation.room import Room, as_room

#: most candidate points :func:`candidate_grid` makes, and most anchors of a random layout
MAX_CANDIDATES, MAX_LAYOUT_ANCHORS = 1_000_000, 100_000

#: the most anchors a plan places: the bound on M of the swarm, the search and the plan
MAX_ANCHORS = 100

__all__ = ["MountingSurface", "mounting_surfaces"]

#: a room's geometry -> the result of simulation.mounting.regions
_REGIONS: dict = {}


def _key(room: Room):
    obstacles = tuple((ob.lo, ob.hi, ob.mountable) for ob in room.obstacles)
    return (room.size, room.corners, room.wall_names, room.mounting, room.anchor_offset,
            room.keepouts, obstacles)  # fmt: skip


def _room_regions(room: Room):
    """Read-only (cells, rectangles) of the room, each (lower (n, 2), upper (n, 2),
    surface (n,)) in the surfaces' (u, v)."""
    room = as_room(room)
    key = _key(room)
    out = _REGIONS.get(key)
    if out is None:
        if len(_REGIONS) >= 64:
            _REGIONS.clear()
        out = _REGIONS[key] = regions(room)
    return out


def _frames(room: Room, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(origins (n, 3), in-plane axes (n, 2, 3)) of the surfaces with indices (n,)."""
    surfs = mounting_surfaces(room)
    o = np.array([s.origin for s in surfs], dtype=float)
    e = np.array([[s.u_axis, s.v_axis] for s in surfs], dtype=float)
    return o[index], e[index]


def allowed_rectangles(room: Room) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The allowed mounting region as rectangles: (lower (R, 2), upper (R, 2), surface (R,))
    in the (u, v) of each surface.

    Per surface (in the order of :func:`mounting_surfaces`, ``surface`` its index) the
    maximal rectangles of its allowed region, largest first; they may overlap and stop
    1 µm outside every keep-out. Without keep-outs, obstacles or a floor plan: one
    rectangle per surface, the surface itself.
    """
    lo, hi, idx = _room_regions(room)[1]
    return lo.copy(), hi.copy(), idx.copy()


def rectangle_corners(room: Room) -> np.ndarray:
    """(R, 4, 3) the corners of every allowed rectangle in room coordinates (m)."""
    lo, hi, idx = _room_regions(room)[1]
    o, e = _frames(room, idx)
    uv = np.stack([lo, np.stack([hi[:, 0], lo[:, 1]], 1), hi, np.stack([lo[:, 0], hi[:, 1]], 1)],
                  axis=1)  # fmt: skip
    return o[:, None] + uv[..., 0, None] * e[:, None, 0] + uv[..., 1, None] * e[:, None, 1]


def allowed_area(room: Room) -> np.ndarray:
    """(S,) allowed mounting area (m²) of each surface: its rectangle minus the keep-outs,
    obstacles and (a polygonal room's ceiling) the outside of the floor plan."""
    lo, hi, idx = _room_regions(room)[0]
    out = np.zeros(len(mounting_surfaces(room)))
    for i in range(len(out)):
        d = (hi - lo)[idx == i]
        out[i] = np.sum(d[:, 0] * d[:, 1])
    return out


def allowed(room: Room, points, tol: float = 1e-9) -> np.ndarray:
    """(...,) bool: each point may carry an anchor: on a mounting rectangle (within ``tol``
    m), in no keep-out box (closed, no tolerance) and inside the room (the floor plan,
    outside the obstacles)."""
    room = as_room(room)
    p = np.asarray(points, dtype=float)
    ok = on_surfaces(room, p, tol) & ~room.in_keepout(p)
    if not room.is_shoebox or room.obstacles:
        ok &= room.contains(p)
    return ok


def project(room: Room, points) -> np.ndarray:
    """Project points (..., 3) onto the nearest allowed mounting rectangle (paper §III-B).

    Each point goes to the closest point of the closest allowed rectangle
    (:func:`allowed_rectangles`), so an anchor may jump from one surface to another, and
    never lands in a keep-out (at worst 1 µm farther than the true nearest allowed point).
    Returns (..., 3).
    """
    p = checks.reals("points", points)
    if p.ndim < 1 or p.shape[-1] != 3:
        raise ValueError(f"points: expected shape (..., 3), got {p.shape}")
    room = as_room(room)
    lo, hi, idx = _room_regions(room)[1]
    o, e = _frames(room, idx)  # (R, 3), (R, 2, 3)
    d = p[..., None, :] - o  # (..., R, 3)
    uv = np.clip(np.einsum("...rk,rjk->...rj", d, e), lo, hi)  # (..., R, 2)
    cand = o + uv[..., 0, None] * e[:, 0] + uv[..., 1, None] * e[:, 1]  # (..., R, 3)
    dist = np.sum((cand - p[..., None, :]) ** 2, axis=-1)
    best = np.argmin(dist, axis=-1)
    return np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]


def surface_index(room: Room, points, tol: float = 1e-9) -> np.ndarray:
    """(...,) index into :func:`mounting_surfaces` of the surface each point lies on
    (within ``tol`` m of its plane and its rectangle), −1 if none."""
    p = checks.reals("points", points)
    if p.ndim < 1 or p.shape[-1] != 3:
        raise ValueError(f"points: expected shape (..., 3), got {p.shape}")
    tol = checks.real("tol", tol, low=0.0, high=1.0, unit="m")
    surfs = mounting_surfaces(room)
    on = np.zeros((*p.shape[:-1], len(surfs)), dtype=bool)
    for i, s in enumerate(surfs):
        uv = s.uv(p)
        on[..., i] = (
            (np.abs(s.height(p)) <= tol)
            & np.all(uv >= np.asarray(s.lower) - tol, axis=-1)
            & np.all(uv <= np.asarray(s.upper) + tol, axis=-1)
        )
    return np.where(on.any(axis=-1), np.argmax(on, axis=-1), -1)


def on_surfaces(room: Room, points, tol: float = 1e-9) -> np.ndarray:
    """(...,) bool: each point lies on a mounting rectangle (within ``tol`` m)."""
    return surface_index(room, points, tol) >= 0


def to_uv(room: Room, points, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """(surface index (...,), uv (..., 2)) of points on the surfaces; ValueError if off them."""
    p = checks.reals("points", points)
    idx = surface_index(room, p, tol)
    if np.any(idx < 0):
        raise ValueError("points: some points are not on an allowed mounting surface")
    o, e = _frames(room, idx)
    return idx, np.einsum("...k,...jk->...j", p - o, e)


def from_uv(room: Room, index, uv, tol: float = 1e-6) -> np.ndarray:
    """(..., 3) points from surface indices (...,) and in-plane coordinates uv (..., 2) in
    metres; ValueError for an index that names no surface or a uv off its rectangle (by
    more than ``tol`` m)."""
    surfs = mounting_surfaces(room)
    last = len(surfs) - 1
    index = checks.reals("index", index, low=0, high=last)
    if np.any(index != np.round(index)):
        raise ValueError(f"index: every entry must be a surface index, an integer in [0, {last}]")
    index = index.astype(int)
    uv = checks.reals("uv", uv, shape=(*index.shape, 2))
    lo = np.array([s.lower for s in surfs])[index]
    hi = np.array([s.upper for s in surfs])[index]
    off = (uv < lo - tol) | (uv > hi + tol)
    if np.any(off):
        k = tuple(int(i) for i in np.argwhere(off.any(axis=-1))[0])
        (u0, v0), (u1, v1) = lo[k], hi[k]
        raise ValueError(
            f"uv: {uv[k].tolist()} at index {list(k)} lies off surface {surfs[index[k]].name!r} "
            f"(u in [{u0:g}, {u1:g}], v in [{v0:g}, {v1:g}] m)"
        )
    out = np.empty((*index.shape, 3))
    for i, s in enumerate(surfs):
        m = index == i
        if np.any(m):
            out[m] = s.point(uv[m])
    return out


def candidate_grid(room: Room, spacing: float = 0.5) -> np.ndarray:
    """(N, 3) candidate mounting points: a grid of about ``spacing`` m on every surface.

    Each rectangle side gets ⌈length/spacing⌉ + 1 evenly spaced points including both
    edges. Two surfaces that meet (a wall and the ceiling, two walls) share the points
    of their common edge: each is kept once, where its first surface lists it.
    Points in a keep-out box are dropped, and every allowed rectangle
    (:func:`allowed_rectangles`) left without a point gets its centre, so that each part
    of the allowed region keeps a candidate.
    """
    spacing = checks.real("spacing", spacing, low=0.0, low_open=True, unit="m")
    n = 0
    for s in mounting_surfaces(room):
        sides = zip(s.lower, s.upper, strict=True)
        n += math.prod(max(2, math.ceil((hi - lo) / spacing - 1e-9) + 1) for lo, hi in sides)
    if n > MAX_CANDIDATES:
        raise ValueError(
            f"spacing: {spacing:g} m gives {n:.3g} candidate points, more than {MAX_CANDIDATES}; "
            "use a larger spacing"
        )
    rlo, rhi, ridx = _room_regions(room)[1]
    plain = room.is_shoebox and not room.obstacles
    pts = []
    for i, s in enumerate(mounting_surfaces(room)):
        axes = [
            np.linspace(lo, hi, max(2, int(np.ceil((hi - lo) / spacing - 1e-9)) + 1))
            for lo, hi in zip(s.lower, s.upper, strict=True)
        ]
        uv = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
        p = s.point(uv)
        if room.keepouts or not plain:
            lo, hi = rlo[ridx == i], rhi[ridx == i]
            keep = ~room.in_keepout(p)
            if not plain:  # outside the floor plan, in an obstacle: in no allowed rectangle
                keep &= np.any(np.all((uv[:, None] >= lo - 1e-9) & (uv[:, None] <= hi + 1e-9),
                                      axis=-1), axis=1)  # fmt: skip
            p, uv = p[keep], uv[keep]
            inside = np.all((uv[:, None] >= lo - 1e-9) & (uv[:, None] <= hi + 1e-9), axis=-1)
            empty = ~inside.any(axis=0)
            p = np.concatenate([p, s.point((lo[empty] + hi[empty]) / 2)])
        pts.append(p)
    return new_points(np.empty((0, 3)), np.concatenate(pts, axis=0))


def new_points(existing, points, tol: float = 1e-3) -> np.ndarray:
    """The points (n, 3) farther than ``tol`` (m) from every existing point (k, 3) and from
    each other (the first of a close pair kept), in their order."""
    from scipy.spatial import cKDTree

    base = np.asarray(existing, dtype=float).reshape(-1, 3)
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    keep = np.ones(len(p), dtype=bool)
    if len(p) and len(base):
        keep &= cKDTree(base).query(p)[0] > tol
    pairs = cKDTree(p).query_pairs(tol, output_type="ndarray") if len(p) > 1 else []
    # in increasing order of the later point: its earlier partner's fate is already known
    for i, j in sorted(map(tuple, pairs), key=lambda ij: (ij[1], ij[0])):
        if keep[i]:
            keep[j] = False
    return p[keep]


def area_counts(room: Room, M: int) -> np.ndarray:
    """Anchors per surface in proportion to allowed area (largest remainder): M = 4 → 1, 1, 2."""
    M = checks.count("M", M, low=1, high=MAX_LAYOUT_ANCHORS)
    areas = allowed_area(as_room(room))
    share = M * areas / areas.sum()
    counts = np.floor(share).astype(int)
    order = np.argsort(-(share - counts), kind="stable")
    counts[order[: M - counts.sum()]] += 1
    return counts


def random_layout(room: Room, M: int, rng: np.random.Generator | int | None = None) -> np.ndarray:
    """(M, 3) anchors uniformly random on the allowed region, counts by :func:`area_counts`.

    Within a surface the points are uniform over its allowed area (a cell of the allowed
    region is drawn with probability ∝ its area, then a point uniformly in it).
    """
    rng = streams.rng("rng", rng)
    clo, chi, cidx = _room_regions(as_room(room))[0]
    out = []
    for i, (s, n) in enumerate(zip(mounting_surfaces(room), area_counts(room, M), strict=True)):
        lo = clo[cidx == i]
        hi = chi[cidx == i]
        if len(lo) == 1:  # no keep-out on this surface: the same draws as without keep-outs
            uv = rng.uniform(lo[0], hi[0], size=(n, 2))
        else:
            area = np.prod(hi - lo, axis=-1)
            k = rng.choice(len(lo), size=n, p=area / area.sum())
            uv = rng.uniform(lo[k], hi[k])
        out.append(s.point(uv))
    return np.concatenate(out, axis=0)


def _edge_segments(room: Room) -> list[tuple[np.ndarray, np.ndarray]]:
    """Where a naive installer puts anchors: the top edge of every mounting wall (in the
    order of ``room.mounting``), or without mounting walls the edge of the first mounting
    surface (ceiling or floor), as (start, end) segments."""
    surfs = mounting_surfaces(room)
    walls = [s for s in surfs if s.name in room.mounting and s.name not in ("ceiling", "floor")]
    if walls:  # wall rectangles have v = z: the top edge is v = upper
        return [
            (s.point([s.lower[0], s.upper[1]]), s.point([s.upper[0], s.upper[1]])) for s in walls
        ]
    s = surfs[0]
    (u0, v0), (u1, v1) = s.lower, s.upper
    loop = [s.point(c) for c in ((u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0))]
    return list(zip(loop[:-1], loop[1:], strict=True))


def naive_layout(room: Room, M: int) -> np.ndarray:
    """(M, 3) a naive layout: M anchors spread evenly along the top edges of the mounting
    walls (without mounting walls: around the edge of the ceiling or floor), the way
    anchors are often installed without planning; anchors in a keep-out are moved to the
    nearest allowed point (:func:`project`).

    The edges are joined end to end and anchor k sits at arc length (k + ½)·ℓ/M along
    them (ℓ their total length). In techtile (south, north walls and ceiling) M = 4 puts
    two anchors along the top of each long wall, at a quarter and three quarters of it.
    A comparison baseline for the report, beside the paper's corners layout.
    """
    room = as_room(room)
    M = checks.count("M", M, low=1, high=MAX_LAYOUT_ANCHORS)
    segments = _edge_segments(room)
    start = np.array([a for a, _ in segments])
    step = np.array([b - a for a, b in segments])
    length = np.linalg.norm(step, axis=-1)
    ends = np.cumsum(length)
    t = (np.arange(M) + 0.5) * ends[-1] / M
    k = np.minimum(np.searchsorted(ends, t), len(segments) - 1)
    frac = (t - (ends[k] - length[k])) / np.where(length[k] > 0, length[k], 1.0)
    return project(room, start[k] + frac[:, None] * step[k])


def aim(room: Room, anchors) -> np.ndarray:
    """(..., M, 3) unit aim vectors of the anchors toward the room centroid (paper §V-A)."""
    return aim_vectors(anchors, as_room(room).centroid)

"""Mounting surfaces: where anchors may go, and the projection back onto them (paper §II).

Each allowed surface is an axis-aligned rectangle ``anchor_offset`` off its plane and at
least ``anchor_offset`` in from the neighbouring planes. A point on a surface is written
(surface index, u, v) with u, v the two in-plane coordinates in increasing axis order
(ceiling: u = x, v = y; south/north: u = x, v = z; west/east: u = y, v = z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simulation.directivity import aim_vectors
from simulation.room import SURFACES, Room


@dataclass(frozen=True)
class MountingSurface:
    """An allowed rectangle: ``axis`` fixed at ``offset``, in-plane axes ``uv_axes``."""

    name: str
    axis: int
    offset: float
    uv_axes: tuple[int, int]
    lower: tuple[float, float]
    upper: tuple[float, float]

    @property
    def area(self) -> float:
        """Area of the rectangle in m²."""
        return (self.upper[0] - self.lower[0]) * (self.upper[1] - self.lower[1])

    def point(self, uv) -> np.ndarray:
        """(..., 3) points from in-plane coordinates (..., 2)."""
        uv = np.asarray(uv, dtype=float)
        out = np.empty((*uv.shape[:-1], 3))
        out[..., self.axis] = self.offset
        out[..., self.uv_axes[0]] = uv[..., 0]
        out[..., self.uv_axes[1]] = uv[..., 1]
        return out


def mounting_surfaces(room: Room) -> tuple[MountingSurface, ...]:
    """The room's allowed mounting rectangles, in the order of ``room.mounting``."""
    o = room.anchor_offset
    out = []
    for name in room.mounting:
        axis, side = SURFACES[name]
        uv = tuple(k for k in range(3) if k != axis)
        out.append(
            MountingSurface(
                name=name,
                axis=axis,
                offset=o if side == 0 else room.size[axis] - o,
                uv_axes=uv,
                lower=(o, o),
                upper=(room.size[uv[0]] - o, room.size[uv[1]] - o),
            )
        )
    return tuple(out)


def _bounds(room: Room) -> tuple[np.ndarray, np.ndarray]:
    """(S, 3) lower and upper corners of the surfaces (equal on the fixed axis)."""
    surfs = mounting_surfaces(room)
    lo = np.empty((len(surfs), 3))
    hi = np.empty((len(surfs), 3))
    for i, s in enumerate(surfs):
        lo[i, s.axis] = hi[i, s.axis] = s.offset
        for k, a in enumerate(s.uv_axes):
            lo[i, a], hi[i, a] = s.lower[k], s.upper[k]
    return lo, hi


def project(room: Room, points) -> np.ndarray:
    """Project points (..., 3) onto the nearest allowed mounting rectangle (paper §III-B).

    Each point goes to the closest point of the closest rectangle, so an anchor may jump
    from one surface to another. Returns (..., 3).
    """
    p = np.asarray(points, dtype=float)
    if not np.all(np.isfinite(p)):
        raise ValueError("points: must be finite (no NaN or inf)")
    lo, hi = _bounds(room)
    cand = np.clip(p[..., None, :], lo, hi)  # (..., S, 3)
    dist = np.sum((cand - p[..., None, :]) ** 2, axis=-1)
    best = np.argmin(dist, axis=-1)
    return np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]


def surface_index(room: Room, points, tol: float = 1e-9) -> np.ndarray:
    """(...,) index into :func:`mounting_surfaces` of the surface each point lies on, −1 if none."""
    p = np.asarray(points, dtype=float)
    lo, hi = _bounds(room)
    on = np.all((p[..., None, :] >= lo - tol) & (p[..., None, :] <= hi + tol), axis=-1)
    return np.where(on.any(axis=-1), np.argmax(on, axis=-1), -1)


def on_surfaces(room: Room, points, tol: float = 1e-9) -> np.ndarray:
    """(...,) bool: each point lies on an allowed mounting rectangle (within ``tol`` m)."""
    return surface_index(room, points, tol) >= 0


def to_uv(room: Room, points, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """(surface index (...,), uv (..., 2)) of points on the surfaces; ValueError if off them."""
    p = np.asarray(points, dtype=float)
    idx = surface_index(room, p, tol)
    if np.any(idx < 0):
        raise ValueError("points: some points are not on an allowed mounting surface")
    surfs = mounting_surfaces(room)
    uv_axes = np.array([s.uv_axes for s in surfs])[idx]  # (..., 2)
    return idx, np.take_along_axis(p, uv_axes, axis=-1)


def from_uv(room: Room, index, uv) -> np.ndarray:
    """(..., 3) points from surface indices (...,) and in-plane coordinates (..., 2)."""
    surfs = mounting_surfaces(room)
    index = np.asarray(index, dtype=int)
    uv = np.asarray(uv, dtype=float)
    out = np.empty((*index.shape, 3))
    for i, s in enumerate(surfs):
        m = index == i
        if np.any(m):
            out[m] = s.point(uv[m])
    return out


def candidate_grid(room: Room, spacing: float = 0.5) -> np.ndarray:
    """(N, 3) candidate mounting points: a grid of about ``spacing`` m on every surface.

    Each rectangle side gets ⌈length/spacing⌉ + 1 evenly spaced points including both
    edges. Shared edges between surfaces are not duplicated (they are 3 cm apart).
    """
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing: must be > 0 m, got {spacing}")
    pts = []
    for s in mounting_surfaces(room):
        axes = [
            np.linspace(lo, hi, max(2, int(np.ceil((hi - lo) / spacing - 1e-9)) + 1))
            for lo, hi in zip(s.lower, s.upper, strict=True)
        ]
        uv = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
        pts.append(s.point(uv))
    return np.concatenate(pts, axis=0)


def area_counts(room: Room, M: int) -> np.ndarray:
    """Anchors per surface in proportion to area (largest remainder): M = 4 → 1, 1, 2."""
    if int(M) != M or M < 1:
        raise ValueError(f"M: number of anchors must be an integer >= 1, got {M}")
    areas = np.array([s.area for s in mounting_surfaces(room)])
    share = M * areas / areas.sum()
    counts = np.floor(share).astype(int)
    order = np.argsort(-(share - counts), kind="stable")
    counts[order[: M - counts.sum()]] += 1
    return counts


def random_layout(room: Room, M: int, rng: np.random.Generator | int | None = None) -> np.ndarray:
    """(M, 3) anchors uniformly random on the surfaces, counts by :func:`area_counts`."""
    rng = np.random.default_rng(rng)
    out = []
    for s, n in zip(mounting_surfaces(room), area_counts(room, M), strict=True):
        uv = rng.uniform(s.lower, s.upper, size=(n, 2))
        out.append(s.point(uv))
    return np.concatenate(out, axis=0)


def aim(room: Room, anchors) -> np.ndarray:
    """(..., M, 3) unit aim vectors of the anchors toward the room centroid (paper §V-A)."""
    return aim_vectors(anchors, room.centroid)

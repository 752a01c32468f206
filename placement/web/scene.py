"""What the planning page shows, as plain JSON-ready dicts: the room's drawing, the
coverage and bound maps of a layout, and anchors moved on their mounting surfaces.

The maps are a horizontal slice at the tag height (the evaluation nodes' median height):
per cell, the anchors heard in line of sight and reach (:func:`analysis.coverage.coverage`,
the receiver's view, docs/model.md "Coverage") and the position error bound
PEB = √tr J⁻¹ (m) from those anchors (:func:`analysis.coverage.bound`, paper eq. (9));
the summary counts the room's evaluation nodes, as the planner does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analysis.coverage import bound, coverage
from analysis.fim import DEFAULT_SIGMA
from placement.cli.common import checked_layout
from placement.coverage import coverage_k
from placement.surfaces import MAX_ANCHORS, project, rectangle_corners
from simulation import checks
from simulation.positioning import MIN_HEARD
from simulation.room import Room

#: the most cells of a map slice (the cell size grows to stay below it)
MAX_CELLS = 2500
#: the smallest cell of a map slice, m
MIN_CELL = 0.1


def _box(lo, hi, name: str = "", **extra) -> dict[str, Any]:
    return {"min": [float(v) for v in lo], "max": [float(v) for v in hi], "name": name, **extra}


def drawing(room: Room) -> dict[str, Any]:
    """The room as the page draws it (metres): ``size``, the floor plan's ``corners``
    (n, 2), ``obstacles``, ``keepouts`` and ``zones`` as boxes, and ``mounting``: the
    allowed mounting rectangles' corners (R, 4, 3)."""
    obstacles = [_box(ob.lo, ob.hi, ob.name, mountable=bool(ob.mountable)) for ob in room.obstacles]
    names = room.keepout_names or ("",) * len(room.keepouts)
    keepouts = [_box(lo, hi, n) for (lo, hi), n in zip(room.keepouts, names, strict=True)]
    names = room.zone_names or ("",) * len(room.zones)
    zones = [_box(lo, hi, n) for (lo, hi), n in zip(room.zones, names, strict=True)]
    return {
        "name": room.name,
        "size": [float(v) for v in room.size],
        "corners": room.floor_corners.tolist(),
        "obstacles": obstacles,
        "keepouts": keepouts,
        "zones": zones,
        "mounting": np.round(rectangle_corners(room), 6).tolist(),
    }


def slice_height(room: Room) -> float:
    """The maps' height (m): the median height of the room's evaluation nodes."""
    return float(np.median(room.grid()[:, 2]))


def slice_cells(room: Room) -> tuple[np.ndarray, float]:
    """(cells (C, 3) the centres of the map's cells inside the room, cell size (m)): a
    grid at :func:`slice_height` with at most :data:`MAX_CELLS` cells over the floor's
    bounding box, cell size a multiple of 5 cm, at least :data:`MIN_CELL`."""
    Lx, Ly, _ = room.size
    cell = max(MIN_CELL, math.ceil(math.sqrt(Lx * Ly / MAX_CELLS) / 0.05) * 0.05)
    xs = np.arange(cell / 2, Lx, cell)
    ys = np.arange(cell / 2, Ly, cell)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    z = np.full(gx.size, slice_height(room))
    pts = np.stack([gx.ravel(), gy.ravel(), z], axis=1)
    return pts[room.contains(pts, margin=min(room.node_margin, cell / 4))], cell


def _stats(values: np.ndarray) -> dict[str, float | None]:
    finite = values[np.isfinite(values)]
    if not len(finite):
        return {"median": None, "p95": None, "finite": 0.0}
    return {
        "median": float(np.median(finite)),
        "p95": float(np.percentile(finite, 95)),
        "finite": float(len(finite) / len(values)),
    }


def maps(room: Room, system, anchors, sigma: float = DEFAULT_SIGMA) -> dict[str, Any]:
    """The coverage and PEB maps of ``anchors`` (M, 3) with ``system``'s signal and
    receiver: ``cells`` (C, 2) x, y and ``cell`` size (m) at ``height``; ``heard`` (C,)
    anchors in line of sight and reach; ``peb`` (C,) m (None where no fix: fewer than 4
    heard or a singular geometry); ``k`` the anchors a node needs (5 for positioning that
    rejects echoes, else 4); ``summary`` over the evaluation nodes: the shares covered by
    k and by 4 anchors, and the PEB's median and P95 (m) where finite."""
    a = np.asarray(anchors, dtype=float)
    cells, size = slice_cells(room)
    height = slice_height(room) if not len(cells) else float(cells[0, 2])
    nodes = room.grid()
    k = coverage_k(system)
    heard_cells = coverage(room, a, cells, system=system)
    peb_cells = bound(room, a, cells, sigma=sigma, system=system)
    heard_nodes = coverage(room, a, nodes, system=system)
    peb_nodes = bound(room, a, nodes, sigma=sigma, system=system)
    return {
        "cells": np.round(cells[:, :2], 6).tolist(),
        "cell": size,
        "height": height,
        "heard": heard_cells.astype(int).tolist(),
        "peb": [float(v) if np.isfinite(v) else None for v in peb_cells],
        "k": k,
        "sigma": sigma,
        "summary": {
            "nodes": len(nodes),
            "covered_k": float(np.mean(heard_nodes >= k)),
            "covered_fix": float(np.mean(heard_nodes >= MIN_HEARD)),
            "peb": _stats(peb_nodes),
        },
    }


def check_layout(room: Room, anchors, min_anchors: int = 4) -> np.ndarray:
    """(M, 3) the layout checked as the command line checks a layout file (at least
    ``min_anchors``, at most :data:`MAX_ANCHORS`, in the room, out of the keep-outs,
    distinct); ValueError with the command line's message."""
    a = checks.points("anchors", anchors)
    if len(a) > MAX_ANCHORS:
        raise ValueError(f"anchors: at most {MAX_ANCHORS} anchors, got {len(a)}")
    return checked_layout(room, a, min_anchors)


def moved(room: Room, anchors, index: int, point) -> np.ndarray:
    """(M, 3) ``anchors`` with anchor ``index`` moved to the mounting surfaces' allowed
    point nearest ``point`` (3,) (:func:`placement.surfaces.project`). A point inside an
    obstacle, a keep-out or outside the room is refused with the layout check's message
    naming the anchor (:meth:`simulation.Room.check_anchors`): the user aimed at a place
    no anchor may go."""
    a = checks.points("anchors", anchors).copy()
    index = checks.count("index", index, low=0, high=len(a) - 1)
    p = checks.reals("point", point)
    if p.shape != (3,):
        raise ValueError(f"point: expected 3 coordinates (x, y, z) in m, got shape {p.shape}")
    a[index] = p
    room.check_anchors(a, min_anchors=1)  # the dropped point itself, named as anchor index
    a[index] = project(room, p)
    return check_layout(room, a, min_anchors=1)


def added(room: Room, anchors, point) -> np.ndarray:
    """(M + 1, 3) ``anchors`` with one more at the allowed mounting point nearest ``point``."""
    a = checks.points("anchors", anchors) if len(anchors) else np.empty((0, 3))
    if len(a) >= MAX_ANCHORS:
        raise ValueError(f"anchors: at most {MAX_ANCHORS} anchors, got {len(a) + 1}")
    return moved(room, np.concatenate([a, np.zeros((1, 3))]), len(a), point)


def removed(anchors, index: int) -> np.ndarray:
    """(M − 1, 3) ``anchors`` without anchor ``index``."""
    a = checks.points("anchors", anchors)
    index = checks.count("index", index, low=0, high=len(a) - 1)
    return np.delete(a, index, axis=0)

"""The mounting sheet: a plan's anchors as an installer measures them.

Each anchor is described on the surface it is mounted on (:mod:`simulation.mounting`):

- on a wall (or a vertical face of a mountable obstacle): the distance along the wall from
  its **reference corner**, the wall's left end as seen from inside the room facing the
  wall (a shoebox's south wall: its south-east corner), the height above the floor, and
  the distance the speaker's acoustic centre stands off the wall (the room's
  ``anchor_offset``);
- on the ceiling (or the floor, or an obstacle's top): x and y from the room's reference
  corner (its first floor-plan corner: a shoebox's south–west corner; an obstacle's top:
  its corner of least x and y), and the height above the floor.

The aim is the direction the simulator points the speaker's cardioid (paper §V-A: at the
room's centroid) as azimuth (degrees from +x toward +y) and elevation (degrees above the
horizontal); on a vertical surface also as a pan from the surface's normal, positive toward
its reference corner, which is how one turns a bracket. The mounting tolerance is the one
the plan assumed (its search's ``mount_tolerance``).

The CSV keeps millimetres (metres with three decimals) and a tenth of a degree; the numbers
read back through :func:`anchors_from_csv` give every coordinate to within 1 mm. The
printable sheet (:mod:`placement.sheet_html`) draws the same numbers.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from placement.mount import COLUMNS, Mount, VerticalFrame
from placement.sheet_html import render
from placement.surfaces import mounting_surfaces, surface_index
from simulation import checks
from simulation.directivity import aim_vectors
from simulation.mounting import face_obstacles
from simulation.output import write_file, write_files
from simulation.room import Room, as_room

#: a shoebox's corners in floor-plan order
_COMPASS = ("south-west", "south-east", "north-east", "north-west")

#: how far (m) a point may lie off a mounting plane and still be on it
_ON = 1e-6


def corner_names(room: Room) -> list[str]:
    """The floor plan's corners as an installer names them: a shoebox's by the compass,
    a polygonal room's corner i by the walls that meet there (``"west/south"``)."""
    room = as_room(room)
    if room.is_shoebox:
        return list(_COMPASS)
    names = room.wall_names
    return [f"{names[i - 1]}/{names[i]}" for i in range(len(names))]


def vertical_frames(room: Room) -> dict[str, VerticalFrame]:
    """The frame of every vertical mounting surface by name: the room's walls (reference:
    the corner at the wall's end, its left end seen from inside) and the vertical faces of
    its mountable obstacles (reference: the face's left edge seen from the room)."""
    room = as_room(room)
    corners = corner_names(room)
    out = {}
    for i, wall in enumerate(room.walls):
        d = wall.direction[:2]
        out[wall.name] = VerticalFrame(
            wall.name, f"{corners[(i + 1) % len(corners)]} corner", tuple(wall.end),
            tuple(-d), tuple(wall.normal[:2]), wall.length, 0.0, wall.height,
        )  # fmt: skip
    faces = face_obstacles(room)
    for s in mounting_surfaces(room):
        if s.name not in faces or abs(s.normal[2]) > 0.5:
            continue
        ob = faces[s.name]
        n = np.asarray(s.normal[:2])
        right = np.array([-n[1], n[0]])
        axis = int(np.argmax(np.abs(n)))
        at = ob.hi[axis] if n[axis] > 0 else ob.lo[axis]
        pts = np.empty((2, 2))  # the face's two vertical edges in plan
        pts[:, axis], pts[:, 1 - axis] = at, (ob.lo[1 - axis], ob.hi[1 - axis])
        start = pts[np.argmin(pts @ right)]
        out[s.name] = VerticalFrame(
            s.name, f"{s.name} left edge", tuple(float(v) for v in start), tuple(right),
            tuple(n), float(ob.hi[1 - axis] - ob.lo[1 - axis]), float(ob.lo[2]), float(ob.hi[2]),
        )  # fmt: skip
    return out


def _plane_reference(room: Room, surface: str) -> tuple[str, tuple[float, float]]:
    """The reference corner (name, (x, y)) of a horizontal surface."""
    ob = face_obstacles(room).get(surface)
    if ob is not None:  # an obstacle's top
        return f"{surface} corner", (float(ob.lo[0]), float(ob.lo[1]))
    c = room.floor_corners[0]
    return f"{corner_names(room)[0]} corner", (float(c[0]), float(c[1]))


def mounts(room: Room, anchors, tolerance: float | None = None) -> list[Mount]:
    """The mounting description of each anchor (M, 3) m in ``room`` (module docstring);
    ``tolerance`` (m) is the mounting tolerance the plan assumed (None: not stated)."""
    room = as_room(room)
    a = checks.points("anchors", anchors)
    if tolerance is not None:
        tolerance = checks.real("tolerance", tolerance, low=0.0, high=1.0, unit="m")
    surfs = mounting_surfaces(room)
    index = surface_index(room, a, tol=_ON)
    frames = vertical_frames(room)
    aim = aim_vectors(a, room.centroid)
    out = []
    for j, (p, i, u) in enumerate(zip(a, index, aim, strict=True)):
        az = math.degrees(math.atan2(u[1], u[0]))
        el = math.degrees(math.asin(float(np.clip(u[2], -1.0, 1.0))))
        common = {"id": j + 1, "height": float(p[2]), "azimuth": az, "elevation": el,
                  "tolerance": tolerance, "position": tuple(float(v) for v in p)}  # fmt: skip
        name = surfs[i].name if i >= 0 else ""
        if name in frames:
            f = frames[name]
            rel = p[:2] - np.asarray(f.start)
            out.append(Mount(surface=name, kind="wall", reference=f.reference,
                             reference_xy=f.start, along=float(rel @ f.right),
                             plan_x=None, plan_y=None, off_surface=float(rel @ f.normal),
                             pan=math.degrees(math.atan2(-(u[:2] @ f.right), u[:2] @ f.normal)),
                             **common))  # fmt: skip
        elif i >= 0:
            ref, xy = _plane_reference(room, name)
            off = abs(float(surfs[i].height(p)) + room.anchor_offset)
            out.append(Mount(surface=name, kind="plane", reference=ref, reference_xy=xy,
                             along=None, plan_x=float(p[0] - xy[0]), plan_y=float(p[1] - xy[1]),
                             off_surface=off, pan=None, **common))  # fmt: skip
        else:
            out.append(Mount(surface="", kind="free", reference="room origin",
                             reference_xy=(0.0, 0.0), along=None, plan_x=float(p[0]),
                             plan_y=float(p[1]), off_surface=0.0, pan=None, **common))  # fmt: skip
    return out


def csv_text(rows: list[Mount]) -> str:
    """The mounts as the text of ``anchors.csv`` (columns :data:`COLUMNS`)."""
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, fieldnames=COLUMNS)
    w.writeheader()
    for r in rows:
        w.writerow(r.row())
    return buf.getvalue()


def write_csv(path, rows: list[Mount]) -> Path:
    """Write the mounts as ``anchors.csv`` (columns :data:`COLUMNS`) to ``path`` (never
    half-written, :mod:`simulation.output`)."""
    return write_file(path, csv_text(rows))


def anchors_from_csv(path, room: Room) -> np.ndarray:
    """(M, 3) m the anchors an installer places from the CSV at ``path``, in ID order: on a
    wall, its reference corner plus ``along`` along the wall and ``off_surface`` into the
    room at ``height``; on a horizontal surface, its reference corner plus (plan x, plan y)
    at ``height``; free anchors at their room coordinates. Only the installer's numbers
    are read, not the room coordinates the file also lists."""
    room = as_room(room)
    frames = vertical_frames(room)
    with Path(path).open(newline="") as fh:
        rows = sorted(csv.DictReader(fh), key=lambda r: int(r["id"]))
    out = []
    for r in rows:
        ref = np.array([float(r["reference_x_m"]), float(r["reference_y_m"])])
        if r["along_m"]:
            f = frames[r["surface"]]
            xy = ref + float(r["along_m"]) * np.asarray(f.right)
            xy = xy + float(r["off_surface_m"]) * np.asarray(f.normal)
        else:
            xy = ref + np.array([float(r["plan_x_m"]), float(r["plan_y_m"])])
        out.append([xy[0], xy[1], float(r["height_m"])])
    return np.array(out, dtype=float).reshape(-1, 3)


def write_sheet(out_dir, room: Room, anchors, *, tolerance: float | None = None,
                title: str | None = None) -> dict[str, Path]:  # fmt: skip
    """Write ``anchors.csv`` and the printable ``sheet.html`` (:mod:`placement.sheet_html`)
    of the layout ``anchors`` (M, 3) m in ``room`` to the folder ``out_dir`` (created);
    the paths written, by name."""
    room = as_room(room)
    rows = mounts(room, anchors, tolerance)
    out = checks.output_path("out_dir", out_dir, kind="dir")
    out.mkdir(parents=True, exist_ok=True)
    html = render(room, rows, vertical_frames(room), title=title or f"Mounting sheet: {room.name}")
    write_files({out / "anchors.csv": csv_text(rows), out / "sheet.html": html})
    return {"csv": out / "anchors.csv", "html": out / "sheet.html"}

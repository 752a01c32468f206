"""The printable mounting sheet (:mod:`placement.sheet`): one self-contained HTML page, inline
CSS and SVG only, laid out as A4 portrait pages.

Pages, in the order an installer uses them: the ceiling plan (the floor plan seen from above
with every anchor, the keep-outs and obstacles, the reference corner) with the conventions;
the table of every anchor (25 rows a page); then one page per wall of the room, in corner
order, and per mountable obstacle face that carries anchors: its elevation as seen from
inside the room, the keep-outs and obstacles against it, each anchor with its dimension
lines from the reference corner (along the wall) and from the floor, and that wall's rows
of the table (a wall without anchors shows its keep-outs; the plan page lists such walls).
Every page is a fixed-size block that breaks before the next, so a browser prints exactly
one sheet per page.
"""

from __future__ import annotations

import html
import math
from typing import Any

import numpy as np

from analysis.stacking import STACKED, stacks
from placement.mount import Mount, VerticalFrame
from simulation.room import Room

#: table rows per printed page
ROWS_PER_PAGE = 25

#: drawing width in SVG units (the page's printable width)
_W = 700.0

#: a box (keep-out or obstacle) this close (m) to a wall is drawn on its elevation
_NEAR = 0.25

_CSS = """
@page{size:A4 portrait;margin:12mm}
*{box-sizing:border-box}
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#1d232a;margin:0;
font-size:10pt;line-height:1.35}
section.page{width:186mm;height:270mm;overflow:hidden;break-after:page;page-break-after:always;
padding:0;margin:0 auto}
section.page:last-child{break-after:auto;page-break-after:auto}
h1{font-size:15pt;margin:0 0 2mm}h2{font-size:12.5pt;margin:0 0 2mm}
.sub{color:#4a535c;margin:0 0 3mm}
svg{display:block;width:100%;height:auto;max-height:150mm;margin:0 0 3mm}
table{border-collapse:collapse;width:100%;font-size:8.5pt}
th,td{border:1px solid #b8bec5;padding:0.8mm 1.2mm;text-align:right;white-space:nowrap}
th{background:#eef1f4}td.l,th.l{text-align:left;white-space:normal}
ul{margin:1mm 0 2mm 5mm;padding:0}li{margin:0.5mm 0}
@media screen{body{background:#e9ecef}section.page{background:#fff;margin:8mm auto;
outline:6mm solid #fff;box-shadow:0 0 0 6mm #fff,0 1px 10mm #0002}}
"""


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _m(x: float | None) -> str:
    return "–" if x is None else f"{x:.3f}"


def _deg(x: float | None) -> str:
    return "–" if x is None else f"{round(x, 1) + 0.0:+.1f}"  # + 0.0: no "-0.0"


def _table(rows: list[Mount]) -> str:
    head = (
        "<tr><th>ID</th><th class=l>surface</th><th class=l>measured from</th>"
        "<th>along</th><th>x</th><th>y</th><th>height</th><th>off</th>"
        "<th>pan</th><th>tilt</th><th>azimuth</th><th>tol.</th></tr>"
    )
    body = []
    for r in rows:
        body.append(
            f"<tr><td>A{r.id}</td><td class=l>{_e(r.surface or 'free-standing')}</td>"
            f"<td class=l>{_e(r.reference)}</td><td>{_m(r.along)}</td><td>{_m(r.plan_x)}</td>"
            f"<td>{_m(r.plan_y)}</td><td>{_m(r.height)}</td><td>{_m(r.off_surface)}</td>"
            f"<td>{_deg(r.pan)}</td><td>{_deg(r.elevation)}</td><td>{_deg(r.azimuth)}</td>"
            f"<td>{_m(r.tolerance)}</td></tr>"
        )
    legend = (
        '<p class="sub">Lengths in m, angles in degrees. <b>pan</b>: from square to '
        "the wall, + toward its reference corner; <b>tilt</b>: above the horizontal "
        "(− down); <b>azimuth</b>: in the plan, from +x toward +y; <b>off</b>: the "
        "acoustic centre's distance from the surface; <b>tol.</b>: the mounting "
        "tolerance the plan assumed.</p>"
    )
    return f"<table>{head}{''.join(body)}</table>{legend}"


def _boxes(room: Room) -> list[tuple[np.ndarray, np.ndarray, str, str]]:
    """(lo (3,), hi (3,), name, kind) of every keep-out and obstacle."""
    out = []
    names = room.keepout_names or ("",) * len(room.keepouts)
    for k, ((lo, hi), name) in enumerate(zip(room.keepouts, names, strict=True)):
        out.append(
            (np.asarray(lo, float), np.asarray(hi, float), name or f"keep-out {k + 1}", "keepout")
        )
    for k, ob in enumerate(room.obstacles):
        out.append(
            (
                np.asarray(ob.lo, float),
                np.asarray(ob.hi, float),
                ob.name or f"obstacle {k + 1}",
                "obstacle",
            )
        )
    return out


def _defs() -> str:
    return (
        '<defs><pattern id="hatch" width="6" height="6" patternUnits="userSpaceOnUse" '
        'patternTransform="rotate(45)"><line x1="0" y1="0" x2="0" y2="6" '
        'stroke="#c0392b" stroke-width="1.5"/></pattern>'
        '<marker id="tick" viewBox="0 0 10 10" refX="5" refY="5" markerWidth="6" '
        'markerHeight="6" orient="auto"><line x1="5" y1="0" x2="5" y2="10" '
        'stroke="#1d232a" stroke-width="1.5"/></marker></defs>'
    )


def _box_style(kind: str) -> str:
    if kind == "keepout":
        return 'fill="url(#hatch)" stroke="#c0392b" stroke-width="1"'
    return 'fill="#d5d8dc" stroke="#6c757d" stroke-width="1"'


def _text(x, y, s, size=11, anchor="start", extra="") -> str:
    return (
        f'<text x="{x:.1f}" y="{y:.1f}" font-size="{size}" text-anchor="{anchor}" '
        f"{extra}>{_e(s)}</text>"
    )


def _dim(x0, y0, x1, y1) -> str:
    return (
        f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x1:.1f}" y2="{y1:.1f}" stroke="#1d232a" '
        'stroke-width="0.8" marker-start="url(#tick)" marker-end="url(#tick)"/>'
    )


def elevation_svg(room: Room, frame: VerticalFrame, rows: list[Mount]) -> str:
    """The elevation of one vertical surface seen from the room: the surface, the boxes
    against it, its anchors with dimension lines from the reference corner and the floor."""
    L, H = frame.length, frame.top - frame.bottom
    left, top, gap = 70.0, 24.0, 17.0
    s = min((_W - left - 30) / L, 300.0 / H)
    bottom = top + H * s
    height = bottom + 30 + gap * len(rows) + 10

    def X(u):
        return left + u * s

    def Y(z):
        return bottom - (z - frame.bottom) * s

    parts = [
        f'<svg viewBox="0 0 {_W:.0f} {height:.0f}" xmlns="http://www.w3.org/2000/svg">',
        _defs(),
        f'<rect x="{X(0):.1f}" y="{top:.1f}" width="{L * s:.1f}" '
        f'height="{H * s:.1f}" fill="#fbfbf8" stroke="#1d232a" stroke-width="2"/>',
    ]
    parts += _boxes_on_wall(room, frame, X, Y, s)
    parts.append(_text(X(0), bottom + 14, f"◀ {frame.reference}", 10))
    parts.append(_text(X(L), bottom + 14, f"{L:.3f} m", 10, "end"))
    parts.append(
        _text(
            X(0) - 6,
            Y(frame.bottom) + 4,
            "floor" if frame.bottom == 0 else f"{frame.bottom:.2f}",
            9,
            "end",
        )
    )
    ordered = sorted(rows, key=lambda r: r.along)
    for k, r in enumerate(ordered):
        # anchors above each other (one along): their heights' dimensions side by side
        beside = sum(abs(q.along - r.along) <= STACKED for q in ordered[:k])
        parts += _anchor_on_wall(r, X, Y(frame.bottom), Y(r.height), bottom + 30 + gap * k, beside)
    parts.append("</svg>")
    return "".join(parts)


def _boxes_on_wall(room: Room, frame: VerticalFrame, X, Y, s: float) -> list[str]:
    """The obstacles and keep-outs against the surface ``frame`` as drawn on its elevation
    (``X``, ``Y``: metres along and up to pixels; ``s`` pixels per metre)."""
    parts = []
    start, right, normal = (np.asarray(v) for v in (frame.start, frame.right, frame.normal))
    for lo, hi, name, kind in _boxes(room):
        if name == frame.name.rsplit(":", 1)[0]:
            continue  # the obstacle whose face this is
        foot = np.array([[x, y] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]) - start
        depth, along = foot @ normal, foot @ right
        z0, z1 = max(lo[2], frame.bottom), min(hi[2], frame.top)
        u0, u1 = max(along.min(), 0.0), min(along.max(), frame.length)
        if depth.min() > _NEAR or depth.max() < -1e-9 or z1 <= z0 or u1 <= u0:
            continue
        parts.append(
            f'<rect x="{X(u0):.1f}" y="{Y(z1):.1f}" width="{(u1 - u0) * s:.1f}" '
            f'height="{(z1 - z0) * s:.1f}" {_box_style(kind)}/>'
        )
        parts.append(_text(X(u0) + 3, Y(z1) + 12, name, 10))
    return parts


def _anchor_on_wall(r: Mount, X, floor: float, y: float, yd: float, beside: int) -> list[str]:
    """One anchor on a wall's elevation: its dimension line along the wall at ``yd`` px, its
    height's from the ``floor`` px (``beside`` anchors below it on the same vertical: this
    one's dimension drawn that many places to the right), its mark at height ``y`` px."""
    x = X(r.along)
    xh = x + 9 + 16 * beside
    near = x - X(0) < 140
    mid = (floor + y) / 2
    return [
        _dim(X(0), yd, x, yd),
        _text(
            X(0) + 4 if near else (X(0) + x) / 2,
            yd - 3,
            f"A{r.id}: {r.along:.3f} m",
            10,
            "start" if near else "middle",
        ),  # fmt: skip
        f'<line x1="{x:.1f}" y1="{y:.1f}" x2="{x:.1f}" y2="{yd:.1f}" '
        'stroke="#8a939c" stroke-width="0.6" stroke-dasharray="3 3"/>',
        _dim(xh, floor, xh, y),
        _text(
            xh + 4,
            mid,
            f"{r.height:.3f} m",
            10,
            extra=f'transform="rotate(-90 {xh + 4:.1f} {mid:.1f})"',
        ),  # fmt: skip
        f'<circle cx="{x:.1f}" cy="{y:.1f}" r="6" fill="#1f77b4" stroke="#fff"/>',
        _text(x - 8, y - 9, f"A{r.id}", 11, "end", 'font-weight="600"'),
    ]


def plan_svg(room: Room, rows: list[Mount]) -> str:
    """The ceiling plan: the floor plan seen from above (north up), the boxes, every anchor
    (ceiling ones with their x, y from the reference corner), the wall names."""
    corners = room.floor_corners
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    pad = 60.0
    s = min((_W - 2 * pad) / (hi[0] - lo[0]), 460.0 / (hi[1] - lo[1]))
    height = (hi[1] - lo[1]) * s + 2 * pad

    def P(x, y):
        return pad + (x - lo[0]) * s, pad + (hi[1] - y) * s

    pts = " ".join(f"{P(*c)[0]:.1f},{P(*c)[1]:.1f}" for c in corners)
    parts = [
        f'<svg viewBox="0 0 {_W:.0f} {height:.0f}" xmlns="http://www.w3.org/2000/svg">',
        _defs(),
        f'<polygon points="{pts}" fill="#fbfbf8" stroke="#1d232a" stroke-width="2"/>',
    ]
    for blo, bhi, name, kind in _boxes(room):
        (x0, y1), (x1, y0) = P(blo[0], blo[1]), P(bhi[0], bhi[1])
        parts.append(
            f'<rect x="{x0:.1f}" y="{y0:.1f}" width="{max(x1 - x0, 1):.1f}" '
            f'height="{max(y1 - y0, 1):.1f}" {_box_style(kind)} opacity="0.8"/>'
        )
        parts.append(_text(x0 + 2, y0 - 3, f"{name} (z {blo[2]:.2f}–{bhi[2]:.2f})", 8.5))
    for wall in room.walls:
        mid = 0.5 * (wall.start + wall.end)
        out = -wall.normal[:2] * 18 / s
        x, y = P(*(mid + out))
        angle = -math.degrees(math.atan2(wall.direction[1], wall.direction[0]))
        if angle > 90 or angle < -90:
            angle += 180
        parts.append(
            _text(
                x,
                y + 4,
                wall.name,
                11,
                "middle",
                f'transform="rotate({angle:.1f} {x:.1f} {y:.1f})" fill="#4a535c"',
            )
        )
    rx, ry = P(*corners[0])  # the ceiling's reference corner (placement.sheet)
    parts.append(f'<circle cx="{rx:.1f}" cy="{ry:.1f}" r="4" fill="#c0392b"/>')
    parts.append(_text(rx + 6, ry + 14, "reference corner (0, 0)", 10, extra='fill="#c0392b"'))
    ceiling = [r for r in rows if r.kind == "plane" and ":" not in r.surface]
    on_walls = [r for r in rows if not (r.kind == "plane" and ":" not in r.surface)]
    for r in ceiling:
        x, y = P(r.position[0], r.position[1])
        dx, anchor = _label_side(x)
        parts.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="6" fill="#1f77b4" stroke="#fff"/>')
        parts.append(_text(x + dx, y - 4, f"A{r.id}", 11, anchor, 'font-weight="600"'))
        parts.append(_text(x + dx, y + 7, f"x {r.plan_x:.3f}", 8.5, anchor))
        parts.append(_text(x + dx, y + 17, f"y {r.plan_y:.3f}", 8.5, anchor))
    # wall anchors one above the other are one spot from above: one label ("A4, A5")
    for stack in stacks([r.position[:2] for r in on_walls]):
        for k in stack:
            x, y = P(on_walls[k].position[0], on_walls[k].position[1])
            parts.append(
                f'<rect x="{x - 5:.1f}" y="{y - 5:.1f}" width="10" height="10" '
                'fill="#2ca02c" stroke="#fff"/>'
            )
        x, y = P(on_walls[stack[0]].position[0], on_walls[stack[0]].position[1])
        dx, anchor = _label_side(x)
        parts.append(_text(x + dx, y + 4, ", ".join(f"A{on_walls[k].id}" for k in stack), 10,
                           anchor))  # fmt: skip
    parts.append("</svg>")
    return "".join(parts)


def _label_side(x: float) -> tuple[float, str]:
    """(dx px, text-anchor) of a label beside a mark at x px: on the side away from the
    nearer end of the drawing, so that none leaves it."""
    return (8.0, "start") if x < _W / 2 else (-8.0, "end")


def _page(title: str, sub: str, body: str) -> str:
    return f'<section class="page"><h2>{_e(title)}</h2><p class="sub">{_e(sub)}</p>{body}</section>'


def render(room: Room, rows: list[Mount], frames: dict[str, VerticalFrame], *, title: str) -> str:
    """The sheet's HTML (module docstring) for the mounts ``rows`` in ``room``, whose
    vertical surfaces are ``frames`` (by name)."""
    # every wall of the room gets a page (its keep-outs, even without anchors), in corner
    # order; an obstacle's face only when it carries anchors
    on_wall: dict[str, list] = {w.name: [] for w in room.walls}
    for r in rows:
        if r.kind == "wall":
            on_wall.setdefault(r.surface, []).append(r)
    empty = [name for name, wall_rows in on_wall.items() if not wall_rows]
    tol = next((r.tolerance for r in rows if r.tolerance is not None), None)
    conventions = (
        "<ul><li>Walls are drawn as seen from inside the room; <b>along</b> is measured "
        "on the wall from its reference corner (its left end), <b>height</b> from the floor "
        "to the speaker's acoustic centre.</li>"
        "<li>Ceiling anchors: <b>x</b>, <b>y</b> from the reference corner of the plan "
        "(x to the right, y up the page).</li>"
        f"<li>The speaker's acoustic centre stands {room.anchor_offset * 100:.1f} cm off "
        "its surface; aim it at the room's centre as the aim column says (pan from square "
        "to the wall, tilt from the horizontal).</li>"
        f"<li>Mounting tolerance assumed by the plan: "
        f"{'not stated' if tol is None else f'{tol * 100:.1f} cm'}.</li>"
        + (f"<li>Walls without anchors: {_e(', '.join(empty))}.</li>" if empty else "")
        + "</ul>"
    )
    size = f"{room.size[2]:.2f} m high"
    pages = [
        f'<section class="page"><h1>{_e(title)}</h1><p class="sub">{_e(room.name)}, '
        f"{len(rows)} anchors, {size}; ceiling plan (north up)</p>"
        f"{plan_svg(room, rows)}{conventions}</section>"
    ]
    for k in range(0, max(len(rows), 1), ROWS_PER_PAGE):
        chunk = rows[k : k + ROWS_PER_PAGE]
        pages.append(
            _page(
                "Anchors",
                f"{room.name}: anchors {k + 1}–{k + len(chunk)} of {len(rows)}",
                _table(chunk),
            )
        )
    for name, wall_rows in on_wall.items():
        f = frames[name]
        sub = (
            f"{f'{len(wall_rows)} anchor(s)' if wall_rows else 'no anchors'}; "
            f"{f.length:.3f} m long, measured from the "
            f"{f.reference} at ({f.start[0]:.3f}, {f.start[1]:.3f})"
        )
        table = _table(wall_rows) if wall_rows else '<p class="sub">Nothing to mount here.</p>'
        pages.append(_page(f"Wall: {name}", sub, elevation_svg(room, f, wall_rows) + table))
    return (
        "<!DOCTYPE html><html lang=en><head><meta charset=utf-8>"
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>"
        + "".join(pages)
        + "</body></html>\n"
    )

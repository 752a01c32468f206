"""Floor plans in DXF, the CAD format floor plans come in (ezdxf).

**Reading** (:func:`read_floor_plan`, :func:`room_from_dxf`): the room's outline is the closed
polyline (LWPOLYLINE or POLYLINE; one whose last point comes back within :data:`GAP` of
its first closes), or the LINEs, ARCs and open polylines joined end to end into one closed
loop, on a named layer (default ``room``), the obstacles the closed axis-aligned rectangles
(polylines or four lines) on another (default ``obstacles``), standing from the floor
to a given height, or, where a text "NAME z Z0-Z1 m" stands at a rectangle's first corner
(as :func:`write_plan` labels them), named NAME from Z0 to Z1 m. Both may be drawn inside
blocks and placed by block references (a column drawn once, placed at every grid point).
Coordinates are converted to metres from the drawing's unit (``mm``, ``cm``, ``m``, ``in``
or ``ft``: the one given, else the one the drawing's header declares, ``$INSUNITS``, else
metres; a warning where the two differ) and shifted so that the outline's lowest x and y
are 0, the room's origin (a warning on the ``simulation.dxf`` logger gives the shift where
there is one: positions in the room, a layout's anchors among them, are the drawing's
minus that shift). An outline with arc
segments (bulges: a rounded wall) is followed by straight walls within
:data:`ARC_TOLERANCE` of its arcs, with a warning. An axis-aligned rectangular outline
gives the shoebox of its size, any other outline a polygonal room
(:meth:`Room.from_corners`).

**Writing** (:func:`write_plan`): the room's outline, obstacles, keep-outs and tag zones as
closed polylines on their own layers (``room``, ``obstacles``, ``keepouts``, ``zones``; a
box as its footprint, labelled with its name and heights), and the anchors as inserts of
the block ``ANCHOR`` on the layer ``anchors`` with the attributes ``ID``, ``Z`` (height
above the floor, m) and ``SURFACE``; in metres (``$INSUNITS`` 6) or millimetres. Reading
a written file gives the room's outline and its obstacles' footprints, names and heights
back (not their absorption or whether anchors may go on them: the drawing has neither).
"""

from __future__ import annotations

import logging
import re
import weakref
from pathlib import Path

import numpy as np

from simulation import checks
from simulation.floorplan import straight_corners
from simulation.output import write_with
from simulation.room import SIZE_RANGE, Room

logger = logging.getLogger(__name__)

#: the drawing units read and written, in metres per unit
UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}
#: DXF $INSUNITS codes of those units
INSUNITS = {"mm": 4, "cm": 5, "m": 6, "in": 1, "ft": 2}
#: the layers written by :func:`write_plan` (and read by default)
LAYERS = ("room", "obstacles", "keepouts", "zones", "anchors")
#: a box's label as :func:`_label` writes it: "NAME z Z0-Z1 m" (heights in m)
LABEL = re.compile(
    r"^(?P<name>.*) z (?P<z0>[0-9.]+(?:e-?[0-9]+)?)-(?P<z1>[0-9.]+(?:e[-+]?[0-9]+)?) m$"
)


def _doc(path):
    import ezdxf

    p = checks.input_file("dxf", path)
    try:
        return ezdxf.readfile(str(p))
    except (OSError, ezdxf.DXFError) as exc:
        raise ValueError(f"dxf {p}: not a readable DXF file ({exc})") from None


def _layers(layer: str) -> list[str]:
    """The layers ``layer`` names, one or several separated by commas, each once (names
    are case-insensitive) as first named."""
    names: dict[str, str] = {}
    for n in layer.split(","):
        names.setdefault(n.strip().lower(), n.strip())
    return [n for n in names.values() if n]


def _names(layer: str) -> set[str]:
    """The layer names of ``layer`` (:func:`_layers`) in lower case."""
    return {n.lower() for n in _layers(layer)}


def _entities(doc, types: tuple[str, ...] | None, layer: str) -> list:
    """The entities of the drawing's model space of the DXF ``types`` (None: all) on ``layer``
    (case-insensitive; several layers separated by commas), those inside block references
    included (:func:`_placed`)."""
    names = _names(layer)
    return [e for e, on in _placed(doc)
            if (types is None or e.dxftype() in types) and on in names]  # fmt: skip


#: each read drawing's :func:`_placed` entities, computed once per drawing
_PLACED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _placed(doc) -> list[tuple]:
    """(entity, its layer in lower case) of every entity of the drawing's model space, those
    inside block references (INSERTs: a column or a desk drawn once and placed many times)
    placed as the references place them (ezdxf's virtual entities; the references
    themselves left out). An entity of a block on layer "0" is on its reference's layer, as
    CAD programs draw it."""
    if doc not in _PLACED:

        def walk(entities, ref_layer):
            for e in entities:
                on = e.dxf.layer if ref_layer is None or e.dxf.layer != "0" else ref_layer
                if e.dxftype() == "INSERT":
                    yield from walk(e.virtual_entities(), on)
                else:
                    yield e, on.lower()

        _PLACED[doc] = list(walk(doc.modelspace(), None))
    return _PLACED[doc]


def _polylines(doc, layer: str, scale: float) -> list:
    """The (vertices (n, 2), closed, has arcs) of every polyline on ``layer``
    (case-insensitive), in drawing units (``scale`` m each). A polyline with arc segments
    (bulges: a rounded wall, an apse) is followed by straight segments whose chords stay
    within :data:`ARC_TOLERANCE` of its arcs (ezdxf's path flattening); the others keep
    their vertices, but for those on a straight wall (:func:`_merge_straight`)."""
    from ezdxf import path as ezpath

    out = []
    for e in _entities(doc, ("LWPOLYLINE", "POLYLINE"), layer):
        pts, closed = _vertices(e)
        arcs = bool(e.has_arc) if e.dxftype() == "LWPOLYLINE" else any(
            v.dxf.bulge for v in e.vertices)  # fmt: skip
        if arcs:
            flat = ezpath.make_path(e).flattening(ARC_TOLERANCE / scale)
            pts = np.array([(v.x, v.y) for v in flat])
        if _comes_back(pts, scale):
            pts, closed = pts[:-1], True
        out.append((_merge_straight(pts, GAP / scale) if closed else pts, closed, arcs))
    return out


def _vertices(e) -> tuple[np.ndarray, bool]:
    """A polyline's vertices (n, 2) in drawing units and whether it is flagged closed."""
    if e.dxftype() == "LWPOLYLINE":
        pts = [(x, y) for x, y, *_ in e.get_points("xy")]
        return np.array(pts, dtype=float).reshape(-1, 2), bool(e.closed)
    pts = [(v.dxf.location.x, v.dxf.location.y) for v in e.vertices]
    return np.array(pts, dtype=float).reshape(-1, 2), bool(e.is_closed)


def _comes_back(pts: np.ndarray, scale: float) -> bool:
    """The points (n, 2) in drawing units (``scale`` m each) end within :data:`GAP` of where
    they start: the polyline closes."""
    return len(pts) > 2 and np.hypot(*(pts[0] - pts[-1])) <= GAP / scale


def _closed(e, scale: float) -> bool:
    """A polyline closes: flagged closed, or it comes back to its first point."""
    pts, flagged = _vertices(e)
    return flagged or _comes_back(pts, scale)


def _outlines(doc, layer: str, scale: float, path) -> list:
    """The room's outlines on ``layer``: its closed polylines, or where it has none, the
    closed loops of its lines, arcs and open polylines (:func:`_line_loops`, every one of
    them in a loop; lines beside a closed polyline, a door's swing, are not the outline)."""
    closed = [p for p in _polylines(doc, layer, scale) if p[1]]
    return closed or _line_loops(doc, layer, scale, path, strict=True)


def _merge_straight(pts: np.ndarray, tol: float) -> np.ndarray:
    """The closed outline pts (n, 2) without the vertices that lie within ``tol`` (its
    units) of the segment between their neighbours (a wall drawn in two pieces, at a
    door), one at a time."""
    while len(pts) > 3:
        k = straight_corners(pts, tol)
        if not k.size:
            break
        pts = np.delete(pts, k[0], axis=0)
    return pts


#: (m) ends of lines, arcs and open polylines closer than this join (a drawing's rounding)
GAP = 1e-3


def _line_loops(doc, layer: str, scale: float, path, strict: bool) -> list:
    """The closed loops that the LINE and ARC entities and the open polylines on ``layer``
    form end to end within :data:`GAP` (a drawing whose walls are single lines or polylines),
    as :func:`_polylines` gives polylines (ezdxf's edgeminer finds the loops). Those in no
    loop: a ValueError
    naming the layer and the file ``path`` (``strict``), else a warning, and they are left
    out."""
    from ezdxf import edgeminer, edgesmith

    entities = [e for e in _entities(doc, ("LINE", "ARC", "LWPOLYLINE", "POLYLINE"), layer)
                if e.dxftype() in ("LINE", "ARC") or not _closed(e, scale)]  # fmt: skip
    if not entities:
        return []
    gap = GAP / scale  # in drawing units
    edges = list(edgesmith.edges_from_entities_2d(entities, gap_tol=gap))
    loops, rest = [], edges
    while rest:
        try:
            loop = edgeminer.find_loop(edgeminer.Deposit(rest, gap_tol=gap), timeout=10.0)
        except TimeoutError:
            loop = ()
        if not loop:
            break
        ids = {e.id for e in loop}
        rest = [e for e in rest if e.id not in ids]
        chain = edgesmith.path2d_from_chain(loop)
        pts = np.array([(v.x, v.y) for v in chain.flattening(ARC_TOLERANCE / scale)])
        if len(pts) > 1 and np.allclose(pts[0], pts[-1]):
            pts = pts[:-1]
        arcs = any(e.payload.dxftype() == "ARC" for e in loop)
        loops.append((_merge_straight(pts, gap), True, arcs))
    if rest and strict:
        raise ValueError(
            f"layer: {len(rest)} of the {len(edges)} lines, arcs and open polylines on layer "
            f"{layer!r} in {path} do not join end to end into closed outlines (a gap over "
            f"{GAP * 1000:g} mm or a stray line); close them or draw each outline as one "
            "closed polyline"
        )
    if rest:
        logger.warning("%s: %d of the %d lines, arcs and open polylines on layer %r close no "
                       "box and are left out", path, len(rest), len(edges), layer)  # fmt: skip
    return loops


#: (m) the largest distance between an arc of a drawing's outline and the straight walls
#: that follow it
ARC_TOLERANCE = 0.05


def read_floor_plan(
    path, *, layer: str = "room", unit: str | None = None, obstacle_layer: str = "obstacles"
) -> tuple[np.ndarray, list[np.ndarray]]:
    """(corners (n, 2), obstacle footprints [(2, 2) min/max rows]) in metres from the DXF
    ``path`` (module docstring), shifted to the outline's origin. ValueError naming the
    file and layer for a missing layer, no outline, an open or a second outline, or an
    obstacle that is not an axis-aligned rectangle."""
    corners, footprints, *_ = _read(path, layer, unit, obstacle_layer)
    return corners, footprints


def _read(path, layer, unit, obstacle_layer):
    """:func:`read_floor_plan`'s (corners, footprints), each footprint's label
    (:func:`_labels`), the drawing's point that became the origin (2,) m and each
    footprint's layer (one of the names of ``obstacle_layer``, separated by commas)."""
    doc = _doc(path)
    scale = UNITS[_unit(doc, unit, path)]
    outlines = _outlines(doc, layer, scale, path)
    layers = sorted({e.dxf.layer for e in doc.modelspace()})
    if not outlines:
        raise ValueError(
            f"layer: no polyline or lines on layer {layer!r} in {path} (its layers: {layers}); "
            "the room's outline is a closed polyline (or lines joined end to end) on that layer"
        )
    if len(outlines) > 1:
        raise ValueError(f"layer: {len(outlines)} outlines on layer {layer!r} in {path}; "
                         "expected one closed outline")  # fmt: skip
    corners, _, arcs = outlines[0]  # closed: an open outline is refused by _line_loops
    corners = corners * scale
    if arcs:
        logger.warning(
            "%s: the outline on layer %r has arc segments: the room follows them with "
            "straight walls within %g m of the arcs (%d corners in all; every wall adds image "
            "sources to simulate)", path, layer, ARC_TOLERANCE, len(corners),
        )  # fmt: skip
    origin = corners.min(axis=0)
    _say_missing(doc, obstacle_layer, path, layer)
    footprints, owners = [], []
    for name in _layers(obstacle_layer):
        found = _footprints(doc, name, scale, origin, path)
        footprints += found
        owners += [name] * len(found)
    labels = _labels(doc, obstacle_layer, scale, origin, footprints)
    return corners - origin, footprints, labels, origin, owners


def _say_missing(doc, layer, path, outline) -> None:
    """A warning where nothing is on the obstacles' ``layer`` but the drawing has layers
    besides the ``outline``'s: it names them (the obstacles may be there)."""
    drawn = {e.dxf.layer for e in doc.modelspace()}
    others = sorted(n for n in drawn if n.lower() not in _names(outline) | {"0", "defpoints"})
    if others and not _entities(doc, None, layer):
        logger.warning("%s: nothing on layer %r, so no obstacles: are they on %s?", path, layer,
                       ", ".join(map(repr, others)))  # fmt: skip


def _footprints(doc, layer, scale, origin, path) -> list[np.ndarray]:
    """The obstacles' footprints (2, 2) m (lowest, highest x and y, from the room's
    ``origin``) on ``layer``: its closed axis-aligned rectangles (polylines or lines; any
    other closed shape: a ValueError), then its circles (a round column) as the squares
    that hold them, with a warning; entities of other kinds there are left out with a
    warning naming them."""
    footprints = []
    blocks = [p for p in _polylines(doc, layer, scale) if p[1]]
    blocks += _line_loops(doc, layer, scale, path, strict=False)
    for k, (pts, _, _) in enumerate(blocks):
        pts = pts * scale - origin
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        on_edges = np.all(
            (np.isclose(pts[:, 0], lo[0]) | np.isclose(pts[:, 0], hi[0]))
            & (np.isclose(pts[:, 1], lo[1]) | np.isclose(pts[:, 1], hi[1]))
        )
        if len(pts) != 4 or not on_edges:
            raise ValueError(
                f"obstacle_layer: polyline {k} on layer {layer!r} in {path} is not a "
                "closed axis-aligned rectangle (obstacles are boxes)"
            )
        footprints.append(np.array([lo, hi]))
    circles = _entities(doc, ("CIRCLE",), layer)
    for c in circles:
        centre = np.array([c.dxf.center.x, c.dxf.center.y]) * scale - origin
        footprints.append(np.array([centre - c.dxf.radius * scale, centre + c.dxf.radius * scale]))
    if circles:
        logger.warning("%s: %d circle(s) on layer %r (round columns) read as the squares that "
                       "hold them: obstacles are boxes", path, len(circles), layer)  # fmt: skip
    other = sorted(e.dxftype() for e in _entities(doc, None, layer)
                   if e.dxftype() not in READ_ON_OBSTACLES)  # fmt: skip
    if other:
        kinds = ", ".join(f"{other.count(t)} {t}" for t in dict.fromkeys(other))
        logger.warning("%s: left out on layer %r: %s (obstacles are read from closed "
                       "rectangles, lines and circles)", path, layer, kinds)  # fmt: skip
    return footprints


#: the DXF entities the obstacles' layer is read from (texts: their labels)
READ_ON_OBSTACLES = ("LWPOLYLINE", "POLYLINE", "LINE", "ARC", "CIRCLE", "TEXT", "MTEXT")


def _labels(doc, layer, scale, origin, footprints) -> list[tuple[str, float, float] | None]:
    """Per footprint (2, 2) m, the (name, z0, z1) m of the text "NAME z Z0-Z1 m" on
    ``layer`` at its first corner (:func:`write_plan`'s label), or None."""
    texts = []
    for e in doc.modelspace().query("TEXT"):
        m = LABEL.match(e.dxf.text.strip()) if e.dxf.layer.lower() in _names(layer) else None
        if m is not None:
            at = np.array([e.dxf.insert.x, e.dxf.insert.y]) * scale - origin
            texts.append((at, m["name"], float(m["z0"]), float(m["z1"])))
    return [next((t[1:] for t in texts if np.allclose(t[0], lo, atol=1e-6)), None)
            for lo, _ in footprints]  # fmt: skip


def outline_origin(path, *, layer: str = "room", unit: str | None = None) -> np.ndarray:
    """(2,) m: the point of the drawing ``path`` that becomes the room's origin (the lowest
    x and y of its outline on ``layer``; module docstring)."""
    doc = _doc(path)
    scale = UNITS[_unit(doc, unit, path, quiet=True)]
    outlines = _outlines(doc, layer, scale, path)
    if not outlines:
        raise ValueError(f"layer: no outline on layer {layer!r} in {path}")
    return outlines[0][0].min(axis=0) * scale


def _unit(doc, unit: str | None, path, quiet: bool = False) -> str:
    """The drawing's unit: ``unit`` (one of :data:`UNITS`), or where it is None the one its
    header declares ($INSUNITS), metres for a drawing without one. A ValueError for another
    unit; a warning where ``unit`` contradicts the header (unless ``quiet``)."""
    if unit is not None:
        checks.choice("unit", unit, list(UNITS))
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    declared = next((u for u, c in INSUNITS.items() if c == code), None)
    if unit is None and code and declared is None:
        raise ValueError(
            f"unit: {path} declares its unit as $INSUNITS {code}, none of "
            f"{', '.join(UNITS)}: give the drawing's unit"
        )
    if unit is not None and declared is not None and unit != declared and not quiet:
        logger.warning("%s: the drawing declares its unit as %s ($INSUNITS %d); read in %s as "
                       "asked", path, declared, code, unit)  # fmt: skip
    return unit if unit is not None else declared or "m"


def _say_shift(path, o) -> None:
    """A warning where the drawing's outline does not start at its origin: o (2,) m."""
    if np.any(np.abs(o) > 1e-9):
        logger.warning(
            "%s: the floor plan is moved by (%.3f, %.3f) m so that its lowest x and y are 0: "
            "positions in this room (a layout's anchors among them) are the drawing's "
            "coordinates minus (%.3f, %.3f) m", path, -o[0], -o[1], o[0], o[1],
        )  # fmt: skip


def room_from_dxf(
    path,
    height: float,
    *,
    layer: str = "room",
    unit: str | None = None,
    obstacle_layer: str = "obstacles",
    obstacle_height: float | dict[str, float] | None = None,
    **kw,
):
    """The room of the DXF floor plan ``path`` (module docstring): ``height`` m high, its
    obstacles as their labels give them or, unlabelled, from the floor to
    ``obstacle_height`` m (needed when a layer has any such; a dict gives it per layer of
    ``obstacle_layer``, by name); every other keyword is a :class:`~simulation.room.Room`
    field."""
    h = checks.real("height", height, low=SIZE_RANGE[0], high=SIZE_RANGE[1], unit="m")
    corners, footprints, labels, origin, owners = _read(path, layer, unit, obstacle_layer)
    obstacles = list(kw.pop("obstacles", None) or [])
    tops = _heights(obstacle_height, [o for o, lab in zip(owners, labels, strict=True)
                                      if lab is None], h, path)  # fmt: skip
    for k, ((lo, hi), lab, owner) in enumerate(zip(footprints, labels, owners, strict=True)):
        if lab is None:
            # named for its layer where the drawing has its own ("A-COLS-3")
            stem = "obstacle" if owner.lower() == "obstacles" else owner
            lab = (f"{stem}-{k}", 0.0, tops[owner.lower()])
        obstacles.append({"min": [lo[0], lo[1], lab[1]], "max": [hi[0], hi[1], lab[2]],
                          "name": lab[0]})  # fmt: skip
    kw.setdefault("name", Path(str(path)).stem)
    _say_shift(path, origin)
    size = corners.max(axis=0)
    rectangle = len(corners) == 4 and np.all(
        np.isclose(corners[:, 0], 0.0) | np.isclose(corners[:, 0], size[0])
    ) & np.all(np.isclose(corners[:, 1], 0.0) | np.isclose(corners[:, 1], size[1]))
    if rectangle:
        return Room(size=(float(size[0]), float(size[1]), h), obstacles=obstacles, **kw)
    return Room.from_corners(corners, h, obstacles=obstacles, **kw)


def _heights(obstacle_height, unlabelled: list[str], h: float, path) -> dict[str, float]:
    """The height (m) of the unlabelled obstacles by their layer (lower case), from
    ``obstacle_height`` (one height for all, or a dict by layer name); a ValueError naming
    a layer whose unlabelled obstacles get none, or a height not in (0, h]."""
    given = obstacle_height if isinstance(obstacle_height, dict) else {
        o: obstacle_height for o in unlabelled}  # fmt: skip
    given = {str(k).lower(): v for k, v in given.items()}
    tops = {}
    for owner in dict.fromkeys(unlabelled):
        if given.get(owner.lower()) is None:
            raise ValueError(
                f"obstacle_height: layer {owner!r} of {path} has {unlabelled.count(owner)} "
                "obstacle(s) without a height label ('NAME z Z0-Z1 m' at a corner): give "
                "their height in m"
            )
        try:
            tops[owner.lower()] = checks.real("obstacle_height", given[owner.lower()], low=0.0,
                                              high=h, low_open=True)  # fmt: skip
        except ValueError as exc:  # which layer's height
            text = str(exc).partition(":")[2].strip()
            raise ValueError(f"obstacle_height: layer {owner!r}: {text}") from None
    return tops


def _label(name: str, z0: float, z1: float) -> str:
    """A box's label, "NAME z Z0-Z1 m" (heights in m), as :data:`LABEL` reads it back."""
    return f"{name} z {z0:g}-{z1:g} m"


def _box_outline(msp, box, layer: str, label: str, scale: float) -> None:
    (x0, y0, z0), (x1, y1, z1) = (np.asarray(box[0]) / scale, np.asarray(box[1]) / scale)
    msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True,
                       dxfattribs={"layer": layer})  # fmt: skip
    text = _label(label, z0 * scale, z1 * scale)
    msp.add_text(text, height=0.08 / scale, dxfattribs={"layer": layer}).set_placement((x0, y0))


def write_plan(path, room, anchors, *, unit: str = "m", surfaces=None) -> Path:
    """Write the room and the anchors (M, 3) m to the DXF ``path`` (module docstring) in
    ``unit``; ``surfaces`` (M,) names the surface of each anchor (default blank)."""
    import ezdxf

    checks.choice("unit", unit, list(UNITS))
    a = checks.points("anchors", anchors)
    surfaces = [""] * len(a) if surfaces is None else [str(s) for s in surfaces]
    scale = UNITS[unit]
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = INSUNITS[unit]
    for name, colour in zip(LAYERS, (7, 1, 3, 5, 6), strict=True):
        doc.layers.add(name, color=colour)
    block = doc.blocks.new("ANCHOR")
    r = 0.05 / scale
    block.add_circle((0, 0), r)
    block.add_line((-r, 0), (r, 0))
    block.add_line((0, -r), (0, r))
    for k, tag in enumerate(("ID", "Z", "SURFACE")):
        block.add_attdef(tag, (1.2 * r, -k * 1.5 * r), dxfattribs={"height": r})
    msp = doc.modelspace()
    corners = np.asarray(room.floor_corners) / scale
    msp.add_lwpolyline([tuple(c) for c in corners], close=True, dxfattribs={"layer": "room"})
    boxes = room.to_dict()  # keep-outs, zones and obstacles as {"min", "max", "name"}
    for layer in ("obstacles", "keepouts", "zones"):
        for k, box in enumerate(boxes.get(layer, [])):
            name = box.get("name") or f"{layer[:-1]}-{k}"
            _box_outline(msp, (box["min"], box["max"]), layer, name, scale)
    for j, (p, s) in enumerate(zip(a, surfaces, strict=True)):
        ref = msp.add_blockref(
            "ANCHOR", (p[0] / scale, p[1] / scale), dxfattribs={"layer": "anchors"}
        )
        ref.add_auto_attribs({"ID": str(j + 1), "Z": f"{p[2]:.4f}", "SURFACE": s})
    return write_with(Path(str(path)), doc.saveas)


def read_anchors(path, unit: str | None = None) -> np.ndarray:
    """(M, 3) the anchors of a DXF written by :func:`write_plan`, in metres (x, y from the
    inserts, z from their ``Z`` attribute), in ID order (``unit``: as :func:`room_from_dxf`)."""
    doc = _doc(path)
    scale = UNITS[_unit(doc, unit, path)]
    rows = []
    for ref in doc.modelspace().query('INSERT[name=="ANCHOR"]'):
        att = {a.dxf.tag: a.dxf.text for a in ref.attribs}
        x, y = ref.dxf.insert.x * scale, ref.dxf.insert.y * scale
        rows.append((int(att["ID"]), x, y, float(att["Z"])))
    rows.sort()
    return np.array([r[1:] for r in rows], dtype=float).reshape(-1, 3)

"""DXF floor plans: reading rooms, writing plans, and the round trip."""

import json

import ezdxf
import numpy as np
import pytest

from placement.cli import main
from simulation import Room
from simulation.dxf import read_anchors, room_from_dxf, write_plan
from simulation.evaluation import simulate_ranges

L_CORNERS = [[0, 0], [7, 0], [7, 3], [3, 3], [3, 6], [0, 6]]


def _drawing(path, polylines, unit_scale=1.0):
    """A DXF with closed (or open) polylines [(layer, points, closed)], scaled."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    for layer, pts, closed in polylines:
        msp.add_lwpolyline([(x * unit_scale, y * unit_scale) for x, y in pts], close=closed,
                           dxfattribs={"layer": layer})  # fmt: skip
    doc.saveas(path)
    return path


def test_a_rectangle_in_millimetres_is_the_shoebox_in_metres(tmp_path):
    """An 8000 × 4000 mm rectangle drawn away from the origin: the techtile-sized shoebox,
    with the same simulated ranges."""
    rect = [(1500, 2500), (9500, 2500), (9500, 6500), (1500, 6500)]
    path = _drawing(tmp_path / "box.dxf", [("room", rect, True)])
    room = room_from_dxf(path, 2.4, unit="mm")
    box = Room(size=(8.0, 4.0, 2.4), name="box")
    assert room.is_shoebox and room.size == box.size and room.name == "box"
    a = box.corners_layout()
    np.testing.assert_array_equal(
        simulate_ranges(room, a, box.grid()[::20], noise=False),
        simulate_ranges(box, a, box.grid()[::20], noise=False),
    )


def test_a_drawing_away_from_the_origin_says_how_far_it_moved(tmp_path, caplog):
    """The room's origin is the outline's lowest corner: the shift is a warning (a layout in
    the drawing's coordinates would lie elsewhere in the room), and none at the origin."""
    from simulation.dxf import outline_origin

    rect = [(1500, 2500), (9500, 2500), (9500, 6500), (1500, 6500)]
    path = _drawing(tmp_path / "box.dxf", [("room", rect, True)])
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room_from_dxf(path, 2.4, unit="mm")
    np.testing.assert_allclose(outline_origin(path, unit="mm"), [1.5, 2.5])
    (record,) = (r for r in caplog.records if "moved" in r.getMessage())
    assert "moved by (-1.500, -2.500) m" in record.getMessage()
    caplog.clear()
    at_origin = _drawing(tmp_path / "lab.dxf", [("room", L_CORNERS, True)])
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room_from_dxf(at_origin, 3.0)
    assert not caplog.records


def test_the_drawings_declared_unit_is_the_default(tmp_path, caplog):
    """A drawing in millimetres that says so ($INSUNITS 4) reads in metres with no unit
    given; a unit given that contradicts the header is used, with a warning; a drawing in
    feet reads too; an unknown declared unit (light years, 16) is refused by name."""
    from simulation.dxf import read_floor_plan

    def drawing(name, code, scale):
        doc = ezdxf.new("R2010")
        doc.header["$INSUNITS"] = code
        doc.modelspace().add_lwpolyline([(x * scale, y * scale) for x, y in L_CORNERS],
                                        close=True, dxfattribs={"layer": "room"})  # fmt: skip
        doc.saveas(tmp_path / name)
        return tmp_path / name

    mm = drawing("mm.dxf", 4, 1000.0)
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        corners, _ = read_floor_plan(mm)
    assert not caplog.records
    np.testing.assert_allclose(corners.max(axis=0), [7.0, 6.0])
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        corners, _ = read_floor_plan(mm, unit="cm")
    np.testing.assert_allclose(corners.max(axis=0), [70.0, 60.0])
    assert "declares its unit as mm ($INSUNITS 4); read in cm as asked" in caplog.text
    corners, _ = read_floor_plan(drawing("ft.dxf", 2, 1 / 0.3048))
    np.testing.assert_allclose(corners.max(axis=0), [7.0, 6.0])
    with pytest.raises(ValueError, match=r"unit: .* declares its unit as \$INSUNITS 16"):
        read_floor_plan(drawing("ly.dxf", 16, 1.0))


def test_an_outline_with_an_arc_is_followed_within_five_centimetres(tmp_path, caplog):
    """A 10 × 5 m room whose east wall is a half circle (a bulge of 1 on the east edge, in
    millimetres): straight walls whose corners lie on the arc and whose chords stay within
    5 cm of it, with a warning; the same outline without the bulge keeps its 4 corners."""
    path = tmp_path / "apse.dxf"
    doc = ezdxf.new("R2010")
    doc.modelspace().add_lwpolyline(
        [(0, 0, 0), (10000, 0, 1), (10000, 5000, 0), (0, 5000, 0)], format="xyb", close=True,
        dxfattribs={"layer": "room"},
    )  # fmt: skip
    doc.saveas(path)
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room = room_from_dxf(path, 3.0, unit="mm")
    assert "arc segments" in caplog.text
    c = room.floor_corners
    apse = c[c[:, 0] > 10.0 + 1e-9]  # the corners beyond the straight walls' end
    assert len(apse) >= 8
    # on the arc to a millimetre (ezdxf follows an arc by Bézier curves)
    np.testing.assert_allclose(np.linalg.norm(apse - [10.0, 2.5], axis=1), 2.5, atol=1e-3)
    assert c[:, 0].max() == pytest.approx(12.5, abs=1e-3)  # the apse reaches 2.5 m out
    ring = np.vstack([c, c[:1]])
    mid = 0.5 * (ring[1:] + ring[:-1])
    on_arc = mid[:, 0] > 10.0 + 1e-9
    sag = 2.5 - np.linalg.norm(mid[on_arc] - [10.0, 2.5], axis=1)
    assert 0 < sag.max() <= 0.05  # each chord within 5 cm of the arc
    straight = _drawing(tmp_path / "box.dxf", [("room", [(0, 0), (10, 0), (10, 5), (0, 5)], True)])
    assert room_from_dxf(straight, 3.0).is_shoebox


def test_a_polygon_outline_and_obstacles(tmp_path):
    """An L in centimetres with two rectangles on the obstacle layer: the polygonal room of
    those corners with two boxes of the given height."""
    path = _drawing(
        tmp_path / "lab.dxf",
        [("room", L_CORNERS, True), ("obstacles", [(1, 1), (1.5, 1), (1.5, 1.5), (1, 1.5)], True),
         ("OBSTACLES", [(5, 1), (6, 1), (6, 2), (5, 2)], True)],
        unit_scale=100.0,
    )  # fmt: skip
    room = room_from_dxf(path, 3.0, unit="cm", obstacle_height=2.0)
    assert not room.is_shoebox
    assert np.allclose(room.floor_corners, L_CORNERS)
    boxes = sorted((tuple(o.lo), tuple(o.hi)) for o in room.obstacles)
    assert np.allclose(boxes[0], [(1, 1, 0), (1.5, 1.5, 2)])
    assert np.allclose(boxes[1], [(5, 1, 0), (6, 2, 2)])


def _lines(path, loops, unit_scale=1.0, shuffle=False):
    """A DXF whose outlines [(layer, points)] are drawn as separate LINEs (in reverse order
    and reversed direction with ``shuffle``: a drawing's lines come in any order)."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    for layer, pts in loops:
        segs = [(a, b) for a, b in zip(pts, [*pts[1:], pts[0]], strict=True)]
        for a, b in reversed(segs) if shuffle else segs:
            a, b = (b, a) if shuffle else (a, b)
            msp.add_line([v * unit_scale for v in a], [v * unit_scale for v in b],
                         dxfattribs={"layer": layer})  # fmt: skip
    doc.saveas(path)
    return path


def test_an_outline_and_obstacles_drawn_as_lines_read_as_polylines(tmp_path):
    """The L and a rectangle on the obstacle layer drawn as single lines (in millimetres, in
    any order and direction): the same room as the polyline drawing; a gap in the outline
    is refused naming the layer."""
    box = [(1, 1), (1.5, 1), (1.5, 1.5), (1, 1.5)]
    lines = _lines(tmp_path / "lines.dxf", [("room", L_CORNERS), ("obstacles", box)],
                   unit_scale=1000.0, shuffle=True)  # fmt: skip
    poly = _drawing(tmp_path / "poly.dxf", [("room", L_CORNERS, True), ("obstacles", box, True)],
                    unit_scale=1000.0)  # fmt: skip
    a = room_from_dxf(lines, 3.0, unit="mm", obstacle_height=2.0)
    b = room_from_dxf(poly, 3.0, unit="mm", obstacle_height=2.0)
    assert {tuple(c) for c in np.round(a.floor_corners, 9)} == {
        tuple(c) for c in np.round(b.floor_corners, 9)}  # fmt: skip
    assert [(tuple(o.lo), tuple(o.hi)) for o in a.obstacles] == [
        (tuple(o.lo), tuple(o.hi)) for o in b.obstacles]  # fmt: skip
    # the south wall drawn in two pieces (at a door), as lines and as a polyline: one wall
    split = [(0, 0), (2.5, 0), *L_CORNERS[1:]]
    for path in (_lines(tmp_path / "split.dxf", [("room", split)]),
                 _drawing(tmp_path / "split2.dxf", [("room", split, True)])):  # fmt: skip
        corners = room_from_dxf(path, 3.0).floor_corners
        assert {tuple(c) for c in np.round(corners, 9)} == {tuple(map(float, c)) for c in L_CORNERS}
    gap = [*L_CORNERS[:-1], (0.0, 5.9)]  # the last wall stops 10 cm short
    doc = ezdxf.new("R2010")
    for u, v in zip(gap, gap[1:], strict=False):
        doc.modelspace().add_line(u, v, dxfattribs={"layer": "room"})
    doc.saveas(tmp_path / "gap.dxf")
    with pytest.raises(ValueError, match="layer: 5 of the 5 lines, arcs and open polylines on "
                       f"layer 'room' in {tmp_path / 'gap.dxf'} do not join"):  # fmt: skip
        room_from_dxf(tmp_path / "gap.dxf", 3.0)


def test_obstacles_placed_as_block_references_are_read(tmp_path):
    """Columns drawn once as a block and placed three times (one of them through a block
    of a column pair: a nested reference), a desk block drawn on the obstacle layer and
    placed turned by 90°, in millimetres: every box where it was placed. A block's entity
    on layer "0" takes its reference's layer; a reference on another layer adds nothing."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (12000, 0), (12000, 8000), (0, 8000)], close=True,
                       dxfattribs={"layer": "room"})  # fmt: skip
    column = doc.blocks.new("COLUMN")
    column.add_lwpolyline([(-250, -250), (250, -250), (250, 250), (-250, 250)], close=True)
    pair = doc.blocks.new("PAIR")
    for x in (0, 4000):
        pair.add_blockref("COLUMN", (x, 0))
    msp.add_blockref("COLUMN", (4000, 4000), dxfattribs={"layer": "obstacles"})
    msp.add_blockref("PAIR", (4000, 6000), dxfattribs={"layer": "obstacles"})
    msp.add_blockref("COLUMN", (10000, 1000), dxfattribs={"layer": "furniture"})
    desk = doc.blocks.new("DESK")
    desk.add_lwpolyline([(0, 0), (1600, 0), (1600, 800), (0, 800)], close=True,
                        dxfattribs={"layer": "obstacles"})  # fmt: skip
    msp.add_blockref("DESK", (1000, 1000), dxfattribs={"layer": "furniture", "rotation": 90})
    doc.saveas(tmp_path / "blocks.dxf")
    room = room_from_dxf(tmp_path / "blocks.dxf", 3.0, unit="mm", obstacle_height=1.0)
    boxes = sorted((round(o.lo[0], 6), round(o.lo[1], 6), round(o.hi[0], 6), round(o.hi[1], 6))
                   for o in room.obstacles)  # fmt: skip
    assert boxes == [(0.2, 1.0, 1.0, 2.6), (3.75, 3.75, 4.25, 4.25), (3.75, 5.75, 4.25, 6.25),
                     (7.75, 5.75, 8.25, 6.25)]  # fmt: skip


def test_a_round_column_is_its_square_and_what_is_not_read_is_said(tmp_path, caplog):
    """A round column (a CIRCLE of radius 0.3 m at (4, 3)) is the square that holds it, with
    a warning; a hatch and a spline on the obstacle layer are named as left out."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (8, 0), (8, 6), (0, 6)], close=True, dxfattribs={"layer": "room"})
    msp.add_circle((4, 3), 0.3, dxfattribs={"layer": "obstacles"})
    msp.add_circle((1, 1), 0.2, dxfattribs={"layer": "furniture"})  # not an obstacle
    msp.add_hatch(dxfattribs={"layer": "obstacles"}).paths.add_polyline_path(
        [(6, 1), (7, 1), (7, 2)], is_closed=True
    )
    msp.add_spline([(1, 5), (2, 5.5), (3, 5)], dxfattribs={"layer": "obstacles"})
    doc.saveas(tmp_path / "round.dxf")
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room = room_from_dxf(tmp_path / "round.dxf", 3.0, obstacle_height=3.0)
    (column,) = room.obstacles
    np.testing.assert_allclose([column.lo, column.hi], [[3.7, 2.7, 0.0], [4.3, 3.3, 3.0]])
    assert "1 circle(s) on layer 'obstacles' (round columns) read as the squares" in caplog.text
    assert "left out on layer 'obstacles': 1 HATCH, 1 SPLINE" in caplog.text


def test_obstacles_on_other_layers_are_pointed_at_and_read_where_named(tmp_path, caplog, capsys):
    """Columns on "A-COLS" and a machine on "EQUIPMENT", nothing on "obstacles": the reader
    says where they may be; named (several layers, by the command line's flag too), both
    are read; an outline alone (no other layer) gets no such warning."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (8, 0), (8, 6), (0, 6)], close=True, dxfattribs={"layer": "walls"})
    msp.add_lwpolyline([(2, 2), (2.4, 2), (2.4, 2.4), (2, 2.4)], close=True,
                       dxfattribs={"layer": "A-COLS"})  # fmt: skip
    msp.add_lwpolyline([(5, 3), (6, 3), (6, 4), (5, 4)], close=True,
                       dxfattribs={"layer": "EQUIPMENT"})  # fmt: skip
    path = tmp_path / "layers.dxf"
    doc.saveas(path)
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        assert not room_from_dxf(path, 3.0, layer="walls").obstacles
    assert "nothing on layer 'obstacles', so no obstacles: are they on 'A-COLS', 'EQUIPMENT'?" \
        in caplog.text  # fmt: skip
    room = room_from_dxf(path, 3.0, layer="walls", obstacle_layer="a-cols, Equipment,A-COLS",
                         obstacle_height=2.0)  # fmt: skip  # a layer named twice: read once
    assert [o.hi[2] for o in room.obstacles] == [2.0, 2.0]
    # a height per layer: the column to the slab, the machine 1.5 m; a layer without one
    # is refused by name
    room = room_from_dxf(path, 3.0, layer="walls", obstacle_layer="A-COLS,EQUIPMENT",
                         obstacle_height={"a-cols": 3.0, "EQUIPMENT": 1.5})  # fmt: skip
    assert [(o.name, o.lo[0], o.hi[2]) for o in room.obstacles] == [
        ("A-COLS-0", 2.0, 3.0), ("EQUIPMENT-1", 5.0, 1.5)]  # fmt: skip
    with pytest.raises(ValueError, match="obstacle_height: layer 'EQUIPMENT' of .* has 1 "):
        room_from_dxf(path, 3.0, layer="walls", obstacle_layer="A-COLS,EQUIPMENT",
                      obstacle_height={"A-COLS": 3.0})  # fmt: skip
    with pytest.raises(ValueError, match=r"obstacle_height: layer 'A-COLS': .* \(0, 3\]"):
        room_from_dxf(path, 3.0, layer="walls", obstacle_layer="A-COLS,EQUIPMENT",
                      obstacle_height={"A-COLS": 3.5, "EQUIPMENT": 1.5})  # fmt: skip
    argv = ["bounds", "--room", str(path), "--room-height", "3", "--dxf-layer", "walls",
            "--dxf-obstacle-layer", "A-COLS,EQUIPMENT"]  # fmt: skip
    assert main([*argv, "--obstacle-height", "A-COLS=3,EQUIPMENT=1.5"]) == 0
    capsys.readouterr()
    assert main([*argv, "--obstacle-height", "A-COLS=tall"]) == 2
    assert "expected a height in m or LAYER=M pairs" in capsys.readouterr().err
    caplog.clear()
    alone = _drawing(tmp_path / "alone.dxf", [("room", L_CORNERS, True)])
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room_from_dxf(alone, 3.0)
    assert not caplog.records


def test_walls_drawn_as_open_polylines_join_and_a_nearly_closed_one_closes(tmp_path):
    """The L's walls as three open polylines and a line, in any direction (in mm), and an
    obstacle drawn as one polyline whose last point stops 0.5 mm short of its first: the
    same room as the closed polylines' drawing."""
    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    mm = [(x * 1000.0, y * 1000.0) for x, y in L_CORNERS]
    msp.add_lwpolyline(mm[:3], dxfattribs={"layer": "room"})
    msp.add_lwpolyline(mm[2:5][::-1], dxfattribs={"layer": "room"})
    msp.add_lwpolyline(mm[4:], dxfattribs={"layer": "room"})
    msp.add_line(mm[0], mm[-1], dxfattribs={"layer": "room"})
    msp.add_lwpolyline([(1000, 1000), (1500, 1000), (1500, 1500), (1000, 1500), (1000, 1000.5)],
                       dxfattribs={"layer": "obstacles"})  # fmt: skip
    doc.saveas(tmp_path / "open.dxf")
    room = room_from_dxf(tmp_path / "open.dxf", 3.0, unit="mm", obstacle_height=2.0)
    assert {tuple(c) for c in np.round(room.floor_corners, 9)} == {
        tuple(map(float, c)) for c in L_CORNERS}  # fmt: skip
    (box,) = room.obstacles
    np.testing.assert_allclose([box.lo, box.hi], [[1.0, 1.0, 0.0], [1.5, 1.5, 2.0]], atol=1e-9)


def test_stray_lines_beside_polylines_are_not_the_outline(tmp_path, caplog):
    """A door's swing drawn as a line on the outline's layer beside the closed polyline, and
    a stray line on the obstacles' layer beside a rectangle: the polylines are read, the
    obstacle layer's stray line is left out with a warning."""
    box = [(1, 1), (2, 1), (2, 2), (1, 2)]
    path = _drawing(tmp_path / "door.dxf", [("room", L_CORNERS, True), ("obstacles", box, True)])
    doc = ezdxf.readfile(path)
    doc.modelspace().add_line((1, 0), (1.8, 0.8), dxfattribs={"layer": "room"})
    doc.modelspace().add_line((4, 1), (5, 1), dxfattribs={"layer": "obstacles"})
    doc.saveas(path)
    with caplog.at_level("WARNING", logger="simulation.dxf"):
        room = room_from_dxf(path, 3.0, obstacle_height=1.0)
    assert np.allclose(room.floor_corners, L_CORNERS) and len(room.obstacles) == 1
    assert (
        "1 of the 1 lines, arcs and open polylines on layer 'obstacles' close no box" in caplog.text
    )


@pytest.mark.parametrize(
    ("polylines", "kw", "name"),
    [
        ([("walls", L_CORNERS, True)], {}, "layer"),  # no outline on the layer
        ([("room", L_CORNERS, False)], {}, "layer"),  # an open outline
        ([("room", L_CORNERS, True), ("room", L_CORNERS, True)], {}, "layer"),  # two
        ([("room", L_CORNERS, True), ("obstacles", [(1, 1), (2, 1), (2, 2)], True)],
         {"obstacle_height": 1.0}, "obstacle_layer"),  # not a rectangle
        ([("room", L_CORNERS, True), ("obstacles", [(1, 1), (2, 1), (2, 2), (1, 2)], True)],
         {}, "obstacle_height"),  # no height for the obstacles
        ([("room", L_CORNERS, True)], {"unit": "inch"}, "unit"),
    ],
)  # fmt: skip
def test_bad_floor_plans_are_refused_by_name(tmp_path, polylines, kw, name):
    path = _drawing(tmp_path / "bad.dxf", polylines)
    with pytest.raises(ValueError, match=name):
        room_from_dxf(path, 3.0, **kw)
    with pytest.raises(ValueError, match="height"):
        room_from_dxf(_drawing(tmp_path / "ok.dxf", [("room", L_CORNERS, True)]), -1.0)


@pytest.mark.parametrize("unit", ["m", "mm"])
def test_a_written_plan_reads_back(tmp_path, unit):
    """The office example with four anchors: its outline, keep-outs and zones on their
    layers, the anchors with their heights, back to 1e-9 m; the room read back from the
    drawing has the office's floor plan."""
    room = Room.from_toml("../examples/office.toml")
    a = np.array([[0.03, 1.0, 2.0], [9.97, 5.0, 2.5], [5.0, 0.03, 2.8], [4.0, 5.97, 1.5]])
    path = write_plan(tmp_path / "office.dxf", room, a, unit=unit, surfaces=list("abcd"))
    np.testing.assert_allclose(read_anchors(path, unit=unit), a, atol=1e-9)
    doc = ezdxf.readfile(path)
    layers = {e.dxf.layer for e in doc.modelspace()}
    assert {"room", "keepouts", "zones", "anchors"} <= layers
    n_keepouts = len(doc.modelspace().query('LWPOLYLINE[layer=="keepouts"]'))
    assert n_keepouts == len(room.keepouts)
    back = room_from_dxf(path, room.size[2], unit=unit)
    assert back.size == room.size and back.is_shoebox


@pytest.mark.parametrize("unit", ["m", "mm"])
def test_a_written_plans_obstacles_read_back_with_their_names_and_heights(tmp_path, unit):
    # the exported labels ("duct z 2.5-3 m") give each box its name and heights, a duct off
    # the floor too; no obstacle_height is needed
    room = Room.from_corners([[0, 0], [6, 0], [8, 4], [0, 4]], 3.0, obstacles=[
        {"min": [1.0, 1.8, 2.5], "max": [5.0, 2.2, 3.0], "name": "duct"},
        {"min": [6.0, 3.0, 0.0], "max": [7.0, 3.6, 1.75], "name": "cabinet"}])  # fmt: skip
    a = np.array([[0.03, 1.0, 2.0], [3.0, 3.97, 2.5], [4.0, 0.03, 1.0], [2.0, 2.0, 2.97]])
    path = write_plan(tmp_path / "t.dxf", room, a, unit=unit)
    back = room_from_dxf(path, 3.0, unit=unit)
    assert [o.name for o in back.obstacles] == ["duct", "cabinet"]
    np.testing.assert_allclose([(*o.lo, *o.hi) for o in back.obstacles],
                               [(*o.lo, *o.hi) for o in room.obstacles], atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(back.floor_corners, room.floor_corners, atol=1e-9)
    # a box drawn by hand beside them has no label: it needs obstacle_height, named
    doc = ezdxf.readfile(path)
    k = 1e-3 if unit == "mm" else 1.0
    doc.modelspace().add_lwpolyline([(2 / k, 0.5 / k), (3 / k, 0.5 / k), (3 / k, 1 / k),
                                     (2 / k, 1 / k)], close=True,
                                    dxfattribs={"layer": "obstacles"})  # fmt: skip
    doc.saveas(path)
    with pytest.raises(ValueError, match="obstacle_height: .* has 1 obstacle.* without a height"):
        room_from_dxf(path, 3.0, unit=unit)
    mixed = room_from_dxf(path, 3.0, unit=unit, obstacle_height=1.2)
    assert [(o.name, o.lo[2], o.hi[2]) for o in mixed.obstacles] == [
        ("duct", 2.5, 3.0), ("cabinet", 0.0, 1.75), ("obstacle-2", 0.0, 1.2)]  # fmt: skip


def test_the_export_and_plan_commands_take_dxf(tmp_path, capsys):
    """``anchorplan export`` writes a plan's DXF; ``--room plan.dxf --room-height`` reads a
    floor plan; a missing height names its flag."""
    room = Room.from_corners(L_CORNERS, 3.0, name="lab")
    a = np.array([[0.03, 1.0, 2.0], [6.97, 1.5, 2.5], [1.5, 5.97, 2.0], [4.0, 0.03, 1.0]])
    res = tmp_path / "res"
    res.mkdir()
    (res / "result.json").write_text(json.dumps({"room": room.to_dict(), "anchors": a.tolist()}))
    dxf = tmp_path / "lab.dxf"
    assert main(["export", str(res), "--dxf", str(dxf)]) == 0
    np.testing.assert_allclose(read_anchors(dxf), a, atol=1e-9)
    assert main(["bounds", "--room", str(dxf), "--room-height", "3"]) == 0
    assert "PEB" in capsys.readouterr().out
    assert main(["bounds", "--room", str(dxf)]) == 2
    assert "--room-height" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "none"), "--dxf", str(dxf)]) == 2

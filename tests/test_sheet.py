"""The mounting sheet: the installer's numbers give back the layout, the drawings are sound."""

import csv
import json
import math
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pytest

from placement.cli import main
from placement.sheet import anchors_from_csv, mounts, write_sheet
from placement.surfaces import random_layout
from simulation import Room
from simulation.directivity import aim_vectors
from simulation.floorplan import Obstacle

L_CORNERS = [(0, 0), (7, 0), (7, 3), (3, 3), (3, 6), (0, 6)]


def _rooms():
    slanted = Room.from_corners([(0, 0), (6, 0), (7.5, 4), (1, 5)], 2.8, name="slanted")
    lab = Room.from_toml("../examples/l-shaped-lab.toml")
    column = Obstacle((2.0, 2.0, 0.0), (2.4, 2.4, 3.0), name="column", mountable=True)
    office = Room.from_toml("../examples/office.toml")
    return [Room.techtile(), office, lab, slanted,
            Room.from_corners(L_CORNERS, 3.0, obstacles=(column,), name="l-column")]  # fmt: skip


@pytest.mark.parametrize("room", _rooms(), ids=lambda r: r.name)
def test_the_csv_read_back_gives_the_layout_to_a_millimetre(tmp_path, room):
    """Random layouts on every mounting surface (walls, slanted walls, the ceiling,
    column faces): the CSV's along/height and x/y numbers, placed from their reference
    corners, give every coordinate to 1 mm."""
    a = random_layout(room, 40, np.random.default_rng(5))
    write_sheet(tmp_path, room, a, tolerance=0.03)
    back = anchors_from_csv(tmp_path / "anchors.csv", room)
    assert back.shape == a.shape
    assert np.abs(back - a).max() <= 1e-3
    rows = list(csv.DictReader((tmp_path / "anchors.csv").open()))
    assert {r["tolerance_m"] for r in rows} == {"0.030"}
    assert all(r["surface"] for r in rows)  # every anchor is on a named surface


def test_a_shoebox_wall_is_measured_from_its_left_corner_seen_from_inside():
    """South wall (y = 0) seen from inside: its left end is the south-east corner, so the
    distance along it is Lx − x; the west wall's is the south-west corner (along = y);
    a ceiling anchor's x, y are from the south-west corner."""
    room = Room(mounting=("south", "north", "west", "east", "ceiling"))
    Lx = room.size[0]
    a = np.array([[2.5, 0.03, 1.2], [0.03, 1.0, 2.0], [3.0, 1.5, 2.37]])
    south, west, ceiling = mounts(room, a)
    assert (south.surface, south.reference) == ("south", "south-east corner")
    assert south.along == pytest.approx(Lx - 2.5) and south.height == pytest.approx(1.2)
    assert south.off_surface == pytest.approx(room.anchor_offset)
    assert (west.reference, west.along) == ("south-west corner", pytest.approx(1.0))
    assert (ceiling.kind, ceiling.plan_x, ceiling.plan_y) == ("plane", 3.0, 1.5)


def test_the_aim_is_the_simulators():
    """Azimuth and elevation give back the unit vector toward the room's centroid; the pan
    is the angle from the wall's normal, + toward the reference corner."""
    room = Room.from_toml("../examples/l-shaped-lab.toml")
    a = random_layout(room, 30, np.random.default_rng(2))
    u = aim_vectors(a, room.centroid)
    for r, v in zip(mounts(room, a), u, strict=True):
        az, el = math.radians(r.azimuth), math.radians(r.elevation)
        w = [math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]
        np.testing.assert_allclose(w, v, atol=1e-12)
    room = Room.techtile()
    (r,) = mounts(room, np.array([[1.0, 0.03, 1.2]]))
    # from x = 1 the centre (x = 4) lies toward +x, the south-east (reference) corner's side
    assert r.pan > 0
    (r,) = mounts(room, np.array([[7.0, 0.03, 1.2]]))
    assert r.pan < 0


def test_the_sheet_has_a_page_per_wall_with_anchors_and_valid_drawings(tmp_path):
    room = Room.from_toml("../examples/office.toml")
    a = np.array([[2.0, 5.97, 2.2], [7.0, 5.97, 2.2], [3.0, 0.03, 2.5], [5.0, 3.0, 2.97]])
    html = write_sheet(tmp_path, room, a, tolerance=0.01)["html"].read_text()
    pages = html.count('<section class="page">')
    assert pages == 1 + 1 + 4  # the ceiling plan, the table, the four walls
    for wall in ("south", "east", "north", "west"):
        assert f"Wall: {wall}" in html
    assert html.count("Nothing to mount here.") == 2  # east and west carry no anchor
    for k in range(1, 5):
        assert f"A{k}" in html
    svgs = html.split("<svg")[1:]
    assert len(svgs) == 1 + 4
    for s in svgs:  # each drawing parses as XML
        ET.fromstring("<svg" + s.split("</svg>")[0] + "</svg>")
    assert "windows" in html and "door" in html  # the keep-outs against the walls


def test_anchors_above_each_other_on_a_wall_are_drawn_apart(tmp_path):
    # three anchors at one point of the office's south wall, at three heights, and one
    # elsewhere: the ceiling plan labels the three once; the wall's drawing gives each
    # height its own dimension line
    room = Room.from_toml("../examples/office.toml")
    a = np.array([[3.0, 0.03, 0.5], [3.0, 0.03, 1.5], [3.0, 0.03, 2.5], [7.0, 5.97, 2.2]])
    html = write_sheet(tmp_path, room, a)["html"].read_text()
    plan, south = (s.split("</svg>")[0] for s in html.split("<svg")[1:3])
    texts = [t.text for t in ET.fromstring("<svg" + plan + "</svg>").iter() if t.text]
    assert "A1, A2, A3" in texts and "A1" not in texts and "A4" in texts
    tree = ET.fromstring("<svg" + south + "</svg>")
    heights = [t for t in tree.iter() if t.text and t.text.endswith(" m") and "A" not in t.text
               and "rotate(-90" in t.get("transform", "")]  # fmt: skip
    assert sorted(t.text for t in heights) == ["0.500 m", "1.500 m", "2.500 m"]
    xs = sorted(float(t.get("x")) for t in heights)
    assert min(np.diff(xs)) >= 14  # side by side, not over each other (10 px text)


def test_the_sheet_command_and_bad_input(tmp_path, capsys):
    room = Room.techtile()
    a = np.array([[1.0, 0.03, 2.0], [7.0, 3.97, 2.0], [4.0, 0.03, 1.0], [4.0, 3.0, 2.37]])
    res = tmp_path / "res"
    res.mkdir()
    result = {"room": room.to_dict(), "anchors": a.tolist(), "settings": {"mount_tolerance": 0.05}}
    (res / "result.json").write_text(json.dumps(result))
    assert main(["sheet", str(res)]) == 0
    rows = list(csv.DictReader((res / "sheet" / "anchors.csv").open()))
    assert [r["tolerance_m"] for r in rows] == ["0.050"] * 4
    assert [r["surface"] for r in rows] == ["south", "north", "south", "ceiling"]
    np.testing.assert_allclose(anchors_from_csv(res / "sheet" / "anchors.csv", room), a, atol=1e-3)
    capsys.readouterr()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["sheet", str(empty)]) == 2
    err = capsys.readouterr().err.strip()
    assert "result.json" in err and len(err.splitlines()) == 1
    assert err.count("RESULT_DIR") == 1


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--room", "{dxf}", "--room-height", "3", "--dxf-layer", "walls"], "walls"),
        (["--room", "{dxf}", "--room-height", "3", "--dxf-unit", "inch"], "--dxf-unit"),
        (["--room", "{dxf}", "--room-height", "-3"], "height"),
    ],
)
def test_bad_floor_plans_exit_2_with_one_line(tmp_path, capsys, args, needle):
    doc = ezdxf.new()
    doc.modelspace().add_lwpolyline([(0, 0), (8, 0), (8, 4), (0, 4)], close=True,
                                    dxfattribs={"layer": "room"})  # fmt: skip
    dxf = tmp_path / "room.dxf"
    doc.saveas(dxf)
    argv = ["bounds", *(s.format(dxf=dxf) for s in args)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1


def test_a_sheet_with_ceiling_anchors_only(tmp_path):
    # no wall anchor: no stack to label on the ceiling plan, one label per ceiling anchor
    room = Room.techtile()
    a = np.array([[1.0, 1.0, 2.37], [7.0, 1.0, 2.37], [1.0, 3.0, 2.37], [7.0, 3.0, 2.37]])
    html = write_sheet(tmp_path, room, a)["html"].read_text()
    plan = html.split("<svg")[1].split("</svg>")[0]
    assert all(f">A{k}<" in plan for k in range(1, 5)) and "#2ca02c" not in plan

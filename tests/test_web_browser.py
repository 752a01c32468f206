"""The planning page in a real browser (headless Chromium driven by Playwright): load the
L-shaped lab, drag an anchor and see the coverage change, drop one into a column and read
the command line's message, refuse M = 2, run a quick plan to the end (its progress
surviving a reload), download the mounting sheet, and draw a room with a slanted wall and
a hanging duct.

It needs a Chromium on the machine (Debian: ``apt-get install chromium``); where there is
none it is skipped, saying so. CI installs one (``.ci/run``)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
CHROMIUM = next(
    (
        p
        for p in (shutil.which("chromium"), shutil.which("chromium-browser"), "/usr/bin/chromium")
        if p and Path(p).exists()
    ),
    None,
)

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        CHROMIUM is None,
        reason="no Chromium on this machine: the browser test "
        "needs one (Debian: apt-get install chromium)",
    ),
]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    from placement.web.app import serve_in_thread
    from placement.web.workspace import Workspace

    ws = Workspace(tmp_path_factory.mktemp("work"), EXAMPLES / "l-shaped-lab.toml")
    srv, url = serve_in_thread(ws)
    yield url + "/", ws
    if ws.plan is not None:
        ws.plan.cancel()
    srv.should_exit = True


@pytest.fixture(scope="module")
def page(server):
    from playwright.sync_api import sync_playwright

    from placement.web.app import CHROMIUM_FLAGS

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=list(CHROMIUM_FLAGS))
        pg = browser.new_page(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
        errors = []
        pg.on("pageerror", lambda e: errors.append(str(e)))
        pg.goto(server[0])
        pg.wait_for_selector("#covered-k")
        yield pg
        browser.close()
        assert not errors, errors


def _drag(page, index: int, to) -> None:
    """Drag anchor ``index`` of the plan view to ``to`` (x, y) m, from a page with no drag
    in flight to the drop's answer drawn."""
    page.wait_for_function("drag === null")
    circle = page.locator(f'.anchor[data-index="{index}"][data-view="plan"] circle')
    box = circle.bounding_box()
    target = page.evaluate(
        """([x, y]) => { const svg = document.getElementById("plan");
          const r = svg.getBoundingClientRect(), vb = svg.viewBox.baseVal;
          const s = vb.width / (state.room.size[0] + 0.8);
          return [r.left + (x + 0.4) * s * r.width / vb.width,
                  r.top + (state.room.size[1] + 0.4 - y) * s * r.height / vb.height]; }""",
        list(to),
    )
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(*target, steps=8)
    page.mouse.up()
    page.wait_for_function("drag === null")


def _row(page, index: int) -> str:
    return page.locator("#anchors tbody tr").nth(index).inner_text()


def test_the_room_file_list_names_the_files_and_selects_the_room_open(page):
    selected = page.evaluate(
        "(() => { const s = document.getElementById('room-file');"
        " return [s.options[s.selectedIndex].text, s.value]; })()"
    )
    assert selected[0] == "l-shaped-lab.toml" and selected[1].endswith("/l-shaped-lab.toml")


def test_drag_an_anchor_and_the_coverage_changes(page):
    before = page.locator("#covered-k").inner_text(), page.get_attribute("#k-line", "d")
    # the seventh anchor, numbered 7 as in the report and the sheet: on the ceiling, west
    assert _row(page, 6).split()[0] == "7"
    assert page.locator('#plan .anchor[data-index="6"] .anchor-number').text_content() == "7"
    assert float(_row(page, 6).split()[3]) == 2.97
    _drag(page, 6, (6.5, 1.5))  # to the ceiling of the bay's east end
    page.wait_for_function(
        "(() => { const c = document.querySelectorAll("
        "'#anchors tbody tr')[6].cells;"
        "return c[1].innerText === '6.50' && c[2].innerText === '1.50'; })()"
    )
    after = page.locator("#covered-k").inner_text(), page.get_attribute("#k-line", "d")
    assert after != before
    assert float(_row(page, 6).split()[3]) == 2.97  # still on the ceiling
    assert page.locator("#error").is_hidden()


def test_a_drop_into_a_column_shows_the_command_lines_message(page):
    # anchor 0 sits on a wall at 1 m: a drop onto column-1's footprint is inside it
    _drag(page, 0, (2.5, 1.5))
    page.wait_for_selector("#error:not([hidden])")
    text = page.locator("#error").inner_text()
    assert text.startswith("error: anchors: anchor(s) [0] lie outside the room or in an obstacle")
    assert "is inside an obstacle" in text


def test_m_2_is_refused_with_the_command_lines_message(page):
    page.fill("input[name=anchors]", "2")
    page.click("#plan-run")
    page.wait_for_function("document.getElementById('error').innerText.includes('--anchors')")
    assert page.locator("#error").inner_text() == (
        "error: --anchors: must be an integer in [4, 100], got 2"
    )


def test_a_room_file_that_does_not_parse_shows_the_command_lines_message(page, tmp_path):
    from test_web import cli_error

    bad = tmp_path / "bad.toml"
    bad.write_text("size = [1, 2\n")
    page.set_input_files("#room-upload", str(bad))
    page.wait_for_function("document.getElementById('error').innerText.includes('TOML')")
    cli = cli_error(["evaluate", "--room", str(bad), "--layout", "x.json", "--out", "o"])
    assert page.locator("#error").inner_text().endswith(cli.split(": ", 1)[1])
    assert "l-shaped-lab" in page.locator("#room-name").inner_text()  # the room stays


def test_a_quick_plan_runs_to_the_end_and_its_sheet_downloads(page, server):
    page.fill("input[name=anchors]", "4")
    page.select_option("select[name=effort]", "quick")
    page.click("#plan-run")
    page.wait_for_selector(".phase progress")
    page.reload()  # the progress is the server's: a reloaded page finds it
    page.wait_for_selector(".phase progress", timeout=30_000)
    assert "running" in page.locator("#plan-state").inner_text()
    page.wait_for_selector("#plan-done", timeout=300_000)
    page.wait_for_function("document.querySelectorAll('#anchors tbody tr').length === 4")
    planned = server[1].plan.status()["result"]["anchors"]
    rows = [[float(v) for v in _row(page, i).split()[1:4]] for i in range(4)]
    np.testing.assert_allclose(rows, planned, atol=0.005 + 1e-9)  # shown to the centimetre
    with page.expect_download(timeout=120_000) as download:
        page.click("#exports a[data-kind=sheet]")
    path = download.value.path()
    assert download.value.suggested_filename == "sheet.html"
    text = Path(path).read_text()
    assert "<html" in text.lower() and text.count("anchor") >= 4


def test_a_slanted_wall_is_drawn_and_a_hanging_duct_labelled_with_its_heights(page, tmp_path):
    # a trapezoid whose east wall runs from (6, 0) to (8, 4), a duct hanging from the ceiling
    room = tmp_path / "trapezoid.toml"
    room.write_text(
        'name = "trapezoid"\ncorners = [[0, 0], [6, 0], [8, 4], [0, 4]]\nheight = 3.0\n'
        '[[obstacle]]\nname = "duct"\nmin = [1.0, 1.8, 2.5]\nmax = [5.0, 2.2, 3.0]\n'
    )
    page.set_input_files("#room-upload", str(room))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('trapezoid')")
    lines = page.evaluate(
        """() => [...document.querySelectorAll('#plan .mounting line')].map(l =>
            ['x1', 'y1', 'x2', 'y2'].map(k => l[k].baseVal.value))"""
    )
    assert len(lines) == 4  # every wall's allowed rectangle, seen from above, the slanted one too
    spans = sorted((round(abs(x2 - x1)) > 0, round(abs(y2 - y1)) > 0) for x1, y1, x2, y2 in lines)
    assert spans.count((True, True)) == 1  # the slanted wall: neither horizontal nor vertical
    assert "duct 2.5–3 m" in page.locator("#plan").text_content()
    # its label dark with a white halo: legible on the box and on the floor beside it
    label = page.locator("#plan .obstacle-label")
    assert (label.get_attribute("fill"), label.get_attribute("stroke")) == ("#252525", "#fff")
    # the maps' slice at tag height does not cut the duct: its outline, the cells under it
    page.wait_for_selector("#plan .obstacle.off-slice", state="attached")
    assert page.locator("#plan .obstacle").count() == 1


def test_a_column_smaller_than_its_label_keeps_it_above_not_on_it(page, tmp_path):
    # a car park: a 0.5 m column in a 24 m hall is smaller than its label, which hid it; a
    # 10 m ramp wall keeps its label on it
    room = tmp_path / "garage.toml"
    room.write_text(
        'name = "garage"\ncorners = [[0, 0], [24, 0], [24, 15], [0, 15]]\nheight = 2.6\n'
        '[[obstacle]]\nname = "column"\nmin = [7.25, 4.75, 0.0]\nmax = [7.75, 5.25, 2.6]\n'
        '[[obstacle]]\nname = "ramp"\nmin = [2.0, 2.0, 0.0]\nmax = [12.0, 2.6, 1.2]\n'
    )
    page.set_input_files("#room-upload", str(room))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('garage')")
    boxes = page.evaluate(
        """() => [...document.querySelectorAll('#plan .obstacle, #plan .obstacle-label')]
                 .map((e) => { const b = e.getBBox(); return [b.y, b.y + b.height]; })"""
    )
    (column, ramp), (column_label, ramp_label) = boxes[:2], boxes[2:]
    assert column_label[1] <= column[0]  # above the column (the page's y points down)
    assert ramp[0] < (ramp_label[0] + ramp_label[1]) / 2 < ramp[1]  # on the wall


def test_a_dxf_plan_moved_to_the_origin_says_so(page):
    # the example floor plan's outline starts at (12, 3) m in the drawing (in millimetres)
    dxf = Path(__file__).resolve().parent.parent / "examples" / "floorplan.dxf"
    page.fill("#room-height", "3")
    page.fill("#obstacle-height", "3")
    page.select_option("#dxf-unit", "mm")
    page.set_input_files("#room-upload", str(dxf))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('floorplan')")
    name = page.locator("#room-name").inner_text()
    assert "moved by (-12.000, -3.000) m to start at 0" in name


def test_what_the_dxf_reader_says_of_a_drawing_is_shown(page, tmp_path):
    # a round column (a circle: read as its square) and a hatch (left out) on the obstacles'
    # layer: both said under the title, without the file's path
    import ezdxf

    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (8, 0), (8, 6), (0, 6)], close=True, dxfattribs={"layer": "room"})
    msp.add_circle((4, 3), 0.3, dxfattribs={"layer": "obstacles"})
    msp.add_hatch(dxfattribs={"layer": "obstacles"}).paths.add_polyline_path(
        [(6, 1), (7, 1), (7, 2)], is_closed=True
    )
    doc.saveas(tmp_path / "round.dxf")
    page.fill("#room-height", "3")
    page.fill("#obstacle-height", "3")
    page.select_option("#dxf-unit", "m")
    page.set_input_files("#room-upload", str(tmp_path / "round.dxf"))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('round')")
    notes = page.locator("#room-notes")
    assert notes.is_visible()
    text = notes.inner_text()
    assert "1 circle(s) on layer 'obstacles' (round columns) read as the squares" in text
    assert "left out on layer 'obstacles': 1 HATCH" in text
    assert str(tmp_path) not in text
    box = tmp_path / "box.toml"  # a room file: nothing to say
    box.write_text('name = "box"\ncorners = [[0, 0], [5, 0], [5, 4], [0, 4]]\nheight = 3.0\n')
    page.set_input_files("#room-upload", str(box))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('box')")
    assert not page.locator("#room-notes").is_visible()


def test_a_drawing_with_its_own_layers_and_heights_per_layer(page, tmp_path):
    # walls on "A-WALL", a column on "A-COLS", a desk on "A-FURN": the page names the
    # layers and gives each its height, as the command line's flags do
    import ezdxf

    doc = ezdxf.new("R2010")
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (8, 0), (8, 6), (0, 6)], close=True, dxfattribs={"layer": "A-WALL"})
    msp.add_lwpolyline([(2, 2), (2.4, 2), (2.4, 2.4), (2, 2.4)], close=True,
                       dxfattribs={"layer": "A-COLS"})  # fmt: skip
    msp.add_lwpolyline([(5, 3), (6.6, 3), (6.6, 3.8), (5, 3.8)], close=True,
                       dxfattribs={"layer": "A-FURN"})  # fmt: skip
    doc.saveas(tmp_path / "cad.dxf")
    page.fill("#room-height", "2.8")
    page.fill("#dxf-layer", "A-WALL")
    page.fill("#dxf-obstacle-layer", "A-COLS,A-FURN")
    page.fill("#obstacle-height", "A-COLS=2.8,A-FURN=0.75")
    page.set_input_files("#room-upload", str(tmp_path / "cad.dxf"))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('cad')")
    labels = sorted(page.locator("#plan .obstacle-label").all_text_contents())
    assert labels == ["A-COLS-0 2.8 m", "A-FURN-1 0.75 m"]
    page.fill("#obstacle-height", "A-COLS=tall")  # refused as the command line refuses it
    page.set_input_files("#room-upload", str(tmp_path / "cad.dxf"))
    page.wait_for_selector("#error:not([hidden])")
    assert "--obstacle-height" in page.locator("#error").inner_text()
    for field in ("#dxf-layer", "#dxf-obstacle-layer", "#obstacle-height"):
        page.fill(field, "")


def test_a_solid_of_several_boxes_is_labelled_once_and_a_zone_kept_in_the_plan(page, tmp_path):
    # an L whose zone box covers the missing corner; a pillar of three boxes meeting face to
    # face and a 0.45 m bench
    room = tmp_path / "pillar.toml"
    room.write_text(
        'name = "pillar"\ncorners = [[0, 0], [8, 0], [8, 4], [4, 4], [4, 7], [0, 7]]\n'
        "height = 3.0\n"
        '[[obstacle]]\nname = "core"\nmin = [1.9, 1.6, 0.0]\nmax = [2.1, 2.4, 3.0]\n'
        '[[obstacle]]\nname = "west"\nmin = [1.7, 1.9, 0.0]\nmax = [1.9, 2.1, 3.0]\n'
        '[[obstacle]]\nname = "east"\nmin = [2.1, 1.9, 0.0]\nmax = [2.3, 2.1, 3.0]\n'
        '[[obstacle]]\nname = "bench"\nmin = [5.0, 1.0, 0.0]\nmax = [6.5, 1.4, 0.45]\n'
        "[[zone]]\nmin = [0.5, 0.5, 1.0]\nmax = [7.5, 6.5, 1.5]\n"
    )
    page.set_input_files("#room-upload", str(room))
    page.wait_for_function("document.getElementById('room-name').innerText.includes('pillar')")
    labels = page.locator("#plan .obstacle-label").all_text_contents()
    assert sorted(labels) == ["bench 0.45 m", "core 3 m"]
    assert page.locator("#plan .obstacle").count() == 4  # every box drawn
    clip = page.locator("#plan .zone").get_attribute("clip-path")
    assert clip == "url(#plan-clip)"
    corners = page.evaluate(
        "document.querySelector('#plan-clip polygon').getAttribute('points').split(' ').length"
    )
    assert corners == 6  # the L's outline
    # three anchors on one vertical line of the south wall: one spot from above, whose top
    # circle carries the three numbers; three spots from the south
    page.evaluate(
        """() => { state.anchors = [[1, 0.03, 1], [5, 0.03, 0.5], [5, 0.03, 1.5], [5, 0.03, 2.5],
                                    [7, 3.97, 2]];
                   drawPlan(); drawElevation(); }"""
    )
    numbers = page.locator("#plan .anchor-number").all_text_contents()
    assert numbers == ["1", "2,3,4", "5"]
    assert page.locator("#plan .anchor").count() == 5  # every circle drawn, each draggable
    sides = page.locator("#elevation .anchor-number").all_text_contents()
    assert sides == ["1", "2", "3", "4", "5"]

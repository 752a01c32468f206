"""The planning page's server (placement.web) through its HTTP API: what the page shows is
the library's computation, what the page sends is checked as the command line checks it
(the same messages), and the page cannot reach files outside the folders it was given."""

from __future__ import annotations

import contextlib
import io
import json
import time
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from analysis.coverage import bound, coverage
from placement.cli import main
from placement.surfaces import allowed
from placement.web import scene
from placement.web.app import create_app
from placement.web.workspace import Workspace
from simulation import Room, System

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
LAB = EXAMPLES / "l-shaped-lab.toml"


def cli_error(argv) -> str:
    """The message ``anchorplan argv`` prints after "error: "."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        assert main(argv) == 2
    return err.getvalue().strip().split(" error: ", 1)[1]


@pytest.fixture
def lab(tmp_path):
    ws = Workspace(tmp_path / "work", LAB, field_draws=1, workers=1)
    with TestClient(create_app(ws)) as client:
        yield client, ws


def test_the_page_and_its_state(lab):
    client, ws = lab
    page = client.get("/")
    assert page.status_code == 200 and "planning page" in page.text
    assert client.get("/static/app.js").status_code == 200
    s = client.get("/api/state").json()
    room = Room.from_toml(LAB)
    assert s["room"]["corners"] == room.floor_corners.tolist()
    assert [o["name"] for o in s["room"]["obstacles"]] == ["column-1", "column-2", "shelf"]
    assert [k["name"] for k in s["room"]["keepouts"]] == ["windows"]
    assert len(s["room"]["zones"]) == 2 and s["system"]["name"] == "paper"
    assert s["files"] and all(f.endswith((".toml", ".dxf")) for f in s["files"])
    assert s["room_id"] in s["files"] and s["room_id"].endswith("/l-shaped-lab.toml")
    assert allowed(room, np.array(s["anchors"])).all()


def test_the_maps_are_the_librarys_coverage_and_bound(lab):
    client, ws = lab
    s = client.get("/api/state").json()
    m = s["maps"]
    cells = np.column_stack([m["cells"], np.full(len(m["cells"]), m["height"])])
    a = np.array(s["anchors"])
    assert m["heard"] == coverage(ws.room, a, cells, system=ws.system).tolist()
    peb = bound(ws.room, a, cells, sigma=m["sigma"], system=ws.system)
    got = np.array([np.inf if v is None else v for v in m["peb"]])
    np.testing.assert_allclose(got, peb, rtol=1e-12)
    nodes = coverage(ws.room, a, ws.room.grid(), system=ws.system)
    assert m["summary"]["covered_k"] == pytest.approx(np.mean(nodes >= m["k"]))
    assert m["k"] == 4 and len(cells) <= scene.MAX_CELLS and not s["system"]["verifies"]
    # the recommended system rejects echoes: it needs 5 anchors in line of sight
    s = client.post("/api/system", json={"system": "recommended"}).json()
    assert s["maps"]["k"] == 5 and s["system"]["name"] == "recommended"
    assert s["system"]["verifies"]  # the page shows the verified share only then


def test_a_moved_anchor_snaps_to_its_surface_and_the_coverage_follows(lab):
    client, ws = lab
    before = client.get("/api/state").json()
    target = [5.5, 1.0, 2.5]  # in the air of the bay: the ceiling or a wall is nearest
    after = client.post("/api/anchors/move", json={"index": 0, "point": target}).json()
    a = np.array(after["anchors"])
    assert allowed(ws.room, a).all()
    assert np.linalg.norm(a[0] - target) < 0.6 and a[1:].tolist() == before["anchors"][1:]
    assert after["maps"]["heard"] != before["maps"]["heard"]


def test_a_drop_into_a_column_or_a_keepout_gives_the_command_lines_message(lab, tmp_path):
    client, ws = lab
    anchors = client.get("/api/state").json()["anchors"]
    for point, what in (([2.5, 1.5, 1.0], "inside an obstacle"), ([3.0, 0.05, 1.5], "windows")):
        r = client.post("/api/anchors/move", json={"index": 2, "point": point})
        assert r.status_code == 400 and what in r.json()["error"]
        layout = tmp_path / "bad.json"
        layout.write_text(json.dumps({"anchors": [*anchors[:2], point, *anchors[3:]]}))
        cli = cli_error(
            ["evaluate", "--room", str(LAB), "--layout", str(layout), "--out", str(tmp_path / "ev")]
        )
        assert cli == f"--layout {layout}: {r.json()['error']}"
    assert client.get("/api/state").json()["anchors"] == anchors  # nothing moved


def test_add_and_remove_anchors(lab):
    client, ws = lab
    n = len(client.get("/api/state").json()["anchors"])
    s = client.post("/api/anchors/add", json={"point": [1.0, 1.0, 3.0]}).json()
    assert len(s["anchors"]) == n + 1 and allowed(ws.room, np.array(s["anchors"])).all()
    s = client.post("/api/anchors/remove", json={"index": 0}).json()
    assert len(s["anchors"]) == n
    r = client.post("/api/anchors/remove", json={"index": n})
    assert r.status_code == 400 and "index" in r.json()["error"]
    r = client.post("/api/anchors/move", json={"index": 0, "point": [1, "a", 2]})
    assert r.status_code == 400 and "point" in r.json()["error"]
    r = client.post("/api/anchors/move", json=[0, 1])
    assert r.status_code == 400 and r.json()["error"] == "request: expected a JSON object"


def test_bad_plan_settings_give_the_command_lines_messages(lab, tmp_path):
    client, ws = lab
    for settings, argv in (
        ({"anchors": 2}, ["--anchors", "2"]),
        ({"anchors": 8, "seed": -1}, ["--seed", "-1"]),
        ({"anchors": 8, "effort": "fast"}, ["--effort", "fast"]),
    ):
        r = client.post("/api/plan", json=settings)
        assert r.status_code == 400, settings
        cli = cli_error(["plan", "--room", str(LAB), "--out", str(tmp_path / "p"), *argv])
        assert r.json()["error"] == cli
    assert client.get("/api/state").json()["plan"] is None  # nothing started


def test_a_room_that_does_not_parse_gives_the_command_lines_message(lab, tmp_path):
    client, ws = lab
    text = "size = [1, 2\n"
    r = client.post("/api/room", json={"upload": {"name": "bad.toml", "content": text}})
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    cli = cli_error(["evaluate", "--room", str(bad), "--layout", "x.json", "--out", "o"])
    assert r.status_code == 400
    assert r.json()["error"] == cli.replace(str(bad), str(ws.work / "uploads" / "bad.toml"))
    assert not any("bad.toml" in f for f in client.get("/api/state").json()["files"])
    r = client.post(
        "/api/room",
        json={
            "upload": {"name": "floorplan.dxf", "content": (EXAMPLES / "floorplan.dxf").read_text()}
        },
    )
    assert r.status_code == 400 and r.json()["error"].startswith("--room-height:")
    r = client.post(
        "/api/room",
        json={
            "upload": {
                "name": "floorplan.dxf",
                "content": (EXAMPLES / "floorplan.dxf").read_text(),
            },
            "room_height": 3.0,
            "dxf_unit": "mm",
            "obstacle_height": 3.0,
        },
    )
    assert r.status_code == 200 and r.json()["room_file"] == "floorplan.dxf"
    # its outline starts at (12, 3) m in the drawing: the page says the plan was moved
    np.testing.assert_allclose(r.json()["room_shift"], [-12.0, -3.0])
    r = client.post("/api/room", json={"file": "1/warehouse-aisles.toml"})
    assert r.json()["room_shift"] is None


def test_the_page_reads_and_writes_only_in_its_folders(lab):
    client, ws = lab
    for name in ("../../etc/passwd", "0/../../secret.toml", "7/x.toml", "0/%2e%2e"):
        r = client.post("/api/room", json={"file": name})
        assert r.status_code == 400 and "room file" in r.json()["error"]
    for name in ("../x.toml", "/tmp/x.toml", "x.py"):
        r = client.post("/api/room", json={"upload": {"name": name, "content": ""}})
        assert r.status_code == 400
    assert not Path("/tmp/x.toml").exists() or Path("/tmp/x.toml").stat().st_size > 0
    r = client.post("/api/room", json={"file": "1/warehouse-aisles.toml"})
    assert r.status_code == 200 and r.json()["room"]["name"] == "warehouse-aisles"
    r = client.get("/api/export/passwd")
    assert r.status_code == 400 and "export" in r.json()["error"]


def test_exports_of_a_hand_moved_layout(lab):
    import ezdxf

    client, ws = lab
    s = client.post("/api/anchors/move", json={"index": 1, "point": [6.0, 1.0, 3.0]}).json()
    layout = client.get("/api/export/layout").json()
    np.testing.assert_allclose(layout["anchors"], s["anchors"])
    csv = client.get("/api/export/csv")
    assert csv.status_code == 200 and len(csv.text.strip().splitlines()) == len(s["anchors"]) + 1
    sheet = client.get("/api/export/sheet")
    assert sheet.status_code == 200 and "<html" in sheet.text.lower()
    dxf = client.get("/api/export/dxf")
    path = ws.work / "downloaded.dxf"
    path.write_bytes(dxf.content)
    blocks = [e for e in ezdxf.readfile(path).modelspace() if e.dxftype() == "INSERT"]
    assert len(blocks) == len(s["anchors"])


def test_the_field_simulation_runs_on_demand_with_its_progress(tmp_path):
    ws = Workspace(tmp_path / "work", None, field_draws=1)
    with TestClient(create_app(ws)) as client:
        s = client.post("/api/field", json={}).json()
        assert s["field"]["total"] == 1
        r = client.post("/api/field", json={})
        assert r.status_code == 400 or r.json()["field"]["state"] == "done"
        for _ in range(600):
            f = client.get("/api/jobs").json()["field"]
            if f["state"] != "running":
                break
            time.sleep(0.1)
        assert f["state"] == "done" and f["done"] == 1
        res = f["result"]
        assert 0 < res["median"] <= res["p95"] and res["fixes"] == 1.0
        assert len(res["rms"]) == len(s["maps"]["cells"])
        # a moved anchor makes the simulated field stale
        s = client.post("/api/anchors/move", json={"index": 0, "point": [4.0, 2.0, 2.4]}).json()
        assert s["field"] is None


def test_serve_checks_its_arguments():
    assert "presets" in cli_error(["serve", "--system", "bogus"])
    assert cli_error(["serve", "--port", "70000"]).startswith("--port")
    assert cli_error(["serve", "--room", "no-such-room.toml"]).startswith("--room")


def test_a_plan_runs_in_the_background_and_can_be_cancelled(lab):
    client, ws = lab
    s = client.post("/api/plan", json={"anchors": 8, "effort": "default"}).json()
    assert s["plan"]["state"] == "running" and "--anchors 8" in s["plan"]["command"]
    r = client.post("/api/plan", json={"anchors": 8})
    assert r.status_code == 400 and "a plan is running" in r.json()["error"]
    for _ in range(300):  # the first phase reports before the cancel
        p = client.get("/api/jobs").json()["plan"]
        if p["progress"]:
            break
        time.sleep(0.1)
    assert p["progress"]["order"][0] == "range table"
    s = client.post("/api/plan/cancel").json()
    assert s["plan"]["state"] == "cancelled" and not ws.plan.running
    assert System.paper().name in s["system"]["name"]
    assert cli_error(["serve", "--plans", "0"]).startswith("--plans")


def test_two_plans_at_once_when_the_user_asks(tmp_path):
    ws = Workspace(tmp_path / "work", None, workers=1, max_plans=2)
    with TestClient(create_app(ws)) as client:
        try:
            for _ in range(2):
                assert client.post("/api/plan", json={"anchors": 4}).status_code == 200
            r = client.post("/api/plan", json={"anchors": 4})
            assert r.status_code == 400 and "2 plans are running (--plans 2)" in r.json()["error"]
            assert len(ws.plans) == 2 and ws.plan is ws.plans[-1]
        finally:
            for plan in ws.plans:
                plan.cancel()
        assert not any(p.running for p in ws.plans)


@pytest.mark.slow
def test_the_report_export_is_the_command_lines_report(lab):
    client, ws = lab
    r = client.get("/api/export/report")
    assert r.status_code == 200 and 'filename="report.html"' in r.headers["content-disposition"]
    assert "<html" in r.text.lower() and "l-shaped-lab" in r.text

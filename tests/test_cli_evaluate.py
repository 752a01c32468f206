import json
from pathlib import Path

import numpy as np

from placement.cli import main
from simulation import Room


def _layout(tmp_path, anchors, name="l.json"):
    p = tmp_path / name
    p.write_text(json.dumps({"anchors": anchors}))
    return p


def test_evaluate_writes_statistics(tmp_path, capsys):
    room = Room.techtile()
    layout = _layout(tmp_path, room.corners_layout().tolist())
    out = tmp_path / "run"
    args = ["evaluate", "--layout", str(layout), "--realizations", "2", "--seed", "3"]
    assert main([*args, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Euclidean position error" in text and "std" in text
    figures = text.split("realizations:\n")[1].split()
    assert figures[0:5:2] == ["median", "mean", "P95"] and "verified" not in figures  # then std
    data = json.loads((out / "evaluation.json").read_text())
    for key in ("room", "anchors", "realizations", "seed", "stats", "per_node", "errors", "nodes"):
        assert key in data
    assert data["realizations"] == 2 and data["seed"] == 3
    assert data["room"] == room.to_dict()
    assert np.array(data["errors"]).shape == (2, 270)
    assert {"std", "mean", "p95", "rms"} <= set(data["stats"])
    assert {"rmse", "dop", "mean"} <= set(data["per_node"])
    e = np.array(data["errors"])
    assert data["stats"]["std"] == np.std(e) and data["stats"]["mean"] == np.mean(e)
    # same seed, same numbers
    out2 = tmp_path / "run2"
    assert main([*args, "--out", str(out2)]) == 0
    assert json.loads((out2 / "evaluation.json").read_text())["errors"] == data["errors"]
    # a bar per realization on stderr, none with --no-progress
    assert "noise realizations" in capsys.readouterr().err
    assert main([*args, "--out", str(tmp_path / "run3"), "--no-progress"]) == 0
    assert "noise realizations" not in capsys.readouterr().err


def test_evaluate_with_room_file(tmp_path):
    room = Room(size=(6.0, 5.0, 3.0), name="small")
    room_file = tmp_path / "r.toml"
    room.to_toml(room_file)
    layout = _layout(tmp_path, room.corners_layout().tolist())
    out = tmp_path / "o"
    assert (
        main(["evaluate", "--layout", str(layout), "--room", str(room_file), "--out", str(out)])
        == 0
    )
    data = json.loads((out / "evaluation.json").read_text())
    assert data["room"]["name"] == "small" and len(data["nodes"]) == 270


def test_evaluate_bad_layouts_exit_2(tmp_path, capsys):
    out = str(tmp_path / "x")
    cases = {
        "at least 4": [[1, 1, 1], [2, 2, 2], [3, 3, 1]],
        "outside": [[1, 1, 1], [2, 2, 2], [3, 3, 1], [9, 1, 1]],
        "finite": [[1, 1, 1], [2, 2, 2], [3, 3, 1], [float("nan"), 1, 1]],
    }
    for i, (msg, anchors) in enumerate(cases.items()):
        layout = _layout(tmp_path, anchors, f"bad{i}.json")
        assert main(["evaluate", "--layout", str(layout), "--out", out]) == 2
        assert msg in capsys.readouterr().err
    layout = _layout(tmp_path, Room.techtile().corners_layout().tolist())
    assert main(["evaluate", "--layout", str(layout), "--realizations", "0", "--out", out]) == 2
    assert "--realizations" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_layout_with_no_fix_anywhere_says_so_without_nan(tmp_path, capsys):
    # the naive 8 anchors of the 24 x 16 m hall with the recommended system: no node hears 4
    from placement import naive_layout

    hall = Path(__file__).resolve().parents[1] / "examples" / "hall.toml"
    layout = _layout(tmp_path, naive_layout(Room.from_toml(hall), 8).tolist())
    args = ["evaluate", "--layout", str(layout), "--room", str(hall), "--system", "recommended"]
    args += ["--realizations", "1", "--no-progress", "--out", str(tmp_path / "run")]
    assert main(args) == 0
    text = capsys.readouterr().out
    data = json.loads((tmp_path / "run" / "evaluation.json").read_text())
    assert data["stats"]["availability"] == 0
    assert "no fix at any node in any realization (availability 0 %)" in text
    assert "nan" not in text.split("realizations:\n")[1]

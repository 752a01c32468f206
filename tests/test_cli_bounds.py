import json

from placement.cli import main


def test_bounds_corners(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["bounds", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "PEB = sqrt(tr J^-1)" in text
    data = json.loads(out.read_text())
    assert len(data["peb"]) == 270 and data["stats"]["n_invalid"] == 0


def test_bounds_bad_layout_exit_2(tmp_path, capsys):
    bad = tmp_path / "l.json"
    bad.write_text(json.dumps({"anchors": [[1, 1, 1], [2, 2, 2], [3, 3, 1]]}))
    assert main(["bounds", "--layout", str(bad)]) == 2
    assert "at least 4" in capsys.readouterr().err


def test_bounds_of_a_collinear_layout_are_infinite_not_nan(tmp_path, capsys):
    line = tmp_path / "l.json"
    line.write_text(json.dumps({"anchors": [[x, 0.03, 0.5] for x in (1, 2, 3, 4)]}))
    assert main(["bounds", "--layout", str(line)]) == 0
    text = capsys.readouterr().out
    assert "collinear" in text and "infinite at all 270 nodes" in text and "nan" not in text

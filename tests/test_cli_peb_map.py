import json
import struct

from placement.cli import main


def png_size(path):
    data = path.read_bytes()[:24]
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_peb_map_cli_writes_png_of_requested_size(tmp_path, capsys):
    layout = tmp_path / "l.json"
    layout.write_text(
        json.dumps({"anchors": [[1, 0.03, 2], [6.5, 3.97, 0.8], [3, 2, 2.37], [5.5, 1.2, 2.37]]})
    )
    out = tmp_path / "map.png"
    argv = ["peb-map", "--layout", str(layout), "--height", "1.2", "--height", "2.0"]
    argv += ["--y-cut", "2", "--size", "9", "6", "--dpi", "40", "--out", str(out)]
    assert main(argv) == 0
    assert png_size(out) == (360, 240)
    text = capsys.readouterr().out
    assert "360 x 240 px" in text and "4 anchors" in text


def test_peb_map_cli_default_corners_and_errors(tmp_path, capsys):
    out = tmp_path / "c.png"
    assert main(["peb-map", "--out", str(out), "--dpi", "30"]) == 0
    assert png_size(out) == (210, 126)  # default single panel 7 × 4.2 in
    assert main(["peb-map", "--out", str(tmp_path / "x.png"), "--height", "9"]) == 2
    assert "--height" in capsys.readouterr().err
    assert main(["peb-map", "--out", str(tmp_path / "x.png"), "--sigma", "0"]) == 2
    assert "--sigma" in capsys.readouterr().err
    assert main(["peb-map", "--out", str(tmp_path / "x.gif")]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"anchors": [[1, 1, 1], [2, 2, 2], [3, 3, 1]]}))
    assert main(["peb-map", "--layout", str(bad), "--out", str(tmp_path / "b.png")]) == 2
    assert "at least 4" in capsys.readouterr().err

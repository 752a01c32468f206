"""The system as one setting (simulation.System): presets, its TOML table, the room file
that carries one, --system on the command line, a plan that records it."""

import json

import pytest

from placement import PlacementResult
from placement.cli import main
from simulation import PRESETS, Positioning, Receiver, Room, System


def test_the_presets():
    paper, recommended = System.preset("paper"), System.preset("recommended")
    assert paper == System() == System.paper() and paper.name == "paper"
    assert paper.receiver == Receiver() and paper.positioning == Positioning()
    assert not paper.positioning.keep_in_room and paper.positioning.method == "ls"
    rx = recommended.receiver
    assert (rx.window, rx.t_wake, rx.pick) == (3840, 0.01, "first-path")
    assert recommended.positioning.keep_in_room and recommended.positioning.method == "robust"
    assert set(PRESETS) == {"paper", "recommended"}
    with pytest.raises(ValueError, match="unknown preset 'best'.*'paper', 'recommended'"):
        System.preset("best")


@pytest.mark.parametrize("system", [System(), System.recommended(),
                                    System(positioning=Positioning(keep_in_room=True),
                                           name="mine")])  # fmt: skip
def test_the_table_round_trips(system):
    assert System.from_dict(system.to_dict()) == system
    assert System.from_dict(json.loads(json.dumps(system.to_dict()))) == system


def test_a_table_starts_from_a_preset_and_changes_fields():
    s = System.from_dict({"preset": "recommended", "positioning": {"method": "ls"}})
    assert s.receiver == System.recommended().receiver and s.positioning.method == "ls"
    assert s.name == "custom"
    assert System.from_dict({"preset": "recommended"}).name == "recommended"


@pytest.mark.parametrize(
    ("table", "says"),
    [
        ({"bogus": 1}, "system: unknown key"),
        ({"positioning": {"foo": 1}}, r"system.positioning: unknown key\(s\) \['foo'\]"),
        ({"positioning": {"method": "median"}}, "system.positioning: method"),
        ({"receiver": {"window": -5}}, "system.receiver: window"),
        ({"signal": {"duration": "long"}}, "system.signal: duration"),
        ({"preset": "fast"}, "unknown preset"),
    ],
)
def test_a_bad_table_is_refused_naming_the_key(table, says):
    with pytest.raises(ValueError, match=says):
        System.from_dict(table)


def test_a_room_file_carries_its_system(tmp_path):
    path = tmp_path / "room.toml"
    path.write_text(
        'size = [10.0, 6.0, 3.0]\nname = "lab"\n\n[system]\nname = "long"\n\n'
        "[system.signal]\nduration = 0.05\n\n[system.receiver]\nt_wake = 0.049\n\n"
        "[system.positioning]\nkeep_in_room = true\n"
    )
    room, system = Room.from_toml(path), System.from_toml(path)
    assert room.name == "lab" and "system" not in room.to_dict()
    assert system.chirp.duration == 0.05 and system.receiver.t_wake == 0.049
    assert system.positioning.keep_in_room and system.name == "long"
    plain = tmp_path / "plain.toml"
    plain.write_text("size = [10.0, 6.0, 3.0]\n")
    assert System.from_toml(plain) == System()
    bad = tmp_path / "bad.toml"
    bad.write_text('size = [10.0, 6.0, 3.0]\n\n[system.positioning]\nmethod = "lms"\n')
    with pytest.raises(ValueError, match=f"system file {bad}: system.positioning: method"):
        System.from_toml(bad)


def test_a_flat_signal_table_in_a_room_file_is_refused_with_the_way_out(tmp_path):
    path = tmp_path / "old.toml"
    path.write_text("size = [8.0, 4.0, 2.4]\n\n[signal]\nduration = 0.05\n")
    with pytest.raises(ValueError, match=r"\[system.signal\]"):
        Room.from_toml(path)


def test_system_on_the_command_line(tmp_path, capsys):
    assert main(["plan", "--system", "bogus", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--system" in err and "'paper'" in err and "'recommended'" in err
    assert "Traceback" not in err


def test_a_plans_result_records_its_system(tmp_path, capsys):
    out = tmp_path / "plan"
    argv = ["plan", "--anchors", "4", "--cost", "peb", "--no-initial", "--particles", "4",
            "--iterations", "2", "--validate-realizations", "0", "--workers", "1",
            "--no-progress", "--system", "recommended", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[1].startswith("system recommended: chirp 30 ms")
    assert "robust least squares" in printed[1]
    back = PlacementResult.read(out)
    assert back.system == System.recommended()
    assert back.system.to_dict() == json.loads((out / "result.json").read_text())["system"]

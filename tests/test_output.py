"""Nothing half-written (simulation.output): a reader sees the old file or the new one; a
write that fails (a full disk) leaves the previous files and says so; an unwritable --out
is refused before any work; two plans into one folder leave a valid result."""

import errno
import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from placement.cli import main
from simulation import output

QUICK = Path(__file__).resolve().parents[1] / "docs" / "examples" / "quick"


def _full_disk_after(monkeypatch, nbytes: int):
    """Every write through Path.write_text/write_bytes writes ``nbytes`` and then fails as
    a full disk does."""
    real_text, real_bytes = Path.write_text, Path.write_bytes

    def text(self, data, *a, **kw):
        real_text(self, data[:nbytes], *a, **kw)
        raise OSError(errno.ENOSPC, "No space left on device", str(self))

    def raw(self, data):
        real_bytes(self, data[:nbytes])
        raise OSError(errno.ENOSPC, "No space left on device", str(self))

    monkeypatch.setattr(Path, "write_text", text)
    monkeypatch.setattr(Path, "write_bytes", raw)


def test_a_failed_write_leaves_the_previous_files(tmp_path, monkeypatch):
    a, b = tmp_path / "result.json", tmp_path / "layout.json"
    output.write_files({a: '{"old": 1}', b: '{"old": 2}'})
    _full_disk_after(monkeypatch, 5)
    with pytest.raises(OSError, match="No space left on device; nothing was written") as exc:
        output.write_files({a: '{"new": 1}' * 100, b: '{"new": 2}'})
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(a)
    monkeypatch.undo()
    assert json.loads(a.read_text()) == {"old": 1} and json.loads(b.read_text()) == {"old": 2}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["layout.json", "result.json"]


def test_a_killed_writer_leaves_the_previous_file(tmp_path):
    """A process killed while it writes (here: in the middle of writing, by SIGKILL) leaves
    the previous file whole; its temporary file is hidden and never the file's name."""
    path = tmp_path / "report.html"
    output.write_file(path, "<p>old</p>")
    code = (
        "import sys, os, signal\n"
        "from simulation import output\n"
        "def writer(tmp):\n"
        "    with open(tmp, 'w') as fh:\n"
        "        fh.write('<p>new, half')\n"
        "        fh.flush()\n"
        "        os.kill(os.getpid(), signal.SIGKILL)\n"
        f"output.write_with({str(path)!r}, writer)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=60)
    assert done.returncode == -9
    assert path.read_text() == "<p>old</p>"
    assert all(p.name.startswith(".") for p in tmp_path.iterdir() if p != path)


def test_a_full_disk_in_the_cli_says_so_and_keeps_the_sheet(tmp_path, monkeypatch, capsys):
    out = tmp_path / "sheet"
    assert main(["sheet", str(QUICK), "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    _full_disk_after(monkeypatch, 10)
    assert main(["sheet", str(QUICK), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "No space left on device; nothing was written" in err and "anchors.csv" in err
    assert "Traceback" not in err
    monkeypatch.undo()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_every_output_is_written_through_a_temporary_file(tmp_path, monkeypatch):
    """result.json, layout.json, the report, the sheet, the DXF and the what-if table go
    through simulation.output: a full disk leaves none of them half-written."""
    import shutil

    plan = tmp_path / "plan"
    shutil.copytree(QUICK, plan)
    assert main(["report", str(plan), "--realizations", "0"]) == 0
    assert main(["sheet", str(plan)]) == 0
    assert main(["export", str(plan), "--dxf", str(plan / "plan.dxf")]) == 0
    files = sorted(p for p in plan.rglob("*") if p.is_file())
    before = {p: p.read_bytes() for p in files}
    _full_disk_after(monkeypatch, 3)
    real_with = output.write_with

    def failing_with(path, writer):  # ezdxf and matplotlib write by name
        def half(tmp):
            Path(tmp).write_bytes(b"half")

        return real_with(path, half)

    monkeypatch.setattr(output, "write_with", failing_with)
    monkeypatch.setattr("simulation.dxf.write_with", failing_with)
    assert main(["report", str(plan), "--realizations", "0"]) == 2
    assert main(["sheet", str(plan)]) == 2
    assert main(["export", str(plan), "--dxf", str(plan / "plan.dxf")]) == 2
    monkeypatch.undo()
    assert sorted(p for p in plan.rglob("*") if p.is_file()) == files
    assert {p: p.read_bytes() for p in files} == before


def test_an_out_under_a_regular_file_is_refused_at_once(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    t0 = time.perf_counter()
    assert main(["plan", "--out", str(tmp_path / "file" / "out"), "--no-progress"]) == 2
    assert time.perf_counter() - t0 < 10
    assert "is a file, not a directory" in capsys.readouterr().err


def test_two_plans_into_one_folder_leave_a_valid_result(tmp_path):
    """Two plans started at once into one folder: result.json and layout.json are one
    plan's, whole (both plans give the same layout)."""
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "placement.cli", "plan", "--anchors", "4", "--cost", "peb",
            "--no-initial", "--particles", "4", "--iterations", "3", "--validate-realizations",
            "0", "--workers", "1", "--no-progress", "--out", str(out)]  # fmt: skip
    procs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for _ in range(2)]  # fmt: skip
    for p in procs:
        assert p.wait(timeout=300) == 0, p.stderr.read().decode()
    result = json.loads((out / "result.json").read_text())
    layout = json.loads((out / "layout.json").read_text())
    assert layout["anchors"] == result["anchors"]
    assert sorted(p.name for p in out.iterdir()) == ["layout.json", "result.json"]

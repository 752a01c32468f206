"""The planning page's state: the room (and how the command line names it), the system,
the layout, the plan and field jobs, and the folders the page may touch.

Everything that arrives from the page is checked here as the command line checks it: a
room file by :func:`placement.cli.common.load_room`, a layout by
:meth:`simulation.Room.check_anchors`, a plan's settings by ``anchorplan plan``'s own
checks (:func:`placement.cli.plan.prepare`); the errors are the command line's. The page
names files only by their names in the folders the user gave; what it writes goes to the
work folder.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import logging
import re
import threading
from pathlib import Path
from typing import Any

import numpy as np

from placement.cli.common import (
    describe_system,
    json_text,
    load_room,
    obstacle_height_text,
    system_choice,
)
from placement.surfaces import naive_layout
from placement.web import jobs, scene
from simulation.dxf import outline_origin
from simulation.output import write_file

#: suffixes of the room files the page may open or upload
ROOM_SUFFIXES = (".toml", ".dxf")
#: the largest uploaded room file, bytes
MAX_UPLOAD = 5_000_000
#: the anchors of a new room's first layout (spread along its walls)
FIRST_ANCHORS = 8
#: the draws of the field simulation
FIELD_DRAWS = 3
#: the mounting tolerance of the field simulation (m), the planner's
FIELD_TOLERANCE = 0.03
#: the exports: name -> file name
EXPORTS = {
    "layout": "layout.json",
    "report": "report.html",
    "sheet": "sheet.html",
    "csv": "anchors.csv",
    "dxf": "plan.dxf",
}

#: the command line runs in this process one at a time (it prints to sys.stdout)
_CLI_LOCK = threading.Lock()


def run_cli(argv: list[str]) -> str:
    """Run ``anchorplan argv`` in this process; its standard output. A failure raises
    ValueError with the command's error message (what follows "error: ")."""
    from placement.cli import main

    out, err = io.StringIO(), io.StringIO()
    with _CLI_LOCK, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    if code != 0:
        lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
        text = lines[-1] if lines else f"exit code {code}"
        raise ValueError(text.split(" error: ", 1)[-1])
    return out.getvalue()


def _safe_name(name: str) -> str:
    base = str(name)
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._ -]{0,100}", base):
        raise ValueError(f"file name: {name!r} is not a plain file name (letters, digits, . _ -)")
    return base


class Workspace:
    """The state behind one page server (module docstring). ``folders``: the folders the
    page may read room files from; ``work``: the folder it writes to; ``room_file`` and
    ``result_dir`` what ``anchorplan serve`` was given; ``workers`` a plan's worker
    processes (0: one per core); ``field_draws`` the draws of the field simulation;
    ``max_plans`` the plans that may run at once (the page shows the latest)."""

    def __init__(
        self,
        work: Path,
        room_file=None,
        result_dir=None,
        room_options=None,
        system: str | None = None,
        workers: int = 0,
        field_draws: int = FIELD_DRAWS,
        max_plans: int = 1,
    ):
        self.work = Path(work).resolve()
        self.work.mkdir(parents=True, exist_ok=True)
        self.folders = [self.work / "uploads"]
        self.folders[0].mkdir(exist_ok=True)
        self.workers, self.field_draws = workers, field_draws
        self.lock = threading.RLock()
        self.plan: jobs.PlanJob | None = None  # the latest: the one the page shows
        self.plans: list[jobs.PlanJob] = []
        self.max_plans = max_plans
        self.field: jobs.FieldJob | None = None
        self.plan_count = 0
        self.result_dir = None if result_dir is None else Path(result_dir).resolve()
        if self.result_dir is not None:
            self.folders.append(self.result_dir)
        if room_file is not None:
            self.folders.append(Path(room_file).resolve().parent)
        self.set_room(room_file, room_options or {}, system)
        if self.result_dir is not None:
            self.open_result(self.result_dir)

    # -- the room, the system, the layout ---------------------------------------------------
    def set_room(self, path, options: dict, system: str | None = None) -> None:
        """Load the room of ``path`` (None: the embedded techtile room) with the DXF
        ``options`` (room_height, obstacle_height, dxf_unit, dxf_layer,
        dxf_obstacle_layer)."""
        from types import SimpleNamespace

        opts = {
            "room_height": None,
            "obstacle_height": None,
            "dxf_unit": None,
            "dxf_layer": "room",
            "dxf_obstacle_layer": "obstacles",
            **options,
        }
        with _warnings("simulation.dxf") as notes:
            room = load_room(None if path is None else str(path), SimpleNamespace(**opts))
        chosen = _system(system, path, room)
        argv = [] if path is None else ["--room", str(path)]
        if path is not None and str(path).lower().endswith(".dxf"):
            argv += [
                "--room-height",
                repr(opts["room_height"]),
                "--dxf-layer",
                opts["dxf_layer"],
                "--dxf-obstacle-layer",
                opts["dxf_obstacle_layer"],
            ]
            if opts["dxf_unit"] is not None:
                argv += ["--dxf-unit", opts["dxf_unit"]]
            if opts["obstacle_height"] is not None:
                argv += ["--obstacle-height", obstacle_height_text(opts["obstacle_height"])]
        shift = None  # where a DXF's outline does not start at its origin, the move
        if path is not None and str(path).lower().endswith(".dxf"):
            o = outline_origin(path, layer=opts["dxf_layer"], unit=opts["dxf_unit"])
            shift = None if not np.any(np.abs(o) > 1e-9) else (-o).tolist()
        with self.lock:
            self.room, self.room_path, self.room_argv = room, path, argv
            self.room_shift = shift
            # what the DXF reader said of the drawing (arcs followed, columns read as
            # squares, entities left out), but the move, which room_shift gives
            self.room_notes = [n.split(": ", 1)[-1] for n in notes if "is moved by" not in n]
            self.system, self.system_name = chosen, system
            self.anchors = naive_layout(room, FIRST_ANCHORS)
            self.field = None

    def set_system(self, name: str | None) -> None:
        chosen = _system(name, self.room_path, self.room)
        with self.lock:
            self.system, self.system_name, self.field = chosen, name, None

    def set_anchors(self, anchors) -> None:
        a = scene.check_layout(self.room, anchors, min_anchors=1)
        with self.lock:
            self.anchors, self.field = a, None

    def room_files(self) -> list[str]:
        """The room files the page may open: ``folder-index/name`` of every .toml and .dxf
        file in the folders the user named (not their subfolders)."""
        out = []
        for i, folder in enumerate(self.folders):
            if folder.is_dir():
                out += [
                    f"{i}/{p.name}"
                    for p in sorted(folder.iterdir())
                    if p.suffix.lower() in ROOM_SUFFIXES and p.is_file()
                ]
        return out

    def _file_id(self, path) -> str | None:
        """The ``folder-index/name`` of ``path`` among :meth:`room_files` (None: not one)."""
        if path is None:
            return None
        path = Path(path).resolve()
        return next((f"{i}/{path.name}" for i, folder in enumerate(self.folders)
                     if folder.resolve() == path.parent), None)  # fmt: skip

    def resolve(self, name: str) -> Path:
        """The file ``folder-index/name`` of :meth:`room_files`; ValueError otherwise."""
        if str(name) not in self.room_files():
            raise ValueError(f"room file: {name!r} is not one of {self.room_files()}")
        index, _, base = str(name).partition("/")
        path = self.folders[int(index)] / _safe_name(base)
        if not path.is_file():
            raise ValueError(f"room file: {name!r} is not one of {self.room_files()}")
        return path

    def upload(self, name: str, content: str) -> Path:
        """Save an uploaded room file in the uploads folder; its path."""
        base = _safe_name(name)
        if Path(base).suffix.lower() not in ROOM_SUFFIXES:
            raise ValueError(f"room file: {base!r} must end with .toml or .dxf")
        if len(content) > MAX_UPLOAD:
            raise ValueError(f"room file: {len(content)} bytes, more than {MAX_UPLOAD}")
        return write_file(self.folders[0] / base, content)

    def snapshot(self) -> dict[str, Any]:
        """What the page shows (JSON-ready)."""
        with self.lock:
            room, system, anchors = self.room, self.system, self.anchors
            plan, field = self.plan, self.field
        return {
            "room": scene.drawing(room),
            "room_file": None if self.room_path is None else Path(self.room_path).name,
            # (dx, dy) m: a DXF plan moved to the room's origin (simulation.dxf)
            "room_shift": self.room_shift,
            "room_notes": self.room_notes,
            "room_id": self._file_id(self.room_path),
            "system": {
                "name": system.name,
                "verifies": system.positioning.method == "robust",
                "chosen": self.system_name,
                "describe": describe_system(room, system),
            },
            "anchors": np.asarray(anchors).tolist(),
            "maps": scene.maps(room, system, anchors) if len(anchors) else None,
            "files": self.room_files(),
            "plan": None if plan is None else plan.status(),
            "field": None if field is None else field.status(),
        }

    # -- the field, the plan, the exports --------------------------------------------------
    def start_field(self, seed: int = 0) -> None:
        with self.lock:
            if self.field is not None and self.field.running:
                raise ValueError("field: a field simulation is running; wait for it to end")
            cells, _ = scene.slice_cells(self.room)
            scene.check_layout(self.room, self.anchors)
            self.field = jobs.FieldJob(
                self.room, self.system, self.anchors, cells, self.field_draws, FIELD_TOLERANCE, seed
            )

    def plan_argv(self, settings: dict[str, Any], out: Path) -> list[str]:
        """``anchorplan plan``'s words for the page's ``settings`` (anchors, effort, cost,
        seed, system), this room, ``--out`` ``out`` and a checkpoint beside it."""
        words = [
            "plan",
            *self.room_argv,
            "--out",
            str(out),
            "--checkpoint",
            str(out.parent / "checkpoint.json"),
            "--no-progress",
        ]
        for key, flag in (
            ("anchors", "--anchors"),
            ("effort", "--effort"),
            ("cost", "--cost"),
            ("seed", "--seed"),
            ("system", "--system"),
        ):
            value = settings.get(key)
            if value is not None and value != "":
                words += [flag, str(value)]
        if settings.get("system") in (None, "") and self.system_name is not None:
            words += ["--system", self.system_name]
        if self.workers:
            words += ["--workers", str(self.workers)]
        return words

    def start_plan(self, settings: dict[str, Any]) -> None:
        """Check the plan's settings as ``anchorplan plan`` does, then run it in the
        background (one plan at a time)."""
        with self.lock:
            running = sum(p.running for p in self.plans)
            if running >= self.max_plans:
                what = "a plan is" if self.max_plans == 1 else f"{running} plans are"
                raise ValueError(f"plan: {what} running (--plans {self.max_plans}); cancel it "
                                 "or wait for it to end")  # fmt: skip
            folder = self.work / "plans" / f"plan-{self.plan_count + 1}"
            argv = self.plan_argv(settings, folder / "out")
            check_plan(argv)
            self.plan_count += 1
            self.plan = jobs.PlanJob(folder, argv, settings)
            self.plans.append(self.plan)

    def open_result(self, folder: Path) -> None:
        """Show the layout of a result folder (``layout.json``, else result.json's)."""
        from placement.cli.common import load_plan

        _, anchors = load_plan(folder)
        self.set_anchors(anchors)

    def scene_folder(self) -> Path:
        """A folder with ``evaluation.json`` of the shown layout (``anchorplan evaluate``
        in the work folder), or the finished plan's result folder when it shows that
        plan's layout: the folder the report, the sheet and the DXF are made from."""
        with self.lock:
            anchors, plan = np.asarray(self.anchors), self.plan
        status = None if plan is None else plan.status()
        if status is not None and status["state"] == "done":
            planned = np.asarray(status["result"]["anchors"], dtype=float)
            if planned.shape == anchors.shape and np.allclose(planned, anchors, atol=1e-9):
                return plan.out
        key = hashlib.sha256(
            json_text({"a": anchors, "r": self.room_argv, "s": self.system_name}).encode()
        ).hexdigest()[:12]
        folder = self.work / "scenes" / key
        if not (folder / "evaluation.json").exists():
            layout = write_file(folder / "layout.json", json_text({"anchors": anchors}))
            system = [] if self.system_name is None else ["--system", self.system_name]
            run_cli(
                [
                    "evaluate",
                    "--layout",
                    str(layout),
                    *self.room_argv,
                    *system,
                    "--out",
                    str(folder),
                ]
            )
        return folder

    def export(self, kind: str) -> Path:
        """The file of export ``kind`` (:data:`EXPORTS`) of the shown layout."""
        if kind not in EXPORTS:
            raise ValueError(f"export: {kind!r} is not one of {list(EXPORTS)}")
        folder = self.scene_folder()
        out = self.work / "exports" / folder.name
        if kind == "layout":
            return write_file(out / "layout.json", json_text({"anchors": self.anchors}))
        if kind in ("sheet", "csv"):
            run_cli(["sheet", str(folder), "--out", str(out)])
        elif kind == "report":
            run_cli(["report", str(folder), "--out", str(out / "report.html")])
        else:
            run_cli(["export", str(folder), "--dxf", str(out / "plan.dxf")])
        return out / EXPORTS[kind]


@contextlib.contextmanager
def _warnings(name: str):
    """The messages of the warnings the logger ``name`` gives within the block (a list
    filled as they come)."""
    messages: list[str] = []

    class Keep(logging.Handler):
        def emit(self, record) -> None:
            messages.append(record.getMessage())

    handler, log = Keep(logging.WARNING), logging.getLogger(name)
    log.addHandler(handler)
    try:
        yield messages
    finally:
        log.removeHandler(handler)


def _system(name: str | None, room_file, room):
    """The system ``--system name`` chooses for ``room`` (its file's [system] table when
    ``name`` is None), checked against the room."""
    chosen = system_choice(name, None if room_file is None else str(room_file))
    chosen.check_room(room)
    return chosen


def check_plan(argv: list[str]) -> None:
    """``anchorplan plan argv``'s arguments checked as the command checks them, without
    planning; ValueError with its message."""
    from placement.cli import build_parser
    from placement.cli.plan import prepare

    err = io.StringIO()
    try:
        with _CLI_LOCK, contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            args = build_parser().parse_args(argv)
    except SystemExit:
        raise ValueError(err.getvalue().strip().split(" error: ", 1)[-1]) from None
    prepare(args)

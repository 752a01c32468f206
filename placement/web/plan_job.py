"""One plan of the planning page, run in its own process: ``python -m
placement.web.plan_job FOLDER`` runs ``anchorplan plan`` with the arguments of
FOLDER/request.json (``{"argv": [...]}``, the command line's words after ``anchorplan``),
its output to FOLDER/log.txt, its progress per phase to FOLDER/progress.json and its exit
code to FOLDER/exit.json. The page's server starts it in a new process group, so that a
cancel stops its worker processes too."""

from __future__ import annotations

import json
import sys
import time
from functools import partial
from pathlib import Path

from placement.serialization import write_json_atomic

#: seconds between two writes of the progress file within a phase
WRITE_INTERVAL = 0.25


class ProgressFile:
    """``progress(phase, done, total)`` (:mod:`analysis.progress`) kept as
    ``{"phases": {phase: [done, total]}, "order": [...], "current": phase}`` in a JSON
    file, written at a phase's start and end and at most every :data:`WRITE_INTERVAL` s."""

    def __init__(self, path: Path):
        self.path, self.last = path, 0.0
        self.state: dict = {"phases": {}, "order": [], "current": None}

    def __call__(self, phase: str, done: int, total: int) -> None:
        new = phase not in self.state["phases"]
        if new:
            self.state["order"].append(phase)
        self.state["phases"][phase] = [int(done), int(total)]
        self.state["current"] = phase
        now = time.monotonic()
        if new or done >= total or now - self.last >= WRITE_INTERVAL:
            self.last = now
            write_json_atomic(self.path, self.state)

    def close(self) -> None:
        write_json_atomic(self.path, self.state)


def main(folder: str) -> int:
    """Run the plan of ``folder`` (module docstring); its exit code."""
    from placement.cli import build_parser, run_command
    from placement.cli import plan as plan_command

    root = Path(folder)
    argv = json.loads((root / "request.json").read_text())["argv"]
    args = build_parser().parse_args(argv)
    progress = ProgressFile(root / "progress.json")
    args.func = partial(plan_command.run, progress=progress)
    code = run_command(args)
    progress.close()
    write_json_atomic(root / "exit.json", {"code": code})
    return code


if __name__ == "__main__":  # pragma: no cover - run by the page's server
    sys.exit(main(sys.argv[1]))

"""The planning page's long work: a plan in its own process group (cancellable, its
progress in files, so a reloaded page finds it), and the field simulation in a thread."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from placement.serialization import write_json_atomic

#: seconds a cancelled plan gets to stop before it is killed
CANCEL_GRACE = 3.0
#: the last lines of a plan's log the page shows
LOG_LINES = 40


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


class PlanJob:
    """``anchorplan plan`` with ``argv`` (its words after ``anchorplan``) run by
    :mod:`placement.web.plan_job` in ``folder`` (its results in ``folder/out``)."""

    def __init__(self, folder: Path, argv: list[str], settings: dict[str, Any]):
        self.folder, self.argv, self.settings = Path(folder), list(argv), dict(settings)
        self.out = self.folder / "out"
        self.started = time.time()
        self.cancelled = False
        self.folder.mkdir(parents=True, exist_ok=True)
        write_json_atomic(self.folder / "request.json", {"argv": self.argv})
        with open(self.folder / "log.txt", "wb") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "placement.web.plan_job", str(self.folder)],
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                start_new_session=True,
                env={**os.environ, "PYTHONUNBUFFERED": "1"},
            )

    @property
    def running(self) -> bool:
        return self.process.poll() is None

    def cancel(self) -> None:
        """Stop the plan and its workers (the whole process group): SIGTERM, then SIGKILL
        after :data:`CANCEL_GRACE` s."""
        if not self.running:
            return
        self.cancelled = True
        for sig, wait in ((signal.SIGTERM, CANCEL_GRACE), (signal.SIGKILL, 10.0)):
            try:
                os.killpg(self.process.pid, sig)
            except ProcessLookupError:
                return
            try:
                self.process.wait(wait)
                break
            except subprocess.TimeoutExpired:
                continue
        try:  # the workers may outlive the group's leader for a moment
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass

    def log(self) -> list[str]:
        try:
            text = (self.folder / "log.txt").read_text(errors="replace")
        except OSError:
            return []
        lines = [ln.rsplit("\r", 1)[-1] for ln in text.splitlines()]
        return [ln for ln in lines if ln.strip()][-LOG_LINES:]

    def status(self) -> dict[str, Any]:
        """``state`` (running, done, failed, cancelled), the ``progress`` per phase, the
        command line, the log's last lines, the ``error`` line of a failed plan, and the
        result (``anchors``, the field figures) of a finished one."""
        code = self.process.poll()
        log = self.log()
        out: dict[str, Any] = {
            "id": self.folder.name,
            "command": "anchorplan " + " ".join(self.argv),
            "settings": self.settings,
            "progress": _read_json(self.folder / "progress.json"),
            "log": log,
            "seconds": time.time() - self.started,
        }
        if code is None:
            out["state"] = "running"
        elif self.cancelled:
            out["state"] = "cancelled"
        elif code == 0 and (self.out / "layout.json").exists():
            out["state"] = "done"
            out["result"] = result_summary(self.out)
        else:
            out["state"] = "failed"
            errors = [ln for ln in log if ": error: " in ln]
            out["error"] = (
                errors[-1].split(": error: ", 1)[1]
                if errors
                else f"the plan stopped with exit code {code}"
            )
        return out


def result_summary(folder: Path) -> dict[str, Any]:
    """The anchors (M, 3) of a result folder's layout.json and, from result.json, the field
    check's median, mean, P95 (m) and verified share."""
    anchors = (_read_json(folder / "layout.json") or {}).get("anchors")
    result = _read_json(folder / "result.json") or {}
    field = ((result.get("validation") or {}).get("field")) or {}
    keys = ("median", "mean", "p95", "verified", "std")
    return {
        "anchors": anchors,
        "folder": folder.name,
        "field": {k: field.get(k) for k in keys if k in field},
    }


class FieldJob:
    """The error at the receiver, simulated in a thread: ``draws`` draws of
    :func:`placement.validation.mounted_errors` (the anchors mounted within ``tolerance``
    m, one noise realization each) at the map's cells, solved by the system's positioning;
    per cell the RMS error, over all the median, mean, P95 and the verified share."""

    def __init__(self, room, system, anchors, cells, draws: int, tolerance: float, seed: int):
        self.args = (room, system, np.asarray(anchors, float), np.asarray(cells, float))
        self.draws, self.tolerance, self.seed = draws, tolerance, seed
        self.done, self.result, self.error = 0, None, None
        self.started = time.time()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    @property
    def running(self) -> bool:
        return self.thread.is_alive()

    def _run(self) -> None:
        from placement.validation import mounted_errors

        room, system, anchors, cells = self.args
        try:
            errors, verified = [], []
            for d in range(self.draws):
                e = mounted_errors(
                    room, anchors, cells, self.tolerance, d, self.seed, system=system
                )
                errors.append(e[0])
                verified.append(e[1])
                self.done = d + 1
            self.result = field_summary(np.array(errors), np.array(verified))
        except (ValueError, MemoryError) as exc:
            self.error = str(exc)

    def status(self) -> dict[str, Any]:
        state = "running" if self.running else ("failed" if self.error else "done")
        return {
            "state": state,
            "done": self.done,
            "total": self.draws,
            "error": self.error,
            "result": self.result,
            "seconds": time.time() - self.started,
        }


def field_summary(errors: np.ndarray, verified: np.ndarray) -> dict[str, Any]:
    """Errors (D, C) m and verified (D, C) of D draws at C cells: per cell the RMS error
    (None where no fix), over all fixes the median, mean, P95 (m), the verified share and
    the share with a fix."""
    ok = np.isfinite(errors)
    e = errors[ok]
    per_cell = _rms_cells(errors, ok)
    stats = (
        {
            "median": float(np.median(e)),
            "mean": float(np.mean(e)),
            "p95": float(np.percentile(e, 95)),
        }
        if len(e)
        else {"median": None, "mean": None, "p95": None}
    )
    return {
        **stats,
        "verified": float(np.mean(verified)),
        "fixes": float(np.mean(ok)),
        "rms": [None if not np.isfinite(v) else float(v) for v in per_cell],
    }


def _rms_cells(errors: np.ndarray, ok: np.ndarray) -> np.ndarray:
    n = ok.sum(axis=0)
    s = np.where(ok, errors, 0.0) ** 2
    return np.where(n > 0, np.sqrt(s.sum(axis=0) / np.maximum(n, 1)), np.inf)

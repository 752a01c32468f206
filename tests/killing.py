"""Kill ``anchorplan plan`` with SIGKILL in a given phase, as a crash or an out-of-memory
killer would (used by tests/test_resume.py and benchmarks/bench_resume.py).

The plan runs with its progress bars on; the phase is known by its bar's name on stderr
(:data:`BARS`). The whole process group is killed, the plan's worker processes with it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

#: the progress bar that shows each phase has begun
BARS = {
    "search": "search:",
    "swarm": "PSO:",
    "refinement": "refinement:",
    "finalists": "finalists:",
    "validation": "validation:",
}


def command(argv: list[str]) -> list[str]:
    """The ``anchorplan`` command line of ``argv`` (this Python's installed package)."""
    return [sys.executable, "-m", "placement.cli", *argv]


def run_and_kill(argv: list[str], phase: str, delay: float = 0.5, timeout: float = 600):
    """Run ``anchorplan argv`` and SIGKILL it ``delay`` seconds after ``phase``'s bar shows;
    returns (seconds until the kill, whether it was killed in that phase, stderr)."""
    proc = subprocess.Popen(command(argv), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)  # fmt: skip
    seen = threading.Event()
    err: list[str] = []

    def read() -> None:
        text = ""
        while chunk := proc.stderr.read1(4096):
            text += chunk.decode(errors="replace")
            if BARS[phase] in text:
                seen.set()
        err.append(text)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    t0 = time.perf_counter()
    killed = seen.wait(timeout) and proc.poll() is None
    if killed:
        time.sleep(delay)
        killed = proc.poll() is None
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    reader.join(timeout=10)
    return time.perf_counter() - t0, killed, "".join(err)


def run(argv: list[str], timeout: float = 900) -> tuple[float, subprocess.CompletedProcess]:
    """Run ``anchorplan argv`` to the end; (seconds, the completed process)."""
    t0 = time.perf_counter()
    done = subprocess.run(command(argv), capture_output=True, text=True, timeout=timeout)
    return time.perf_counter() - t0, done

"""What resuming a killed plan costs, per phase (BENCHMARKS.md, "Resuming a killed plan").

Run:

    python benchmarks/bench_resume.py                       # anchorplan plan --anchors 8
    python benchmarks/bench_resume.py --args "--anchors 8 --effort quick"

First the plan runs uninterrupted. Then, for each phase, it is started with a fresh
``--checkpoint``, killed with SIGKILL ``--delay`` seconds after the phase's progress bar
shows, and started again with the same checkpoint to the end. One JSON line per phase:
the seconds until the kill, the seconds of the resumed run, what the kill cost (the two
together minus the uninterrupted run's seconds) and whether the resumed run's result.json
is the uninterrupted one's (tests/drift.py's tolerances).
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import tempfile
from pathlib import Path

from _common import emit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from drift import compare  # noqa: E402
from killing import BARS, run, run_and_kill  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--args", default="--anchors 8", help="the plan's arguments")
    ap.add_argument("--delay", type=float, default=1.0, help="seconds into the phase")
    ap.add_argument("--phases", nargs="+", default=list(BARS), choices=list(BARS))
    opts = ap.parse_args()
    plan = ["plan", *shlex.split(opts.args)]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        plain, done = run([*plan, "--no-progress", "--out", str(tmp / "plain")])
        if done.returncode:
            sys.exit(done.stderr)
        reference = json.loads((tmp / "plain" / "result.json").read_text())
        emit("resume", phase=None, args=opts.args, uninterrupted_s=plain)
        for phase in opts.phases:
            ckpt, out = tmp / f"{phase}.ckpt", tmp / phase
            argv = [*plan, "--checkpoint", str(ckpt), "--out", str(out)]
            killed_s, killed, _ = run_and_kill(argv, phase, delay=opts.delay)
            resumed_s, done = run([*argv, "--no-progress"])
            same = done.returncode == 0 and not compare(
                reference, json.loads((out / "result.json").read_text())
            )
            emit("resume", phase=phase, args=opts.args, killed=killed, killed_after_s=killed_s,
                 resumed_s=resumed_s, cost_s=killed_s + resumed_s - plain,
                 uninterrupted_s=plain, same_result=same)  # fmt: skip


if __name__ == "__main__":
    main()

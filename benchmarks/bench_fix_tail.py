"""Where a layout's wrong fixes come from: the field's tags grouped by how many anchors
they see in line of sight (BENCHMARKS.md, "Rooms with obstacles").

Run:

    python benchmarks/bench_fix_tail.py docs/examples/l-shaped-lab-recommended
    python benchmarks/bench_fix_tail.py docs/benchmarks/robust/l-shaped-lab-recommended-before \\
        --room examples/l-shaped-lab.toml \\
        --system docs/benchmarks/robust/recommended-no-detection.toml

The layout of RESULT_DIR/layout.json (the room and system of its result.json unless
``--room`` / ``--system`` are given) in ``--draws`` field draws (300 random tags in the
zones, anchors mounted within 3 cm, the validation's streams of seed 0), positions solved
by the system. One JSON line per number of anchors in sight: the tags, the share of fixes
more than ``--off`` m off, the verified share; then one line on the fixes that are off:
the share that rest on a hidden anchor whose range is shorter than its direct distance by
more than 0.1 m (a range no path explains: the receiver picked noise before any path
arrived); one on why they are off (fewer than 5 direct ranges; 5 or more whose own fix is
off, their anchors in a row; 5 or more that fix the tag, another set kept); then the
field figure of all of them (median, mean, P95 and RMS of the error,
the verified share and the share of verified fixes more than 0.5 m off).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from _common import emit

from placement.cli.common import plan_system
from placement.validation import _mounted_ranges, random_nodes
from simulation import Room, locate, streams
from simulation.polyhedral import line_of_sight


def _scene(args):
    folder = Path(args.result_dir)
    anchors = np.array(json.loads((folder / "layout.json").read_text())["anchors"], dtype=float)
    res = {} if args.room else json.loads((folder / "result.json").read_text())
    room = Room.from_toml(args.room) if args.room else Room.from_dict(res["room"])
    return room, plan_system(folder, args.system), anchors


#: why a fix is off (:func:`_causes`)
CAUSES = ("fewer_than_5_direct", "direct_set_off", "another_set_kept")


def _causes(room, anchors, nodes, excess, R, off) -> dict:
    """How many of the fixes off at ``nodes`` (n, 3) had fewer than 5 direct ranges
    (within 5 cm of the distance: ``excess`` (n, M) = range − distance), how many had 5 or
    more that fix the tag more than ``off`` m off (least squares started at the tag), and
    how many had 5 or more that fix it but the solver kept another set."""
    direct = np.abs(excess) < 0.05  # NaN compares False
    few = direct.sum(axis=1) < 5
    region = (np.zeros(3), np.asarray(room.size, dtype=float))
    x = locate(anchors, np.where(direct[~few], R[~few], np.nan), region=region, bounded=True,
               x0=nodes[~few])  # fmt: skip
    off_alone = np.linalg.norm(x - nodes[~few], axis=-1) > off
    return {"fewer_than_5_direct": int(few.sum()), "direct_set_off": int(off_alone.sum()),
            "another_set_kept": int((~off_alone).sum())}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result_dir")
    ap.add_argument("--room", help="a room file (default: the result's room)")
    ap.add_argument("--system", help="a preset or a TOML file (default: the result's)")
    ap.add_argument("--draws", type=int, default=5)
    ap.add_argument("--off", type=float, default=0.3, help="a fix this far off is wrong, m")
    args = ap.parse_args()
    room, system, anchors = _scene(args)
    seen, error, verified, short, causes = [], [], [], [], []
    for d in range(args.draws):
        nodes = random_nodes(room, 300, streams.stream(0, 0, d))
        R = _mounted_ranges(room, system, anchors, nodes, 0.03, d, 0, None, 1)
        fix = system.positioning.locate(room, anchors, R, full_output=True)
        los = line_of_sight(room, anchors, nodes)
        dist = np.linalg.norm(nodes[:, None] - anchors[None], axis=-1)
        seen.append(los.sum(axis=1))
        error.append(np.linalg.norm(fix.x - nodes, axis=-1))
        verified.append(fix.verified)
        short.append(np.any(~los & (dist - R > 0.1), axis=1))  # NaN compares False
        off = np.linalg.norm(fix.x - nodes, axis=-1) > args.off
        causes.append(_causes(room, anchors, nodes[off], R[off] - dist[off], R[off], args.off))
    seen, error, verified, short = map(np.concatenate, (seen, error, verified, short))
    off = error > args.off  # NaN (no fix) compares False
    found = error[np.isfinite(error)]
    for k in np.unique(seen):
        m = seen == k
        emit("fix_tail", room=room.name, system=system.name, seen=int(k), tags=int(m.sum()),
             off=float(off[m].mean()), verified=float(verified[m].mean()))  # fmt: skip
    emit("fix_tail_off", room=room.name, system=system.name, tags=int(seen.size),
         off=float(off.mean()), off_with_short_hidden_range=float(np.mean(short[off]))
         if off.any() else 0.0)  # fmt: skip
    emit("fix_tail_causes", room=room.name, system=system.name,
         **{k: int(sum(c[k] for c in causes)) for k in CAUSES})  # fmt: skip
    wrong = np.mean(verified & (error > 0.5)) / max(verified.mean(), 1e-12)
    emit("fix_field", room=room.name, system=system.name, tags=int(error.size),
         found=int(found.size), median=float(np.median(found)), mean=float(found.mean()),
         p95=float(np.percentile(found, 95)), rms=float(np.sqrt(np.mean(found**2))),
         verified=float(verified.mean()), verified_wrong=float(wrong))  # fmt: skip


if __name__ == "__main__":
    main()

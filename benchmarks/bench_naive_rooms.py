"""The positioning in every room file of the project, on the naive layout (BENCHMARKS.md,
"The examples planned again with the current positioning").

Run:

    python benchmarks/bench_naive_rooms.py [--anchors 8 12] [--draws 4] [--rooms t-hall ...]

For each room file of ``examples/`` and ``docs/benchmarks/rooms/``, the naive layout of
each M (``placement.naive_layout``) is evaluated in the field with the recommended system
(its chirp as long as the room file's own, the window moved with it: ``with_room_chirp``):
``--draws`` draws of 300 random tags in the zones, anchors mounted within 3 cm, one noise
realization, the streams of seed 7 as ``bench_against_naive.py`` draws them. No plan: a
layout nobody tuned for the room puts the solver among echoes, shadows and tags that see
3 or 4 anchors. One JSON line per room and M: the share of the tags fixed, the median,
mean, P95 and RMS of the error over the fixes (left out where no tag is fixed), the share
verified and, of those, the share more than 0.5 m off.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _common import emit, error_summary, field_draws, with_room_chirp

from placement import naive_layout
from simulation import Room
from simulation.system import System

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--anchors", type=int, nargs="+", default=[8, 12])
    ap.add_argument("--draws", type=int, default=4)
    ap.add_argument("--rooms", nargs="+", help="room files by name (e.g. t-hall); default all")
    args = ap.parse_args()
    files = sorted((ROOT / "examples").glob("*.toml"))
    files += sorted((ROOT / "docs" / "benchmarks" / "rooms").glob("*.toml"))
    for path in files:
        if args.rooms and path.stem not in args.rooms:
            continue
        room = Room.from_toml(path)
        system = with_room_chirp(System.recommended(), System.from_toml(path))
        for M in args.anchors:
            E = field_draws(room, naive_layout(room, M), system, args.draws)
            e, verified = E[0], E[1] > 0
            wrong = np.mean(verified & (e > 0.5)) / max(verified.mean(), 1e-12)
            emit("naive_rooms", room=room.name, file=str(path.relative_to(ROOT)), anchors=M,
                 tags=int(e.size), fixed=float(np.isfinite(e).mean()), **error_summary(e),
                 verified=float(verified.mean()), verified_wrong=float(wrong))  # fmt: skip


if __name__ == "__main__":
    main()

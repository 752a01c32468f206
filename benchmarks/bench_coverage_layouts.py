"""Layouts chosen for line-of-sight coverage alone, simulated: does seeing k anchors make
the fix right? For each M, the coverage program (`placement.coverage.select_coverage`,
candidates every ``--spacing`` m, k = 5, HiGHS) picks M candidates in the room; the
recommended system then simulates ``--draws`` field draws at the room's evaluation nodes
with the anchors mounted within 3 cm (`placement.validation.mounted_errors`).

    python benchmarks/bench_coverage_layouts.py --anchors 10 16 20 24

One JSON line per M: the covered share, the bound and the greedy pick's share; median,
mean, P95 of the error (m); the verified share and the share of verified fixes more than
0.5 m off."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _common import emit, with_room_chirp

from analysis.coverage import heard
from placement.coverage import plane_groups, select_coverage
from placement.surfaces import candidate_grid
from placement.validation import mounted_errors
from simulation import Room, System

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--room", default="examples/warehouse-aisles.toml")
    ap.add_argument("--anchors", type=int, nargs="+", default=[10, 16, 20, 24])
    ap.add_argument("--spacing", type=float, default=0.5)
    ap.add_argument("--draws", type=int, default=3)
    args = ap.parse_args()
    room = Room.from_toml(ROOT / args.room)
    own = System.from_toml(ROOT / args.room)
    system = with_room_chirp(System.recommended(), own)
    nodes = room.grid()
    cand = candidate_grid(room, args.spacing)
    V = heard(room, cand, nodes, system=system)
    for M in args.anchors:
        t0 = time.perf_counter()
        sel = select_coverage(V, M, k=5, groups=plane_groups(room, cand))
        anchors = cand[sel.indices]
        runs = [mounted_errors(room, anchors, nodes, 0.03, d, 0, system=system)
                for d in range(args.draws)]  # fmt: skip
        e = np.concatenate([r[0] for r in runs])
        v = np.concatenate([r[1] for r in runs]) > 0
        f = e[np.isfinite(e)]
        emit("coverage_layouts", room=room.name, anchors=M, covered=sel.covered,
             bound=sel.bound, status=sel.status, greedy=sel.greedy,
             median=float(np.median(f)), mean=float(f.mean()),
             p95=float(np.percentile(f, 95)), verified=float(v.mean()),
             verified_wrong=float(np.mean(v & (e > 0.5)) / max(v.mean(), 1e-12)),
             seconds=time.perf_counter() - t0)  # fmt: skip


if __name__ == "__main__":
    main()

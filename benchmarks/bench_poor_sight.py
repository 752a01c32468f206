"""What counting poor geometry costs a plan: :func:`placement.dilution.poor_sight_share` per
layout scored, in a room's own candidates and sight points (BENCHMARKS.md, "Poor geometry
counted as shadows").

Run:

    python benchmarks/bench_poor_sight.py --room examples/warehouse-aisles.toml \\
        --system docs/benchmarks/robust/warehouse-recommended.toml --M 20

The room's candidate grid (the search's spacing) and its 2 000 sight points with what each
sees; then random layouts of M candidates scored in batches of 64 (a search's batch), with
the GDOP limit and without it (the count of the points seeing fewer than 4 only). One JSON
line: microseconds per layout, each way.
"""

from __future__ import annotations

import numpy as np
from _common import best_time, candidates_in_sight, emit, room_and_system, room_parser

from placement.coverage import SHADOW_GDOP
from placement.dilution import poor_sight_share


def main() -> None:
    ap = room_parser(__doc__)
    ap.add_argument("--M", type=int, default=20)
    args = ap.parse_args()
    room, system = room_and_system(args)
    cand, pts, seen = candidates_in_sight(room, system)
    rng = np.random.default_rng(0)
    S = np.stack([rng.choice(len(cand), args.M, replace=False) for _ in range(64)])
    poor_sight_share(pts, cand, seen, S, 4, SHADOW_GDOP)  # compile
    with_limit = best_time(lambda: poor_sight_share(pts, cand, seen, S, 4, SHADOW_GDOP))
    counts = best_time(lambda: poor_sight_share(pts, cand, seen, S, 4))
    poor = poor_sight_share(pts, cand, seen, S, 4, SHADOW_GDOP)
    emit("poor_sight", room=room.name, M=args.M, candidates=len(cand), points=len(pts),
         us_per_layout_gdop=1e6 * with_limit / len(S), us_per_layout_counts=1e6 * counts / len(S),
         share_poor_median=float(np.median(poor)))  # fmt: skip


if __name__ == "__main__":
    main()

"""A layout chosen for its geometry alone: the anchors' GDOP at the room's sight points,
no simulated range (BENCHMARKS.md, "Where the warehouse's field error comes from").

Run:

    python benchmarks/bench_gdop_only.py docs/examples/warehouse-sweep/layouts.json --M 20 \\
        --room examples/warehouse-aisles.toml \\
        --system docs/benchmarks/robust/warehouse-recommended.toml \\
        --out docs/benchmarks/robust/warehouse-geometry/gdop_only_layouts.json

From the given layout snapped to the nearest candidates of the search's grid, a swap search
(``--steps`` steps of 64 random swaps, the best taken when it lowers the objective;
numpy ``default_rng(0)``) minimizes the mean GDOP² (each capped at 50²) over the room's
2 000 sight points, the GDOP taken over the anchors each point sees in line of sight and
reach, keeping at least 95 % of the points in sight of 5. Writes the layout as a sweep's
layouts.json (key M) for ``bench_field_geometry.py``; one JSON line with the GDOP median,
P90 and P97 before and after.
"""

from __future__ import annotations

import json

import numpy as np
from _common import candidates_in_sight, emit, room_and_system, room_parser
from bench_field_geometry import load_layout

from analysis.fim import peb

#: the GDOP a point's term is capped at (a point in a shadow counts this much)
CAP = 50.0
SWAPS = 64


def gdops(cand, V, pts, layouts) -> np.ndarray:
    """(L, Q) GDOP at the points of each layout (L, M) of candidate indices, capped."""
    sigma = np.where(np.moveaxis(V[:, layouts], 0, 1), 1.0, np.inf)
    return np.minimum(peb(cand[layouts], pts, sigma=sigma), CAP)


def swap_search(cand, V, pts, S, steps: int, rng) -> np.ndarray:
    """(M,) the layout S (M,) improved by random swaps (module docstring)."""
    M = len(S)
    best = float(np.mean(gdops(cand, V, pts, S[None]) ** 2))
    for _ in range(steps):
        trials = np.repeat(S[None], SWAPS, axis=0)
        i = rng.integers(0, M, SWAPS)  # the anchor swapped, then its new candidate
        trials[np.arange(SWAPS), i] = rng.integers(0, len(cand), SWAPS)
        distinct = np.array([len(set(t)) == M for t in trials])
        seen5 = np.mean(np.sum(V[:, trials], axis=-1) >= 5, axis=0) >= 0.95  # (L,)
        score = np.where(distinct & seen5, np.mean(gdops(cand, V, pts, trials) ** 2, axis=1),
                         np.inf)  # fmt: skip
        k = int(np.argmin(score))
        if score[k] < best:
            best, S = float(score[k]), trials[k]
    return S


def main() -> None:
    ap = room_parser(__doc__)
    ap.add_argument("layout", help="the starting layout: layout.json or layouts.json")
    ap.add_argument("--M", type=int, default=None)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    room, system = room_and_system(args)
    cand, pts, V = candidates_in_sight(room, system)
    start = load_layout(args.layout, args.M)
    S0 = np.array([int(np.argmin(np.linalg.norm(cand - a, axis=1))) for a in start])
    S = swap_search(cand, V, pts, S0, args.steps, np.random.default_rng(0))
    with open(args.out, "w") as f:
        json.dump({str(len(S)): cand[S].tolist()}, f)
    g0, g1 = gdops(cand, V, pts, S0[None])[0], gdops(cand, V, pts, S[None])[0]
    emit("gdop_only", room=room.name, M=len(S), candidates=len(cand), points=len(pts),
         start=[float(np.percentile(g0, q)) for q in (50, 90, 97)],
         found=[float(np.percentile(g1, q)) for q in (50, 90, 97)], out=args.out)  # fmt: skip


if __name__ == "__main__":
    main()

"""PEB throughput: one layout on the grid, a dense PEB map, and a batch of layouts.

Run: python benchmarks/bench_bounds.py  (prints one JSON line per result)
Targets (issue 2): 270 nodes × 8 anchors ≤ 0.5 ms; 10⁶ points × 8 anchors ≤ 1 s.
"""

import numpy as np
from _common import best_time, emit

import analysis
from placement import random_layout
from simulation import Room


def main() -> None:
    rng = np.random.default_rng(0)
    room = Room.techtile()
    nodes = room.grid()
    anchors = random_layout(room, 8, rng)

    t = best_time(lambda: analysis.peb(anchors, nodes), repeat=50, number=10)
    emit("peb_grid", nodes=len(nodes), anchors=8, seconds=t, target_seconds=5e-4)

    pts = rng.uniform(0, 1, size=(1_000_000, 3)) * np.array(room.size)
    t = best_time(lambda: analysis.peb(anchors, pts), repeat=3)
    emit("peb_map", points=len(pts), anchors=8, seconds=t, target_seconds=1.0)

    layouts = np.stack([random_layout(room, 8, rng) for _ in range(1000)])
    t = best_time(lambda: analysis.peb(layouts, nodes), repeat=3)
    emit("peb_batch", layouts=1000, nodes=len(nodes), anchors=8, seconds=t)


if __name__ == "__main__":
    main()

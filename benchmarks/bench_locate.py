"""The range-table scorer: least-squares positioning of many layouts at once.

Run: python benchmarks/bench_locate.py [--layouts 240] [--repeat 5]
Prints one JSON line per M (4, 8, 10): the time per position fix and per layout of
``table_costs`` on a range table of the techtile room (0.8 m candidate grid, 2 exact draws
and 1 moved draw at the 270 nodes, 810 fixes per layout), scoring layouts in batches of
24 as the search does. The table is built once per run (about 100 candidates).
"""

import argparse
import time

import numpy as np
from _common import best_time, emit

from placement.rangetable import table_costs
from placement.simselect import SearchOptions, search_table
from simulation import Room


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layouts", type=int, default=240)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    room = Room.techtile()
    t0 = time.perf_counter()
    table = search_table(room, SearchOptions(spacing=0.8), rng=0)
    emit("table", candidates=len(table.candidates), seconds=time.perf_counter() - t0)
    rng = np.random.default_rng(0)
    N = len(table.candidates)
    for M in (4, 8, 10):
        layouts = np.stack([rng.choice(N, M, replace=False) for _ in range(args.layouts)])
        batches = [layouts[i : i + 24] for i in range(0, len(layouts), 24)]
        table_costs(table, batches[0])  # warm-up (a compiled kernel loads here)
        seconds = best_time(lambda b=batches: [table_costs(table, x) for x in b], args.repeat)
        fixes = len(layouts) * table.draws * table.nodes.shape[1]
        emit(
            "table_costs",
            M=M,
            layouts=len(layouts),
            fixes=fixes,
            seconds=seconds,
            us_per_fix=seconds / fixes * 1e6,
            ms_per_layout=seconds / len(layouts) * 1e3,
        )


if __name__ == "__main__":
    main()

"""Which figure the planner should minimize in a user's room: the paper's variance, the RMS
or the P95 of the simulated error (BENCHMARKS.md, "The cost in a user's room").

Run:

    python benchmarks/bench_costs.py --rooms techtile examples/l-shaped-lab.toml \\
        --costs variance rms p95 --system recommended --effort quick --anchors 8 --seeds 2

Each run is ``seed_then_pso(room, M, system=..., cost=..., effort=..., rng=seed)``; one JSON
line with the field check's median, mean, P95 and σ (random tags in the zones, anchors
mounted within 3 cm), its share of verified fixes, the share of nodes seeing k anchors in
line of sight, and the plan's seconds. ``--summary`` prints the table.
"""

from __future__ import annotations

import argparse
import statistics
import time

from _common import emit, read_lines


def run(room_arg: str, cost: str, system: str, effort: str, M: int, seed: int, pool) -> None:
    from placement import seed_then_pso
    from simulation import Room, System

    room = Room.techtile() if room_arg == "techtile" else Room.from_toml(room_arg)
    base = System.preset(system)
    if room_arg != "techtile":  # the room file's chirp and window start, the preset's rest
        own = System.from_toml(room_arg)
        if own.chirp != base.chirp and system == "recommended":  # a long chirp: keep its
            base = base.with_signal(duration=own.chirp.duration,  # reach, a 20 ms window
                                    t_wake=own.chirp.duration - 0.02)  # fmt: skip
    t0 = time.perf_counter()
    res = seed_then_pso(room, M, system=base, cost=cost, effort=effort, rng=seed,
                        executor=pool, progress=False)  # fmt: skip
    f, v = res.validation.field, res.validation
    emit("costs", room=room.name, cost=cost, system=base.name, effort=effort, M=M, seed=seed,
         seconds=time.perf_counter() - t0,
         field={"median": f.median, "mean": f.mean, "p95": f.p95, "std": f.std,
                "verified": f.verified},
         grid={"median": v.median, "mean": v.mean, "p95": v.p95, "std": v.std},
         covered=v.covered, coverage_k=v.coverage_k, anchors=res.anchors.tolist())  # fmt: skip


def summary(rows) -> None:
    med = statistics.median
    print("| room | cost | runs | field median (m) | field mean (m) | field P95 (m) | field σ (m) "
          "| verified | line of sight |")  # fmt: skip
    print("|---" * 9 + "|")
    for room in dict.fromkeys(r["room"] for r in rows):
        for cost in dict.fromkeys(r["cost"] for r in rows):
            rs = [r for r in rows if r["room"] == room and r["cost"] == cost]
            if not rs:
                continue
            f = {k: med([r["field"][k] for r in rs]) for k in rs[0]["field"]}
            print(f"| {room} | {cost} | {len(rs)} | {f['median']:.3f} | {f['mean']:.3f} | "
                  f"{f['p95']:.3f} | {f['std']:.3f} | {100 * f['verified']:.1f} % | "
                  f"{100 * med([r['covered'] for r in rs]):.1f} % |")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", nargs="+", default=["techtile"])
    ap.add_argument("--costs", nargs="+", default=["variance", "rms", "p95"])
    ap.add_argument("--system", default="recommended")
    ap.add_argument("--effort", default="quick")
    ap.add_argument("--anchors", type=int, default=8)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--summary", nargs="+", metavar="JSONL")
    args = ap.parse_args()
    if args.summary:
        summary(read_lines(args.summary))
        return
    from placement.workers import WorkerPool

    with WorkerPool(args.workers) as pool:
        for room in args.rooms:
            for seed in range(args.seeds):
                for cost in args.costs:
                    run(room, cost, args.system, args.effort, args.anchors, seed, pool)


if __name__ == "__main__":
    main()

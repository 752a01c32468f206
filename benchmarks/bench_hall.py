"""A hall three times the paper's reach: two signal designs, planned and validated.

Run: python benchmarks/bench_hall.py [--anchors 10] [--seed 0] [--workers 2]

``examples/hall.toml`` (24 × 16 × 6 m, ISO 9613-1 air, tags at 0.5–2 m over the floor) is
planned with ``seed_then_pso`` (the defaults of ``anchorplan plan``) under two signal
designs, every other setting equal:

- ``paper``: the paper's 30 ms chirp, its 1 ms window at 29 ms (reach 9.95 m), with the
  hall's detection threshold (false alarm <= 1e-3);
- ``hall``: the file's 90 ms chirp, its 1 ms window at 89 ms (reach 30.5 m).

One JSON line per design: the plan time, the validated σ / mean / P95 (over the fixes) and
availability at the zone nodes, at held-out nodes and under mounting error, the share of
zone nodes that hear 4 anchors (analysis.covered_share), and the layout.
"""

import argparse
import dataclasses
import time
from concurrent.futures import ProcessPoolExecutor

from _common import emit

import analysis
from placement import seed_then_pso
from simulation import Room, System


def designs(path: str) -> dict[str, System]:
    """The paper's system (with the hall's threshold) and the hall file's own."""
    paper = System.paper()
    paper = dataclasses.replace(
        paper, receiver=dataclasses.replace(paper.receiver, false_alarm=1e-3), name="custom"
    )
    return {"paper": paper, "hall": System.from_toml(path)}


def summary(block: dict) -> dict:
    keys = ("std", "mean", "p95", "availability")
    return {k: block.get(k) for k in keys}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--anchors", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=["paper", "hall"])
    args = ap.parse_args()
    room = Room.from_toml("examples/hall.toml")
    for name, system in designs("examples/hall.toml").items():
        if name not in args.designs:
            continue
        t0 = time.perf_counter()
        with ProcessPoolExecutor(args.workers) as ex:
            res = seed_then_pso(
                room, args.anchors, rng=args.seed, executor=ex, progress=False, system=system
            )
        seconds = time.perf_counter() - t0
        v = res.validation.to_dict()
        emit(
            "hall",
            design=name,
            M=args.anchors,
            seed=args.seed,
            reach_m=system.reach(room.speed_of_sound),
            chirp_ms=system.chirp.duration * 1e3,
            plan_seconds=seconds,
            phases=res.timings,
            zone=summary(v),
            held_out_grid=summary(v["held_out"]["grid"]),
            held_out_random=summary(v["held_out"]["random"]),
            mounting=summary(v["mounting"]),
            covered_share=analysis.covered_share(room, res.anchors, room.grid(), system=system),
            reach_exceeded=res.settings.reach["exceeded"],
            anchors=res.anchors.tolist(),
        )


if __name__ == "__main__":
    main()

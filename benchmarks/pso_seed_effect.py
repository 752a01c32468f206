"""Evaluations the seeded swarm needed to reach the unseeded swarm's final cost (issue 5),
read from the best-cost histories that bench_paper.py saved (15 evaluations per iteration).

Run: python benchmarks/pso_seed_effect.py [layouts.json ...]
(default: docs/benchmarks/layouts.json docs/benchmarks/seed1/layouts.json)
"""

import json
import sys

from _common import emit


def first_reach(history: list[float], target: float, particles: int) -> int | None:
    """Evaluations until the best cost is ≤ target (iteration granularity), None if never."""
    return next((particles * (i + 1) for i, c in enumerate(history) if c <= target), None)


def main(paths: list[str]) -> None:
    for path in paths:
        layouts = json.load(open(path))
        for key, unseeded in layouts.items():
            if not key.startswith("pso/"):
                continue
            seeded = layouts.get("stp/" + key[4:])
            if seeded is None:
                continue
            k = int(unseeded.get("particles", 15))
            target = unseeded["history"][-1]
            n_u = first_reach(unseeded["history"], target, k)
            n_s = first_reach(seeded["history"], target, k)
            emit(
                "pso_seed_effect",
                layouts=path,
                key=key[4:],
                unseeded_final_cost=target,
                unseeded_nfev_to_reach=n_u,
                seeded_nfev_to_reach=n_s,
                ratio=None if n_s is None else n_s / n_u,
                seeded_final_cost=seeded["history"][-1],
            )


if __name__ == "__main__":
    main(sys.argv[1:] or ["docs/benchmarks/layouts.json", "docs/benchmarks/seed1/layouts.json"])

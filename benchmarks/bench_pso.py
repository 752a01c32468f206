"""Seeded versus unseeded PSO on the simulated cost (issue 5 acceptance).

For each M and seed, runs ``seed_then_pso`` unseeded (the paper's random swarm) and seeded
("auto": relaxation + refinement + best random layouts) with the same evaluation noise
streams, and reports the evaluations the seeded run needed to reach the unseeded run's
final cost, and both final layouts' validated σ / mean / P95.

Run: python benchmarks/bench_pso.py [--anchors 4 8] [--seeds 5] [--workers 2]
     [--iterations 40] [--validate 100]
"""

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

from _common import emit

from placement.plan import seed_then_pso
from simulation import Room


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--anchors", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--particles", type=int, default=15)
    ap.add_argument("--iterations", type=int, default=40)
    ap.add_argument("--validate", type=int, default=100)
    args = ap.parse_args()
    room = Room.techtile()
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        for M in args.anchors:
            for seed in range(args.seeds):
                runs = {}
                for label, seeds in (("unseeded", None), ("seeded", "auto")):
                    t0 = time.perf_counter()
                    runs[label] = res = seed_then_pso(
                        room,
                        M,
                        particles=args.particles,
                        iterations=args.iterations,
                        seeds=seeds,
                        seed=seed,
                        executor=ex,
                        progress=False,
                        validate_realizations=args.validate,
                    )
                    v = res.validation
                    emit(
                        "pso_run",
                        M=M,
                        seed=seed,
                        swarm=label,
                        cost=res.cost,
                        nfev=res.nfev,
                        nit=res.nit,
                        message=res.message,
                        validated_std=v["std"],
                        validated_mean=v["mean"],
                        validated_p95=v["p95"],
                        mean_peb=v["mean_peb"],
                        seeds={s.name: s.cost for s in res.seeds},
                        seconds=time.perf_counter() - t0,
                        timings=res.timings,
                    )
                target = runs["unseeded"].cost
                base = runs["unseeded"].pso.nfev_to_reach(target)
                need = runs["seeded"].pso.nfev_to_reach(target)
                emit(
                    "pso_seeded_vs_unseeded",
                    M=M,
                    seed=seed,
                    unseeded_final_cost=target,
                    unseeded_nfev_to_reach=base,
                    seeded_nfev_to_reach=need,
                    ratio=None if need is None else need / base,
                    seeded_final_cost=runs["seeded"].cost,
                    unseeded_std=runs["unseeded"].validation["std"],
                    seeded_std=runs["seeded"].validation["std"],
                    unseeded_p95=runs["unseeded"].validation["p95"],
                    seeded_p95=runs["seeded"].validation["p95"],
                )


if __name__ == "__main__":
    main()

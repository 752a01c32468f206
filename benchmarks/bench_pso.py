"""Seeded versus unseeded PSO on the simulated cost (issue 5 acceptance).

For each M and seed, runs ``seed_then_pso`` unseeded (the paper's random swarm) and seeded
("auto": simulation-driven candidate search, relaxations + refinements, best random
layouts) with the same evaluation noise streams, and reports the evaluations the seeded run
needed to reach the unseeded run's final best cost, and both chosen layouts' validated σ /
mean / P95. Each run is saved to ``DIR/M{M}_s{seed}_{swarm}.json`` (costs of every evaluation,
history, validation, timings); runs already saved are read back instead of rerun (unless
``--force``), so the unseeded and seeded halves can run at different times.

Run: python benchmarks/bench_pso.py [--anchors 4 8] [--seeds 5] [--workers 2]
     [--swarms unseeded seeded] [--iterations 40] [--validate 100] [--dir DIR]
"""

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from _common import emit

from placement.plan import seed_then_pso
from placement.pso import nfev_to_reach
from placement.serialization import to_jsonable
from simulation import Room

SWARMS = {"unseeded": None, "seeded": "auto"}


def run(room, M, seed, swarm, args, ex) -> dict:
    t0 = time.perf_counter()
    res = seed_then_pso(
        room,
        M,
        particles=args.particles,
        iterations=args.iterations,
        seeds=SWARMS[swarm],
        seed=seed,
        executor=ex,
        progress=False,
        validate_realizations=args.validate,
    )
    v = {k: x for k, x in res.validation.items() if k not in ("errors", "per_node")}
    return {
        "M": M,
        "seed": seed,
        "swarm": swarm,
        "anchors": res.anchors.tolist(),
        "cost": res.cost,
        "nfev": res.nfev,
        "nit": res.nit,
        "message": res.message,
        "history": res.history,
        "costs": np.asarray(res.pso.costs).tolist(),
        "validation": v,
        "seeds": [s.to_dict() for s in res.seeds],
        "finalists": [{k: f[k] for k in ("pso_cost", "cost")} for f in res.finalists],
        "seed_search": res.settings.get("seed_search", {}),
        "timings": res.timings,
        "seconds": time.perf_counter() - t0,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--anchors", type=int, nargs="+", default=[4, 8])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--particles", type=int, default=15)
    ap.add_argument("--iterations", type=int, default=40)
    ap.add_argument("--validate", type=int, default=100)
    ap.add_argument("--swarms", nargs="+", choices=list(SWARMS), default=list(SWARMS))
    ap.add_argument("--dir", default="docs/benchmarks/pso")
    ap.add_argument("--force", action="store_true", help="rerun runs that are already saved")
    args = ap.parse_args()
    out = Path(args.dir)
    out.mkdir(parents=True, exist_ok=True)
    room = Room.techtile()
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        for M in args.anchors:
            for seed in range(args.seeds):
                runs = {}
                for swarm in SWARMS:
                    path = out / f"M{M}_s{seed}_{swarm}.json"
                    if path.exists() and not args.force:
                        runs[swarm] = json.loads(path.read_text())
                        continue
                    if swarm not in args.swarms:
                        continue
                    runs[swarm] = r = run(room, M, seed, swarm, args, ex)
                    path.write_text(json.dumps(to_jsonable(r)))
                    emit(
                        "pso_run",
                        **{k: r[k] for k in ("M", "seed", "swarm", "cost", "nfev", "nit")},
                        validated_std=r["validation"]["std"],
                        validated_mean=r["validation"]["mean"],
                        validated_p95=r["validation"]["p95"],
                        mean_peb=r["validation"]["mean_peb"],
                        seeds={s["name"]: s["cost"] for s in r["seeds"]},
                        seconds=r["seconds"],
                        timings=r["timings"],
                    )
                if len(runs) < 2:
                    continue
                u, s = runs["unseeded"], runs["seeded"]
                target = u["history"][-1]  # the swarm's final best cost
                base = nfev_to_reach(u["costs"], target)
                need = nfev_to_reach(s["costs"], target)
                emit(
                    "pso_seeded_vs_unseeded",
                    M=M,
                    seed=seed,
                    unseeded_final_cost=target,
                    unseeded_nfev_to_reach=base,
                    seeded_nfev_to_reach=need,
                    ratio=None if need is None else need / base,
                    seeded_final_cost=s["cost"],
                    seeded_nfev=s["nfev"],
                    seed_search_equivalent_evaluations=s["seed_search"].get(
                        "equivalent_evaluations"
                    ),
                    seed_search_table_nfev=s["seed_search"].get("nfev"),
                    unseeded_seconds=u["seconds"],
                    seeded_seconds=s["seconds"],
                    seeded_seeding_seconds=s["timings"].get("seeding"),
                    unseeded_std=u["validation"]["std"],
                    seeded_std=s["validation"]["std"],
                    unseeded_mean=u["validation"]["mean"],
                    seeded_mean=s["validation"]["mean"],
                    unseeded_p95=u["validation"]["p95"],
                    seeded_p95=s["validation"]["p95"],
                )


if __name__ == "__main__":
    main()

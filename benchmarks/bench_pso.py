"""seed_then_pso against the paper's Table I, per phase, and what the swarm adds.

For each M and seed, runs ``seed_then_pso(room, M, rng=seed)`` with its defaults and
records:
- the validated σ / mean / P95 (m) at the 270 nodes (R = 100, the run's own validation
  noise), at held-out nodes (a 10 × 7 × 6 grid and 300 random points) and under mounting
  error (3 cm, 10 draws);
- the seconds and cost evaluations of every phase (search, swarm, refinement, finalists,
  validation);
- the best seed (the lowest swarm cost at the swarm's first iteration) validated on the
  same draws as the chosen layout: the swarm improved on its seeds when the chosen layout's
  σ is below the best seed's;
- with ``--unseeded``, the same run with an unseeded swarm of the paper's size (15
  particles × 40 iterations, random start, the same cost);
- with ``--baseline DIR``, the layouts saved in DIR (``M{M}_s{seed}_seeded.json``, e.g. the
  earlier docs/benchmarks/pso runs) validated with the same settings and draws.

Each run is saved to ``DIR/M{M}_s{seed}[_unseeded].json`` and read back instead of rerun
(unless ``--force``). One JSON line per run; ``pso_tables.py DIR`` prints the tables.

Run: python benchmarks/bench_pso.py [--anchors 4 6 8 10] [--seeds 5] [--workers 2]
     [--unseeded] [--baseline docs/benchmarks/pso] [--dir docs/benchmarks/plan]
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _common import emit

from placement import PSOOptions
from placement.plan import seed_then_pso
from placement.serialization import to_jsonable
from placement.streams import phase_seed
from placement.validation import validate_layout
from placement.workers import WorkerPool
from simulation import Room


def _summary(v: dict) -> dict:
    return {
        "std": v["std"],
        "mean": v["mean"],
        "p95": v["p95"],
        "availability": v.get("availability"),
        "held_out": v.get("held_out"),
        "mounting": v.get("mounting"),
    }


def _validation_rng(res) -> int:
    """The validation stream of a run (as seed_then_pso derives it)."""
    return phase_seed(res.settings.seed, "validation")


def run(room, M, seed, args, ex, unseeded=False) -> dict:
    t0 = time.perf_counter()
    kw = {}
    if unseeded:
        kw = dict(initial=None, swarm=PSOOptions(particles=15, iterations=40, tol=0.0))
    res = seed_then_pso(room, M, rng=seed, executor=ex, progress=False, **kw)
    seconds = time.perf_counter() - t0
    out = {
        "M": M,
        "seed": seed,
        "swarm": "unseeded" if unseeded else "seeded",
        "anchors": res.anchors.tolist(),
        "cost": res.cost,
        "nfev": res.nfev,
        "nit": res.nit,
        "history": res.history,
        "validation": _summary(res.validation.to_dict()),
        "initial": [s.to_dict() for s in res.initial],
        "finalists": [{k: f[k] for k in ("source", "pso_cost", "cost")} for f in res.finalists],
        "chosen": next(
            (f["source"] for f in res.finalists if np.array_equal(f["anchors"], res.anchors)),
            "swarm",
        ),
        "search_result": dict(res.settings.search_result),
        "timings": res.timings,
        "nfev_by_phase": {k: p["nfev"] for k, p in res.phases.items()},
        "seconds": seconds,
    }
    if res.initial:
        best = min(res.initial, key=lambda s: s.cost)
        v = validate_layout(room, best.anchors, rng=_validation_rng(res), executor=ex).to_dict()
        out["best_seed"] = {"name": best.name, "anchors": best.anchors.tolist(), **_summary(v)}
    return out


def baseline(room, M, seed, folder: Path, ex) -> dict | None:
    path = folder / f"M{M}_s{seed}_seeded.json"
    if not path.exists():
        return None
    anchors = np.array(json.loads(path.read_text())["anchors"])
    rng = phase_seed(seed, "validation")
    v = validate_layout(room, anchors, rng=rng, executor=ex).to_dict()
    return {"source": str(path), "anchors": anchors.tolist(), **_summary(v)}


def _emit(r: dict) -> None:
    v = r["validation"]
    h, m = v.get("held_out") or {}, v.get("mounting") or {}
    fields = dict(
        M=r["M"],
        seed=r["seed"],
        swarm=r["swarm"],
        std=v["std"],
        mean=v["mean"],
        p95=v["p95"],
        availability=v.get("availability"),
        held_out_grid_std=(h.get("grid") or {}).get("std"),
        held_out_random_std=(h.get("random") or {}).get("std"),
        mounting_std=m.get("std"),
        chosen=r["chosen"],
        seconds=r["seconds"],
        timings=r["timings"],
        nfev_by_phase=r["nfev_by_phase"],
    )
    if "best_seed" in r:
        fields["best_seed_std"] = r["best_seed"]["std"]
        fields["swarm_improved"] = v["std"] < r["best_seed"]["std"]
    if r.get("baseline"):
        b = r["baseline"]
        fields["baseline_std"] = b["std"]
        fields["baseline_held_out_grid_std"] = b["held_out"]["grid"]["std"]
        fields["baseline_mounting_std"] = b["mounting"]["std"]
    emit("plan_run", **fields)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--anchors", type=int, nargs="+", default=[4, 6, 8, 10])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--unseeded", action="store_true", help="also run unseeded swarms")
    ap.add_argument("--baseline", metavar="DIR", help="earlier layouts to validate alike")
    ap.add_argument("--dir", default="docs/benchmarks/plan")
    ap.add_argument("--force", action="store_true", help="rerun runs that are already saved")
    args = ap.parse_args()
    out = Path(args.dir)
    out.mkdir(parents=True, exist_ok=True)
    room = Room.techtile()
    with WorkerPool(max_workers=args.workers) as ex:
        for M in args.anchors:
            for seed in range(args.seeds):
                for unseeded in (False, True) if args.unseeded else (False,):
                    path = out / f"M{M}_s{seed}{'_unseeded' if unseeded else ''}.json"
                    if path.exists() and not args.force:
                        continue
                    r = run(room, M, seed, args, ex, unseeded)
                    if args.baseline and not unseeded:
                        r["baseline"] = baseline(room, M, seed, Path(args.baseline), ex)
                    path.write_text(json.dumps(to_jsonable(r)))
                    _emit(r)


if __name__ == "__main__":
    main()

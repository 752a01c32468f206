"""The search's settings against the spread of seed_then_pso's σ over seeds.

For each seed, the range table is built once, exactly as ``seed_then_pso(room, M,
rng=seed)`` builds it (it depends on the seed, not on M), and shared by the runs at every
M; each run is ``seed_then_pso`` with its defaults except the search's settings given as
``--search`` (a JSON object of :class:`placement.simselect.SearchOptions` fields). With
``--search '{}'`` the runs are the default plans of ``bench_pso.py`` (same layouts).
``--cost`` plans for another cost statistic than the paper's variance (on the same
tables: the table holds ranges, not costs).

With ``--table-seed T`` every run searches seed T's table instead of its own: the search,
swarm, finalists and validation keep the run's seed, so the spread over seeds is then
what the run's other random choices make of one table. ``--first-seed S`` runs seeds
S, S + 1, … instead of 0, 1, … (other seeds than the benchmark's, same settings).

One JSON line per run: the validated σ / mean / P95 at the 270 nodes (R = 100, the run's
own validation noise), σ at the held-out grid, the random points and under mounting
error, the chosen finalist, the finalists' fresh-draw costs (m²) and the seconds of every
phase (the table's seconds apart: it is built once per seed). ``--summary JSONL`` prints
the two tables of BENCHMARKS.md ("Levers on the spread") from such files (several may be
given; the seeded runs of ``bench_pso.py``'s ``bench_plan.jsonl`` count as the default
settings): the runs per setting, and how much σ varies from seed to seed. Runs of other
seeds, and runs marked ``"refinement": "joint"`` (``fine_optima`` layouts refined on one
shared grown table, as the plan did before it refined each on its own), are grouped apart.

Run: python benchmarks/bench_search_levers.py [--search '{"evaluations": 9000}']
     [--anchors 4 6 8 10] [--seeds 5] [--first-seed S] [--table-seed T] [--cost variance]
     [--workers 2]
"""

import json
import statistics
import time

import numpy as np
from _common import PAPER_TABLE1, emit, read_lines, runs_parser, spread

from placement.initial import build_table
from placement.plan import Planner
from placement.simselect import SearchOptions
from placement.workers import WorkerPool
from simulation import Room


def run(room, M, seed, table, options, ex, workers, cost="variance") -> dict:
    t0 = time.perf_counter()
    planner = Planner(room, M, rng=seed, cost=cost, search=options, executor=ex,
                      progress=False, table=table)  # fmt: skip
    res = planner.solve()
    v = res.validation.to_dict()
    return dict(
        M=M,
        seed=seed,
        std=v["std"],
        mean=v["mean"],
        p95=v["p95"],
        availability=v.get("availability"),
        held_out_grid_std=v["held_out"]["grid"]["std"],
        held_out_random_std=v["held_out"]["random"]["std"],
        mounting_std=v["mounting"]["std"],
        chosen=next(
            (f["source"] for f in res.finalists if np.array_equal(f["anchors"], res.anchors)),
            "swarm",
        ),
        finalists={f["source"]: f["cost"] for f in res.finalists},
        anchors=res.anchors.tolist(),
        seconds=time.perf_counter() - t0,
        timings=res.timings,
    )


def _lines(paths: list[str]):
    """The runs of ``paths``; the seeded runs of ``bench_pso.py`` (``bench_plan.jsonl``)
    are the default settings on each seed's own table."""
    for r in read_lines(paths):
        if r["bench"] == "plan_run" and r.get("swarm") == "seeded":
            yield {**r, "search": {}, "table_seed": None}
        elif r["bench"] == "search_levers":
            yield r


def _note(r: dict) -> str:
    """What sets a run's group apart beyond its settings and table: another cost than the
    variance, other seeds, or the joint refinement of an earlier version."""
    notes = [f"cost {r['cost']}"] if r.get("cost", "variance") != "variance" else []
    if r.get("refinement") == "joint":
        notes.append("joint refinement")
    if r.get("first_seed"):
        notes.append(f"seeds from {r['first_seed']}")
    return ", ".join(notes)


def summary(paths: list[str]) -> None:
    """Per (search settings, table seed) and M: σ per seed, median, worst, spread, runs
    below Table I on σ and P95 and on the mean, and the mean σ where the tags will be."""
    groups: dict[tuple, list[dict]] = {}
    for r in _lines(paths):
        tseed = -1 if r["table_seed"] is None else r["table_seed"]
        key = (json.dumps(r["search"], sort_keys=True), tseed, r["M"], _note(r))
        groups.setdefault(key, []).append(r)
    print(
        "| search | table | M | σ per seed (m) | median | worst | spread "
        "| below Table I: σ and P95 / mean "
        "| mean σ: held-out grid / random points / mounting error (m) |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    # the default settings first, then each setting: on its own tables (the benchmark's
    # seeds, then others) before a shared one
    for (search, tseed, M, note), rs in sorted(
        groups.items(), key=lambda g: (g[0][0] != "{}", g[0][0], g[0][1] >= 0, g[0][3], g[0])
    ):
        rs = sorted(rs, key=lambda r: r["seed"])
        s = [r["std"] for r in rs]
        p = PAPER_TABLE1[M]
        below = sum(r["std"] < p["std"] and r["p95"] < p["p95"] for r in rs)
        mean_below = sum(r["mean"] < p["mean"] for r in rs)
        where = " / ".join(
            f"{statistics.mean(r[k] for r in rs):.3f}"
            for k in ("held_out_grid_std", "held_out_random_std", "mounting_std")
        )
        table = ("own" if tseed < 0 else f"seed {tseed}") + (f", {note}" if note else "")
        print(
            f"| `{search}` | {table} | {M} | {', '.join(f'{x:.3f}' for x in s)} "
            f"| {statistics.median(s):.3f} | {max(s):.3f} | {spread(s):.1%} "
            f"| {below} / {mean_below} of {len(rs)} | {where} |"
        )
    print()
    odds(groups)


def _sd(runs: list[list[float]]) -> float:
    """The standard deviation of σ over seeds as a fraction of the median, pooled over
    groups of runs (each about its own mean)."""
    dev = np.concatenate([(np.array(s) - np.mean(s)) / np.median(s) for s in runs])
    return float(np.sqrt(np.sum(dev**2) / (len(dev) - len(runs))))


def odds(groups: dict[tuple, list[dict]], target: float = 0.05, seeds: int = 5) -> None:
    """Per M, the run-to-run standard deviation of σ (as a fraction of the median) of the
    default settings and pooled over every setting searched on its own tables (with the
    paper's cost), and the chance that ``seeds`` seeds spread by at most ``target`` if σ
    were normal with it: the range of n normal draws over their standard deviation
    follows the studentized range with infinite degrees of freedom."""
    from scipy.stats import studentized_range

    def chance(sd: float) -> float:
        return float(studentized_range.cdf(target / sd, seeds, np.inf))

    print(
        f"| M | sd of σ / median: default (5 runs) | pooled: settings, runs, sd "
        f"| chance {seeds} seeds spread ≤ {target:.0%}: default / pooled sd "
        f"| sd for a 90 % chance |"
    )
    print("|---|---|---|---|---|")
    need = target / studentized_range.ppf(0.9, seeds, np.inf)
    for M in sorted({k[2] for k in groups}):
        own = {
            k: [r["std"] for r in rs]
            for k, rs in groups.items()
            if k[2] == M
            and k[1] < 0
            and all(r.get("cost", "variance") == "variance" for r in rs)  # the paper's cost
        }
        runs = [s for s in own.values() if len(s) > 1]
        if not runs:
            continue
        pooled = _sd(runs)
        default = own.get(("{}", -1, M, ""), [])
        base = _sd([default]) if len(default) > 1 else None
        b, cb = ("—", "—") if base is None else (f"{base:.2%}", f"{chance(base):.2f}")
        print(
            f"| {M} | {b} | {len(runs)}, {sum(map(len, runs))}, {pooled:.2%} "
            f"| {cb} / {chance(pooled):.2f} | {need:.2%} |"
        )


def main() -> None:
    ap = runs_parser(__doc__, anchors=[4, 6, 8, 10])
    ap.add_argument("--search", default="{}", help="SearchOptions fields as a JSON object")
    ap.add_argument("--table-seed", type=int, help="every run searches this seed's table")
    ap.add_argument("--first-seed", type=int, default=0, help="the first seed to run")
    ap.add_argument(
        "--cost", default="variance", choices=("variance", "mean", "p95", "rms"),
        help="the plan's cost statistic (default: the paper's variance)",
    )  # fmt: skip
    args = ap.parse_args()
    if args.summary:
        summary(args.summary)
        return
    fields = json.loads(args.search)
    options = SearchOptions(**fields)
    room = Room.techtile()
    with WorkerPool(max_workers=args.workers) as ex:
        table = None
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            tseed = seed if args.table_seed is None else args.table_seed
            if table is None or args.table_seed is None:
                t0 = time.perf_counter()
                table = build_table(room, options, None, tseed, ex)
                table_seconds = time.perf_counter() - t0
            for M in args.anchors:
                r = run(room, M, seed, table, options, ex, args.workers, args.cost)
                emit(
                    "search_levers", search=fields, cost=args.cost, table_seed=args.table_seed,
                    first_seed=args.first_seed, table_seconds=table_seconds, **r,
                )  # fmt: skip


if __name__ == "__main__":
    main()

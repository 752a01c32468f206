"""The effort presets: what each delivers in the field and at the paper's nodes, and its time.

Run (one command per preset; the opening table of BENCHMARKS.md):

    python benchmarks/bench_effort.py --effort quick --anchors 4 6 8 10 --seeds 10
    python benchmarks/bench_effort.py --effort default --anchors 4 6 8 10 --seeds 10
    python benchmarks/bench_effort.py --effort thorough --anchors 4 6 8 10 --seeds 5
    python benchmarks/bench_effort.py --summary RUNS.jsonl [...]   # the table

    python benchmarks/bench_effort.py --effort default --anchors 8 --system recommended

Each run is ``seed_then_pso(techtile, M, system=..., rng=seed, effort=...)`` on
``--workers`` processes (as ``anchorplan plan --anchors M --effort ... --seed ...
--system ...``; ``--system`` default the paper's, the system Table I compares with; seeds
``--first-seed`` … ``--first-seed + --seeds − 1``), one JSON line: its seconds (the plan,
and per phase), the field check (random tags, anchors mounted within 3 cm) σ / mean /
P95 / median, and the validation at the 270 nodes σ / mean / P95 / median beside the
paper's Table I. ``--summary`` prints, per preset, system and M: the field σ and P95
(median and worst over the seeds), the field's median error (median), the 270-node σ and
P95 (median and worst) against Table I, how many runs beat Table I's σ, and the median
seconds per phase.
"""

from __future__ import annotations

import dataclasses
import json
import statistics
import time

from _common import PAPER_TABLE1, emit, read_lines, runs_parser

from placement.effort import EFFORT_NAMES

PHASES = ("search", "pso", "refinement", "finalists", "validation")


def run(effort: str, M: int, seed: int, pool, variant: dict, system: str = "paper") -> None:
    from placement import seed_then_pso

    t0 = time.perf_counter()
    res = seed_then_pso(None, M, system=system, rng=seed, effort=effort, executor=pool,
                        progress=False, **variant)  # fmt: skip
    seconds = time.perf_counter() - t0
    v, f = res.validation, res.validation.field
    changed = {k: _changes(effort, k, v) for k, v in variant.items()}
    emit("effort", effort=effort, M=M, seed=seed, variant=changed, system=res.system.name,
         seconds=seconds, phases={k: p["seconds"] for k, p in res.phases.items()},
         field={"std": f.std, "mean": f.mean, "p95": f.p95, "median": f.median,
                "availability": f.availability},
         grid={"std": v.std, "mean": v.mean, "p95": v.p95, "median": v.median,
               "realizations": v.realizations},
         table1=PAPER_TABLE1.get(M), anchors=res.anchors.tolist())  # fmt: skip


def _changes(effort: str, phase: str, options) -> dict:
    """The fields of ``options`` that differ from the preset's options of ``phase``."""
    from placement.effort import effort_options

    base = dataclasses.asdict(getattr(effort_options(effort), phase))
    return {k: v for k, v in dataclasses.asdict(options).items() if base[k] != v}


def summary(rows: list[dict]) -> None:
    """The markdown table of finished runs (module docstring)."""
    med = statistics.median
    print("| preset | M | runs | field σ median / worst (m) | field P95 median / worst (m) "
          "| field median, median (m) "
          "| 270-node σ median / worst (m) | Table I σ | beats Table I σ "
          "| 270-node P95 median / worst (m) | Table I P95 | seconds median (max) "
          "| per phase, median s |")  # fmt: skip
    print("|---" * 13 + "|")

    def name(r) -> str:
        v = r.get("variant") or {}
        system = "" if r.get("system", "paper") == "paper" else f", system {r['system']}"
        return r["effort"] + system + "".join(f", {k} {json.dumps(c)}" for k, c in v.items())

    keys = sorted({(name(r), r["effort"], r["M"]) for r in rows},
                  key=lambda k: (EFFORT_NAMES.index(k[1]), k[0], k[2]))  # fmt: skip
    for label, _, M in keys:
        rs = [r for r in rows if name(r) == label and r["M"] == M]
        fs, fp = [r["field"]["std"] for r in rs], [r["field"]["p95"] for r in rs]
        gs, gp = [r["grid"]["std"] for r in rs], [r["grid"]["p95"] for r in rs]
        fm = [r["field"]["median"] for r in rs if "median" in r["field"]]
        unbounded = f"{med(fm):.3f}" if fm else "–"
        t1 = PAPER_TABLE1.get(M) or {}
        beats = sum(s < t1.get("std", float("inf")) for s in gs)
        secs = [r["seconds"] for r in rs]
        phases = " / ".join(f"{med([r['phases'].get(p, 0) for r in rs]):.1f}" for p in PHASES)
        print(f"| {label} | {M} | {len(rs)} | {med(fs):.3f} / {max(fs):.3f} | "
              f"{med(fp):.3f} / {max(fp):.3f} | {unbounded} | {med(gs):.3f} / {max(gs):.3f} | "
              f"{t1.get('std', float('nan')):.3f} | {beats} of {len(rs)} | "
              f"{med(gp):.3f} / {max(gp):.3f} | {t1.get('p95', float('nan')):.3f} | "
              f"{med(secs):.1f} ({max(secs):.1f}) | {phases} |")  # fmt: skip
    print(f"\nper phase: {' / '.join(PHASES)}")


def main() -> None:
    ap = runs_parser(__doc__, [8], seeds_help="seeds 0 … N−1 (5)")
    ap.add_argument("--effort", default="default", choices=EFFORT_NAMES)
    ap.add_argument("--system", default="paper", help="the system planned for (a preset)")
    ap.add_argument("--first-seed", type=int, default=0, help="seeds from this one (0)")
    ap.add_argument(
        "--finalist-exact-draws",
        type=int,
        metavar="N",
        help="a variant: the preset's finalists with N of their draws exact, "
        "the others field-like (moved nodes, mounted anchors)",
    )
    ap.add_argument(
        "--search-draws",
        type=int,
        metavar="N",
        help="a variant: the preset's range table with N draws",
    )
    ap.add_argument("--search-exact-draws", type=int, metavar="N",
                    help="a variant: the preset's range table with N exact draws")  # fmt: skip
    ap.add_argument(
        "--fine-optima",
        type=int,
        metavar="N",
        help="a variant: the preset's search refining the N best swarm layouts",
    )
    ap.add_argument(
        "--finalist-draws",
        type=int,
        metavar="N",
        help="a variant: the preset's finalists scored on N fresh draws",
    )
    args = ap.parse_args()
    if args.summary:
        summary(read_lines(args.summary))
        return
    from placement.effort import effort_options
    from placement.workers import WorkerPool

    preset, variant = effort_options(args.effort), {}
    finalists = {
        k: v
        for k, v in (("exact_draws", args.finalist_exact_draws), ("draws", args.finalist_draws))
        if v is not None
    }
    if finalists:
        variant["finalists"] = dataclasses.replace(preset.finalists, **finalists)
    table = {
        k: v
        for k, v in (
            ("draws", args.search_draws),
            ("exact_draws", args.search_exact_draws),
            ("fine_optima", args.fine_optima),
        )
        if v is not None
    }
    if table:
        variant["search"] = dataclasses.replace(preset.search, **table)  # fmt: skip
    with WorkerPool(args.workers) as pool:
        for M in args.anchors:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                run(args.effort, M, seed, pool, variant, args.system)


if __name__ == "__main__":
    main()

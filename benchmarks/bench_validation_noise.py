"""How far does a layout's validated σ move with the validation's own noise?

The spread target compares the σ of five runs, each validated on its own noise draws. This
benchmark separates the two parts of that spread: it validates the layout of every saved
plan (``docs/benchmarks/plan/M{M}_s{seed}.json``, the 20-run benchmark) again under
``--validations`` validation seeds. Validation seed v draws what a plan run with
``rng=v`` draws (the plan's defaults: R = 100 at the 270 nodes, held-out grid and random
points, 3 cm mounting error), so seed v = the run's seed reproduces the run's own figure.

One JSON line per (M, layout seed, validation seed) (``bench: "validation"``).
``--summary`` prints, per M, each layout's σ range over the validation seeds, and the
spread of σ over the layouts both as the benchmark measures it (each on its own run's
draws) and with the validation noise averaged out (each layout's mean σ).

Run: python benchmarks/bench_validation_noise.py [--anchors 8] [--validations 5]
     [--workers 2] > validation_noise.jsonl
Table: python benchmarks/bench_validation_noise.py --summary validation_noise.jsonl

``--layouts RUNS.jsonl [...]`` validates instead the distinct layouts of finished
``bench_effort.py`` runs at each M of ``--anchors``, under validation seeds
``--first-validation`` … (one line per layout and validation seed, ``bench:
"layout_validation"``, with the run seeds that returned the layout); ``--summary`` then
prints each layout's σ, P95 and mean error averaged over the validation seeds.
"""

import json
from pathlib import Path

import numpy as np
from _common import emit, read_lines, runs_parser, spread
from bench_candidates import validation_figures

from placement.workers import WorkerPool, run_calls
from simulation import Room

PLANS = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "plan"


def summary(rows: list[dict]) -> None:
    """Per M: each layout's σ over the validation seeds (min–max, mean), and the spread of
    σ over the layouts on their own runs' draws and with the noise averaged out (the
    ``validation`` lines of ``rows``)."""
    rows = [r for r in rows if r["bench"] == "validation"]
    print("| M | layout seed: σ min–max (mean) over validation seeds (m) | range / mean "
          "| spread on own draws | spread of mean σ |")  # fmt: skip
    print("|---|---|---|---|---|")
    for M in sorted({r["M"] for r in rows}):
        seeds = sorted({r["seed"] for r in rows if r["M"] == M})
        own, means, cells, ranges = [], [], [], []
        for s in seeds:
            sd = {r["validation_seed"]: r["std"] for r in rows if (r["M"], r["seed"]) == (M, s)}
            v = np.array(list(sd.values()))
            own.append(sd[s])
            means.append(v.mean())
            ranges.append((v.max() - v.min()) / v.mean())
            cells.append(f"{s}: {v.min():.4f}–{v.max():.4f} ({v.mean():.4f})")
        r_txt = f"{100 * min(ranges):.1f}–{100 * max(ranges):.1f} %"
        print(f"| {M} | {'; '.join(cells)} | {r_txt} | {100 * spread(own):.1f} % "
              f"| {100 * spread(means):.1f} % |")  # fmt: skip


def layouts_summary(rows: list[dict]) -> None:
    """Per M: each distinct layout's runs and its σ, P95 and mean error averaged over the
    validation seeds, from the lowest σ up (the ``layout_validation`` lines of ``rows``)."""
    rows = [r for r in rows if r["bench"] == "layout_validation"]
    print("| M | runs (seeds) | σ (m) | P95 (m) | mean (m) | validations |")
    print("|---|---|---|---|---|---|")
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["M"], json.dumps(r["anchors"])), []).append(r)

    def key(item):
        return item[0][0], np.mean([r["std"] for r in item[1]])

    for (M, _), g in sorted(groups.items(), key=key):
        seeds = ", ".join(str(s) for s in g[0]["runs"])
        stats = [np.mean([r[k] for r in g]) for k in ("std", "p95", "mean")]
        print(f"| {M} | {seeds} | {stats[0]:.4f} | {stats[1]:.3f} | {stats[2]:.3f} | {len(g)} |")


def effort_layouts(paths: list[str], M: int) -> list[tuple[list, list[int]]]:
    """The distinct layouts (to 1 mm) of the ``bench_effort.py`` lines at M in ``paths``,
    each with the seeds of the runs that returned it, in order of first appearance."""
    seeds: dict[tuple, list[int]] = {}  # rounded layout -> run seeds, in insertion order
    for r in read_lines(paths):
        if r.get("bench") == "effort" and r["M"] == M:
            a = np.round(np.asarray(r["anchors"]), 3)
            seeds.setdefault(tuple(map(tuple, a.tolist())), []).append(r["seed"])
    return [([list(p) for p in a], s) for a, s in seeds.items()]


def validate_runs(args, room) -> None:
    """The ``--layouts`` mode (module docstring)."""
    first = args.first_validation
    with WorkerPool(args.workers) as ex:
        for M in args.anchors:
            for anchors, runs in effort_layouts(args.layouts, M):
                vs = range(first, first + args.validations)
                calls = [(validation_figures, (room, anchors, v)) for v in vs]
                for v, r in zip(vs, run_calls(ex, calls), strict=True):
                    emit("layout_validation", M=M, runs=runs, validation_seed=v,
                         anchors=anchors, **r)  # fmt: skip


def main() -> None:
    ap = runs_parser(__doc__, anchors=[8], seeds_help="saved plans M{M}_s0 … per M")
    ap.add_argument("--validations", type=int, default=5)
    ap.add_argument("--layouts", metavar="JSONL", nargs="+",
                    help="validate the distinct layouts of bench_effort.py runs")  # fmt: skip
    ap.add_argument("--first-validation", type=int, default=100,
                    help="with --layouts: the first validation seed (100)")  # fmt: skip
    args = ap.parse_args()
    if args.summary:
        rows = read_lines(args.summary)
        for bench, table in (("validation", summary), ("layout_validation", layouts_summary)):
            if any(r["bench"] == bench for r in rows):
                table(rows)
        return
    room = Room.techtile()
    if args.layouts:
        validate_runs(args, room)
        return
    with WorkerPool(args.workers) as ex:
        for M in args.anchors:
            for seed in range(args.seeds):
                anchors = json.loads((PLANS / f"M{M}_s{seed}.json").read_text())["anchors"]
                calls = [(validation_figures, (room, anchors, v)) for v in range(args.validations)]
                for v, r in enumerate(run_calls(ex, calls)):
                    emit("validation", M=M, seed=seed, validation_seed=v, anchors=anchors, **r)


if __name__ == "__main__":
    main()

"""How good can the choice among the planner's candidates be? The ceiling of the finalists.

For each M and seed, builds the run's range table as ``seed_then_pso(room, M, rng=seed)``
does (same streams, default :class:`~placement.simselect.SearchOptions`), takes the
search's ``--keep`` best distinct optima and the table refinement of its two best
(:func:`~placement.simselect.refine_on_table`), and validates every candidate on the
run's own validation draws (the plan's defaults: R = 100 at the 270 nodes, held-out grid
and random points, 3 cm mounting error). Each candidate is also scored on ``--draws``
fresh scene draws (half at the exact nodes, half moved), kept per draw, so that choice
rules can be compared afterwards without simulating again.

One JSON line per candidate (``bench: "candidate"``). ``--summary`` then chooses, for
each (M, seed), the candidate of each rule:
- ``table``: the lowest table cost (the search's answer);
- ``fresh_k``: the lowest variance over the first k exact and the first k moved fresh
  draws (k = ``--draws`` / 4: the plan's finalists; k = ``--draws`` / 2: all draws);
- ``exact_k``, ``exact``: the lowest variance over the first k or all exact fresh draws;
- ``moved``: the lowest variance over the moved fresh draws only;
- ``oracle``: the lowest validated σ at the 270 nodes, which no rule can beat.
The spread of σ over seeds under the oracle bounds what any choice among these candidates
can reach.

Run: python benchmarks/bench_candidates.py [--anchors 8 4] [--seeds 5] [--keep 8]
     [--draws 16] [--workers 2] > candidates.jsonl
Tables: python benchmarks/bench_candidates.py --summary candidates.jsonl (the choices, then
how noisy one fresh draw is, exact and moved, against the candidates' differences)
"""

import numpy as np
from _common import emit, read_lines, runs_parser, spread

from placement.costs import DrawsCost
from placement.initial import build_table
from placement.rangetable import node_draws
from placement.simselect import SearchOptions, refine_on_table, simulated_select
from placement.streams import phase_seed
from placement.validation import validate_layout
from placement.workers import WorkerPool, run_calls
from simulation import Room


def _candidates(room, M, seed, keep, ex, workers):
    """[(name, anchors, table cost)]: the search's optima and the refined two best."""
    opt = SearchOptions()
    table = build_table(room, opt, None, seed, ex)
    sel = simulated_select(
        room, M, options=opt, table=table, rng=phase_seed(seed, "search"), executor=ex,
        workers=workers,
    )  # fmt: skip
    layouts = sel.layouts(keep)
    costs = [c for _, c in sel.optima[: len(layouts)]]
    out = [(f"search-{k + 1}", a, c) for k, (a, c) in enumerate(zip(layouts, costs, strict=True))]
    refined, _, _ = refine_on_table(
        room, table, layouts[:2], options=opt, rng=phase_seed(seed, "refinement"), executor=ex,
        workers=workers,
    )  # fmt: skip
    out += [(f"refined-{k + 1}", a, f) for k, (a, f, _) in enumerate(refined)]
    return out


def _fresh_moments(room, anchors, seed, draws):
    """(2, draws) mean and mean square of the errors (m, m²) on each fresh draw."""
    exact = draws // 2
    sets = node_draws(room, room.grid(), draws, exact, phase_seed(seed, "finalist_nodes"))
    cost = DrawsCost(
        room, sets, exact_draws=exact, mount_tolerance=0.03, seed=phase_seed(seed, "finalists")
    )
    e = cost.errors(anchors).reshape(draws, -1)
    return np.stack([e.mean(axis=1), (e**2).mean(axis=1)])


def validation_figures(room, anchors, seed) -> dict:
    """σ and P95 at the 270 nodes, held-out and mounting-error σ of a layout validated as
    ``seed_then_pso(..., rng=seed)`` validates its answer."""
    v = validate_layout(
        room, anchors, rng=phase_seed(seed, "validation"), mount_tolerance=0.03
    ).to_dict()
    return {
        "std": v["std"],
        "p95": v["p95"],
        "mean": v["mean"],
        "held_out_grid": v["held_out"]["grid"]["std"],
        "held_out_random": v["held_out"]["random"]["std"],
        "mounting": v["mounting"]["std"],
    }


def _candidate(room, anchors, seed, draws):
    m = _fresh_moments(room, anchors, seed, draws)
    fresh = {"fresh_mean": m[0].tolist(), "fresh_meansq": m[1].tolist()}
    return {**validation_figures(room, anchors, seed), **fresh}


def _variance(c, idx) -> float:
    m, q = np.asarray(c["fresh_mean"])[idx], np.asarray(c["fresh_meansq"])[idx]
    return float(q.mean() - m.mean() ** 2)


def _mean_square(c, idx) -> float:
    return float(np.mean(np.asarray(c["fresh_meansq"])[idx]))


def _choices(cands, draws) -> dict:
    half = draws // 2
    exact, moved = list(range(half)), list(range(half, draws))
    rules = {"table": lambda c: c["table_cost"]}
    for k in sorted({half // 2, half}):
        rules[f"fresh_{k}"] = lambda c, k=k: _variance(c, exact[:k] + moved[:k])
    rules[f"exact_{half // 2}"] = lambda c: _variance(c, exact[: half // 2])
    rules["exact"] = lambda c: _variance(c, exact)
    rules["moved"] = lambda c: _variance(c, moved)
    # the mean square (σ² + mean²) instead of the variance: does weighing the mean help P95?
    rules[f"rms_{half // 2}"] = lambda c: _mean_square(c, exact[: half // 2] + moved[: half // 2])
    rules["rms_exact"] = lambda c: _mean_square(c, exact)
    rules["oracle"] = lambda c: c["std"]
    out = {}
    for name, key in rules.items():
        c = min(cands, key=key)
        out[name] = {
            k: c[k]
            for k in ("candidate", "std", "p95", "held_out_grid", "held_out_random", "mounting")
        }
    return out


def draw_noise(cands, draws) -> None:
    """Print, per M, how much a candidate's variance varies from one fresh draw to the next
    (standard deviation over its exact draws and over its moved draws, averaged over the
    candidates, m²) against how far apart a run's candidates are (the standard deviation of
    their validated σ², averaged over the runs)."""
    half = draws // 2
    print("| M | per-draw variance, exact draws: sd (m²) | moved draws: sd (m²) | moved / exact "
          "| a run's candidates: sd of validated σ² (m²) |")  # fmt: skip
    print("|---|---|---|---|---|")
    for M in sorted({c["M"] for c in cands}):
        mine = [c for c in cands if c["M"] == M]
        per_draw = [np.asarray(c["fresh_meansq"]) - np.asarray(c["fresh_mean"]) ** 2 for c in mine]
        ex = float(np.mean([np.std(v[:half], ddof=1) for v in per_draw]))
        mv = float(np.mean([np.std(v[half:], ddof=1) for v in per_draw]))
        runs = {c["seed"] for c in mine}
        apart = np.mean(
            [np.std([c["std"] ** 2 for c in mine if c["seed"] == s], ddof=1) for s in runs]
        )
        print(f"| {M} | {ex:.4f} | {mv:.4f} | {mv / ex:.1f} | {apart:.4f} |")


def summary(paths: list[str]) -> None:
    """Print, per M and rule, each seed's choice (σ / P95 at the 270 nodes, held-out grid σ),
    the spread of σ over seeds (max − min over the median) and in how many seeds the choice
    validates below the search's best layout (``search-1``), as a markdown table; the row
    "any" counts the seeds where some candidate does."""
    rows = read_lines(paths)
    cands = [r for r in rows if r["bench"] == "candidate"]
    keys = sorted({(r["M"], r["seed"]) for r in cands})
    draws = len(cands[0]["fresh_mean"])
    choices = [
        {
            "M": M,
            "seed": seed,
            **_choices([c for c in cands if (c["M"], c["seed"]) == (M, seed)], draws),
        }
        for M, seed in keys
    ]
    first = {(r["M"], r["seed"]): r["std"] for r in cands if r["candidate"] == "search-1"}
    best = {(r["M"], r["seed"]): r["oracle"]["std"] for r in choices}
    print("| M | rule | σ / P95 (held-out grid σ) per seed (m) | candidate per seed "
          "| spread of σ | below search-1 |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for M in sorted({r["M"] for r in choices}):
        runs = sorted((r for r in choices if r["M"] == M), key=lambda r: r["seed"])
        for rule in [k for k in runs[0] if k not in ("M", "seed")]:
            picks = [r[rule] for r in runs]
            sd = [p["std"] for p in picks]
            cells = ", ".join(
                f"{p['std']:.3f} / {p['p95']:.3f} ({p['held_out_grid']:.3f})" for p in picks
            )
            names = ", ".join(p["candidate"] for p in picks)
            below = sum(p["std"] < first[(M, r["seed"])] for p, r in zip(picks, runs, strict=True))
            tail = f"{100 * spread(sd):.1f} % | {below} of {len(runs)}"
            print(f"| {M} | {rule} | {cells} | {names} | {tail} |")
        below = sum(best[(M, r["seed"])] < first[(M, r["seed"])] for r in runs)
        print(f"| {M} | any | | | | {below} of {len(runs)} |")
    print()
    where_tags(choices)
    print()
    draw_noise(cands, draws)


def where_tags(choices) -> None:
    """Print, per M and rule, the mean over seeds of the chosen layouts' held-out grid,
    random-point and mounting-error σ (m)."""
    print("| M | rule | mean σ: 270 nodes | held-out grid | random points | mounting error |")
    print("|---|---|---|---|---|---|")
    for M in sorted({r["M"] for r in choices}):
        runs = [r for r in choices if r["M"] == M]
        for rule in ("fresh_4", "exact", "moved", "oracle"):
            mean = {
                k: np.mean([r[rule][k] for r in runs])
                for k in ("std", "held_out_grid", "held_out_random", "mounting")
            }
            print(f"| {M} | {rule} | {mean['std']:.3f} | {mean['held_out_grid']:.3f} "
                  f"| {mean['held_out_random']:.3f} | {mean['mounting']:.3f} |")  # fmt: skip


def main() -> None:
    ap = runs_parser(__doc__, anchors=[8, 4])
    ap.add_argument("--keep", type=int, default=8)
    ap.add_argument("--draws", type=int, default=16)
    args = ap.parse_args()
    if args.summary:
        summary(args.summary)
        return
    room = Room.techtile()
    with WorkerPool(args.workers) as ex:
        for M in args.anchors:
            for seed in range(args.seeds):
                found = _candidates(room, M, seed, args.keep, ex, args.workers)
                calls = [(_candidate, (room, a, seed, args.draws)) for _, a, _ in found]
                for (name, a, f), r in zip(found, run_calls(ex, calls), strict=True):
                    c = {"candidate": name, "table_cost": float(f), **r}
                    emit("candidate", M=M, seed=seed, anchors=np.asarray(a).tolist(), **c)


if __name__ == "__main__":
    main()

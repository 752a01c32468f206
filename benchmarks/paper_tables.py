"""Markdown tables for BENCHMARKS.md from the JSON lines of the benchmark scripts.

Run: python benchmarks/paper_tables.py [--dir docs/benchmarks]
Reads DIR/results.jsonl (bench_paper.py) and, if present, DIR/bench_simulator.jsonl and
DIR/bench_analytic.jsonl; prints the tables. Numbers are only copied and rounded here.
"""

import argparse
import json
from pathlib import Path


def load(path: Path) -> list[dict]:
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if line.startswith("{"):
            out.append(json.loads(line))
    return out


def f(x, nd=3):
    if x is None:
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return str(x)
    return f"{x:.{nd}f}"


def table(head, rows):
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def last(recs, name, **match):
    """The last record ``name`` matching ``match`` (a resumed run appends newer lines)."""
    hit = [r for r in recs if r["bench"] == name and all(r.get(k) == v for k, v in match.items())]
    return hit[-1] if hit else None


def unique(recs, name, keys):
    seen = {}
    for r in recs:
        if r["bench"] == name:
            seen[tuple(r.get(k) for k in keys)] = r
    return list(seen.values())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", default="docs/benchmarks")
    d = Path(ap.parse_args().dir)
    R = load(d / "results.jsonl")

    print("### (a) corners versus optimized, M = 4\n")
    names = {"corners": "corners", "pso": "paper-PSO", "stp": "seed_then_pso"}
    rows = []
    for k, name in names.items():
        r = last(R, "corners_vs_optimized", layout=k)
        if r:
            rows.append(
                [
                    name,
                    r["realizations"],
                    f(r["std"]),
                    f(r["paper_std"]),
                    f(r["mean"]),
                    f(r["p95"]),
                    f(r["mean_dop"], 2),
                    f(r["median_dop"], 2),
                    f(r["mean_dop_precision"], 2),
                    f(r["paper_mean_dop"], 2),
                    f(r["robust_range_sigma"], 4),
                ]
            )
    print(
        table(
            [
                "layout",
                "R",
                "σ (m)",
                "paper σ",
                "mean (m)",
                "P95 (m)",
                "mean DOP",
                "median DOP",
                "mean precision DOP",
                "paper mean DOP",
                "robust σ_r (m)",
            ],
            rows,
        )
    )

    print("\n### (b) Table I\n")
    rows = []
    for r in sorted(
        unique(R, "table1", ("M", "method", "seed")),
        key=lambda r: (r["M"], r["method"] != "paper-PSO", r["seed"]),
    ):
        rows.append(
            [
                r["M"],
                r["method"],
                r["seed"],
                r["realizations"],
                f"{f(r['std'])} / {f(r['paper_std'])}",
                f"{f(r['mean'])} / {f(r['paper_mean'])}",
                f"{f(r['p95'])} / {f(r['paper_p95'])}",
                "σ " + f(r["beats_paper_std"]) + ", P95 " + f(r["beats_paper_p95"]),
                f"{r['pso_iterations']} / {r['max_iterations']}",
            ]
        )
    print(
        table(
            [
                "M",
                "method",
                "seed",
                "R",
                "σ ours / paper (m)",
                "mean ours / paper (m)",
                "P95 ours / paper (m)",
                "below paper?",
                "PSO iterations run / max",
            ],
            rows,
        )
    )

    print("\n### (c) bound-driven versus simulation-driven\n")
    rows = []
    order = {"PEB-optimal": 0, "paper-PSO": 1, "seed_then_pso": 2}
    for r in sorted(
        unique(R, "bound_vs_sim", ("M", "layout", "seed")),
        key=lambda r: (r["M"], order[r["layout"]], r["seed"]),
    ):
        q = r["rmse_over_peb_quantiles"]
        rows.append(
            [
                r["M"],
                r["layout"],
                f(r["mean_peb"], 4),
                f(r["std"]),
                f(r["mean"]),
                f(r["p95"]),
                " / ".join(f(q[k], 1) for k in ("q5", "q25", "q50", "q75", "q95")),
                f(r["fraction_rmse_gt_2peb"], 2),
                f(r["outlier_range_fraction"], 3),
                f(r["seconds_to_obtain"], 1),
            ]
        )
    print(
        table(
            [
                "M",
                "layout",
                "mean PEB (m)",
                "σ (m)",
                "mean (m)",
                "P95 (m)",
                "RMSE/PEB q5 / q25 / q50 / q75 / q95",
                "nodes RMSE > 2 PEB",
                "ranges |err| > 0.2 m",
                "seconds to obtain",
            ],
            rows,
        )
    )

    print("\n### (d) speed\n")
    rows = []
    for r in R:
        if r["bench"] == "swarm_batch" and "serial_seconds" in r:
            rows.append(
                [
                    r["M"],
                    r["particles"],
                    f(r["serial_seconds"], 2),
                    f(r["pool_seconds"], 2),
                    f(r["speedup"], 2),
                    f(r["seconds_per_evaluation_serial"], 3),
                    f(r["same_costs"]),
                    f(r["load_average"][0], 1),
                ]
            )
    print(
        table(
            [
                "M",
                "layouts",
                "serial (s)",
                "ProcessPoolExecutor(2) (s)",
                "speed-up",
                "s / evaluation (serial)",
                "identical costs",
                "load average (1 min)",
            ],
            rows,
        )
    )
    print()
    rows = []
    for r in sorted(
        unique(R, "pso_speed", ("M", "method", "seed")), key=lambda r: (r["M"], r["method"])
    ):
        rows.append(
            [
                r["M"],
                r["method"],
                f"{r['nit']}",
                r["nfev"],
                f(r["pso_seconds"], 1),
                f(r["seconds_per_iteration"], 2),
                f(r["seconds_per_evaluation"], 3),
                f(r["seeding_seconds"], 1),
            ]
        )
    print(
        table(
            [
                "M",
                "method",
                "iterations",
                "evaluations",
                "PSO (s)",
                "s / iteration",
                "s / evaluation (wall, pool)",
                "seeding (s)",
            ],
            rows,
        )
    )

    S = load(d / "bench_simulator.jsonl")
    if S:
        print("\n### simulator (bench_simulator.py)\n")
        for r in S:
            if r["bench"] in ("layout_time", "pra_pipeline", "r500"):
                keep = {k: v for k, v in r.items() if k not in ("python", "machine")}
                print("-", json.dumps(keep))
    A = load(d / "bench_analytic.jsonl")
    if A:
        print("\n### relaxation and refinement (bench_analytic.py)\n")
        rows = []
        for r in A:
            if r["bench"] == "relax_select":
                rows.append(
                    [
                        r["criterion"],
                        r["N"],
                        r["M"],
                        f(r["compile_solve_seconds_best"], 2),
                        f(r["total_seconds"], 2),
                        f(r["gap"], 4),
                        f(r.get("value_over_exhaustive"), 4),
                    ]
                )
        print(
            table(
                [
                    "criterion",
                    "N",
                    "M",
                    "compile+solve best (s)",
                    "total (s)",
                    "certified gap",
                    "vs exhaustive",
                ],
                rows,
            )
        )
        print()
        rows = []
        for r in A:
            if r["bench"] == "refine_peb":
                rows.append(
                    [
                        r["M"],
                        r["start"],
                        r["hessian"],
                        f(r["seconds"], 2),
                        r["status"],
                        f(r["mean_peb_before_m"], 4),
                        f(r["mean_peb_after_m"], 4),
                    ]
                )
        print(
            table(
                ["M", "start", "Hessian", "seconds", "status", "mean PEB before (m)", "after (m)"],
                rows,
            )
        )


if __name__ == "__main__":
    main()

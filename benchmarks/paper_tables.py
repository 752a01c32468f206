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


def _dop_cells(r: dict) -> list[str]:
    """Mean / median of the paper's DOP (σ/σ_r) and of the RMS-based one (RMSE/σ_r).

    Records with ``mean_dop_rms`` carry both (``mean_dop`` is then the paper's DOP); in
    older records ``mean_dop`` was the RMS-based DOP and the paper's is unknown."""
    if "mean_dop_rms" in r:
        paper = (r.get("mean_dop"), r.get("median_dop"))
        rms = (r.get("mean_dop_rms"), r.get("median_dop_rms"))
    else:
        paper, rms = (None, None), (r.get("mean_dop"), r.get("median_dop"))
    return [f(paper[0], 2), f(paper[1], 2), f(rms[0], 2), f(rms[1], 2)]


def section_a(R: list[dict]) -> None:
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
                    *_dop_cells(r),
                    f(r["mean_dop_precision"], 2),
                    f(r["paper_mean_dop"], 2),
                    f(r["robust_range_sigma"], 4),
                ]
            )
    head = ["layout", "R", "σ (m)", "paper σ", "mean (m)", "P95 (m)"]
    head += ["mean DOP (paper: σ/σ_r)", "median DOP (paper)", "mean DOP_RMS (RMSE/σ_r)"]
    head += ["median DOP_RMS", "mean precision DOP", "paper mean DOP", "robust σ_r (m)"]
    print(table(head, rows))


def section_b(R: list[dict]) -> None:
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
    head = ["M", "method", "seed", "R", "σ ours / paper (m)", "mean ours / paper (m)"]
    head += ["P95 ours / paper (m)", "below paper?", "PSO iterations run / max"]
    print(table(head, rows))


def section_c(R: list[dict]) -> None:
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
    head = ["M", "layout", "mean PEB (m)", "σ (m)", "mean (m)", "P95 (m)"]
    head += ["RMSE/PEB q5 / q25 / q50 / q75 / q95", "nodes RMSE > 2 PEB"]
    head += ["ranges |err| > 0.2 m", "seconds to obtain"]
    print(table(head, rows))


def section_d(R: list[dict]) -> None:
    print("\n### (d) speed\n")
    rows = [
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
        for r in R
        if r["bench"] == "swarm_batch" and "serial_seconds" in r
    ]
    head = ["M", "layouts", "serial (s)", "ProcessPoolExecutor(2) (s)", "speed-up"]
    head += ["s / evaluation (serial)", "identical costs", "load average (1 min)"]
    print(table(head, rows))
    print()
    rows = [
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
        for r in sorted(
            unique(R, "pso_speed", ("M", "method", "seed")), key=lambda r: (r["M"], r["method"])
        )
    ]
    head = ["M", "method", "iterations", "evaluations", "PSO (s)", "s / iteration"]
    head += ["s / evaluation (wall, pool)", "seeding (s)"]
    print(table(head, rows))


def simulator(S: list[dict]) -> None:
    print("\n### simulator (bench_simulator.py)\n")
    for r in S:
        if r["bench"] in ("layout_time", "pra_pipeline", "r500"):
            keep = {k: v for k, v in r.items() if k not in ("python", "machine")}
            print("-", json.dumps(keep))


def analytic(A: list[dict]) -> None:
    print("\n### relaxation and refinement (bench_analytic.py)\n")
    rows = [
        [
            r["criterion"],
            r["N"],
            r["M"],
            f(r["compile_solve_seconds_best"], 2),
            f(r["total_seconds"], 2),
            f(r["gap"], 4),
            f(r.get("value_over_exhaustive"), 4),
        ]
        for r in A
        if r["bench"] == "relax_select"
    ]
    head = ["criterion", "N", "M", "compile+solve best (s)", "total (s)", "certified gap"]
    print(table([*head, "vs exhaustive"], rows))
    print()
    rows = [
        [
            r["M"],
            r["start"],
            r["hessian"],
            f(r["seconds"], 2),
            r["status"],
            f(r["mean_peb_before_m"], 4),
            f(r["mean_peb_after_m"], 4),
        ]
        for r in A
        if r["bench"] == "refine_peb"
    ]
    head = ["M", "start", "Hessian", "seconds", "status", "mean PEB before (m)", "after (m)"]
    print(table(head, rows))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", default="docs/benchmarks")
    d = Path(ap.parse_args().dir)
    R = load(d / "results.jsonl")
    section_a(R)
    section_b(R)
    section_c(R)
    section_d(R)
    S = load(d / "bench_simulator.jsonl")
    if S:
        simulator(S)
    A = load(d / "bench_analytic.jsonl")
    if A:
        analytic(A)


if __name__ == "__main__":
    main()

"""Markdown table of seeded versus unseeded swarms from the runs bench_pso.py saved.

Run: python benchmarks/pso_tables.py [DIR]   (default: docs/benchmarks/pso)
"""

import json
import sys
from pathlib import Path

from _common import PAPER_TABLE1

from placement.pso import nfev_to_reach


def main(folder: str) -> None:
    d = Path(folder)
    print(
        "| M | seed | unseeded: final cost (m²), reach / nfev, σ / P95 (m), s "
        "| seeded: first cost, reach, ratio, nfev, σ / P95 (m), s (seed search s) "
        "| seed search: table eq. evaluations, positioning-only layouts "
        "| ratio counting the seeding's wall time as evaluations "
        "| chosen finalist (unseeded, seeded) |"
    )
    print("|---|---|---|---|---|---|---|")
    for up in sorted(d.glob("M*_s*_unseeded.json"), key=lambda p: p.name):
        sp = up.with_name(up.name.replace("unseeded", "seeded"))
        if not sp.exists():
            continue
        u, s = json.loads(up.read_text()), json.loads(sp.read_text())
        t = u["history"][-1]  # the unseeded swarm's final best cost
        base, need = nfev_to_reach(u["costs"], t), nfev_to_reach(s["costs"], t)
        ratio = "never" if need is None else f"{need / base:.4f}"
        uv, sv, ss = u["validation"], s["validation"], s["seed_search"]
        # the seeding's wall time in evaluations at this run's own seconds per evaluation
        seeding = s["timings"]["seeding"] / (s["timings"]["pso"] / s["nfev"])
        ratio_all = "never" if need is None else f"{(seeding + need) / base:.2f}"
        print(
            f"| {u['M']} | {u['seed']} "
            f"| {t:.4f}, {base} / {u['nfev']}, {uv['std']:.3f} / {uv['p95']:.3f}, "
            f"{u['seconds']:.0f} "
            f"| {s['costs'][0][0]:.4f}, {need if need else '—'}, {ratio}, {s['nfev']}, "
            f"{sv['std']:.3f} / {sv['p95']:.3f}, {s['seconds']:.0f} "
            f"({s['timings']['seeding']:.0f}) "
            f"| {ss['equivalent_evaluations']:.1f}, {ss['nfev']} "
            f"| {ratio_all} ({seeding:.0f} + {need or '—'}) / {base} "
            f"| {chosen(u)}, {chosen(s)} |"
        )

    print("\nseed_then_pso (seeded runs) against the paper's Table I, validated over R = 100:\n")
    print("| M | paper σ / mean / P95 (m) | runs: seed σ / mean / P95 (m) | σ and P95 below |")
    print("|---|---|---|---|")
    for M, paper in PAPER_TABLE1.items():
        runs = sorted(
            (json.loads(p.read_text()) for p in d.glob(f"M{M}_s*_seeded.json")),
            key=lambda r: r["seed"],
        )
        if not runs:
            continue
        cells, below = [], 0
        for r in runs:
            v = r["validation"]
            cells.append(f"{r['seed']}: {v['std']:.3f} / {v['mean']:.3f} / {v['p95']:.3f}")
            below += v["std"] < paper["std"] and v["p95"] < paper["p95"]
        print(
            f"| {M} | {paper['std']:.3f} / {paper['mean']:.3f} / {paper['p95']:.3f} "
            f"| {'; '.join(cells)} | {below} of {len(runs)} |"
        )


def chosen(run: dict) -> str:
    """Which finalist (by PSO cost, 1 = the swarm's best) had the lowest re-scored cost."""
    f = run.get("finalists") or []
    if not f:
        return "—"
    k = min(range(len(f)), key=lambda i: f[i]["cost"])
    return f"{k + 1} of {len(f)}"


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks/pso")

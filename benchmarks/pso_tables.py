"""Markdown table of seeded versus unseeded swarms from the runs bench_pso.py saved.

Run: python benchmarks/pso_tables.py [DIR]   (default: docs/benchmarks/pso)
"""

import json
import sys
from pathlib import Path

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


def chosen(run: dict) -> str:
    """Which finalist (by PSO cost, 1 = the swarm's best) had the lowest re-scored cost."""
    f = run.get("finalists") or []
    if not f:
        return "—"
    k = min(range(len(f)), key=lambda i: f[i]["cost"])
    return f"{k + 1} of {len(f)}"


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks/pso")

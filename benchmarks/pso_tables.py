"""Markdown tables of the seed_then_pso runs bench_pso.py saved.

Run: python benchmarks/pso_tables.py [DIR]   (default: docs/benchmarks/plan)

Prints: Table I per M (σ / mean / P95 per seed, median and worst, against the paper);
held-out nodes and mounting error against the earlier layouts (when bench_pso ran with
``--baseline``); what the swarm and the refinement add over the best seed; the seconds and
evaluations of every phase; and, when present, the unseeded swarms.
"""

import json
import statistics
import sys
from pathlib import Path

from _common import PAPER_TABLE1, spread


def _runs(d: Path, suffix: str = "") -> dict[int, list[dict]]:
    out: dict[int, list[dict]] = {}
    for p in sorted(d.glob(f"M*_s*{suffix}.json")):
        if not suffix and p.stem.endswith("_unseeded"):
            continue
        r = json.loads(p.read_text())
        out.setdefault(r["M"], []).append(r)
    return {M: sorted(rs, key=lambda r: r["seed"]) for M, rs in sorted(out.items())}


def table1(runs: dict[int, list[dict]]) -> None:
    print("| M | paper σ / mean / P95 (m) | runs: seed σ / mean / P95 (m) | median σ / P95 "
          "| worst σ / P95 | spread of σ / median | below the paper (σ and P95) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for M, rs in runs.items():
        p = PAPER_TABLE1.get(M, {})
        v = [r["validation"] for r in rs]
        s, q = [x["std"] for x in v], [x["p95"] for x in v]
        cells = "; ".join(
            f"{r['seed']}: {x['std']:.3f} / {x['mean']:.3f} / {x['p95']:.3f}"
            for r, x in zip(rs, v, strict=True)
        )
        below = sum(x["std"] < p.get("std", 0) and x["p95"] < p.get("p95", 0) for x in v)
        med = statistics.median(s)
        paper = f"{p['std']:.3f} / {p['mean']:.3f} / {p['p95']:.3f}" if p else "—"
        print(
            f"| {M} | {paper} | {cells} | {med:.3f} / {statistics.median(q):.3f} "
            f"| {max(s):.3f} / {max(q):.3f} | {spread(s):.1%} "
            f"| {below} of {len(rs)} |"
        )


def robustness(runs: dict[int, list[dict]]) -> None:
    print(
        "\n| M | seed | σ at the 270 nodes | held-out grid σ / P95 | random points σ / P95 "
        "| mounting error σ / P95 | earlier layout: 270 / held-out grid / mounting σ |"
    )
    print("|---|---|---|---|---|---|---|")
    for M, rs in runs.items():
        for r in rs:
            v = r["validation"]
            h, m = v["held_out"], v["mounting"]
            b = r.get("baseline")
            base = "—"
            if b:
                base = (f"{b['std']:.3f} / {b['held_out']['grid']['std']:.3f} / "
                        f"{b['mounting']['std']:.3f}")  # fmt: skip
            print(
                f"| {M} | {r['seed']} | {v['std']:.3f} "
                f"| {h['grid']['std']:.3f} / {h['grid']['p95']:.3f} "
                f"| {h['random']['std']:.3f} / {h['random']['p95']:.3f} "
                f"| {m['std']:.3f} / {m['p95']:.3f} | {base} |"
            )


def stages(runs: dict[int, list[dict]]) -> None:
    print("\n| M | seed | chosen | σ chosen / best seed (m) | held-out σ chosen / best seed "
          "| mounting σ chosen / best seed | swarm's best cost below its seeds' |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for M, rs in runs.items():
        for r in rs:
            v, b = r["validation"], r.get("best_seed")
            if not b:
                continue
            first = min(s["cost"] for s in r["seeds"])
            print(
                f"| {M} | {r['seed']} | {r['chosen']} | {v['std']:.3f} / {b['std']:.3f} "
                f"| {v['held_out']['grid']['std']:.3f} / {b['held_out']['grid']['std']:.3f} "
                f"| {v['mounting']['std']:.3f} / {b['mounting']['std']:.3f} "
                f"| {'yes' if r['history'][-1] < first else 'no'} |"
            )


def phases(runs: dict[int, list[dict]]) -> None:
    print("\n| M | seed | total s | search s (table layouts) | swarm s (simulations) "
          "| refinement s (table layouts) | finalists s | validation s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for M, rs in runs.items():
        for r in rs:
            t, n = r["timings"], r["nfev_by_phase"]
            print(
                f"| {M} | {r['seed']} | {t['total']:.0f} | {t.get('search', 0):.0f} "
                f"({n.get('search', 0)}) | {t.get('pso', 0):.0f} ({n.get('pso', 0)}) "
                f"| {t.get('refinement', 0):.0f} ({n.get('refinement', 0)}) "
                f"| {t.get('finalists', 0):.0f} | {t.get('validation', 0):.0f} |"
            )


def unseeded(seeded: dict[int, list[dict]], runs: dict[int, list[dict]]) -> None:
    if not runs:
        return
    print("\n| M | seed | unseeded (15 × 40): σ / P95, s | seeded (default): σ / P95, s |")
    print("|---|---|---|---|")
    for M, rs in runs.items():
        by_seed = {r["seed"]: r for r in seeded.get(M, [])}
        for u in rs:
            s = by_seed.get(u["seed"])
            uv = u["validation"]
            cell = "—"
            if s:
                cell = (f"{s['validation']['std']:.3f} / {s['validation']['p95']:.3f}, "
                        f"{s['timings']['total']:.0f}")  # fmt: skip
            print(
                f"| {M} | {u['seed']} | {uv['std']:.3f} / {uv['p95']:.3f}, "
                f"{u['timings']['total']:.0f} | {cell} |"
            )


def main(folder: str) -> None:
    d = Path(folder)
    runs = _runs(d)
    table1(runs)
    robustness(runs)
    stages(runs)
    phases(runs)
    unseeded(runs, _runs(d, "_unseeded"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks/plan")

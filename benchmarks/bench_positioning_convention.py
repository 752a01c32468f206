"""How the positioning convention moves the reported figures (docs/model.md, "Positioning").

Run: python benchmarks/bench_positioning_convention.py [--layout DIR] [--draws 10]
     python benchmarks/bench_positioning_convention.py --runs RUNS.jsonl [...] [--draws 10]

A system's positioning solves positions one of two ways: started inside the room (its
centre, or the linear solution when that lies in the room) and either kept inside it
(``Positioning(keep_in_room=True)``, the recommended system's) or not (the paper's). For the
layout of ``DIR/layout.json`` (default:
the committed techtile example) this prints one JSON line per convention with σ / mean /
P95 (m) on the same ranges:

- ``room-bounded`` (the planner's): ``locate(region=(0, room.size), bounded=True)``;
- ``room-start``: the same start, the iterates unbounded (the simulator's default);
- ``anchors-start``: no room given, started in the anchors' bounding box (``locate``'s
  default without a region);

for the 270 nodes (``--draws`` noise realizations, exact mounting) and for the field
check (``--draws`` draws of 300 random tags with the anchors mounted within 3 cm).

``--runs``: for every run of ``bench_effort.py`` (its anchors, preset, M and seed), the 270
nodes' σ / P95 kept in the room and unbounded on the same ``--draws`` realizations, one
JSON line per run, then per preset and M the medians and worst.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from _common import emit

from placement.rangetable import mounted_points
from placement.validation import random_nodes, summary
from simulation import Room
from simulation.evaluation import RangingScene
from simulation.positioning import locate

CONVENTIONS = {
    "room-bounded": {"bounded": True, "room": True},
    "room-start": {"bounded": False, "room": True},
    "anchors-start": {"bounded": False, "room": False},
}


def errors(room, anchors, scenes, conv) -> np.ndarray:
    """(draws · P,) errors of the ``(nodes, ranges)`` pairs solved by convention ``conv``."""
    region = (np.zeros(3), np.asarray(room.size, float)) if conv["room"] else None
    out = []
    for nodes, ranges in scenes:
        x = locate(anchors, ranges, region=region, bounded=conv["bounded"])
        out.append(np.linalg.norm(x - nodes, axis=-1))
    return np.concatenate(out)


def runs(paths: list[str], draws: int) -> None:
    """The ``--runs`` table (module docstring)."""
    import statistics

    from _common import read_lines

    room, out = Room.techtile(), {}
    for r in read_lines(paths):
        anchors = np.array(r["anchors"])
        scene = RangingScene(room, anchors, room.grid())
        pairs = [(scene.nodes, scene.ranges(np.random.default_rng(d))) for d in range(draws)]
        s = {name: summary(errors(room, anchors, pairs, CONVENTIONS[name]))
             for name in ("room-bounded", "room-start")}  # fmt: skip
        row = {n: (v["std"], v["p95"]) for n, v in s.items()}
        out.setdefault((r["effort"], r["M"]), []).append(row)
        figures = {f"{n}_{k}": v[k] for n, v in s.items() for k in ("std", "p95")}
        emit("positioning_convention_runs", effort=r["effort"], M=r["M"], seed=r["seed"],
             draws=draws, **figures)  # fmt: skip
    med = statistics.median
    print("| preset | M | runs | σ kept in the room, median / worst (m) "
          "| σ unbounded, median / worst (m) | P95 unbounded, median / worst (m) |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for (effort, M), rows in out.items():
        b, u = [x["room-bounded"][0] for x in rows], [x["room-start"][0] for x in rows]
        up = [x["room-start"][1] for x in rows]
        print(
            f"| {effort} | {M} | {len(rows)} | {med(b):.3f} / {max(b):.3f} | "
            f"{med(u):.3f} / {max(u):.3f} | {med(up):.3f} / {max(up):.3f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = Path(__file__).resolve().parents[1]
    ap.add_argument("--layout", default=str(root / "docs/examples/techtile"))
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--runs", nargs="+", metavar="JSONL", help="lines of bench_effort.py")
    args = ap.parse_args()
    if args.runs:
        runs(args.runs, args.draws)
        return
    room = Room.techtile()
    anchors = np.array(json.loads(Path(args.layout, "layout.json").read_text())["anchors"])
    grid = RangingScene(room, anchors, room.grid())
    checks = {"grid": [(grid.nodes, grid.ranges(np.random.default_rng(d)))
                       for d in range(args.draws)]}  # fmt: skip
    field = []
    for d in range(args.draws):
        tags = random_nodes(room, 300, np.random.default_rng(1000 + d))
        mounted = mounted_points(room, anchors, np.arange(len(anchors)), d, 0.03, False, 7)
        scene = RangingScene(room, mounted, tags)
        field.append((tags, scene.ranges(np.random.default_rng(2000 + d))))
    checks["field"] = field
    for check, scenes in checks.items():
        for name, conv in CONVENTIONS.items():
            s = summary(errors(room, anchors, scenes, conv))
            emit("positioning_convention", check=check, convention=name, draws=args.draws,
                 **{k: s[k] for k in ("std", "mean", "p95", "availability")})  # fmt: skip


if __name__ == "__main__":
    main()

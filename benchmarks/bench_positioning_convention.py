"""How the positioning convention moves the reported figures (docs/model.md, "Positioning").

Run: python benchmarks/bench_positioning_convention.py [--layout DIR] [--draws 10]

Every figure of a plan solves positions one way: started inside the room (its centre, or
the linear solution when that lies in the room), every iterate kept inside the room
(``simulation.positioning.KEEP_IN_ROOM``). For the layout of ``DIR/layout.json`` (default:
the committed techtile example) this prints one JSON line per convention with σ / mean /
P95 (m) on the same ranges:

- ``room-bounded`` (the planner's): ``locate(region=(0, room.size), bounded=True)``;
- ``room-start``: the same start, the iterates unbounded (the simulator's default);
- ``anchors-start``: no room given, started in the anchors' bounding box (``locate``'s
  default without a region);

for the 270 nodes (``--draws`` noise realizations, exact mounting) and for the field
check (``--draws`` draws of 300 random tags with the anchors mounted within 3 cm).
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = Path(__file__).resolve().parents[1]
    ap.add_argument("--layout", default=str(root / "docs/examples/techtile"))
    ap.add_argument("--draws", type=int, default=10)
    args = ap.parse_args()
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

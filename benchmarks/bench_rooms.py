"""A planned layout against the naive layout and anchors in the corners, in a real room.

Run: python benchmarks/bench_rooms.py RESULT_DIR [--workers 2]

RESULT_DIR is an ``anchorplan plan`` folder (``result.json``), e.g. of
``examples/l-shaped-lab.toml`` or ``examples/warehouse-aisles.toml``. The planned layout,
the naive layout of the same M (``placement.naive_layout``: evenly along the top edges of
the mounting walls) and the corners layout (``Room.corners_layout``: one anchor in every
corner of a polygonal room's floor plan, alternately low and high; the paper's four for a
shoebox) are validated with the plan's own validation settings and noise streams. One
JSON line per layout:

- σ / mean / P95 (over the fixes) and availability at the zone nodes, the held-out grid
  and random points, and under mounting error;
- ``in_sight_4``: the share of zone nodes with 4 or more anchors in line of sight (and
  within the reach: ``analysis.covered_share``);
- the bound-versus-simulation gap, split by line of sight: the median over the zone nodes
  of the simulated RMSE over the PEB of the anchors in sight (σ_r = 0.04 m), for nodes
  that see every anchor and for those that see only some; and the share of nodes whose
  bound is infinite (fewer than 4 in sight) with their median RMSE.
"""

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from _common import emit

import analysis
from placement import naive_layout
from placement.streams import phase_seed
from placement.validation import validate_layout
from simulation import Room
from simulation.polyhedral import line_of_sight
from simulation.statistics import node_rmse


def _summary(v: dict) -> dict:
    return {k: v.get(k) for k in ("std", "mean", "p95", "availability")}


def gap(room: Room, anchors: np.ndarray, nodes: np.ndarray, errors: np.ndarray) -> dict:
    rmse = node_rmse(errors)
    sight = line_of_sight(room, anchors, nodes)  # (P, M)
    pebs = analysis.bound(room, anchors, nodes, 0.04)
    full, some = sight.all(axis=1), ~sight.all(axis=1)
    finite = np.isfinite(pebs) & np.isfinite(rmse)

    def median_ratio(mask):
        m = mask & finite
        return float(np.median(rmse[m] / pebs[m])) if m.any() else None

    inf = ~np.isfinite(pebs)
    return {
        "nodes_full_sight": int(full.sum()),
        "gap_full_sight": median_ratio(full),
        "nodes_partial_sight": int(some.sum()),
        "gap_partial_sight": median_ratio(some),
        "share_bound_infinite": float(inf.mean()),
        "rmse_where_bound_infinite": float(np.median(rmse[inf & np.isfinite(rmse)]))
        if np.any(inf & np.isfinite(rmse))
        else None,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result", help="an anchorplan plan folder")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    d = json.loads((Path(args.result) / "result.json").read_text())
    room = Room.from_dict(d["room"])
    planned = np.asarray(d["anchors"], dtype=float)
    seed = int(d["settings"]["seed"])
    tol = float(d["settings"]["mount_tolerance"])
    layouts = {
        "planned": planned,
        "naive": naive_layout(room, len(planned)),
        "corners": room.corners_layout(),
    }
    nodes = room.grid()
    with ProcessPoolExecutor(args.workers) as ex:
        for name, a in layouts.items():
            v = validate_layout(room, a, rng=phase_seed(seed, "validation"), mount_tolerance=tol,
                                executor=ex).to_dict()  # fmt: skip
            errors = np.asarray(v["errors"], dtype=float)
            emit(
                "rooms",
                room=room.name,
                layout=name,
                M=int(len(a)),
                zone=_summary(v),
                held_out_grid=_summary(v["held_out"]["grid"]),
                held_out_random=_summary(v["held_out"]["random"]),
                mounting=_summary(v["mounting"]),
                in_sight_4=analysis.covered_share(room, a, nodes),
                **gap(room, a, nodes, errors),
                anchors=a.tolist(),
            )


if __name__ == "__main__":
    main()

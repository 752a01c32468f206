"""The positioning that rejects echoes against least squares: its errors, how often it is
wrong when it says a fix is verified, and what a fix costs (BENCHMARKS.md, "Positioning
that rejects echoes").

Run:

    python benchmarks/bench_robust.py                        # the example rooms
    python benchmarks/bench_robust.py --rooms techtile --receiver paper
    python benchmarks/bench_robust.py --rooms l-shaped-lab --by-used

For each room (its committed example layout planned for that receiver,
docs/examples/<room>-recommended/layout.json for the recommended one where it exists, else
docs/examples/<room>/layout.json, else the corners layout; or ``--layout``),
``--realizations`` noise
realizations of the simulated ranges at the room's nodes with the receiver of
``--receiver`` (the recommended system's 20 ms first-path receiver, or the paper's),
solved by least squares (unbounded, and kept in the room) and by the robust method kept in
the floor plan. One JSON line per room and solver: median / mean / P95 / σ of the error,
the share of verified fixes and of verified fixes more than 0.5 m off, and the seconds per
fix (the best of ``--repeat`` runs, on one thread; with the fixes' qualities, and so the
map check) with its ratio to unbounded least squares measured in the same run, and the
seconds per position alone (no qualities: what the planner's scores ask for). With
``--by-used``, the robust fixes' seconds by how many anchors each fix kept.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _common import emit, with_room_chirp

from simulation import Positioning, Room, System
from simulation.evaluation import RangingScene

ROOT = Path(__file__).resolve().parents[1]
ROOMS = {
    "techtile": (None, "techtile"),
    "l-shaped-lab": ("examples/l-shaped-lab.toml", "l-shaped-lab"),
    "warehouse-aisles": ("examples/warehouse-aisles.toml", "warehouse-aisles"),
    "office": ("examples/office.toml", "office"),
    "hall": ("examples/hall.toml", "hall"),
    "ordinary-room": ("examples/ordinary-room.toml", "ordinary-room"),
}


def _scene(name: str, receiver: str, layout: Path | None = None):
    path, example = ROOMS[name]
    if (ROOT / "docs" / "examples" / f"{example}-{receiver}").is_dir():
        example = f"{example}-{receiver}"  # the layout planned for that receiver
    room = Room.techtile() if path is None else Room.from_toml(ROOT / path)
    own = System() if path is None else System.from_toml(ROOT / path)
    system = System.recommended() if receiver == "recommended" else System()
    system = with_room_chirp(system, own)
    layout = layout or ROOT / "docs" / "examples" / example / "layout.json"
    anchors = (np.array(json.loads(layout.read_text())["anchors"]) if layout.exists()
               else room.corners_layout())  # fmt: skip
    return room, system, anchors


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", nargs="+", default=["techtile", "l-shaped-lab", "warehouse-aisles"])
    ap.add_argument("--receiver", choices=("recommended", "paper"), default="recommended")
    ap.add_argument("--realizations", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--range-sigma",
        type=float,
        default=0.01,
        help="the robust solver's range sigma, m (the paper receiver's: about 0.1)",
    )
    ap.add_argument(
        "--layout",
        type=Path,
        help="a layout.json (its anchors) to use instead of the committed example's; one room",
    )
    ap.add_argument(
        "--by-used",
        action="store_true",
        help="also time the robust fixes grouped by how many anchors each fix kept",
    )
    args = ap.parse_args()
    if args.layout is not None and len(args.rooms) != 1:
        ap.error(f"--layout: needs exactly one room in --rooms, got {len(args.rooms)}")
    solvers = {
        "ls": Positioning(),
        "ls kept in the room": Positioning(keep_in_room=True),
        "robust kept in the room": Positioning(
            method="robust", keep_in_room=True, range_sigma=args.range_sigma
        ),
    }
    for name in args.rooms:
        room, system, anchors = _scene(name, args.receiver, args.layout)
        where = str(args.layout) if args.layout else "the committed example"
        scene = RangingScene(room, anchors, system=system)
        rngs = [np.random.default_rng(r) for r in range(args.realizations)]
        R = scene.ranges_batch(rngs)
        base = None
        for label, pos in solvers.items():
            pos.locate(room, anchors, R[:1])  # compile
            best = bare = np.inf
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                fix = pos.locate(room, anchors, R, full_output=True)
                t1 = time.perf_counter()
                pos.locate(room, anchors, R)  # positions only: no qualities, no map check
                best, bare = min(best, t1 - t0), min(bare, time.perf_counter() - t1)
            per_fix, bare = best / R[..., 0].size, bare / R[..., 0].size
            base = per_fix if base is None else base
            e = np.linalg.norm(fix.x - scene.nodes, axis=-1).ravel()
            v = fix.verified.ravel()
            f = e[np.isfinite(e)]
            if f.size == 0:  # no node heard 4 anchors: nothing to describe
                emit("robust", room=room.name, receiver=args.receiver, solver=label,
                     anchors=len(anchors), fixes=int(e.size), found=0)  # fmt: skip
                continue
            emit("robust", room=room.name, receiver=args.receiver, solver=label,
                 layout=where, anchors=len(anchors), fixes=int(e.size), found=int(f.size),
                 median=float(np.median(f)),
                 mean=float(f.mean()), p95=float(np.percentile(f, 95)), std=float(f.std()),
                 verified=float(v.mean()), range_sigma=args.range_sigma,
                 verified_wrong=float(np.mean(v & (e > 0.5)) / max(v.mean(), 1e-12)),
                 seconds_per_fix=per_fix, ratio_to_ls=per_fix / base,
                 seconds_per_position=bare, position_ratio_to_ls=bare / base)  # fmt: skip
            if args.by_used and pos.method == "robust":
                _by_used(room, anchors, R, fix, pos, args, base)


def _by_used(room, anchors, R, fix, pos, args, base) -> None:
    """One line per number of anchors kept: the share of the fixes and the seconds per fix
    of those rows solved alone (with qualities; the best of ``--repeat``), and its ratio
    to least squares' seconds per fix over all the fixes. The rows are repeated up to the
    count of all the fixes, so that the call's fixed cost weighs on each group as on all."""
    rows, used = R.reshape(-1, R.shape[-1]), fix.used.reshape(-1, R.shape[-1]).sum(axis=1)
    for k in np.unique(used):
        share = float(np.mean(used == k))
        sub = rows[used == k]
        sub = np.tile(sub, (-(-len(rows) // len(sub)), 1))
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            pos.locate(room, anchors, sub, full_output=True)
            best = min(best, time.perf_counter() - t0)
        emit("robust_by_used", room=room.name, receiver=args.receiver, used=int(k),
             share=share, seconds_per_fix=best / len(sub),
             ratio_to_ls=best / len(sub) / base)  # fmt: skip


if __name__ == "__main__":
    main()

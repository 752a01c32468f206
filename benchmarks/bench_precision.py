"""Does the float32 receiver DSP pick the same correlation index as float64?

Run: python benchmarks/bench_precision.py [--layouts 8] [--realizations 5]
Prints one JSON line per layout and a summary line. Over the techtile room's 270 nodes,
several layouts (the paper's corners, random layouts with M = 4, 6, 8, 10) and several
noise realizations, the same noisy windows go through both precisions; the figures are
the share of windows with the same index, the largest range difference where they
differ, and σ / P95 of the position errors with either precision on the same windows.
The float32 DSP may be the default only where the share is at least 99.9 %.
"""

import argparse

import numpy as np
from _common import emit

from placement import random_layout
from simulation import Room, locate
from simulation.evaluation import RangingScene


def compare(room, anchors, realizations, seed):
    s64 = RangingScene(room, anchors, precision="float64")
    d32 = RangingScene(room, anchors[:1], precision="float32").dsp
    rng = np.random.default_rng(seed)
    windows = np.stack([s64.noisy_windows(rng) for _ in range(realizations)])
    k64 = s64.dsp.indices(windows)
    k32 = d32.indices(windows)
    c = room.speed_of_sound
    r64 = s64.receiver.range_from_index(k64, c)
    r32 = s64.receiver.range_from_index(k32, c)
    region = (np.zeros(3), np.asarray(room.size, dtype=float))
    nodes = s64.nodes
    e64 = np.linalg.norm(locate(anchors, r64, region=region) - nodes, axis=-1)
    e32 = np.linalg.norm(locate(anchors, r32, region=region) - nodes, axis=-1)
    diff = k64 != k32
    return {
        "windows": int(k64.size),
        "same_index_share": float(1 - diff.mean()),
        "differing": int(diff.sum()),
        "max_range_difference_m": float(np.max(np.abs(r64 - r32))) if diff.any() else 0.0,
        "std_float64": float(np.std(e64)),
        "std_float32": float(np.std(e32)),
        "p95_float64": float(np.percentile(e64, 95)),
        "p95_float32": float(np.percentile(e32, 95)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layouts", type=int, default=8, help="random layouts besides corners")
    ap.add_argument("--realizations", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    room = Room.techtile()
    rng = np.random.default_rng(args.seed)
    layouts = [("corners", room.corners_layout())]
    for i in range(args.layouts):
        M = (4, 6, 8, 10)[i % 4]
        layouts.append((f"random-M{M}-{i}", random_layout(room, M, rng)))
    total = differing = 0
    for k, (name, anchors) in enumerate(layouts):
        rec = compare(room, anchors, args.realizations, args.seed + 1 + k)
        emit("precision_layout", layout=name, M=len(anchors), **rec)
        total += rec["windows"]
        differing += rec["differing"]
    emit(
        "precision_summary",
        layouts=len(layouts),
        realizations=args.realizations,
        windows=total,
        same_index_share=1 - differing / total,
        target=0.999,
    )


if __name__ == "__main__":
    main()

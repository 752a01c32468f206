"""How the first-path pick's settings were chosen: ρ and κ against the error.

Run: python benchmarks/bench_first_path.py --layout DIR [--window-ms 20] [--seed 0]

The layout ``DIR/layout.json`` (the techtile plan of ``anchorplan plan --anchors 8``) is
evaluated at the paper's 270 nodes (2 noise draws) in the techtile room and in the same box
with every surface at α = 0.2, with a window of ``--window-ms`` closing with the chirp and
the first-path pick for every ρ (``first_path_ratio``) and κ (``first_path_noise``) of the
grid, and with the paper's pick for reference. One JSON line per setting: median / mean /
σ / P95 (m, over the fixes) and availability. These nodes and this layout chose the
defaults; the pyroomacoustics agreement and the study use other nodes and layouts.
"""

import argparse
import dataclasses
import json

import numpy as np
from _common import emit
from bench_receiver import ROOMS, stats

from simulation.evaluation import evaluate_layout
from simulation.system import System, closing_window


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layout", required=True, metavar="DIR")
    ap.add_argument("--window-ms", type=float, default=20.0)
    ap.add_argument("--ratios", type=float, nargs="+", default=[0.2, 0.3, 0.5, 0.7, 0.9])
    ap.add_argument("--noise", type=float, nargs="+", default=[0.0, 2.0, 4.0, 8.0])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    anchors = np.array(json.load(open(f"{args.layout}/layout.json"))["anchors"])
    base = closing_window(System.paper(), args.window_ms * 1e-3)
    settings = [("paper", None, None)] + [
        ("first-path", r, k) for r in args.ratios for k in args.noise
    ]
    for room_name, room in ROOMS.items():
        for pick, ratio, kappa in settings:
            rx = dataclasses.replace(base.receiver, pick=pick)
            if ratio is not None:
                rx = dataclasses.replace(rx, first_path_ratio=ratio, first_path_noise=kappa)
            system = dataclasses.replace(base, receiver=rx)
            ev = evaluate_layout(room, anchors, realizations=2, rng=args.seed, system=system)
            emit(
                "first_path",
                room=room_name,
                window_ms=args.window_ms,
                pick=pick,
                ratio=ratio,
                noise=kappa,
                nodes270=stats(ev.errors),
            )


if __name__ == "__main__":
    main()

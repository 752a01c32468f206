"""What a longer receiver window costs the simulator, per window and per evaluation.

Run: python benchmarks/bench_receiver_speed.py [--windows 1 2 5 10 20 30] [--repeat 3]

For windows of W ms closing with the 30 ms chirp (the receiver study's designs), in the
techtile room with the 8-anchor layout of ``layout.json`` next to this script's argument
``--layout DIR`` (default: the corners layout twice over), one JSON line per W:

- ``synthesis_us``: noise-free windows, µs per window (270 nodes × 8 anchors);
- ``dsp_us``: the receiver DSP (float32, the simulator's default; its form: one matrix
  below 1024 samples, FFTs from there), µs per window, paper's pick;
- ``noise_us``: drawing the noise of one window;
- ``evaluation_s``: one ``evaluate_layout`` (270 nodes, 2 realizations), seconds;
- ``table_us``: one range-table column (16 candidates × 270 nodes × 3 draws), µs per
  (candidate, node, draw);

each the best of ``--repeat`` runs, and its ratio to the 1 ms window's measured in the same
run.
"""

import argparse
import dataclasses
import json

import numpy as np
from _common import best_time, emit

from placement.rangetable import _columns, node_draws
from placement.surfaces import candidate_grid, naive_layout
from simulation import Room, Signal
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.signal import closing_window


def figures(room: Room, anchors, repeat: int) -> dict:
    scene = RangingScene(room, anchors)
    rng = np.random.default_rng(0)
    n = scene.windows.shape[0] * scene.windows.shape[1]
    out = {
        "synthesis_us": best_time(lambda: RangingScene(room, anchors), repeat) / n * 1e6,
        "noise_us": best_time(lambda: scene.noise(rng), repeat) / n * 1e6,
    }
    w = scene.noisy_windows(rng)
    out["dsp_us"] = best_time(lambda: scene.dsp.picks(w), repeat) / n * 1e6
    out["evaluation_s"] = best_time(
        lambda: evaluate_layout(room, anchors, realizations=2, rng=0), repeat
    )
    nodes = node_draws(room, room.grid(), 3, 2, 0)
    cands = candidate_grid(room, 0.4)[:16]
    spec = dict(exact_draws=2, mount_tolerance=0.03, seed=0, precision="float32")
    t = best_time(lambda: _columns(room, cands, np.arange(16), nodes, spec), repeat)
    out["table_us"] = t / (16 * nodes.shape[1] * 3) * 1e6
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--windows", type=float, nargs="+", default=[1, 2, 5, 10, 20, 30])
    ap.add_argument("--layout", metavar="DIR", help="a plan folder with layout.json")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    base = Room.techtile()
    if args.layout:
        anchors = np.array(json.load(open(f"{args.layout}/layout.json"))["anchors"])
    else:
        anchors = naive_layout(base, 8)
    ref = None
    for w in args.windows:
        room = dataclasses.replace(base, signal=closing_window(Signal(), w * 1e-3))
        figures(room, anchors, 1)  # build the DSP, compile, warm the caches
        f = figures(room, anchors, args.repeat)
        ref = f if ref is None else ref
        rx = room.signal.receiver
        emit(
            "receiver_speed",
            window_ms=w,
            samples=rx.window,
            dsp_form=RangingScene(room, anchors[:1], base.grid()[:1]).dsp.form,
            **f,
            **{f"{k}_ratio": f[k] / ref[k] for k in f},
        )


if __name__ == "__main__":
    main()

"""What a longer receiver window costs the simulator, per window and per evaluation.

Run: python benchmarks/bench_receiver_speed.py [--windows 1 2 5 10 20 30] [--repeat 3]
     python benchmarks/bench_receiver_speed.py --plan [--workers 2]

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

``--plan``: the README's plan (M = 8, seed 0, the plan's defaults, ``--workers`` processes)
with the paper's receiver and with a 20 ms window from 10 ms with the first-path pick, one
after the other: one JSON line each with its seconds, and the ratio.
"""

import argparse
import json
import time

import numpy as np
from _common import best_time, emit

from placement.rangetable import _columns, node_draws
from placement.surfaces import candidate_grid, naive_layout
from simulation import Room, System
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.system import closing_window


def figures(room: Room, system: System, anchors, repeat: int) -> dict:
    scene = RangingScene(room, anchors, system=system)
    rng = np.random.default_rng(0)
    n = scene.windows.shape[0] * scene.windows.shape[1]
    out = {
        "synthesis_us": best_time(lambda: RangingScene(room, anchors, system=system), repeat)
        / n
        * 1e6,
        "noise_us": best_time(lambda: scene.noise(rng), repeat) / n * 1e6,
    }
    w = scene.noisy_windows(rng)
    out["dsp_us"] = best_time(lambda: scene.dsp.picks(w), repeat) / n * 1e6
    out["evaluation_s"] = best_time(
        lambda: evaluate_layout(room, anchors, realizations=2, rng=0, system=system), repeat
    )
    nodes = node_draws(room, room.grid(), 3, 2, 0)
    cands = candidate_grid(room, 0.4)[:16]
    spec = dict(exact_draws=2, mount_tolerance=0.03, seed=0, precision="float32", system=system)
    t = best_time(lambda: _columns(room, cands, np.arange(16), nodes, spec), repeat)
    out["table_us"] = t / (16 * nodes.shape[1] * 3) * 1e6
    return out


def plans(workers: int) -> None:
    """The two plans of ``--plan`` (module docstring)."""
    from placement import seed_then_pso
    from placement.workers import WorkerPool

    base = Room.techtile()
    designs = {
        "1ms-paper": System.paper(),
        "20ms-first-path": closing_window(System.paper(), 0.02, "first-path"),
    }
    seconds = {}
    for label, sig in designs.items():
        with WorkerPool(workers) as pool:
            t0 = time.perf_counter()
            res = seed_then_pso(
                base,
                8,
                system=sig,
                cost="variance",
                rng=0,
                executor=pool,
                progress=False,
            )  # as `anchorplan plan`
            seconds[label] = time.perf_counter() - t0
        emit("receiver_plan", design=label, seconds=seconds[label], workers=workers,
             std=res.validation.std, mean=res.validation.mean, p95=res.validation.p95,
             ratio=seconds[label] / seconds["1ms-paper"],
             phases={k: round(v["seconds"], 2) for k, v in res.phases.items()})  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--windows", type=float, nargs="+", default=[1, 2, 5, 10, 20, 30])
    ap.add_argument("--layout", metavar="DIR", help="a plan folder with layout.json")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--plan", action="store_true", help="time the two plans instead")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    if args.plan:
        plans(args.workers)
        return
    base = Room.techtile()
    if args.layout:
        anchors = np.array(json.load(open(f"{args.layout}/layout.json"))["anchors"])
    else:
        anchors = naive_layout(base, 8)
    ref = None
    for w in args.windows:
        system = closing_window(System.paper(), w * 1e-3)
        figures(base, system, anchors, 1)  # build the DSP, compile, warm the caches
        f = figures(base, system, anchors, args.repeat)
        ref = f if ref is None else ref
        rx = system.receiver
        emit(
            "receiver_speed",
            window_ms=w,
            samples=rx.window,
            dsp_form=RangingScene(base, anchors[:1], base.grid()[:1], system=system).dsp.form,
            **f,
            **{f"{k}_ratio": f[k] / ref[k] for k in f},
        )


if __name__ == "__main__":
    main()

"""Full simulator throughput and the ratio against the pyroomacoustics pipeline.

Run: python benchmarks/bench_simulator.py [--quick] [--skip-r500]
Prints one JSON line per result. Targets (issue 3): per-layout time (270 nodes, one noisy
realization) ≥ 100× faster than the pyroomacoustics pipeline on the same pairs; R = 500
realizations with M = 4 in ≤ 2 minutes on 2 cores, peak memory < 2 GB.

Figures:
- ``stage_*``: the pieces of one M = 4 layout (paths, window synthesis before/after the
  factorized form, noise σ, DSP before (the literal per-window chain) and after, on one
  and two threads, LS).
- ``layout_time``: ``evaluate_layout(room, anchors, realizations=1)`` for M = 4 (corners)
  and M = 8 (a random layout), float64 (the reference) and float32 DSP.
- ``pra_pipeline``: pyroomacoustics windows for the same 270 × 4 pairs (1 MHz RIRs,
  convolution, resampling; whole-response and truncated convolution) plus the same DSP,
  the ratio, and the noise-free range agreement of the two pipelines.
- ``r500``: R = 500, M = 4 in a child process, FFTs on 2 threads (BLAS uses its default
  threads): wall time and peak RSS.
The machine's load average is printed: on a shared machine every time is inflated.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy.fft
from _common import best_time, emit

from placement import random_layout
from simulation import Room, evaluate_layout
from simulation.evaluation import RangingScene
from simulation.multipath import ImageSet, compute_paths
from simulation.noise import noise_sigma
from simulation.positioning import locate
from simulation.receiver import dsp_for, reference_chain
from simulation.synthesis import synthesize, synthesize_direct

# the pyroomacoustics peer is test code (tests/peer.py), not part of the package
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from peer import pra_windows

R500_CHILD = """
import json, resource, time, sys
sys.path.insert(0, {root!r})
from simulation import Room, evaluate_layout
room = Room.techtile()
t0, c0 = time.perf_counter(), time.process_time()
ev = evaluate_layout(room, room.corners_layout(), realizations=500, rng=0, workers={workers})
dt, cpu = time.perf_counter() - t0, time.process_time() - c0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({{"seconds": dt, "cpu_seconds": cpu, "peak_rss_bytes": rss,
                  "std": ev.std, "mean": ev.mean, "p95": ev.p95, "mean_dop": float(ev.dop.mean()),
                  "mean_dop_rms": float(ev.dop_rms.mean()),
                  "n_unconverged": ev.n_unconverged}}))
"""


def stages(room, anchors, repeat):
    nodes = room.grid()
    c = room.speed_of_sound
    images = ImageSet.for_room(room)
    t = best_time(lambda: compute_paths(room, anchors, nodes, images=images), repeat=repeat)
    emit("stage_paths", M=len(anchors), seconds=t)
    paths = compute_paths(room, anchors, nodes, images=images)
    tau = paths.delays(c)
    scene = RangingScene(room, anchors, nodes)
    ch, rx = scene.chirp, scene.receiver
    t_new = best_time(lambda: synthesize(tau, paths.amplitude, ch, rx), repeat=repeat)
    t_old = best_time(lambda: synthesize_direct(tau, paths.amplitude, ch, rx), repeat=repeat)
    emit("stage_synthesis", M=len(anchors), seconds=t_new, before_seconds=t_old)
    t = best_time(lambda: noise_sigma(room, anchors, images=images), repeat=repeat)
    emit("stage_noise_sigma", M=len(anchors), seconds=t)
    w = scene.noisy_windows(np.random.default_rng(0)).reshape(-1, rx.window)
    dsp = dsp_for()
    t_dsp = best_time(lambda: dsp.indices(w), repeat=repeat)
    with scipy.fft.set_workers(2):
        t_dsp2 = best_time(lambda: dsp.indices(w), repeat=repeat)
    t_corr = best_time(lambda: dsp.correlation(w), repeat=repeat)
    curve = dsp.correlation(w)
    t_lp = best_time(lambda: dsp.lowpass(curve), repeat=repeat)
    n_ref = 40
    t_ref = best_time(lambda: [reference_chain(x) for x in w[:n_ref]], repeat=2) / n_ref
    emit(
        "stage_dsp",
        windows=len(w),
        seconds=t_dsp,
        seconds_2_threads=t_dsp2,
        correlation_seconds=t_corr,
        lowpass_seconds=t_lp,
        before_seconds_literal_chain=t_ref * len(w),
        nfft=dsp.nfft,
    )
    t32 = best_time(lambda: dsp_for(precision="float32").indices(w), repeat=repeat)
    emit("stage_dsp_float32", windows=len(w), seconds=t32)
    r = scene.ranges(np.random.default_rng(1))
    region = (np.zeros(3), np.array(room.size))
    t = best_time(lambda: locate(anchors, r, region=region), repeat=repeat)
    fix = locate(anchors, r, region=region, full_output=True)
    emit("stage_locate", nodes=len(nodes), seconds=t, mean_iterations=float(fix.nit.mean()))


def layout_times(room, layouts, repeat):
    out = {}
    for name, a in layouts.items():
        for prec in ("float64", "float32"):
            for workers in (1, 2):
                t = best_time(
                    lambda a=a, p=prec, w=workers: evaluate_layout(
                        room, a, realizations=1, precision=p, workers=w
                    ),
                    repeat=repeat,
                )
                out[name, prec, workers] = t
                c0 = time.process_time()
                evaluate_layout(room, a, realizations=1, precision=prec, workers=workers)
                emit(
                    "layout_time",
                    layout=name,
                    M=len(a),
                    nodes=270,
                    precision=prec,
                    fft_workers=workers,
                    seconds=t,
                    cpu_seconds_one_run=time.process_time() - c0,
                    load_average=os.getloadavg()[0],
                )
    return out


def pra_pipeline(room, anchors, ours, nodes):
    dsp = dsp_for()
    c = room.speed_of_sound
    res = {}
    for truncate in (False, True):
        t0 = time.perf_counter()
        w = pra_windows(room, anchors, nodes, truncate=truncate)
        r_peer = dsp.ranges(w, c)
        res[truncate] = time.perf_counter() - t0
    clean = RangingScene(room, anchors, nodes).ranges(noise=False)
    dr = np.abs(clean - r_peer)
    ratios = {
        f"ratio_{conv}_{prec}_w{w}": res[conv == "truncated"] / ours["corners", prec, w]
        for conv in ("full", "truncated")
        for prec in ("float64", "float32")
        for w in (1, 2)
    }
    emit(
        "pra_pipeline",
        pairs=int(dr.size),
        seconds_full_convolution=res[False],
        seconds_truncated=res[True],
        ours_seconds_float64=ours["corners", "float64", 1],
        **ratios,
        agree_1cm=float(np.mean(dr <= 0.01)),
        agree_5mm=float(np.mean(dr <= 0.005)),
        max_abs_diff_m=float(dr.max()),
        target_ratio=100,
        load_average=os.getloadavg()[0],
    )


def r500(workers):
    root = str(Path(__file__).resolve().parents[1])
    out = subprocess.run(
        [sys.executable, "-c", R500_CHILD.format(root=root, workers=workers)],
        capture_output=True,
        text=True,
        check=True,
    )
    rec = json.loads(out.stdout.strip().splitlines()[-1])
    emit(
        "r500",
        M=4,
        realizations=500,
        fft_workers=workers,
        target_seconds=120,
        target_peak_bytes=2 * 2**30,
        load_average=os.getloadavg()[0],
        **rec,
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    ap.add_argument("--skip-r500", action="store_true")
    args = ap.parse_args()
    repeat = 2 if args.quick else 5
    room = Room.techtile()
    corners = room.corners_layout()
    m8 = random_layout(room, 8, np.random.default_rng(0))
    emit("machine", cpus=os.cpu_count(), load_average=os.getloadavg())
    stages(room, corners, repeat)
    ours = layout_times(room, {"corners": corners, "random8": m8}, repeat)
    pra_pipeline(room, corners, ours, room.grid())
    if not args.skip_r500:
        r500(workers=2)


if __name__ == "__main__":
    main()

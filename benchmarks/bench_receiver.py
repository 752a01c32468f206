"""The receiver study: accuracy against window length and pick, with and without co-design.

Run: python benchmarks/bench_receiver.py --layout techtile=paper:DIR [--layout ...]
        [--windows 1 2 5 10 20 30] [--picks paper first-path] [--realizations 2]
        [--field-draws 10] [--seed 0] [--own]
     python benchmarks/bench_receiver.py --peer 40 [--windows 20]

Each ``--layout ROOM=NAME:DIR`` names a planned layout (``DIR/layout.json`` from
``anchorplan plan``) and the room it was planned in (``techtile``, or ``ordinary``: the
techtile box with every surface at α = 0.2, ``examples/ordinary-room.toml``); NAME says
for which receiver it was planned (``paper``: the paper's 1 ms window and pick, so the
layout a user of the paper's design has; or the design's label, e.g. ``20ms-first-path``,
for the co-designed layout). Every layout is evaluated under every receiver design (with
``--own``, a co-designed layout under its own design only):

- a window of W ms (N = W · 192 samples at 192 kHz) that ends with the chirp (t_wake =
  30 ms − W, so 1 ms is the paper's window, 30 ms opens with the chirp);
- the pick: the paper's (the strongest arrival) or the first path's.

One JSON line per (room, layout, design): median / mean / σ / P95 (m, over the fixes) and
the availability at the paper's 270 nodes (``--realizations`` noise draws), the same under
the field figure (``--field-draws`` draws of 300 tag points uniform in the room's node
volume with the anchors mounted within 3 cm of the plan, one noise draw each, positions
bounded to the room), the samples the tag processes per fix (N per anchor, times M: the
energy proxy), and the seconds of the evaluation.

``--peer N``: the pyroomacoustics peer (``tests/peer.py``) on held-out pairs instead (a
random 4-anchor layout and N random tag points per room, none used to choose the
first-path settings), per room, window and pick: the share of pairs whose ranges agree
within 1 cm and 5 mm, and the median relative difference of the windows.
"""

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
from _common import emit

from placement.rangetable import mounted_points
from placement.validation import random_nodes
from simulation import Room, System
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.positioning import locate
from simulation.system import closing_window

ALL = ("floor", "ceiling", "south", "north", "west", "east")
ROOMS = {
    "techtile": Room.techtile(),
    "ordinary": dataclasses.replace(
        Room.techtile(), name="ordinary-room", absorption={k: 0.2 for k in ALL}
    ),
}


def design(window_ms: float, pick: str) -> System:
    """The paper's system with a window of ``window_ms`` ending with the chirp, ``pick``."""
    return closing_window(System.paper(), window_ms * 1e-3, pick)


def stats(errors) -> dict:
    e = np.asarray(errors, dtype=float).ravel()
    fixes = e[np.isfinite(e)]
    return {
        "median": float(np.median(fixes)),
        "mean": float(fixes.mean()),
        "std": float(fixes.std()),
        "p95": float(np.percentile(fixes, 95)),
        "availability": float(fixes.size / e.size),
    }


def field_errors(room: Room, system: System, anchors, draws: int, seed: int) -> np.ndarray:
    """(draws, 300) errors at random tag points with the anchors mounted within 3 cm."""
    ids = np.arange(len(anchors))
    out = []
    region = (np.zeros(3), np.asarray(room.size, float))
    for d in range(draws):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(11, d)))
        nodes = random_nodes(room, 300, rng)
        mounted = mounted_points(room, anchors, ids, d, 0.03, False, seed)
        scene = RangingScene(room, mounted, nodes, system=system)
        x = locate(anchors, scene.ranges(rng), region=region)
        out.append(np.linalg.norm(x - nodes, axis=-1))
    return np.array(out)


def peer(n_nodes: int, windows, picks, seed: int) -> None:
    """Agreement with pyroomacoustics on held-out pairs (module docstring)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from peer import pra_windows

    from placement.surfaces import random_layout
    from simulation.multipath import compute_paths
    from simulation.received import received_windows
    from simulation.receiver import dsp_for

    rng = np.random.default_rng(seed)
    for room_name, base in ROOMS.items():
        a = random_layout(base, 4, rng)
        nodes = random_nodes(base, n_nodes, rng)
        for w in windows:
            sig = design(w, "paper")
            c = base.speed_of_sound
            ours = received_windows(compute_paths(base, a, nodes), c, receiver=sig.receiver)
            theirs = pra_windows(base, a, nodes, receiver=sig.receiver)
            rel = np.abs(ours - theirs).max(axis=-1) / np.abs(ours).max(axis=-1)
            for pick in picks:
                rx = dataclasses.replace(sig.receiver, pick=pick)
                dsp = dsp_for(receiver=rx)
                dr = np.abs(dsp.ranges(ours, c) - dsp.ranges(theirs, c))
                emit("receiver_peer", room=room_name, window_ms=w, pick=pick, pairs=dr.size,
                     within_1cm=float(np.mean(dr <= 0.01)),
                     within_5mm=float(np.mean(dr <= 0.005)),
                     window_relative_difference_median=float(np.median(rel)))  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layout", action="append", metavar="ROOM=NAME:DIR")
    ap.add_argument("--peer", type=int, metavar="N", help="the peer's agreement on N tag points")
    ap.add_argument("--windows", type=float, nargs="+", default=[1, 2, 5, 10, 20, 30])
    ap.add_argument("--picks", nargs="+", default=["paper", "first-path"])
    ap.add_argument("--realizations", type=int, default=2)
    ap.add_argument("--field-draws", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--own",
        action="store_true",
        help="evaluate a layout named after a design (e.g. 20ms-first-path) under that design "
        "only; layouts named paper under every design",
    )
    args = ap.parse_args()
    if args.peer:
        peer(args.peer, args.windows, args.picks, args.seed)
        return
    if not args.layout:
        ap.error("--layout: at least one planned layout (or --peer N)")
    for spec in args.layout:
        room_name, _, rest = spec.partition("=")
        name, _, folder = rest.partition(":")
        anchors = np.array(json.load(open(f"{folder}/layout.json"))["anchors"])
        for w in args.windows:
            for pick in args.picks:
                if args.own and name != "paper" and name != f"{w:g}ms-{pick}":
                    continue
                sig = design(w, pick)
                room = ROOMS[room_name]
                t0 = time.perf_counter()
                ev = evaluate_layout(room, anchors, realizations=args.realizations, rng=args.seed,
                                     system=sig)  # fmt: skip
                field = field_errors(room, sig, anchors, args.field_draws, args.seed)
                emit(
                    "receiver",
                    room=room_name,
                    layout=name,
                    window_ms=w,
                    pick=pick,
                    t_wake=sig.receiver.t_wake,
                    samples=sig.receiver.window,
                    samples_per_fix=sig.receiver.window * len(anchors),
                    nodes270=stats(ev.errors),
                    field=stats(field),
                    seconds=time.perf_counter() - t0,
                )


if __name__ == "__main__":
    main()

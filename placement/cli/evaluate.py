"""``anchorplan evaluate``: Monte Carlo evaluation of a layout with the full simulator."""

from __future__ import annotations

import time
from pathlib import Path

from analysis.percent import percent
from placement.cli.common import (
    add_room_argument,
    add_system_arguments,
    availability_note,
    describe_room,
    describe_system,
    load_layout,
    load_room,
    load_system,
    output_dir,
    write_json,
)
from simulation import checks


def register(sub) -> None:
    """Add ``anchorplan evaluate`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "evaluate",
        help="simulate a layout (chirps, reverberation, noise, DSP, positioning)",
        description="Run the full chirp-based reverberant simulation of a layout over the "
        "room's evaluation grid for R noise realizations, solve the positions with the "
        "system's positioning (the paper's least squares by default), and write "
        "DIR/evaluation.json with the Euclidean error statistics (metres), per-node RMSE and "
        "DOP.",
    )
    p.add_argument(
        "--layout", metavar="L.json", required=True, help='{"anchors": [[x, y, z], ...]}'
    )
    add_room_argument(p)
    p.add_argument("--realizations", type=int, default=1, help="noise realizations R (1)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--seed", type=int, default=0, help="random seed (0)")
    p.add_argument(
        "--snr", type=float, default=30.0, help="SNR in dB at each anchor's closest node (30)"
    )
    p.add_argument("--out", metavar="DIR", required=True, help="output folder")
    add_system_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan evaluate`` on parsed ``args``; the exit status (0: done)."""
    from analysis.progress import ProgressBar
    from simulation import evaluate_layout
    from simulation.evaluation import BYTES_PER_RANGE
    from simulation.noise import check_snr

    out_dir = output_dir("--out", args.out)
    checks.count("--realizations", args.realizations, low=1)
    checks.count("--seed", args.seed, low=0)
    check_snr("--snr", args.snr)
    room = load_room(args.room, args)
    system = load_system(args, room)
    anchors = load_layout(args.layout, room)
    checks.check_size(
        "--realizations",
        args.realizations * len(room.grid()) * len(anchors) * BYTES_PER_RANGE,
        value=args.realizations,
        hint="use fewer realizations",
    )
    t0 = time.perf_counter()
    bar = ProgressBar(not args.no_progress, "noise realizations")
    try:
        ev = evaluate_layout(room, anchors, realizations=args.realizations, rng=args.seed,
                             snr_db=args.snr, system=system, progress=bar.update)  # fmt: skip
    finally:
        bar.close()
    seconds = time.perf_counter() - t0
    data = ev.to_dict()
    data["seconds"] = seconds
    out = write_json(Path(out_dir) / "evaluation.json", data)
    st = ev.stats
    print(f"room {room.name}: {describe_room(room)}")
    print(
        f"{len(anchors)} anchors, {len(ev.nodes)} nodes, {ev.realizations} realization(s), "
        f"seed {args.seed}, SNR {ev.snr_db:g} dB, {seconds:.1f} s"
    )
    print(describe_system(room, system))
    print("Euclidean position error in metres over the fixes of all nodes and realizations:")
    # what the tags see first (and a robust system's verified share), then sigma
    robust = system.positioning.method == "robust"
    verified = f"  verified {percent(ev.verified)} %" if robust else ""
    if st["availability"] == 0:  # no fix to describe: no figure rather than nan
        print("  no fix at any node in any realization (availability 0 %)")
    else:
        print(
            f"  median {st['median']:.4f}  mean {st['mean']:.4f}  P95 {st['p95']:.4f}{verified}"
            f"  std {st['std']:.4f}  rms {st['rms']:.4f}  max {st['max']:.4f}"
            + availability_note(st)
        )
    if ev.geometry != "3d":
        print(f"  the anchors are {ev.geometry}: positions may be ambiguous (see anchor_geometry)")
    if ev.n_unconverged:
        print(f"  {ev.n_unconverged} position fix(es) did not converge (flagged in the JSON)")
    print(f"wrote {out}")
    return 0

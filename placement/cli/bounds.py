"""``anchorplan bounds``: PEB statistics of a layout on the evaluation grid."""

from __future__ import annotations

from analysis import bound, error_stats
from analysis.fim import DEFAULT_SIGMA, check_sigma
from placement.cli.common import (
    add_room_argument,
    add_system_arguments,
    describe_room,
    load_layout,
    load_room,
    load_system,
    output_file,
    write_json,
)
from simulation import degeneracy


def register(sub) -> None:
    """Add ``anchorplan bounds`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "bounds",
        help="PEB statistics of a layout (default: the corners layout) on the node grid",
        description="Print the position error bound PEB = sqrt(tr J^-1) (metres) of a layout "
        "over the room's evaluation grid, for a constant range sigma.",
    )
    p.add_argument("--layout", metavar="L.json", help="layout file (default: corners layout)")
    add_room_argument(p)
    p.add_argument(
        "--sigma", type=float, default=DEFAULT_SIGMA, help="range sigma in metres (0.04)"
    )
    p.add_argument("--out", metavar="FILE.json", help="also write the statistics as JSON")
    add_system_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan bounds`` on parsed ``args``; the exit status (0: done)."""
    if args.out is not None:
        output_file("--out", args.out)
    check_sigma(args.sigma, "--sigma")
    room = load_room(args.room, args)
    system = load_system(args, room)
    anchors = room.corners_layout() if args.layout is None else load_layout(args.layout, room)
    nodes = room.grid()
    values = bound(room, anchors, nodes, args.sigma, system=system)
    stats = error_stats(values)
    print(f"room {room.name}: {describe_room(room)}")
    print(f"{len(anchors)} anchors, {len(nodes)} nodes, range sigma {args.sigma:g} m")
    geometry = degeneracy.geometry(anchors)
    if geometry != "3d":
        print(f"note: the anchors are {geometry}")
    print("PEB = sqrt(tr J^-1) in metres over the grid, from the anchors each node hears:")
    if stats["n"] == 0:  # no statistic of an empty set: say what the bound is
        print(f"  infinite at all {len(nodes)} nodes (singular nodes {stats['n_invalid']})")
    else:
        print(
            f"  mean {stats['mean']:.4f}  median {stats['median']:.4f}  "
            f"P95 {stats['p95']:.4f}  max {stats['max']:.4f}  singular nodes {stats['n_invalid']}"
        )
    if args.out:
        write_json(
            args.out,
            {
                "room": room.to_dict(),
                "system": system.to_dict(),
                "anchors": anchors,
                "sigma": args.sigma,
                "peb_definition": "sqrt(tr J^-1), metres",
                "peb": values,
                "stats": stats,
            },
        )
    return 0

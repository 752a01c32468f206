"""``anchorplan bounds``: PEB statistics of a layout on the evaluation grid."""

from __future__ import annotations

import numpy as np

from analysis import error_stats, peb
from placement.cli.common import add_room_argument, load_layout, load_room, write_json


def register(sub) -> None:
    p = sub.add_parser(
        "bounds",
        help="PEB statistics of a layout (default: the corners layout) on the node grid",
        description="Print the position error bound PEB = sqrt(tr J^-1) (metres) of a layout "
        "over the room's evaluation grid, for a constant range sigma.",
    )
    p.add_argument("--layout", metavar="L.json", help="layout file (default: corners layout)")
    add_room_argument(p)
    p.add_argument("--sigma", type=float, default=0.04, help="range sigma in metres (0.04)")
    p.add_argument("--out", metavar="FILE.json", help="also write the statistics as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    room = load_room(args.room)
    if args.sigma is None or not np.isfinite(args.sigma) or args.sigma <= 0:
        raise ValueError(f"--sigma: must be > 0 m, got {args.sigma}")
    anchors = room.corners_layout() if args.layout is None else load_layout(args.layout, room)
    nodes = room.grid()
    values = peb(anchors, nodes, sigma=args.sigma)
    stats = error_stats(values)
    print(f"room {room.name} {room.size[0]:g} x {room.size[1]:g} x {room.size[2]:g} m")
    print(f"{len(anchors)} anchors, {len(nodes)} nodes, range sigma {args.sigma:g} m")
    print("PEB = sqrt(tr J^-1) in metres over the grid:")
    print(
        f"  mean {stats.mean:.4f}  median {stats.median:.4f}  P95 {stats.p95:.4f}  "
        f"max {stats.max:.4f}  singular nodes {stats.n_invalid}"
    )
    if args.out:
        write_json(
            args.out,
            {
                "room": room.to_dict(),
                "anchors": anchors,
                "sigma": args.sigma,
                "peb_definition": "sqrt(tr J^-1), metres",
                "peb": values,
                "stats": stats.to_dict(),
            },
        )
    return 0

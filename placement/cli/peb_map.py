"""``anchorplan peb-map``: PEB heat maps of a layout, written as an image."""

from __future__ import annotations

import math
from pathlib import Path

from placement.cli.common import add_room_argument, load_layout, load_room


def register(sub) -> None:
    p = sub.add_parser(
        "peb-map",
        help="draw PEB heat maps of a layout (slices at heights, x/y cuts) to an image",
        description="Draw the position error bound PEB = sqrt(tr J^-1) (metres) of a layout "
        "on horizontal slices (--height, repeatable; default: mid height) and vertical "
        "cuts (--x-cut, --y-cut) of the room, anchors marked; format from --out's suffix.",
    )
    p.add_argument("--layout", metavar="L.json", help="layout file (default: corners layout)")
    add_room_argument(p)
    p.add_argument("--sigma", type=float, default=0.04, help="range sigma in metres (0.04)")
    p.add_argument(
        "--height", type=float, action="append", metavar="Z", help="slice height in m (repeat)"
    )
    p.add_argument("--x-cut", type=float, action="append", default=[], metavar="X")
    p.add_argument("--y-cut", type=float, action="append", default=[], metavar="Y")
    p.add_argument("--resolution", type=float, default=0.05, help="cell size in m (0.05)")
    p.add_argument(
        "--scale", choices=("auto", "linear", "log"), default="auto", help="colour scale"
    )
    p.add_argument("--vmax", type=float, help="clip the colour scale at this PEB (m)")
    p.add_argument("--dpi", type=float, default=100, help="resolution (100)")
    p.add_argument("--size", type=float, nargs=2, metavar=("W", "H"), help="figure size in inches")
    p.add_argument("--out", metavar="FILE.png", required=True, help="output image")
    p.set_defaults(func=run)


def _positive(name: str, v) -> None:
    if v is not None and not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name}: must be > 0, got {v}")


def run(args) -> int:
    from analysis import figures

    room = load_room(args.room)
    for name in ("--sigma", "--resolution", "--dpi", "--vmax"):
        _positive(name, getattr(args, name[2:].replace("-", "_")))
    if args.size is not None:
        for v in args.size:
            _positive("--size", v)
    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise ValueError(f"--out: use a .png, .svg or .pdf file name, got {out.name!r}")
    anchors = room.corners_layout() if args.layout is None else load_layout(args.layout, room)
    fig = figures.peb_map(
        room,
        anchors,
        sigma=args.sigma,
        heights=args.height,
        x_cuts=args.x_cut,
        y_cuts=args.y_cut,
        resolution=args.resolution,
        scale=args.scale,
        vmax=args.vmax,
        figsize=None if args.size is None else tuple(args.size),
        dpi=args.dpi,
    )
    figures.save(fig, out)
    w, h = (round(v * args.dpi) for v in fig.get_size_inches())
    print(f"wrote {out} ({w} x {h} px, {len(anchors)} anchors, sigma {args.sigma:g} m)")
    return 0

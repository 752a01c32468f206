"""``anchorplan peb-map``: PEB heat maps of a layout, written as an image."""

from __future__ import annotations

import math

from analysis.fim import DEFAULT_SIGMA
from placement.cli.common import (
    add_room_argument,
    add_system_arguments,
    load_layout,
    load_room,
    load_system,
    output_file,
)
from simulation import checks

#: limits that keep a map's memory and time bounded
MAX_CELLS = 4_000_000  # PEB cells per panel
MAX_PIXELS = 50_000_000  # pixels of the image
MAX_PANELS = 24
DPI_RANGE = (10.0, 2400.0)
SIZE_RANGE = (1.0, 100.0)  # inches


def register(sub) -> None:
    """Add ``anchorplan peb-map`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "peb-map",
        help="draw PEB heat maps of a layout (slices at heights, x/y cuts) to an image",
        description="Draw the position error bound PEB = sqrt(tr J^-1) (metres) of a layout "
        "on horizontal slices (--height, repeatable; default: mid height) and vertical "
        "cuts (--x-cut, --y-cut) of the room, anchors marked; format from --out's suffix.",
    )
    p.add_argument("--layout", metavar="L.json", help="layout file (default: corners layout)")
    add_room_argument(p)
    p.add_argument(
        "--sigma", type=float, default=DEFAULT_SIGMA, help="range sigma in metres (0.04)"
    )
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
    add_system_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan peb-map`` on parsed ``args``; the exit status (0: done)."""
    from analysis import figures
    from analysis.fim import check_sigma

    out = output_file("--out", args.out, suffixes=(".png", ".svg", ".pdf"))
    check_sigma(args.sigma, "--sigma")
    checks.real("--resolution", args.resolution, low=0.0, low_open=True, unit="m")
    checks.real("--dpi", args.dpi, low=DPI_RANGE[0], high=DPI_RANGE[1])
    if args.vmax is not None:
        checks.real("--vmax", args.vmax, low=0.0, low_open=True, unit="m")
    if args.size is not None:
        for v in args.size:
            checks.real("--size", v, low=SIZE_RANGE[0], high=SIZE_RANGE[1], unit="inches")
    room = load_room(args.room, args)
    system = load_system(args, room)
    planes = [("--height", 2, z) for z in args.height or ()]
    planes += [("--x-cut", 0, x) for x in args.x_cut] + [("--y-cut", 1, y) for y in args.y_cut]
    if len(planes) > MAX_PANELS:
        raise ValueError(
            f"--height/--x-cut/--y-cut: at most {MAX_PANELS} panels, got {len(planes)}"
        )
    for name, axis, value in planes:
        checks.real(name, value, low=0.0, high=room.size[axis], unit="m")
    for _, axis, _ in planes or [("--height", 2, None)]:
        u, v = (room.size[i] for i in range(3) if i != axis)
        cells = max(2, math.ceil(u / args.resolution)) * max(2, math.ceil(v / args.resolution))
        if cells > MAX_CELLS:
            raise ValueError(
                f"--resolution: {args.resolution:g} m gives {cells:.3g} cells per panel, more "
                f"than {MAX_CELLS}; use a coarser resolution"
            )
    if args.size is not None and args.size[0] * args.size[1] * args.dpi**2 > MAX_PIXELS:
        raise ValueError(
            f"--size/--dpi: {args.size[0]:g} x {args.size[1]:g} inches at {args.dpi:g} dpi is "
            f"{args.size[0] * args.size[1] * args.dpi**2:.3g} pixels, more than {MAX_PIXELS}"
        )
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
        system=system,
    )
    w, h = (round(v * args.dpi) for v in fig.get_size_inches())
    if w * h > MAX_PIXELS:
        raise ValueError(
            f"--dpi: {args.dpi:g} dpi gives a {w} x {h} pixel image, more than {MAX_PIXELS} "
            "pixels; lower --dpi or --size"
        )
    figures.save(fig, out)
    print(f"wrote {out} ({w} x {h} px, {len(anchors)} anchors, sigma {args.sigma:g} m)")
    return 0

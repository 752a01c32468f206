"""``anchorplan export``: a plan's room and anchors as a DXF drawing."""

from __future__ import annotations

from placement.cli.common import load_plan, output_file
from simulation import checks
from simulation.dxf import UNITS


def register(sub) -> None:
    """Add ``anchorplan export`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "export",
        help="write a plan's room and anchors as a DXF drawing",
        description="Read RESULT_DIR/result.json (anchorplan plan) or evaluation.json and "
        "write a DXF: the room's outline, obstacles, keep-outs and tag zones on their own "
        "layers, the anchors as ANCHOR blocks with their ID, height (Z, m) and surface.",
    )
    p.add_argument("result_dir", metavar="RESULT_DIR", help="folder with result.json")
    p.add_argument("--dxf", metavar="FILE.dxf", required=True, help="the DXF file to write")
    p.add_argument("--unit", choices=tuple(UNITS), default="m", help="drawing unit (m)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan export`` on parsed ``args``; the exit status (0: done)."""
    from placement.surfaces import mounting_surfaces, surface_index
    from simulation.dxf import write_plan

    result_dir = checks.input_dir("RESULT_DIR", args.result_dir)
    out = output_file("--dxf", args.dxf, suffixes=(".dxf",))
    room, anchors = load_plan(result_dir)
    surfs = mounting_surfaces(room)
    names = [surfs[i].name if i >= 0 else "" for i in surface_index(room, anchors, tol=1e-6)]
    write_plan(out, room, anchors, unit=args.unit, surfaces=names)
    print(f"wrote {out}: {len(anchors)} anchors in {room.name}, unit {args.unit}")
    return 0

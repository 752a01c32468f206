"""``anchorplan sheet``: a plan's mounting sheet (anchors.csv and a printable sheet.html)."""

from __future__ import annotations

from placement.cli.common import load_plan
from simulation import checks


def register(sub) -> None:
    """Add ``anchorplan sheet`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "sheet",
        help="write the installer's mounting sheet of a plan",
        description="Read RESULT_DIR/result.json (or evaluation.json) and write OUT/anchors.csv "
        "(per anchor: its surface, the distance along the wall from the wall's reference "
        "corner or x, y on the ceiling, the height, the aim and the mounting tolerance) and "
        "OUT/sheet.html, printable on A4: a ceiling plan, the table, and an elevation of each "
        "wall that carries anchors.",
    )
    p.add_argument("result_dir", metavar="RESULT_DIR", help="folder with result.json")
    p.add_argument("--out", metavar="DIR", help="output folder (RESULT_DIR/sheet)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan sheet`` on parsed ``args``; the exit status (0: done)."""
    from placement.sheet import write_sheet

    result_dir = checks.input_dir("RESULT_DIR", args.result_dir)
    out = checks.output_path("--out", args.out or result_dir / "sheet", kind="dir")
    room, anchors = load_plan(result_dir)
    paths = write_sheet(out, room, anchors, tolerance=_tolerance(result_dir))
    print(f"wrote {paths['csv']} and {paths['html']}: {len(anchors)} anchors in {room.name}")
    return 0


def _tolerance(result_dir) -> float | None:
    """The mounting tolerance (m) the plan assumed, None when the folder does not say."""
    from analysis.report_data import load_results

    result = load_results(result_dir).get("result") or {}
    settings = result.get("settings") or {}
    tol = settings.get("mount_tolerance", (settings.get("search") or {}).get("mount_tolerance"))
    return None if tol is None else float(tol)

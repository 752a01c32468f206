"""``anchorplan report``: one self-contained HTML report of a result folder."""

from __future__ import annotations

import time


def register(sub) -> None:
    p = sub.add_parser(
        "report",
        help="write a self-contained HTML report (figures embedded) of a result folder",
        description="Read RESULT_DIR/result.json (anchorplan plan) and/or "
        "RESULT_DIR/evaluation.json (anchorplan evaluate) and write one HTML file with the "
        "settings, layout coordinates, error statistics, PEB (sqrt(tr J^-1), metres), the "
        "bound-versus-simulation gap and the figures. No network access, no external files.",
    )
    p.add_argument("result_dir", metavar="RESULT_DIR", help="folder with result/evaluation.json")
    p.add_argument("--out", metavar="FILE.html", help="output file (RESULT_DIR/report.html)")
    p.add_argument(
        "--realizations",
        type=int,
        default=10,
        help="realizations simulated here for the corners reference and per-axis errors "
        "(10; 0: no simulation)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of those simulations (0)")
    p.add_argument(
        "--sigma", type=float, default=None, help="range sigma of the PEB in m (plan's, 0.04)"
    )
    p.add_argument("--dpi", type=float, default=100, help="resolution of the figures (100)")
    p.add_argument("--figures", metavar="DIR", help="also write every figure as a PNG here")
    p.set_defaults(func=run)


def run(args) -> int:
    from analysis.report import write_report

    if args.realizations is None or args.realizations < 0:
        raise ValueError(f"--realizations: must be an integer >= 0, got {args.realizations}")
    if args.dpi is None or not args.dpi > 0:
        raise ValueError(f"--dpi: must be > 0, got {args.dpi}")
    t0 = time.perf_counter()
    path, rep = write_report(
        args.result_dir,
        args.out,
        realizations=args.realizations,
        seed=args.seed,
        sigma=args.sigma,
        dpi=args.dpi,
        figures_dir=args.figures,
    )
    for note in rep.notes:
        print(f"note: {note}")
    size = path.stat().st_size / 1024
    print(
        f"wrote {path} ({size:.0f} KiB, {len(rep.figures)} figures, "
        f"{len(rep.layouts)} layouts, {time.perf_counter() - t0:.1f} s)"
    )
    return 0

"""``anchorplan report``: one self-contained HTML report of a result folder."""

from __future__ import annotations

import time

from placement.cli.common import output_dir, output_file
from simulation import checks

DPI_RANGE = (10.0, 600.0)
MAX_REALIZATIONS = 10_000


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
    from analysis.noise import SIGMA_RANGE
    from analysis.report import load_results, write_report

    result_dir = checks.input_dir("RESULT_DIR", args.result_dir)
    if args.out is not None:
        output_file("--out", args.out, suffixes=(".html", ".htm"))
    else:
        output_file("RESULT_DIR", result_dir / "report.html")
    if args.figures is not None:
        output_dir("--figures", args.figures)
    checks.count("--realizations", args.realizations, low=0, high=MAX_REALIZATIONS)
    checks.count("--seed", args.seed, low=0)
    checks.real("--dpi", args.dpi, low=DPI_RANGE[0], high=DPI_RANGE[1])
    if args.sigma is not None:
        lo, hi = SIGMA_RANGE
        checks.real("--sigma", args.sigma, low=lo, high=hi, low_open=True, unit="m")
    try:
        load_results(result_dir)
    except (ValueError, FileNotFoundError) as exc:
        msg = str(exc) if "RESULT_DIR" in str(exc) else f"RESULT_DIR {result_dir}: {exc}"
        raise ValueError(msg) from None
    t0 = time.perf_counter()
    try:
        path, rep = write_report(
            result_dir,
            args.out,
            realizations=args.realizations,
            seed=args.seed,
            sigma=args.sigma,
            dpi=args.dpi,
            figures_dir=args.figures,
        )
    except ValueError as exc:
        msg = str(exc) if "RESULT_DIR" in str(exc) else f"RESULT_DIR {result_dir}: {exc}"
        raise ValueError(msg) from None
    except (TypeError, KeyError, IndexError, AttributeError) as exc:  # malformed result files
        raise ValueError(
            f"RESULT_DIR {result_dir}: the result files are malformed ({type(exc).__name__}: {exc})"
        ) from None
    for note in rep.notes:
        print(f"note: {note}")
    size = path.stat().st_size / 1024
    print(
        f"wrote {path} ({size:.0f} KiB, {len(rep.figures)} figures, "
        f"{len(rep.layouts)} layouts, {time.perf_counter() - t0:.1f} s)"
    )
    return 0

"""``anchorplan report``: one self-contained HTML report of a result folder."""

from __future__ import annotations

import time

from placement.cli.common import output_dir, output_file
from simulation import checks

DPI_RANGE = (10.0, 600.0)
MAX_REALIZATIONS = 10_000


def register(sub) -> None:
    """Add ``anchorplan report`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "report",
        help="write a self-contained HTML report (figures embedded) of a result folder",
        description="Read RESULT_DIR/result.json (anchorplan plan) and/or "
        "RESULT_DIR/evaluation.json (anchorplan evaluate) and write one HTML file: the "
        "layout (coordinates, plan view, error statistics), its comparison with a naive "
        "layout of the same M (anchors spread evenly along the top edges of the mounting "
        "walls) and the paper's corners layout (error statistics, both DOPs, PEB "
        "sqrt(tr J^-1) in metres, the bound-versus-simulation gap), the figures, and the "
        "settings. No network access, no external files.",
    )
    p.add_argument("result_dir", metavar="RESULT_DIR", help="folder with result/evaluation.json")
    p.add_argument("--out", metavar="FILE.html", help="output file (RESULT_DIR/report.html)")
    p.add_argument(
        "--realizations",
        type=int,
        default=10,
        help="realizations simulated here for the naive and corners comparisons and per-axis "
        "errors (10; 0: no simulation)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of those simulations (0)")
    p.add_argument(
        "--sigma",
        type=float,
        default=None,
        help="range sigma of the PEB in m (the plan's, else 0.04)",
    )
    p.add_argument("--dpi", type=float, default=100, help="resolution of the figures (100)")
    p.add_argument("--figures", metavar="DIR", help="also write every figure as a PNG here")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan report`` on parsed ``args``; the exit status (0: done)."""
    from analysis.fim import check_sigma
    from analysis.report import write_report
    from analysis.report_data import load_results, main_anchors, room_of
    from placement.surfaces import naive_layout

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
        check_sigma(args.sigma, "--sigma")
    if (result_dir / "sweep.json").is_file() and not (result_dir / "result.json").exists():
        return _sweep_report(result_dir, args)
    try:
        data = load_results(result_dir)
        room = room_of(data)
        naive = naive_layout(room, len(main_anchors(data)))
    except (ValueError, FileNotFoundError) as exc:
        raise _refused(result_dir, exc) from None
    except (TypeError, KeyError, IndexError, AttributeError) as exc:  # malformed result files
        raise _malformed(result_dir, exc) from None
    t0 = time.perf_counter()
    try:
        path, rep = write_report(
            result_dir,
            args.out,
            realizations=args.realizations,
            rng=args.seed,
            comparisons={"naive": naive},
            sigma=args.sigma,
            dpi=args.dpi,
            figures_dir=args.figures,
            progress=not args.no_progress,
        )
    except ValueError as exc:
        raise _refused(result_dir, exc) from None
    except (TypeError, KeyError, IndexError, AttributeError) as exc:  # malformed result files
        raise _malformed(result_dir, exc) from None
    for note in rep.notes:
        print(f"note: {note}")
    size = path.stat().st_size / 1024
    print(
        f"wrote {path} ({size:.0f} KiB, {len(rep.figures)} figures, "
        f"{len(rep.layouts)} layouts, {time.perf_counter() - t0:.1f} s)"
    )
    return 0


def _refused(result_dir, exc: Exception) -> ValueError:
    msg = str(exc)
    return ValueError(msg if "RESULT_DIR" in msg else f"RESULT_DIR {result_dir}: {msg}")


def _malformed(result_dir, exc: Exception) -> ValueError:
    return ValueError(
        f"RESULT_DIR {result_dir}: the result files are malformed ({type(exc).__name__}: {exc})"
    )


def _sweep_report(result_dir, args) -> int:
    """The report of an ``anchorplan sweep`` folder."""
    import json

    from analysis.sweep_report import write_sweep_report

    try:
        path = write_sweep_report(result_dir, args.out, dpi=args.dpi)
    except (json.JSONDecodeError, KeyError, TypeError) as exc:
        raise ValueError(
            f"RESULT_DIR {result_dir}: sweep.json is not a sweep result ({exc})"
        ) from None
    print(f"wrote {path}")
    return 0

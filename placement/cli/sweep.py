"""``anchorplan sweep``: how many anchors — plan every M of a range, compare, recommend."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re
import time

from analysis.percent import percent
from placement.cli.common import (
    add_effort_argument,
    add_room_argument,
    add_system_arguments,
    describe_system,
    json_text,
    load_room,
    load_system,
    number,
    output_dir,
    write_json,
)
from placement.cli.plan import _executor
from simulation import checks
from simulation.output import write_files


def register(sub) -> None:
    """Add ``anchorplan sweep`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "sweep",
        help="plan every anchor count of a range and recommend the smallest that meets a P95",
        description="Plan M anchors for every M of --anchors (one shared range table), "
        "validate each layout, and recommend the smallest M whose validated P95 meets "
        "--target-p95. Writes sweep.json and sweep.png to --out.",
    )
    p.add_argument("--anchors", "-M", default="4-10", help="anchor counts, e.g. 4-10 or 4,6,8")
    p.add_argument("--target-p95", type=float, metavar="M", help="P95 to meet, m")
    p.add_argument(
        "--target-availability",
        type=float,
        default=0.99,
        metavar="A",
        help="share of node realizations with a fix to reach (0.99)",
    )
    p.add_argument(
        "--target-coverage",
        type=float,
        default=0.95,
        metavar="C",
        help="share of the nodes that see k anchors in line of sight and reach to reach "
        "(k = 5 for a system that rejects echoes, else 4; 0.95; 0: off)",
    )
    add_room_argument(p)
    p.add_argument("--seed", type=int, default=0, help="random seed (0)")
    p.add_argument("--workers", type=int, default=0, help="worker processes (0: one per core)")
    p.add_argument(
        "--validate-realizations",
        type=int,
        help="validation realizations (the preset's: quick 8, default 100)",
    )
    add_effort_argument(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--out", metavar="DIR", default="anchorplan-sweep", help="output folder")
    p.add_argument(
        "--windows",
        type=float,
        nargs="+",
        metavar="MS",
        help="sweep receiver designs too: windows of these lengths (ms) closing with the chirp "
        "(1 is the paper's), each with every --picks; one sweep of M per design",
    )
    p.add_argument(
        "--picks",
        nargs="+",
        choices=("paper", "first-path"),
        help="the picks of the receiver designs (with --windows; default: the room's pick)",
    )
    add_system_arguments(p)
    p.set_defaults(func=run, scheduler=None, eval_timeout=None)


def parse_counts(text: str) -> list[int]:
    """Anchor counts from "4-10", "4,6,8" or "8"."""
    spec = str(text).strip()
    m = re.fullmatch(r"([0-9]+)\s*-\s*([0-9]+)", spec)
    if m:
        lo, hi = int(m.group(1)), int(m.group(2))
        if lo > hi:
            raise ValueError(f"--anchors: expected LOW-HIGH with LOW <= HIGH, got {text!r}")
        return list(range(lo, hi + 1))
    if re.fullmatch(r"[0-9]+(\s*,\s*[0-9]+)*", spec):
        counts = [int(v) for v in spec.split(",")]
        if len(set(counts)) < len(counts):
            raise ValueError(f"--anchors: each anchor count once, got {text!r}")
        return counts
    raise ValueError(f"--anchors: expected a range like 4-10 or a list like 4,6,8, got {text!r}")


def design_table(summary: list[dict]) -> str:
    """The receiver designs' table: per design and M the field's median / mean / P95 (what
    the tags see), then σ, mean and P95 at the evaluation nodes, the availability and the
    samples a fix takes."""
    lines = [" design               M   field median/mean/P95   sigma    mean     P95"
             "  availability  samples/fix"]  # fmt: skip
    for d in summary:
        field = "/".join(number(d[k], ".3f") for k in ("field_median", "field_mean", "field_p95"))
        lines.append(
            f" {d['design']:18s} {d['M']:2d}   {field:<21s}  {d['std']:6.3f}  {d['mean']:6.3f}"
            f"  {d['p95']:6.3f}  {percent(d['availability'], 2):>10} %  {d['samples_per_fix']:11d}"
        )
    return "\n".join(lines)


def row_line(row) -> str:
    """One sweep row as the CLI prints it as it finishes: the field's median, mean and P95
    (what the recommendation reads) and the verified share first, then σ, P95 and
    availability at the evaluation nodes; the nodes' mean, σ, P95 and availability without
    a field check."""
    nodes = (
        f"sigma {row.std:.3f} m, P95 {row.p95:.3f} m, availability {percent(row.availability, 2)} %"
    )
    if not math.isfinite(row.field_median):
        return f"mean {row.mean:.3f} m, {nodes}"
    verified = (
        f", verified {percent(row.field_verified)} %" if math.isfinite(row.field_verified) else ""
    )
    return (
        f"field median {row.field_median:.3f} m, mean {row.field_mean:.3f} m, "
        f"P95 {row.field_p95:.3f} m{verified}; nodes {nodes}"
    )


def designs(args, room, system) -> dict[str, object]:
    """The systems of the receiver designs of ``--windows`` × ``--picks`` by label ("20ms-
    first-path"), each ``system`` with that window and pick; {"": system} without
    ``--windows``."""
    from simulation.system import closing_window

    if args.windows is None:
        if args.picks is not None:
            raise ValueError("--picks: sweeps receiver designs with --windows; give both")
        return {"": system}
    picks = args.picks or [system.receiver.pick]
    out = {}
    for ms in args.windows:
        checks.real("--windows", ms, low=0.0, low_open=True, unit="ms")
        for pick in picks:
            try:
                design = closing_window(system, ms * 1e-3, pick)
                design.check_room(room)
                out[f"{ms:g}ms-{pick}"] = design
            except ValueError as exc:
                raise ValueError(f"--windows: {ms:g} ms: {exc}") from None
    return out


def run(args) -> int:
    """Run ``anchorplan sweep`` on parsed ``args``; the exit status (0: done)."""
    out = output_dir("--out", args.out)
    room = load_room(args.room, args)
    system = load_system(args, room)
    systems = designs(args, room, system)
    if list(systems) == [""]:
        _run_one(args, room, system, out)
        return 0
    summary = []
    for label, s in systems.items():
        print(f"receiver design {label}", flush=True)
        res = _run_one(args, room, s, out / label)
        rx = s.receiver
        summary += [
            {"design": label, "window": rx.window, "t_wake": rx.t_wake, "pick": rx.pick,
             "samples_per_fix": rx.window * row.M, **{k: getattr(row, k) for k in
             ("M", "field_median", "field_mean", "field_p95", "std", "mean", "p95",
              "availability", "seconds")}}
            for row in res.rows
        ]  # fmt: skip
    write_json(out / "designs.json", {"kind": "receiver designs", "rows": summary})
    print(design_table(summary))
    print(f"wrote {out / 'designs.json'} and one sweep folder per design")
    return 0


def _run_one(args, room, system, out):
    """One sweep of M for one room and system into ``out``; its result."""
    from analysis.figures import png_bytes, sweep_curves
    from analysis.paper import TABLE1
    from placement.anchor_sweep import sweep
    from placement.effort import effort_options

    counts = [checks.count("--anchors", m, low=4, high=100) for m in parse_counts(args.anchors)]
    if args.target_p95 is not None:
        checks.real("--target-p95", args.target_p95, low=0.0, low_open=True, unit="m")
    checks.real("--target-availability", args.target_availability, low=0.0, high=1.0, low_open=True)
    checks.real("--target-coverage", args.target_coverage, low=0.0, high=1.0)
    checks.count("--seed", args.seed, low=0)
    checks.count("--workers", args.workers, low=0, high=1024)
    validation = effort_options(args.effort).validation
    if args.validate_realizations is not None:
        checks.count("--validate-realizations", args.validate_realizations, low=0, high=100_000)
        validation = dataclasses.replace(validation, realizations=args.validate_realizations)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        executor = _executor(args, stack)
        print(f"sweeping M = {counts} in {room.name}, seed {args.seed}", flush=True)
        print(describe_system(room, system), flush=True)

        def report(M, row):
            print(f"  M = {M:2d}: {row_line(row)} ({row.seconds:.0f} s)", flush=True)

        res = sweep(
            room,
            counts,
            system=system,
            target_p95=args.target_p95,
            target_availability=args.target_availability,
            target_coverage=args.target_coverage,
            rng=args.seed,
            executor=executor,
            validation=validation,
            effort=args.effort,
            progress=not args.no_progress,
            on_row=report,
        )
    rows = [r.to_dict() for r in res.rows]
    paper = TABLE1 if room.name == "techtile" else None
    curves = png_bytes(
        sweep_curves(rows, res.target_p95, paper, target_coverage=res.target_coverage)
    )
    write_files({out / "sweep.json": res.to_json(indent=1) + "\n",
                 out / "layouts.json": json_text({str(r.M): r.anchors for r in res.rows}),
                 out / "sweep.png": curves})  # fmt: skip
    _print_table(res, paper)
    print(f"wrote {out / 'sweep.json'} and {out / 'sweep.png'} ({time.perf_counter() - t0:.0f} s)")
    return res


def _print_table(res, paper) -> None:
    head = (" M   field median/mean/P95   sigma    mean     P95  availability  line of sight"
            "  held-out sigma")  # fmt: skip
    print(head + ("   paper sigma/mean/P95" if paper else ""))
    for r in res.rows:
        ref = ""
        if paper and r.M in paper:
            p = paper[r.M]
            ref = f"   {p['std']:.3f}/{p['mean']:.3f}/{p['p95']:.3f}"
        print(
            f"{r.M:2d}  {number(r.field_median, '7.3f')}/{number(r.field_mean, '.3f')}/"
            f"{number(r.field_p95, '<7.3f')}  {r.std:6.3f}  {r.mean:6.3f}  {r.p95:6.3f}  "
            f"{percent(r.availability, 2):>10} %  {percent(r.covered):>6} % k={r.coverage_k}"
            f"  {number(r.held_out_std, '14.3f')}{ref}"
        )
    goal = f"availability >= {100 * res.target_availability:g} %"
    if res.target_coverage > 0:
        goal += f", line of sight >= {100 * res.target_coverage:g} %"
    if res.target_p95 is not None:
        goal += f" and field P95 <= {res.target_p95:g} m"
    if res.recommended is None:
        print(f"no M in the sweep reaches {goal}")
    else:
        print(f"recommended: M = {res.recommended} (smallest with {goal})")

"""``anchorplan stress``: what if an anchor fails, the air is warmer, the mounting sloppier."""

from __future__ import annotations

import json
import time

from analysis.percent import percent
from placement.cli.common import load_plan, output_file, plan_system
from simulation import checks
from simulation.output import write_file


def register(sub) -> None:
    """Add ``anchorplan stress`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "stress",
        help="what if: one anchor down, the air warmer or colder, mounting error",
        description="Read RESULT_DIR/result.json (or evaluation.json) and simulate the layout "
        "with each anchor down, with the air 5 and 10 degC off the room's temperature while "
        "the receiver keeps the configured speed of sound, and mounted within 0, 1, 3, 5 and "
        "10 cm of the plan. Prints the tables and writes RESULT_DIR/stress.json.",
    )
    p.add_argument("result_dir", metavar="RESULT_DIR", help="folder with result.json")
    p.add_argument("--realizations", type=int, default=10, help="noise draws (10)")
    p.add_argument("--draws", type=int, default=10, help="mounting draws per tolerance (10)")
    p.add_argument("--seed", type=int, default=0, help="random seed (0)")
    p.add_argument("--out", metavar="FILE.json", help="output file (RESULT_DIR/stress.json)")
    p.add_argument(
        "--system",
        metavar="NAME|FILE",
        help="the system to stress (a preset or a TOML file; default: the plan's)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan stress`` on parsed ``args``; the exit status (0: done)."""
    from placement.stress import stress

    result_dir = checks.input_dir("RESULT_DIR", args.result_dir)
    out = output_file("--out", args.out or result_dir / "stress.json", suffixes=(".json",))
    checks.count("--realizations", args.realizations, low=1, high=10_000)
    checks.count("--draws", args.draws, low=1, high=10_000)
    checks.count("--seed", args.seed, low=0)
    room, anchors = load_plan(result_dir)
    system = plan_system(result_dir, args.system)
    t0 = time.perf_counter()
    print(f"system {system.describe()}")
    res = stress(room, anchors, realizations=args.realizations, draws=args.draws, rng=args.seed,
                 system=system, progress=not args.no_progress)  # fmt: skip
    _print(res, robust=system.positioning.method == "robust")
    write_file(out, json.dumps(res.to_dict(), indent=1) + "\n")
    print(f"wrote {out} ({time.perf_counter() - t0:.0f} s)")
    return 0


def _print(res, robust: bool) -> None:
    """The three tables, each row what a user's tags see first: median, mean and P95 of the
    error (m), the share of verified fixes (a robust system's), then σ and availability."""
    head = "  median    mean     P95" + ("  verified" if robust else "") + "   sigma  availability"

    def cells(r) -> str:
        verified = f"  {percent(r['verified']):>6} %" if robust else ""
        return (f"  {r['median']:6.3f}  {r['mean']:6.3f}  {r['p95']:6.3f}{verified}  "
                f"{r['std']:6.3f}  {percent(r['availability'], 2):>10} %")  # fmt: skip

    print(f"one anchor down     {head}  hearing >= 4")
    for r in res.anchor_down:
        mark = "  <- worst" if r["anchor"] == res.worst_anchor else ""
        print(f"  anchor {r['anchor'] + 1:2d} down  {cells(r)}  "
              f"{100 * r['covered_share']:10.1f} %{mark}")  # fmt: skip
    print(f"air temperature     {head}")
    for r in res.temperature:
        print(f"  {r['offset']:+5.1f} degC ({r['temperature']:4.1f}){cells(r)}")
    print(f"mounting tolerance  {head}")
    for r in res.mounting:
        print(f"  {100 * r['tolerance']:5.1f} cm         {cells(r)}")

"""``anchorplan plan``: the main job — seed_then_pso on a room, results to a folder."""

from __future__ import annotations

import contextlib
import dataclasses
import re
import time

from analysis.percent import percent
from placement.cli.common import (
    add_effort_argument,
    add_room_argument,
    add_system_arguments,
    availability_note,
    cost_text,
    describe_room,
    describe_system,
    json_text,
    load_room,
    load_system,
    output_dir,
)
from placement.costs import AUTO, COST_NAMES, default_cost
from placement.workers import available_cores
from simulation import checks
from simulation.output import write_files

#: seconds to wait for a Dask scheduler before giving up
SCHEDULER_TIMEOUT = 3
#: limits of the command line's numbers (the library's are wider)
MAX_WORKERS = 1024
MAX_REALIZATIONS = 1000
MAX_SEARCH_CANDIDATES = 10_000


def register(sub) -> None:
    """Add ``anchorplan plan`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "plan",
        help="optimize an anchor layout (range-table search + swarm on the full simulation)",
        description="Plan where to mount M anchors: a search over candidate mounting points "
        "on a table of simulated ranges, a particle swarm around its best layouts, a choice "
        "among the finalists on fresh draws, and a validation of the chosen layout (at the "
        "evaluation nodes, at held-out nodes and under mounting error). Writes result.json "
        "and layout.json to --out.",
    )
    p.add_argument("--anchors", "-M", type=int, default=8, help="number of anchors M (8)")
    add_room_argument(p)
    p.add_argument(
        "--cost",
        choices=(AUTO, *COST_NAMES),
        default=AUTO,
        help="what the plan makes small (auto: variance, the paper's, for the paper's system "
        "in the paper's room; rms elsewhere)",
    )
    add_effort_argument(p)
    p.add_argument("--particles", type=int, help="swarm size (library default)")
    p.add_argument("--iterations", type=int, help="swarm iterations (library default)")
    p.add_argument(
        "--mount-tolerance",
        type=float,
        metavar="M",
        help="radius of the in-plane mounting error scored and validated, m (0.03)",
    )
    p.add_argument(
        "--validate-realizations",
        type=int,
        help="noise realizations validating the chosen layout (the preset's: quick 8, "
        "default 100; 0: no validation)",
    )
    p.add_argument(
        "--no-initial",
        action="store_true",
        help="no starting layouts: an unseeded swarm of random particles (the paper's setting)",
    )
    _add_search_arguments(p)
    p.add_argument("--seed", type=int, default=0, help="random seed (0)")
    p.add_argument(
        "--workers",
        type=int,
        default=0,
        help="local worker processes (0: one per available core)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://...)")
    p.add_argument("--checkpoint", metavar="PATH", help="checkpoint file; resumes if present")
    p.add_argument(
        "--eval-timeout",
        type=float,
        metavar="SECONDS",
        help="a particle evaluation taking longer costs inf (default: no limit)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--out", metavar="DIR", default="anchorplan-out", help="output folder")
    add_system_arguments(p)
    p.set_defaults(func=run)


def _add_search_arguments(p) -> None:
    """The flags of the range-table search and of the finalists (:func:`plan_options`)."""
    p.add_argument("--search-spacing", type=float, help="candidate spacing of the search, m")
    p.add_argument("--search-chains", type=int, help="independent search chains")
    p.add_argument("--search-evaluations", type=int, help="table layouts scored per chain")
    p.add_argument("--search-draws", type=int, help="scene draws of the range table")
    p.add_argument("--refine-layouts", type=int, metavar="N",
                   help="the swarm's distinct layouts refined on the fine lattices "
                   "(default: 1, every one with 4 anchors)")  # fmt: skip
    p.add_argument(
        "--min-coverage",
        type=float,
        metavar="SHARE",
        help="keep every layout to this share of the nodes seeing 5 anchors in line of sight "
        "and reach, where M anchors can (off)",
    )
    p.add_argument(
        "--finalists",
        type=int,
        help="best distinct swarm layouts scored, with the starting layouts and the refined "
        "layout, on fresh draws (the preset's: 1, thorough 3)",
    )
    p.add_argument(
        "--finalist-draws",
        type=int,
        help="fresh draws of the finalists (the preset's: quick 3, default 12, thorough 24)",
    )
    p.add_argument(
        "--finalist-exact-draws",
        type=int,
        help="of those, draws at the exact nodes and planned points (the preset's: all)",
    )


def _connect(address: str, stack: contextlib.ExitStack):
    try:
        from dask.distributed import Client
    except ImportError:
        raise ValueError("--scheduler needs dask: pip install 'anchorplan[dask]'") from None
    if not re.fullmatch(r"([a-z]+://)?[^\s:/]+:\d+", address):
        raise ValueError(f"--scheduler: expected an address like tcp://host:8786, got {address!r}")
    try:
        client = Client(address, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ValueError(
            f"--scheduler {address}: cannot connect within {SCHEDULER_TIMEOUT} s "
            f"({' '.join(str(exc).split())})"
        ) from None
    stack.enter_context(client)
    return client.get_executor()


def _executor(args, stack: contextlib.ExitStack):
    if args.scheduler:
        return _connect(args.scheduler, stack)
    workers = args.workers or available_cores()
    if workers > 1:
        from placement.workers import WorkerPool

        return stack.enter_context(WorkerPool(max_workers=workers))
    return None


#: the options objects' fields that a flag of this command sets, by the flag's name
FLAGS = {
    "search": {"spacing": "--search-spacing", "chains": "--search-chains",
               "evaluations": "--search-evaluations", "draws": "--search-draws",
               "exact_draws": "--search-draws", "mount_tolerance": "--mount-tolerance",
               "min_coverage": "--min-coverage", "fine_optima": "--refine-layouts"},
    "swarm": {"particles": "--particles", "iterations": "--iterations",
              "eval_timeout": "--eval-timeout"},
    "finalists": {"count": "--finalists", "draws": "--finalist-draws",
                  "exact_draws": "--finalist-exact-draws"},
    "validation": {"realizations": "--validate-realizations"},
}  # fmt: skip


def _as_flag(kind: str, exc: ValueError) -> ValueError:
    """The library's error about an option's field, naming the flag that sets it."""
    text = str(exc)
    name, _, rest = text.partition(":")
    flag = FLAGS[kind].get(name)
    return ValueError(f"{flag}:{rest}" if flag else text)


def plan_options(args) -> dict:
    """The library's options objects from the command line's flags: the ``--effort``
    preset's objects with the values of the flags given; an error names the flag."""
    from placement.effort import effort_options
    from placement.plan import default_swarm

    initial = None if args.no_initial else "auto"
    given = {
        "search": {"spacing": args.search_spacing, "chains": args.search_chains,
                   "evaluations": args.search_evaluations, "draws": args.search_draws,
                   "mount_tolerance": args.mount_tolerance, "min_coverage": args.min_coverage,
                   "fine_optima": args.refine_layouts},
        "swarm": {"particles": args.particles, "iterations": args.iterations,
                  "eval_timeout": args.eval_timeout},
        "finalists": {"count": args.finalists, "draws": args.finalist_draws,
                      "exact_draws": args.finalist_exact_draws},
        "validation": {"realizations": args.validate_realizations},
    }  # fmt: skip
    preset = effort_options(args.effort)
    base = {"search": preset.search, "swarm": default_swarm(args.cost, initial),
            "finalists": preset.finalists, "validation": preset.validation}  # fmt: skip
    out = {"initial": initial, "effort": args.effort}
    for kind, values in given.items():
        changes = {k: v for k, v in values.items() if v is not None}
        try:
            out[kind] = dataclasses.replace(base[kind], **changes)
        except ValueError as exc:
            if kind == "search" and str(exc).startswith("exact_draws"):
                exact = base["search"].exact_draws  # the draws at the exact nodes
                raise ValueError(f"--search-draws: must be at least the search's {exact} "
                                 f"exact draws, got {args.search_draws}") from None  # fmt: skip
            raise _as_flag(kind, exc) from None
    return out


def _check_args(args, room, system) -> dict:
    """Every number and file of the command, checked before any work; returns the
    library's options (:func:`plan_options`)."""
    from placement.pso import load_checkpoint
    from placement.surfaces import MAX_ANCHORS, candidate_grid
    from simulation.evaluation import BYTES_PER_RANGE

    opts = plan_options(args)
    if opts["finalists"].count > opts["swarm"].particles:
        raise ValueError(f"--finalists: must be an integer in [1, {opts['swarm'].particles}] "
                         f"(the swarm's particles), got {opts['finalists'].count}")  # fmt: skip
    checks.count("--seed", args.seed, low=0)
    checks.count("--workers", args.workers, low=0, high=MAX_WORKERS)
    if args.scheduler and args.workers > 0:
        raise ValueError("--scheduler and --workers: choose one")
    M = checks.count("--anchors", args.anchors, low=4, high=MAX_ANCHORS)
    search = opts["search"]
    if not args.no_initial and args.cost != "peb":
        spacing = search.spacing_for(room)
        n = len(candidate_grid(room, spacing))
        if n > MAX_SEARCH_CANDIDATES:
            raise ValueError(
                f"--search-spacing: {spacing:g} m gives {n} candidate points, more "
                f"than {MAX_SEARCH_CANDIDATES}; use a larger spacing"
            )
        if M > n:
            raise ValueError(
                f"--anchors: {M} anchors exceed the {n} candidate points of the search "
                f"(--search-spacing {spacing:g} m) in this room"
            )
    R = opts["validation"].realizations
    checks.check_size("--validate-realizations", R * len(room.grid()) * M * BYTES_PER_RANGE,
                      value=R, hint="use fewer realizations")  # fmt: skip
    if args.checkpoint is not None:
        checks.output_path("--checkpoint", args.checkpoint)
        state = load_checkpoint(args.checkpoint)  # a damaged file fails here, not at the end
        if state is not None:
            print(
                f"checkpoint {args.checkpoint}: found (iteration {state['iteration']}); "
                "it is resumed if it was written by this same command",
                flush=True,
            )
    return opts


def prepare(args):
    """(the output folder, the room, the system, the library's options) of parsed ``args``:
    every number and file checked before any work (``args.cost`` "auto" resolved)."""
    out = output_dir("--out", args.out)
    room = load_room(args.room, args)
    system = load_system(args, room)
    if args.cost == AUTO:
        args.cost = default_cost(room, system)
    return out, room, system, _check_args(args, room, system)


def run(args, progress=None) -> int:
    """Run ``anchorplan plan`` on parsed ``args``; the exit status (0: done). ``progress``:
    a callable ``progress(phase, done, total)`` instead of the bars (:mod:`analysis.progress`)."""
    from placement.plan import seed_then_pso

    out, room, system, opts = prepare(args)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        executor = _executor(args, stack)
        workers = args.workers or available_cores()
        print(
            f"planning {args.anchors} anchors in {room.name} "
            f"({describe_room(room)}), cost {args.cost}, "
            f"seed {args.seed}, {workers if executor is not None else 1} worker(s)",
            flush=True,
        )
        print(describe_system(room, system), flush=True)
        res = seed_then_pso(room, args.anchors, system=system, cost=args.cost, **opts,
                            executor=executor,
                            rng=args.seed,
                            progress=progress or not args.no_progress,
                            checkpoint=args.checkpoint)  # fmt: skip
    write_files({out / "result.json": res.to_json(indent=1) + "\n",
                 out / "layout.json": json_text({"anchors": res.anchors})})  # fmt: skip
    _print_result(res, args)
    print(
        f"wrote {out / 'result.json'} and {out / 'layout.json'} ({time.perf_counter() - t0:.1f} s)"
    )
    return 0


def _print_result(res, args) -> None:
    from numpy import array_equal

    search = res.settings.search_result
    if search.get("resumed"):
        print(f"search: resumed from {args.checkpoint}.search.json")
    cover = search.get("coverage")
    picks = [("coverage", "the nodes", cover), ("sight", "the room's random tag points",
                                                search.get("sight"))]  # fmt: skip
    for n, (name, points, sel) in enumerate(p for p in picks if p[2]):
        print(f"{name} selection: {percent(sel['covered'])} % of {points} see {sel['k']} "
              f"anchors in line of sight and reach (bound {percent(sel['bound'])} %, "
              f"{sel['status']}; greedy {percent(sel['greedy'])} %): the "
              f"{('first', 'second')[n]} search chain's start")  # fmt: skip
    share, target = res.settings.search.min_coverage, search.get("coverage_target")
    if target and target.get("shadow_error"):
        poor = (f" or seeing them at a GDOP above {target['gdop_limit']:g}"
                if target.get("gdop_limit") else "")  # fmt: skip
        print(f"shadows: a tag seeing fewer than {target['sight_k']} anchors in line of sight"
              f"{poor} counts as a fix {target['shadow_error']:.2f} m off (the RMS error of "
              "fixes in shadows in random layouts)")  # fmt: skip
    if share and target:
        print(f"coverage target: every layout kept to {100 * share:g} % of the nodes seeing "
              f"{target['k']} anchors in line of sight and reach")  # fmt: skip
    elif share and cover:
        print(f"coverage target {100 * share:g} %: not applied, {res.settings.M} anchors "
              f"cover {100 * cover['covered']:.1f} % at most found")  # fmt: skip
    elif share and search:
        print(f"coverage target {100 * share:g} %: met by every layout (every node sees every "
              "candidate point in line of sight and reach)")  # fmt: skip
    for s in res.initial:
        table = "" if s.table_cost != s.table_cost else f"   table cost {cost_text(s.table_cost)}"
        print(f"  initial {s.name:<12} swarm cost {cost_text(s.cost)}{table}")
    swarm = res.pso
    extra = {} if swarm is None else swarm.extra
    if extra.get("resumed_from") is not None:
        print(f"resumed from checkpoint {args.checkpoint} after iteration {extra['resumed_from']}")
    its = "iteration" if res.nit == 1 else "iterations"
    swarm_nfev = res.phases.get("pso", {}).get("nfev", 0)
    print(f"swarm: {res.nit} {its}, {swarm_nfev} evaluations, {res.message}")
    if swarm is not None and swarm.failures:
        print(
            f"  {swarm.failures} evaluation(s) failed and cost inf: "
            f"{extra.get('lost', 0)} lost to dead worker processes, "
            f"{extra.get('timeouts', 0)} over --eval-timeout, "
            f"{swarm.failures - extra.get('lost', 0) - extra.get('timeouts', 0)} errors"
        )
    for f in res.finalists:
        mark = "*" if array_equal(f["anchors"], res.anchors) else " "
        print(
            f" {mark}finalist {f['source']:<10} swarm cost {cost_text(f['pso_cost'])}, "
            f"fresh draws {cost_text(f['cost'])}"
        )
    print("anchors (m):")
    for a in res.anchors:
        print(f"  {a[0]:7.3f} {a[1]:7.3f} {a[2]:7.3f}")
    _print_validation(res.validation, res.system.positioning.method == "robust")
    for note in (echo_note(res.room, res.system, res.validation), coverage_note(res)):
        if note:
            print(note)
    _print_phases(res)


def coverage_note(res) -> str | None:
    """A note where a plan for robust positioning left the zone short of the anchors a fix
    needs to be verified (k in line of sight and reach) while the coverage selection shows
    that M anchors cover it: the search, free of a coverage target, traded coverage for the
    error at the nodes. None with a coverage target, without robust positioning, or where
    the plan covers :data:`COVERAGE_NOTE` of the nodes or the selection cannot."""
    v, cover = res.validation, res.settings.search_result.get("coverage")
    if (res.system.positioning.method != "robust" or res.settings.search.min_coverage
            or not cover or v is None or not v.covered == v.covered):  # fmt: skip
        return None
    if cover["covered"] < COVERAGE_NOTE or v.covered >= COVERAGE_NOTE:
        return None
    field = "" if v.field is None else f" (verified in the field: {percent(v.field.verified)} %)"
    return (f"note: {percent(v.covered)} % of the nodes see {v.coverage_k} anchors in line of "
            f"sight and reach, where the coverage selection covers {percent(cover['covered'])} "
            f"% with {res.settings.M}: a fix is verified only where {v.coverage_k} consistent "
            f"anchors are heard{field}. --min-coverage {COVERAGE_NOTE:g} keeps every layout to "
            f"that share (it can cost field P95 elsewhere: BENCHMARKS.md, \"A coverage target "
            "the plan keeps to\").")  # fmt: skip


#: the share of the nodes seeing k anchors below which a plan free of a coverage target,
#: where the coverage selection reaches it, prints :func:`coverage_note`
COVERAGE_NOTE = 0.95


def echo_note(room, system, validation) -> str | None:
    """A note where least squares meets echoes: in a room whose walls or obstacles hide
    anchors from some tags, a receiver there ranges on an echo and least squares keeps
    the range, so the fix moves by metres; the recommended system rejects such ranges
    (docs/model.md, "Positioning that rejects echoes"). None elsewhere, or when the field
    check's median is within 0.1 m."""
    field = None if validation is None else validation.field
    if (system.positioning.method != "ls" or field is None or not field.median > ECHO_NOTE_M
            or (room.is_convex and not room.obstacles)):  # fmt: skip
        return None
    return (f"note: walls or obstacles hide anchors from some tags here; their receivers range "
            f"on echoes and least squares keeps those ranges (field median {field.median:.2f} "
            "m). The recommended system (--system recommended: a first-path receiver, echoes "
            "rejected) plans such rooms to centimetres (BENCHMARKS.md, \"Rooms we had not "
            "seen\").")  # fmt: skip


#: (m) a field median above this, with least squares in a room that hides anchors, prints
#: :func:`echo_note`
ECHO_NOTE_M = 0.1


def _print_validation(v, robust: bool = False) -> None:
    """The validation's summary lines, the field check first: what an installation gets."""
    if v is None:
        return
    if v.field is not None:
        f = v.field
        print(f"field ({f.draws} draws of {f.tags_per_draw} random tags, anchors mounted "
              f"within {100 * f.tolerance_m:g} cm): " + _stats(f, robust))  # fmt: skip
    print(f"validation, {v.realizations} realizations at the {len(v.per_node['rmse'])} nodes: "
          + _stats(v, robust))  # fmt: skip
    if v.covered == v.covered:
        print(f"  line of sight: {percent(v.covered)} % of the nodes see {v.coverage_k} or "
              "more anchors in line of sight and reach")  # fmt: skip
    if v.held_out is not None:
        for d, what in ((v.held_out.grid, "held-out grid"), (v.held_out.random, "random points")):
            print(f"  {what} ({d.nodes} nodes): " + _stats(d, robust))
    if v.mounting is not None:
        m = v.mounting
        print(f"  mounting error <= {100 * m.tolerance_m:g} cm ({m.draws} draws): "
              + _stats(m, robust))  # fmt: skip


def _stats(s, robust: bool = False) -> str:
    """ "median … m, mean … m, P95 … m[, verified … %], sigma … m" and the availability of
    a summary: what a user's tags see first (the share of verified fixes for a system that
    verifies them, ``robust``), the paper's σ after."""
    verified = f", verified {percent(s.verified)} %" if robust else ""
    return (f"median {s.median:.3f} m, mean {s.mean:.3f} m, P95 {s.p95:.3f} m{verified}, "
            f"sigma {s.std:.3f} m"
            + availability_note({"availability": s.availability}))  # fmt: skip


def _print_phases(res) -> None:
    parts = []
    for phase, p in res.phases.items():
        n = f" ({p['nfev']} {p['counts'].split(' (')[0]})" if p["nfev"] else ""
        parts.append(f"{phase} {p['seconds']:.1f} s{n}")
    print("phases: " + ", ".join(parts) + f"; total {res.timings['total']:.1f} s")

"""``anchorplan plan``: the main job — seed_then_pso on a room, results to a folder."""

from __future__ import annotations

import contextlib
import re
import time

from placement.cli.common import add_room_argument, load_room, output_dir, write_json
from placement.costs import COST_NAMES
from placement.workers import available_cores
from simulation import checks

#: seconds to wait for a Dask scheduler before giving up
SCHEDULER_TIMEOUT = 3
#: limits of the command line's numbers (the library's are wider)
MAX_WORKERS = 1024
MAX_REALIZATIONS = 1000
MAX_SEARCH_CANDIDATES = 10_000


def register(sub) -> None:
    p = sub.add_parser(
        "plan",
        help="optimize an anchor layout (seeds + PSO on the full simulation)",
        description="Plan where to mount M anchors: seeds (a simulation-driven search over "
        "candidate points, convex relaxation and PEB refinement), particle swarm "
        "optimization on the simulated positioning error, and validation of the best "
        "layout. Writes result.json and layout.json to --out.",
    )
    p.add_argument("--anchors", "-M", type=int, default=8, help="number of anchors M (8)")
    add_room_argument(p)
    p.add_argument("--particles", type=int, default=15, help="swarm size (15)")
    p.add_argument("--iterations", type=int, default=40, help="maximum iterations (40)")
    p.add_argument("--cost", choices=COST_NAMES, default="variance", help="cost (variance)")
    p.add_argument(
        "--realizations", type=int, default=1, help="noise realizations per evaluation (1)"
    )
    p.add_argument(
        "--validate-realizations",
        type=int,
        default=100,
        help="realizations to validate the best layout (100)",
    )
    p.add_argument("--no-seeds", action="store_true", help="unseeded swarm (paper's setting)")
    p.add_argument(
        "--search-starts",
        type=int,
        help="local searches of the simulation-driven seed search (8; 0: skip it)",
    )
    p.add_argument(
        "--search-realizations",
        type=int,
        help="noise realizations in the seed search's range table (3)",
    )
    p.add_argument(
        "--search-spacing",
        type=float,
        help="spacing of the seed search's candidate points in m (0.6)",
    )
    p.add_argument(
        "--finalists",
        type=int,
        default=None,
        help="best distinct swarm layouts re-scored before choosing (4, at most --particles; "
        "1: the swarm's best)",
    )
    p.add_argument(
        "--finalist-realizations",
        type=int,
        default=10,
        help="noise realizations per re-scored finalist (10)",
    )
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
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", metavar="DIR", default="anchorplan-out", help="output folder")
    p.set_defaults(func=run)


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


def _check_args(args, room) -> None:
    """Every number and file of the command, checked before any work."""
    from placement.exhaustive import DEFAULT_SPACING
    from placement.pso import MAX_ANCHORS, MAX_ITERATIONS, MAX_PARTICLES, load_checkpoint
    from placement.surfaces import candidate_grid
    from simulation.evaluation import BYTES_PER_RANGE

    checks.count("--particles", args.particles, low=2, high=MAX_PARTICLES)
    checks.count("--iterations", args.iterations, low=1, high=MAX_ITERATIONS)
    checks.count("--realizations", args.realizations, low=1, high=MAX_REALIZATIONS)
    checks.count("--validate-realizations", args.validate_realizations, low=0)
    if args.finalists is not None:  # an explicit value: at most one per particle
        checks.count("--finalists", args.finalists, low=1, high=args.particles)
    checks.count(
        "--finalist-realizations", args.finalist_realizations, low=1, high=MAX_REALIZATIONS
    )
    checks.count("--seed", args.seed, low=0)
    checks.count("--workers", args.workers, low=0, high=MAX_WORKERS)
    if args.scheduler and args.workers > 0:
        raise ValueError("--scheduler and --workers: choose one")
    if args.eval_timeout is not None:
        checks.real("--eval-timeout", args.eval_timeout, low=0.0, low_open=True, unit="s")
    if args.search_starts is not None:
        checks.count("--search-starts", args.search_starts, low=0, high=10_000)
    if args.search_spacing is not None:
        checks.real("--search-spacing", args.search_spacing, low=0.0, low_open=True, unit="m")
    if args.search_realizations is not None:
        checks.count("--search-realizations", args.search_realizations, low=1, high=100)
    M = checks.count("--anchors", args.anchors, low=4, high=MAX_ANCHORS)
    if not args.no_seeds:
        n = len(candidate_grid(room, DEFAULT_SPACING))
        if M > n:
            raise ValueError(
                f"--anchors: {M} anchors exceed the {n} candidate points of the seeds' "
                f"relaxation in this room; use at most {n} or --no-seeds"
            )
        if args.cost != "peb" and args.search_starts != 0:
            spacing = 0.6 if args.search_spacing is None else args.search_spacing
            try:
                n = len(candidate_grid(room, spacing))
            except ValueError as exc:
                raise ValueError(f"--search-{exc}") from None
            if n > MAX_SEARCH_CANDIDATES:
                raise ValueError(
                    f"--search-spacing: {spacing:g} m gives {n} candidate points, more than "
                    f"{MAX_SEARCH_CANDIDATES}; use a larger spacing"
                )
            if M > n:
                raise ValueError(
                    f"--anchors: {M} anchors exceed the {n} candidate points of the seed "
                    f"search (--search-spacing {spacing:g} m)"
                )
    checks.check_size(
        "--validate-realizations",
        args.validate_realizations * len(room.grid()) * M * BYTES_PER_RANGE,
        value=args.validate_realizations,
        hint="use fewer realizations",
    )
    if args.checkpoint is not None:
        checks.output_path("--checkpoint", args.checkpoint)
        state = load_checkpoint(args.checkpoint)  # a damaged file fails here, not at the end
        if state is not None:
            print(
                f"checkpoint {args.checkpoint}: found (iteration {state['iteration']}); "
                "it is resumed if it was written by this same command",
                flush=True,
            )


def run(args) -> int:
    from numpy import array_equal as np_equal

    from placement.plan import seed_then_pso
    from placement.pso import default_eval_timeout

    out = output_dir("--out", args.out)
    room = load_room(args.room)
    _check_args(args, room)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        executor = _executor(args, stack)
        print(
            f"planning {args.anchors} anchors in {room.name} "
            f"({room.size[0]:g} x {room.size[1]:g} x {room.size[2]:g} m), cost {args.cost}, "
            f"{args.particles} particles x {args.iterations} iterations, seed {args.seed}",
            flush=True,
        )
        with default_eval_timeout(args.eval_timeout):
            res = seed_then_pso(
                room,
                args.anchors,
                particles=args.particles,
                iterations=args.iterations,
                cost=args.cost,
                realizations=args.realizations,
                seeds=None if args.no_seeds else "auto",
                search={
                    key: value
                    for key, value in (
                        ("starts", args.search_starts),
                        ("realizations", args.search_realizations),
                        ("spacing", args.search_spacing),
                    )
                    if value is not None  # unset: the library's default
                },
                finalists=4 if args.finalists is None else args.finalists,
                finalist_realizations=args.finalist_realizations,
                executor=executor,
                seed=args.seed,
                progress=not args.no_progress,
                checkpoint=args.checkpoint,
                validate_realizations=args.validate_realizations,
            )
    out.mkdir(parents=True, exist_ok=True)
    (out / "result.json").write_text(res.to_json(indent=1) + "\n")
    write_json(out / "layout.json", {"anchors": res.anchors})
    for s in res.seeds:
        print(f"  seed {s.name:<22} mean PEB {s.mean_peb:.4f} m   cost {s.cost:.4g}")
    swarm = res.pso
    extra = {} if swarm is None else swarm.extra
    if extra.get("resumed_from") is not None:
        print(f"resumed from checkpoint {args.checkpoint} after iteration {extra['resumed_from']}")
    print(f"PSO: {res.nit} iterations, {res.nfev} evaluations, {res.message}")
    if swarm is not None and swarm.failures:
        print(
            f"  {swarm.failures} evaluation(s) failed and cost inf: "
            f"{extra.get('lost', 0)} lost to dead worker processes, "
            f"{extra.get('timeouts', 0)} over --eval-timeout, "
            f"{swarm.failures - extra.get('lost', 0) - extra.get('timeouts', 0)} errors"
        )
    for k, f in enumerate(res.finalists):
        mark = "*" if np_equal(f["anchors"], res.anchors) else " "
        print(
            f" {mark}finalist {k + 1}: PSO cost {f['pso_cost']:.4g}, "
            f"re-scored {f['cost']:.4g} over {args.finalist_realizations} realizations"
        )
    print(f"chosen layout: {res.cost_name} cost {res.cost:.4g} in the swarm")
    print("anchors (m):")
    for a in res.anchors:
        print(f"  {a[0]:7.3f} {a[1]:7.3f} {a[2]:7.3f}")
    v = res.validation
    if v:
        print(
            f"validation over {v['realizations']} realizations: sigma {v['std']:.3f} m, "
            f"mean {v['mean']:.3f} m, P95 {v['p95']:.3f} m; "
            f"mean PEB {v['mean_peb']:.4f} m (sqrt tr CRLB, sigma_r 0.04 m)"
        )
    print(
        f"wrote {out / 'result.json'} and {out / 'layout.json'} ({time.perf_counter() - t0:.1f} s)"
    )
    return 0

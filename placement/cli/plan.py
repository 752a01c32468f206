"""``anchorplan plan``: the main job — seed_then_pso on a room, results to a folder."""

from __future__ import annotations

import contextlib
import os
import time
from pathlib import Path

from placement.cli.common import add_room_argument, load_room, write_json
from placement.costs import COST_NAMES


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
        default=4,
        help="best distinct swarm layouts re-scored before choosing (4; 1: the swarm's best)",
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
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", metavar="DIR", default="anchorplan-out", help="output folder")
    p.set_defaults(func=run)


def _executor(args, stack: contextlib.ExitStack):
    if args.scheduler and args.workers > 0:
        raise ValueError("--scheduler and --workers: choose one")
    if args.scheduler:
        try:
            from dask.distributed import Client
        except ImportError:
            raise ValueError("--scheduler needs dask: pip install 'anchorplan[dask]'") from None
        client = stack.enter_context(Client(args.scheduler))
        return client.get_executor()
    if args.workers < 0:
        raise ValueError(f"--workers: must be >= 0 (0: one per core), got {args.workers}")
    workers = args.workers or available_cores()
    if workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        return stack.enter_context(ProcessPoolExecutor(max_workers=workers))
    return None


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


def run(args) -> int:
    from numpy import array_equal as np_equal

    from placement.plan import seed_then_pso

    room = load_room(args.room)
    out = Path(args.out)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        executor = _executor(args, stack)
        print(
            f"planning {args.anchors} anchors in {room.name} "
            f"({room.size[0]:g} x {room.size[1]:g} x {room.size[2]:g} m), cost {args.cost}, "
            f"{args.particles} particles x {args.iterations} iterations, seed {args.seed}",
            flush=True,
        )
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
            finalists=args.finalists,
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
    print(f"PSO: {res.nit} iterations, {res.nfev} evaluations, {res.message}")
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

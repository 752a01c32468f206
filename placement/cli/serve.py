"""``anchorplan serve``: the planning page on a local web server."""

from __future__ import annotations

import tempfile

from placement.cli.common import add_room_argument, system_choice
from placement.workers import available_cores
from simulation import checks

#: the address the page is served on unless --host says otherwise: this machine only
LOCALHOST = "127.0.0.1"
#: the most plans a server runs at once
MAX_PLANS = 16


def register(sub) -> None:
    """Add ``anchorplan serve`` and its arguments to the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "serve",
        help="open the planning page: move anchors, watch coverage and error, run plans",
        description="Serve the planning page on this machine and print its address: the "
        "room in plan and elevation, anchors dragged along their mounting surfaces with the "
        "coverage (anchors in line of sight and reach) and the PEB map updated at once, the "
        "error at the receiver simulated on demand, plans run in the background, and the "
        "exports (layout, report, mounting sheet, DXF). The page reads room files only from "
        "the folders named here (--room's, --result) and writes only to --work.",
    )
    add_room_argument(p)
    p.add_argument("--result", metavar="DIR", help="a result folder whose layout the page opens")
    p.add_argument("--system", metavar="NAME", help="a preset (paper, recommended) or a TOML file")
    p.add_argument("--port", type=int, default=8765, help="port (8765; 0: any free port)")
    p.add_argument(
        "--host",
        default=LOCALHOST,
        help=f"address to listen on ({LOCALHOST}: this machine only; anything else lets "
        "other machines use the page and run plans)",
    )
    p.add_argument(
        "--work",
        metavar="DIR",
        help="folder for plans, uploads and exports (a new temporary folder)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=0,
        help="worker processes of a plan (0: one per available core)",
    )
    p.add_argument("--plans", type=int, default=1, help="plans that may run at once (1; the "
                   "page shows the latest, the others write to --work)")  # fmt: skip
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``anchorplan serve`` on parsed ``args`` until interrupted; the exit status."""
    import uvicorn

    from placement.web.app import create_app
    from placement.web.workspace import Workspace

    checks.count("--port", args.port, low=0, high=65535)
    checks.count("--workers", args.workers, low=0, high=available_cores() * 64)
    checks.count("--plans", args.plans, low=1, high=MAX_PLANS)
    if args.result is not None:
        checks.input_dir("--result", args.result)
    if args.room is not None:
        checks.input_file("--room", args.room)
    system_choice(args.system, args.room)  # an unknown name lists the presets, before serving
    work = checks.output_path(
        "--work", args.work or tempfile.mkdtemp(prefix="anchorplan-"), kind="dir"
    )
    options = {
        "room_height": args.room_height,
        "obstacle_height": args.obstacle_height,
        "dxf_unit": args.dxf_unit,
        "dxf_layer": args.dxf_layer,
        "dxf_obstacle_layer": args.dxf_obstacle_layer,
    }
    ws = Workspace(
        work, args.room, args.result, options, args.system, args.workers, max_plans=args.plans
    )
    config = uvicorn.Config(create_app(ws), host=args.host, port=args.port, log_level="warning")
    server = uvicorn.Server(config)
    print(f"planning page for {ws.room.name}: work folder {work}", flush=True)
    if args.host != LOCALHOST:
        print(f"listening on {args.host}: other machines can reach this page", flush=True)
    _announce(server, args.host)
    server.run()
    for plan in ws.plans:
        plan.cancel()
    return 0


def _announce(server, host: str) -> None:
    """Print the page's address once the server listens (the port may be chosen by the
    system)."""
    import threading
    import time

    def wait():
        while not server.started and not server.should_exit:
            time.sleep(0.05)
        if server.started:
            port = server.servers[0].sockets[0].getsockname()[1]
            print(
                f"open http://{'localhost' if host == LOCALHOST else host}:{port}/ "
                "(Ctrl-C stops the server)",
                flush=True,
            )

    threading.Thread(target=wait, daemon=True).start()

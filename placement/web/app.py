"""The planning page's ASGI application (FastAPI): the page itself and a small JSON API
over a :class:`placement.web.workspace.Workspace`.

Every request that changes something answers with the page's whole state (room, system,
layout, maps, jobs), so the page has one way to draw. Bad input answers 400 with
``{"error": message}``, the command line's message; any other failure 500 with one line,
never a stack trace.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Annotated, Any

from fastapi import Body, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from placement.cli.common import obstacle_heights
from placement.web.workspace import EXPORTS, Workspace
from simulation import checks

STATIC = Path(__file__).parent / "static"
#: a request's JSON object
JSONBody = Annotated[dict[str, Any], Body()]
OptionalBody = Annotated[dict[str, Any] | None, Body()]


def _errors(app: FastAPI) -> None:
    @app.exception_handler(ValueError)
    async def bad_input(_: Request, exc: ValueError):
        return JSONResponse({"error": " ".join(str(exc).split())}, status_code=400)

    @app.exception_handler(RequestValidationError)
    async def not_an_object(_: Request, exc: RequestValidationError):
        return JSONResponse({"error": "request: expected a JSON object"}, status_code=400)

    @app.exception_handler(FileNotFoundError)
    async def missing(_: Request, exc: FileNotFoundError):
        return JSONResponse({"error": " ".join(str(exc).split())}, status_code=400)

    @app.exception_handler(Exception)
    async def failure(_: Request, exc: Exception):
        text = " ".join(str(exc).split())
        return JSONResponse({"error": f"{type(exc).__name__}: {text}"}, status_code=500)


def _point(body: dict, key: str = "point") -> list[float]:
    value = body.get(key)
    if not isinstance(value, list) or len(value) != 3:
        raise ValueError(f"{key}: expected [x, y, z] in m, got {value!r}")
    return [checks.real(key, v) for v in value]


def _number(flag: str, value) -> float:
    """A number typed in the page, refused as argparse refuses it on the command line."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"argument {flag}: invalid float value: {value!r}") from None


def _heights(text: str):
    """The obstacle height typed in the page ("2.5", or "A-COLS=2.8,A-FURN=0.75"), refused
    as the command line refuses it."""
    try:
        return obstacle_heights(text)
    except argparse.ArgumentTypeError as exc:
        raise ValueError(f"argument --obstacle-height: {exc}") from None


def _room_routes(app: FastAPI, ws: Workspace) -> None:
    @app.post("/api/room")
    def room(body: JSONBody):
        options = {
            k: body[k]
            for k in (
                "room_height",
                "obstacle_height",
                "dxf_unit",
                "dxf_layer",
                "dxf_obstacle_layer",
            )
            if body.get(k) not in (None, "")
        }
        if "room_height" in options:
            options["room_height"] = _number("--room-height", options["room_height"])
        if "obstacle_height" in options:
            options["obstacle_height"] = _heights(str(options["obstacle_height"]))
        if body.get("upload") is not None:
            up = body["upload"]
            path = ws.upload(str(up.get("name", "")), str(up.get("content", "")))
        elif body.get("file"):
            path = ws.resolve(body["file"])
        else:
            path = None
        try:
            ws.set_room(path, options, body.get("system") or None)
        except (ValueError, OSError):
            if body.get("upload") is not None:
                path.unlink(missing_ok=True)  # keep only the uploads that open
            raise
        return ws.snapshot()

    @app.post("/api/system")
    def system(body: JSONBody):
        ws.set_system(body.get("system") or None)
        return ws.snapshot()


def _anchor_routes(app: FastAPI, ws: Workspace) -> None:
    from placement.web import scene

    @app.post("/api/anchors/move")
    def move(body: JSONBody):
        ws.set_anchors(scene.moved(ws.room, ws.anchors, body.get("index"), _point(body)))
        return ws.snapshot()

    @app.post("/api/anchors/add")
    def add(body: JSONBody):
        ws.set_anchors(scene.added(ws.room, ws.anchors, _point(body)))
        return ws.snapshot()

    @app.post("/api/anchors/remove")
    def remove(body: JSONBody):
        ws.set_anchors(scene.removed(ws.anchors, body.get("index")))
        return ws.snapshot()


def _job_routes(app: FastAPI, ws: Workspace) -> None:
    @app.post("/api/field")
    def field(body: OptionalBody = None):
        ws.start_field(checks.count("--seed", (body or {}).get("seed", 0), low=0))
        return ws.snapshot()

    @app.post("/api/plan")
    def plan(body: JSONBody):
        ws.start_plan(body)
        return ws.snapshot()

    @app.post("/api/plan/cancel")
    def cancel():
        if ws.plan is not None:
            ws.plan.cancel()
        return ws.snapshot()

    @app.post("/api/plan/open")
    def open_plan():
        status = None if ws.plan is None else ws.plan.status()
        if status is None or status["state"] != "done":
            raise ValueError("plan: no finished plan to open")
        ws.set_anchors(status["result"]["anchors"])
        return ws.snapshot()

    @app.get("/api/export/{kind}")
    def export(kind: str):
        path = ws.export(kind)
        return FileResponse(path, filename=path.name)


def create_app(ws: Workspace) -> FastAPI:
    """The page and its API over the workspace ``ws``."""
    app = FastAPI(title="anchorplan", docs_url=None, redoc_url=None, openapi_url=None)
    _errors(app)

    @app.get("/")
    def index():
        return FileResponse(STATIC / "index.html")

    @app.get("/api/state")
    def state():
        return ws.snapshot()

    @app.get("/api/jobs")
    def job_state():
        plan, field = ws.plan, ws.field
        return {
            "plan": None if plan is None else plan.status(),
            "field": None if field is None else field.status(),
        }

    @app.get("/api/exports")
    def exports():
        return list(EXPORTS)

    _room_routes(app, ws)
    _anchor_routes(app, ws)
    _job_routes(app, ws)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    return app


#: what a headless Chromium needs to show the page on a sandboxed machine without network
#: (no GPU, no calls home): the flags of the browser test, the benchmark and the screenshot
CHROMIUM_FLAGS = ("--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync")  # fmt: skip


def serve_in_thread(ws: Workspace, host: str = "127.0.0.1", port: int = 0, timeout: float = 30.0):
    """Serve the page over ``ws`` from a daemon thread (uvicorn; ``port`` 0: a free one);
    (the server, its address "http://host:port"). ``server.should_exit = True`` stops it."""
    import threading
    import time

    import uvicorn

    server = uvicorn.Server(uvicorn.Config(create_app(ws), host=host, port=port,
                                           log_level="warning"))  # fmt: skip
    threading.Thread(target=server.run, daemon=True).start()
    deadline = time.monotonic() + timeout
    while not server.started:
        if time.monotonic() > deadline:
            raise TimeoutError(f"the page's server did not start within {timeout:g} s")
        time.sleep(0.05)
    return server, f"http://{host}:{server.servers[0].sockets[0].getsockname()[1]}"

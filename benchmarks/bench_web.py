"""Latency of the planning page's update after a drag: one anchor moved (the server snaps
it, recomputes the coverage and PEB maps and answers with the page's state), in the
example rooms (techtile, the L-shaped lab, the warehouse, the 24 m hall, the office and
the ordinary room), with the paper's and the recommended
system. Two figures per case, both milliseconds over ``--moves`` moves:

- ``server``: the HTTP round trip of ``POST /api/anchors/move`` from a client beside the
  server (uvicorn on localhost), JSON included;
- ``page``: in headless Chromium, from the page's request to the end of its redraw (what a
  user waits for after letting go of an anchor); skipped without a Chromium.

    python benchmarks/bench_web.py [--moves 30] [--rooms techtile hall ...]

One JSON line per (room, system)."""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (the checkout's packages)
import httpx
import numpy as np

from placement.web.app import CHROMIUM_FLAGS, serve_in_thread
from placement.web.workspace import Workspace

ROOT = Path(__file__).resolve().parents[1]
ROOMS = {
    "techtile": None,
    "l-shaped-lab": ROOT / "examples" / "l-shaped-lab.toml",
    "warehouse-aisles": ROOT / "examples" / "warehouse-aisles.toml",
    "hall": ROOT / "examples" / "hall.toml",
    "office": ROOT / "examples" / "office.toml",
    "ordinary-room": ROOT / "examples" / "ordinary-room.toml",
}


def _targets(room, n: int, rng) -> list[list[float]]:
    """n drag targets 5 cm under the ceiling, in the floor plan, out of the obstacles and
    keep-outs (where a user may let go of an anchor)."""
    size = room.size
    p = np.column_stack(
        [
            rng.uniform(0, size[0], 20 * n),
            rng.uniform(0, size[1], 20 * n),
            np.full(20 * n, size[2] - 0.05),
        ]
    )
    p = p[room.contains(p) & ~room.in_keepout(p)][:n]
    return p.tolist()


def _server_ms(url: str, targets) -> list[float]:
    out = []
    with httpx.Client(base_url=url, timeout=60) as client:
        for p in targets:
            t0 = time.perf_counter()
            r = client.post("/api/anchors/move", json={"index": 0, "point": p})
            out.append(1e3 * (time.perf_counter() - t0))
            r.raise_for_status()
    return out


def _page_ms(url: str, targets, chromium: str) -> list[float]:
    from playwright.sync_api import sync_playwright

    js = """async (p) => { const t0 = performance.now();
        await act("POST", "/api/anchors/move", { index: 0, point: p });
        return performance.now() - t0; }"""
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=list(CHROMIUM_FLAGS))
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.goto(url)
        page.wait_for_selector("#covered-k")
        out = [page.evaluate(js, p) for p in targets]
        browser.close()
    return out


def _stats(ms: list[float]) -> dict:
    return {
        "median_ms": round(statistics.median(ms), 1),
        "p95_ms": round(float(np.percentile(ms, 95)), 1),
        "max_ms": round(max(ms), 1),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=30)
    ap.add_argument("--rooms", nargs="+", choices=list(ROOMS), default=list(ROOMS))
    args = ap.parse_args()
    chromium = shutil.which("chromium")
    for name in args.rooms:
        path = ROOMS[name]
        for system in ("paper", "recommended"):
            ws = Workspace(Path(tempfile.mkdtemp()), path, system=system)
            server, url = serve_in_thread(ws)
            targets = _targets(ws.room, args.moves, np.random.default_rng(0))
            row = {
                "bench": "web_drag",
                "room": name,
                "system": system,
                "moves": args.moves,
                "cells": len(ws.snapshot()["maps"]["cells"]),
                "anchors": len(ws.anchors),
                "server": _stats(_server_ms(url, targets)),
            }
            if chromium:
                row["page"] = _stats(_page_ms(url, targets, chromium))
            print(json.dumps(row), flush=True)
            server.should_exit = True


if __name__ == "__main__":
    main()

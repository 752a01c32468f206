"""The README's picture of the planning page: the L-shaped lab with the recommended
system's committed plan, the error at the receiver simulated, the coverage layer shown.

    python scripts/page_screenshot.py docs/images/planning-page.png

Needs a Chromium (Debian: apt-get install chromium) and playwright (the test extras)."""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from pathlib import Path

import uvicorn
from playwright.sync_api import sync_playwright

from placement.web.app import create_app
from placement.web.workspace import Workspace

ROOT = Path(__file__).resolve().parent.parent
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--no-first-run",
    "--disable-component-update",
    "--disable-sync",
]


def main(out: str) -> None:
    ws = Workspace(
        Path(tempfile.mkdtemp()),
        ROOT / "examples" / "l-shaped-lab.toml",
        ROOT / "docs" / "examples" / "l-shaped-lab-recommended",
        system="recommended",
    )
    server = uvicorn.Server(uvicorn.Config(create_app(ws), port=0, log_level="warning"))
    threading.Thread(target=server.run, daemon=True).start()
    while not server.started:
        time.sleep(0.05)
    port = server.servers[0].sockets[0].getsockname()[1]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=FLAGS)
        page = browser.new_page(viewport={"width": 1400, "height": 980})
        page.goto(f"http://127.0.0.1:{port}/")
        page.wait_for_selector("#covered-k")
        page.click("#field-run")
        page.wait_for_selector("#field-stats", timeout=300_000)
        page.screenshot(path=out)
        browser.close()
    server.should_exit = True


if __name__ == "__main__":
    main(sys.argv[1])

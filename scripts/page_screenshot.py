"""The README's picture of the planning page: the L-shaped lab with the recommended
system's committed plan, the error at the receiver simulated, the coverage layer shown.

    python scripts/page_screenshot.py docs/images/planning-page.png

Needs a Chromium (Debian: apt-get install chromium) and playwright (the test extras)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from playwright.sync_api import sync_playwright

from placement.web.app import CHROMIUM_FLAGS, serve_in_thread
from placement.web.workspace import Workspace

ROOT = Path(__file__).resolve().parent.parent


def main(out: str) -> None:
    ws = Workspace(
        Path(tempfile.mkdtemp()),
        ROOT / "examples" / "l-shaped-lab.toml",
        ROOT / "docs" / "examples" / "l-shaped-lab-recommended",
        system="recommended",
    )
    server, url = serve_in_thread(ws)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=list(CHROMIUM_FLAGS))
        page = browser.new_page(viewport={"width": 1400, "height": 980})
        page.goto(url + "/")
        page.wait_for_selector("#covered-k")
        page.click("#field-run")
        page.wait_for_selector("#field-stats", timeout=300_000)
        page.screenshot(path=out)
        browser.close()
    server.should_exit = True


if __name__ == "__main__":
    main(sys.argv[1])

"""Print mounting sheets to PDF in a real headless browser and check nothing is cut off.

Run: python benchmarks/check_sheet_print.py SHEET_DIR [SHEET_DIR ...] [--browser /usr/bin/chromium]
        [--png DIR]

For each ``SHEET_DIR/sheet.html`` (``anchorplan sheet``): Chromium prints it to A4 PDF
(``--print-to-pdf``, no header or footer), and the check counts the PDF's pages against the
sheet's page sections (a section taller than its page would spill onto an extra page); it
also loads the sheet at the printable width of an A4 page (186 mm at 96 px/in) with a small
probe script that measures each section's content against the section box and the page width
(an SVG or table wider than the page would be cut off at the side). One JSON line per sheet:
sections, PDF pages, the sections whose content overflows, and ``ok``. ``--png DIR``
also renders each PDF page to PNG (pdftoppm) to look at, as ``DIR/<folder>-sheet-<page>.png``
where <folder> holds SHEET_DIR.

Needs Chromium (Debian: ``apt-get install chromium``; ``poppler-utils`` for ``--png``).
"""

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from _common import emit

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
)

#: measures every page section: content taller than the section, or wider than the page
PROBE = """<script>
window.addEventListener('load', () => {
  const bad = [];
  document.querySelectorAll('section.page').forEach((s, i) => {
    let bottom = 0, right = 0;
    const box = s.getBoundingClientRect();
    s.querySelectorAll('*').forEach(el => {
      const r = el.getBoundingClientRect();
      bottom = Math.max(bottom, r.bottom); right = Math.max(right, r.right);
    });
    if (bottom > box.bottom + 0.5 || right > box.right + 0.5)
      bad.push(i + ':' + Math.round(right - box.right) + ':' + Math.round(bottom - box.bottom));
  });
  document.body.setAttribute('data-overflow', bad.join(','));
  document.body.setAttribute('data-sections', document.querySelectorAll('section.page').length);
});
</script>"""

#: the printable width of A4 with 12 mm margins, in CSS px
A4_PRINT_WIDTH_PX = round(186 / 25.4 * 96)


def pdf_pages(pdf: Path) -> int:
    """Pages of a PDF (its /Type /Page objects)."""
    return len(re.findall(rb"/Type\s*/Page(?!s)", pdf.read_bytes()))


def run(browser: str, args: list[str], cwd: Path) -> str:
    user = tempfile.mkdtemp(prefix="chromium-")
    try:
        out = subprocess.run(
            [browser, *FLAGS, f"--user-data-dir={user}", *args],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return out.stdout


def check(sheet_dir: Path, browser: str, png: Path | None) -> None:
    html = (sheet_dir / "sheet.html").read_text()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        pdf = tmp / "sheet.pdf"
        (tmp / "sheet.html").write_text(html)
        run(browser, ["--no-pdf-header-footer", f"--print-to-pdf={pdf}", "sheet.html"], tmp)
        pages = pdf_pages(pdf) if pdf.exists() else 0
        (tmp / "probe.html").write_text(html.replace("</body>", PROBE + "</body>"))
        dom = run(
            browser,
            [
                f"--window-size={A4_PRINT_WIDTH_PX + 200},1200",
                "--virtual-time-budget=3000",
                "--dump-dom",
                "probe.html",
            ],
            tmp,
        )
        sections = int(re.search(r'data-sections="(\d+)"', dom).group(1))
        overflow = re.search(r'data-overflow="([^"]*)"', dom).group(1)
        if png is not None and pdf.exists():
            png.mkdir(parents=True, exist_ok=True)
            subprocess.run(
                [
                    "pdftoppm",
                    "-png",
                    "-r",
                    "70",
                    str(pdf),
                    str(png / f"{sheet_dir.resolve().parent.name}-sheet"),
                ],
                check=True,
            )
    # section index: px it spills to the right, px below its page box
    bad = [[int(v) for v in b.split(":")] for b in overflow.split(",") if b]
    emit(
        "sheet_print",
        sheet=str(sheet_dir),
        sections=sections,
        pdf_pages=pages,
        overflowing_sections=bad,
        ok=pages == sections and not bad,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sheets", nargs="+", metavar="SHEET_DIR")
    ap.add_argument("--browser", default=shutil.which("chromium") or "/usr/bin/chromium")
    ap.add_argument("--png", type=Path, metavar="DIR", help="render the PDF pages to PNG here")
    args = ap.parse_args()
    if not Path(args.browser).exists():
        sys.exit(f"check_sheet_print: no browser at {args.browser} (apt-get install chromium)")
    for d in args.sheets:
        check(Path(d), args.browser, args.png)


if __name__ == "__main__":
    main()

"""What a reader sees: page 1 of each report.pdf, and each report.html on a desktop and on a phone, as PNG.

Usage: ``python benchmarks/look.py OUT_FOLDER [OUT_FOLDER ...] [--index DIR/index.html] [--to PNG_DIR]``

Each OUT_FOLDER is a report bundle (a folder holding report.html or
report.pdf) or a folder with bundles anywhere beneath it. For each bundle,
page 1 of report.pdf is rendered at 80 dpi (``pdftoppm``) and report.html is
screenshot whole, top to bottom, in headless Chromium 1280 px wide and 390 px
wide (a phone); ``--index`` adds the same two screenshots of an index page.
The PNGs go to ``--to`` (default ``benchmarks/out/look/``); their paths are
printed, with each PDF's page count, page size and file size (``pdfinfo``).
A tool for a person looking at the reports, not a test: it checks nothing.
Needs ``chromium`` and poppler-utils (``pdftoppm``, ``pdfinfo``).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from harness import OUT

WIDTHS = (1280, 390)
"""Desktop and phone widths of the screenshots, CSS pixels."""
TIMEOUT_S = 180
"""Longest a Chromium run may take; a 50-page report 390 px wide is 58,000 px tall and takes about 20 s."""

_CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                   # This machine refuses outside connections: without these Chromium's own fetches hang.
                   "--disable-background-networking", "--disable-component-update", "--disable-sync",
                   "--hide-scrollbars"]

# --screenshot captures the window only, so the page's full height is measured
# first, in a frame of the same width, from a page of this script's own: the
# report's Content-Security-Policy forbids scripts inside it.
_MEASURE = """<!DOCTYPE html><html><body style="margin:0">
<iframe id="page" src="{url}" scrolling="no" style="width:{width}px;height:1000px;border:0"></iframe>
<script>
document.getElementById("page").addEventListener("load", function () {{
  var page = this.contentDocument;
  document.body.setAttribute("data-height", String(Math.max(page.documentElement.scrollHeight,
                                                            page.body.scrollHeight)));
}});
</script></body></html>
"""


def bundles(folder: Path) -> list[Path]:
    """``folder`` if it is a report bundle, else every bundle beneath it, in path order."""
    if (folder / "report.html").is_file() or (folder / "report.pdf").is_file():
        return [folder]
    found = {p.parent for name in ("report.html", "report.pdf") for p in folder.rglob(name)}
    return sorted(found)


def chromium(args: list[str]) -> subprocess.CompletedProcess:
    """Run headless Chromium with a fresh profile, so no run sees another's cache or settings."""
    with tempfile.TemporaryDirectory(prefix="look-chromium-") as profile:
        return subprocess.run([shutil.which("chromium"), *_CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                              capture_output=True, text=True, timeout=TIMEOUT_S)


def page_height(page: Path, width: int) -> int | None:
    """The full height in CSS pixels of ``page`` laid out ``width`` px wide, or None when it could not be read."""
    with tempfile.TemporaryDirectory(prefix="look-measure-") as folder:
        wrapper = Path(folder) / "measure.html"
        wrapper.write_text(_MEASURE.format(url=page.resolve().as_uri(), width=width))
        done = chromium(["--allow-file-access-from-files", f"--window-size={width},1000", "--dump-dom",
                         wrapper.as_uri()])
    found = re.search(r'data-height="(\d+)"', done.stdout)
    return int(found.group(1)) if found else None


def screenshot(page: Path, width: int, png: Path) -> str:
    """Screenshot ``page`` whole at ``width`` into ``png``; returns a note on what was captured."""
    height = page_height(page, width)
    note = f"{width}x{height}"
    if height is None:
        height, note = 2000, f"{width}x2000, the top only: the page's height could not be measured"
    done = chromium([f"--window-size={width},{height}", f"--screenshot={png}", page.resolve().as_uri()])
    if done.returncode != 0 or not png.is_file():
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise RuntimeError(f"chromium could not screenshot {page}: {last}")
    return note


def pdf_summary(pdf: Path) -> str:
    """Page count, page size and file size of ``pdf``, as pdfinfo reads them."""
    info = dict(line.split(":", 1) for line in
                subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True, check=True).stdout.splitlines()
                if ":" in line)
    size_mb = pdf.stat().st_size / 1e6
    return f"{info.get('Pages', '?').strip()} pages, {info.get('Page size', '?').strip()}, {size_mb:.2f} MB"


def first_page(pdf: Path, png: Path) -> None:
    """Page 1 of ``pdf`` at 80 dpi as ``png``."""
    subprocess.run(["pdftoppm", "-r", "80", "-f", "1", "-l", "1", "-png", "-singlefile", str(pdf),
                    str(png.with_suffix(""))], check=True, capture_output=True, timeout=TIMEOUT_S)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path, metavar="OUT_FOLDER",
                        help="A report bundle, or a folder with bundles beneath it.")
    parser.add_argument("--index", type=Path, help="An index page (index.html) to screenshot as well.")
    parser.add_argument("--to", type=Path, default=OUT / "look", help="Where the PNGs go.")
    args = parser.parse_args()
    for tool, package in (("chromium", "chromium"), ("pdftoppm", "poppler-utils"), ("pdfinfo", "poppler-utils")):
        if shutil.which(tool) is None:
            sys.exit(f"look.py: {tool} not found; install it with: apt-get install -y {package}")
    found = [b for folder in args.folders for b in bundles(folder)]
    if not found and args.index is None:
        sys.exit(f"look.py: no report.html or report.pdf in or under {', '.join(map(str, args.folders))}")
    if args.index is not None and not args.index.is_file():
        sys.exit(f"look.py: --index {args.index}: no such file")
    args.to.mkdir(parents=True, exist_ok=True)
    # Bundles are named after their photos, so two folders can share a name: the parent tells them apart.
    names = [b.name if [x.name for x in found].count(b.name) == 1 else f"{b.parent.name}_{b.name}" for b in found]
    for bundle, name in zip(found, names):
        print(bundle)
        pdf = bundle / "report.pdf"
        if pdf.is_file():
            png = args.to / f"{name}-pdf-page1.png"
            first_page(pdf, png)
            print(f"  {png}  (report.pdf: {pdf_summary(pdf)})")
        html = bundle / "report.html"
        if html.is_file():
            for width in WIDTHS:
                png = args.to / f"{name}-html-{width}.png"
                print(f"  {png}  ({screenshot(html, width, png)})")
    if args.index is not None:
        print(args.index)
        for width in WIDTHS:
            png = args.to / f"index-{width}.png"
            print(f"  {png}  ({screenshot(args.index, width, png)})")


if __name__ == "__main__":
    main()

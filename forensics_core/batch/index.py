"""``DIR/index.html``: the whole batch on one page, one row per photo, the strongest support for Hp first.

Each row shows a thumbnail, the photo's name, the evaluative statement and
the fused likelihood ratio (:func:`forensics_core.report.wording.statement`),
the screening line, the detectors that found something (each with its
finding's headline) and a relative link to the photo's report. Photos that
failed show their one-line reason.

The page is self-contained and safe to open from an untrusted output
folder: every image is a ``data:`` URL, nothing is fetched, and a
Content-Security-Policy allows only the page's own stylesheet and its one
small script (sorting by a column), by their SHA-256 hashes. Rows are
already sorted by the likelihood ratio, so the page is complete without
JavaScript. File names and detectors' text come from the evidence: they are
escaped by Jinja2's autoescape and shown with control and bidirectional
characters as escapes (:func:`forensics_core.text.visible`).

Thumbnails are decoded from the photos again (at a reduced JPEG scale) and
only when the file still has the bytes that were analysed; the photos are
only read.
"""

from __future__ import annotations

import base64
import hashlib
import io
import json
import os
import warnings
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np
from jinja2 import Environment, FunctionLoader, StrictUndefined, Template
from PIL import Image

from .. import __version__
from ..atomic import write_atomic
from ..evidence import ALLOWED_FORMATS
from ..findings import Findings
from ..manifest import FINDINGS_NAME, HTML_NAME, PDF_NAME
from ..report import images, wording
from ..report.render import template_text
from ..text import visible
from .plan import INDEX_HTML, SUMMARY_CSV, SUMMARY_JSON
from .resume import is_temp_name
from .summary import Row

TEMPLATE = "index.html.j2"
THUMB_SIDE = 160
"""Longest side of a thumbnail, pixels."""

_THUMB_QUALITY = 75
_THUMB_THREADS = 4
_DONE = ("analysed", "resumed", "duplicate")
_LINKED = (HTML_NAME, PDF_NAME, FINDINGS_NAME)
# Pillow's modes wider than 8 bits, shown by their type's range as the report shows them.
_WIDE_MODES = ("I", "I;16", "I;16B", "I;16L", "I;16N", "F")
# A sentence ends at . ! or ? before a capital, digit or bracket: "p = 0.01" and "e.g. the" do not end one.


@dataclass(frozen=True)
class BatchPhoto:
    """One input of the batch, as the index takes it.

    Attributes
    ----------
    path : Path
        The photo as found (its real name, which may hold bytes that are not UTF-8).
    row : Row
        Its line of the summary.
    folder : Path or None
        Its output folder, None when it has none (unreadable input).
    """

    path: Path
    row: Row
    folder: Path | None


@dataclass(frozen=True)
class Found:
    """A detector that found something, with its finding in one sentence."""

    detector: str
    headline: str


@dataclass
class IndexRow:
    """One row of the page; every text is shown as is (escaped) and nothing is marked safe.

    Attributes
    ----------
    name : str
        The photo's file name.
    path : str
        Its path as given to the batch.
    note : str or None
        What else to know (a duplicate, a row from an earlier run).
    statement : wording.Statement or None
        None for a photo that failed.
    log10_lr : float or None
        The fused log10 likelihood ratio, the page's sort key.
    label : str
        The screening's label (``consistent``, ``inconsistent``, ``inconclusive``), or ``failed``.
    screening : str or None
        The screening line.
    found : list of Found
    reason : str or None
        Why the photo failed, one line.
    href : str or None
        Relative, percent-encoded link to its report or findings.
    link_text : str or None
        The linked file's name.
    thumbnail : str or None
        A ``data:`` URL of a JPEG.
    thumb_size : tuple of int
        Its width and height.
    """

    name: str
    path: str
    note: str | None = None
    statement: wording.Statement | None = None
    log10_lr: float | None = None
    label: str = "failed"
    screening: str | None = None
    found: list[Found] = field(default_factory=list)
    reason: str | None = None
    href: str | None = None
    link_text: str | None = None
    thumbnail: str | None = None
    thumb_size: tuple[int, int] = (0, 0)

    @property
    def side(self) -> str:
        """``hp``, ``hd`` or ``none``: the side the statement's words support, for the row's colour."""
        side = self.statement.side if self.statement is not None else 0
        return {1: "hp", -1: "hd"}.get(side, "none")


def _one_line(text: str) -> str:
    return visible(" ".join(text.split()))


def found_by(findings: Findings) -> list[Found]:
    """The detectors that found something (:func:`~forensics_core.report.wording.found_something`), each with
    its finding in one sentence (:func:`~forensics_core.report.wording.row_sentence`)."""
    return [Found(visible(f.name), visible(" ".join(wording.row_sentence(f).split()))) for f in findings.detectors
            if wording.found_something(f, findings.verdict)]


def _read_findings(folder: Path) -> Findings:
    """The findings in ``folder``; OSError, ValueError, KeyError or TypeError when they cannot be read."""
    return Findings.from_dict(json.loads((folder / FINDINGS_NAME).read_bytes()))


def _link(out_dir: Path, folder: Path) -> tuple[str, str] | None:
    """The relative href of the folder's report (else its PDF, else its findings) and the file's name."""
    for name in _LINKED:
        if (folder / name).is_file():
            # Raw bytes of the name, percent-encoded: '#', '?', '%' and bytes that are not UTF-8 stay part of the path.
            relative = os.fsencode(folder.relative_to(out_dir))
            return f"{quote(relative, safe='/')}/{name}", name
    return None


def _finished_row(row: IndexRow, findings: Findings) -> None:
    verdict = findings.verdict
    row.statement = wording.statement(verdict)
    row.log10_lr = verdict.likelihood_ratio.log10_lr if verdict.likelihood_ratio is not None else None
    row.label = verdict.label.value
    row.screening = visible(wording.screening(verdict, where=False))
    row.found = found_by(findings)


def _photo_row(out_dir: Path, photo: BatchPhoto) -> tuple[IndexRow, Findings | None]:
    summary = photo.row
    row = IndexRow(name=visible(photo.path.name), path=visible(summary.photo))
    if summary.duplicate_of is not None:
        row.note = f"same bytes as {visible(summary.duplicate_of)}"
    findings = None
    if photo.folder is not None:
        try:
            findings = _read_findings(photo.folder)
        except (OSError, ValueError, KeyError, TypeError):
            findings = None
        # A folder may still hold an earlier photo's findings; only those of these bytes are linked.
        if findings is not None and findings.evidence.sha256 != summary.sha256:
            findings = None
        if findings is not None and (link := _link(out_dir, photo.folder)) is not None:
            row.href, row.link_text = link
    if summary.outcome in _DONE and findings is not None:
        _finished_row(row, findings)
    elif summary.outcome in _DONE:
        row.reason = f"cannot read {visible(str(photo.folder))}/{FINDINGS_NAME}"
    elif summary.outcome == "pending":
        row.reason = "not analysed: the batch was stopped before this photo was done"
    else:
        row.reason = _one_line(summary.error or "failed")
    return row, findings


def _earlier_rows(out_dir: Path, listed: Iterable[Path]) -> list[tuple[IndexRow, Findings]]:
    """Rows for the folders in ``out_dir`` that hold findings but no input of this run names (earlier runs).

    A link to a folder already listed (a duplicate's) adds nothing and is left out.
    """
    seen = {os.path.realpath(p) for p in listed}
    found = []
    try:
        entries = sorted(os.scandir(out_dir), key=lambda e: e.name)
    except OSError:
        return []
    for entry in entries:
        if entry.name.startswith(".") or is_temp_name(entry.name) or not entry.is_dir():
            continue
        folder = Path(entry.path)
        real = os.path.realpath(folder)
        if real in seen:
            continue
        try:
            findings = _read_findings(folder)
        except (OSError, ValueError, KeyError, TypeError):
            continue
        seen.add(real)
        ev = findings.evidence
        row = IndexRow(name=visible(ev.name), path=visible(ev.path),
                       note="from an earlier run: not among this run's inputs")
        _finished_row(row, findings)
        if (link := _link(out_dir, folder)) is not None:
            row.href, row.link_text = link
        found.append((row, findings))
    return found


def _small_image(img: Image.Image) -> Image.Image:
    if img.mode in _WIDE_MODES:
        return images.display_image(np.asarray(img), THUMB_SIDE)[0]
    img.thumbnail((THUMB_SIDE, THUMB_SIDE), Image.Resampling.LANCZOS, reducing_gap=2.0)
    return img.convert("RGB")


def thumbnail(photo: Path, sha256: str) -> tuple[str, tuple[int, int]] | None:
    """A JPEG ``data:`` URL of ``photo`` at most :data:`THUMB_SIDE` pixels long (stored grid, orientation not
    applied), and its size.

    Parameters
    ----------
    photo : Path
        Only read.
    sha256 : str
        The bytes that were analysed: a file that no longer has them gets no thumbnail, since it would show
        something other than what was examined.

    Returns
    -------
    tuple or None
        None when the file cannot be read, has other bytes, or does not decode.
    """
    try:
        data = photo.read_bytes()
    except OSError:
        return None
    if hashlib.sha256(data).hexdigest() != sha256:
        return None
    try:
        with Image.open(io.BytesIO(data), formats=ALLOWED_FORMATS) as img:
            # JPEG: decode at a reduced DCT scale, far cheaper than a full decode.
            img.draft("RGB", (THUMB_SIDE, THUMB_SIDE))
            small = _small_image(img)
        buffer = io.BytesIO()
        small.save(buffer, "JPEG", quality=_THUMB_QUALITY)
    # Any decoder's exception: a thumbnail that cannot be made costs the thumbnail only.
    except Exception:
        return None
    return f"data:image/jpeg;base64,{base64.b64encode(buffer.getvalue()).decode('ascii')}", small.size


def _add_thumbnails(rows: Sequence[tuple[IndexRow, Path, str]]) -> None:
    """Fill the rows' thumbnails from (row, photo, sha256), each distinct photo decoded once, a few at a time."""
    wanted = list(dict.fromkeys((path, sha) for _, path, sha in rows))
    # Pillow only warns between its pixel limit and twice that; a photo the batch took in is no bomb.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        with ThreadPoolExecutor(max_workers=_THUMB_THREADS) as pool:
            made = dict(zip(wanted, pool.map(lambda key: thumbnail(*key), wanted)))
    for row, path, sha in rows:
        if (thumb := made[path, sha]) is not None:
            row.thumbnail, row.thumb_size = thumb


def _sort_key(row: IndexRow) -> tuple[int, float, str]:
    if row.reason is not None:
        return 2, 0.0, row.name.casefold()
    if row.log10_lr is None:
        return 1, 0.0, row.name.casefold()
    return 0, -row.log10_lr, row.name.casefold()


def build_rows(out_dir: Path, photos: Sequence[BatchPhoto]) -> list[IndexRow]:
    """The page's rows: every input of the batch and every other folder of findings in ``out_dir``, sorted by the
    fused likelihood ratio (highest first), then photos without one, then failures.

    Parameters
    ----------
    out_dir : Path
        The batch's output folder.
    photos : sequence of BatchPhoto
        The batch's inputs, in any order.
    """
    rows = []
    to_draw: list[tuple[IndexRow, Path, str]] = []
    for photo in photos:
        row, findings = _photo_row(out_dir, photo)
        rows.append(row)
        if row.reason is None and findings is not None:
            to_draw.append((row, photo.path, findings.evidence.sha256))
    for row, findings in _earlier_rows(out_dir, [p.folder for p in photos if p.folder is not None]):
        rows.append(row)
        to_draw.append((row, Path(findings.evidence.path), findings.evidence.sha256))
    _add_thumbnails(to_draw)
    return sorted(rows, key=_sort_key)


def _environment() -> Environment:
    # The project's own template, autoescaped like the report's: nothing from the evidence is marked safe.
    return Environment(loader=FunctionLoader(template_text), autoescape=True, undefined=StrictUndefined,
                       trim_blocks=True, lstrip_blocks=True)


def _block(template: Template, name: str) -> str:
    """The text of one of the template's blocks, exactly as the page will carry it."""
    return "".join(template.blocks[name](template.new_context({})))


def _digest(text: str) -> str:
    return "sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii")


def csp(script: str, style: str) -> str:
    """The page's Content-Security-Policy: this script and this stylesheet, images inline, nothing fetched.

    Parameters
    ----------
    script, style : str
        The exact text of the page's ``<script>`` and ``<style>`` elements.
    """
    return (f"script-src '{_digest(script)}'; style-src '{_digest(style)}'; default-src 'none'; img-src data:; "
            f"base-uri 'none'; form-action 'none'")


def render_index(out_dir: Path, rows: Sequence[IndexRow], created: str | None = None) -> str:
    """The page's HTML.

    Parameters
    ----------
    out_dir : Path
        The batch's output folder, named in the title.
    rows : sequence of IndexRow
        In the order shown.
    created : str or None
        The page's date as printed; default now, as ``2024-05-01 10:00:00 UTC``.
    """
    template = _environment().get_template(TEMPLATE)
    script, style = _block(template, "script"), _block(template, "style")
    failed = sum(r.reason is not None for r in rows)
    context: dict[str, Any] = {
        "csp": csp(script, style),
        "title": visible(out_dir.name or str(out_dir)),
        "created": created or datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "version": __version__,
        "rows": rows,
        "counts": {"photos": len(rows), "failed": failed, "examined": len(rows) - failed},
        "summary_csv": SUMMARY_CSV if (out_dir / SUMMARY_CSV).is_file() else None,
        "summary_json": SUMMARY_JSON if (out_dir / SUMMARY_JSON).is_file() else None,
    }
    return template.render(context)


def write_index(out_dir: Path, photos: Sequence[BatchPhoto]) -> Path:
    """Write ``out_dir/index.html`` atomically; see :mod:`forensics_core.batch.index`.

    Parameters
    ----------
    out_dir : Path
    photos : sequence of BatchPhoto
        Every input of the batch; the page also lists other folders of findings already in ``out_dir``.

    Returns
    -------
    Path
        The page.
    """
    return write_atomic(out_dir / INDEX_HTML, render_index(out_dir, build_rows(out_dir, photos)).encode("utf-8"))

"""The report's HTML laid out as a PDF by WeasyPrint, loading nothing but what the safe fetcher allows."""

from __future__ import annotations

import logging
from importlib.resources import as_file, files
from pathlib import Path

from .. import templates
from .fetcher import SafeFetcher
from .weasy import weasyprint


def lay_out(html: str) -> tuple[bytes, list[str]]:
    """Lay out ``html`` as a PDF (print media): the PDF, and the URLs the fetcher refused.

    WeasyPrint's own messages are kept out of the user's terminal.
    """
    with as_file(files(templates)) as assets:
        fetcher = SafeFetcher(Path(assets))
        logger = logging.getLogger("weasyprint")
        previous = logger.propagate
        logger.propagate = False
        try:
            pdf = weasyprint.HTML(string=html, url_fetcher=fetcher, media_type="print").write_pdf()
        finally:
            logger.propagate = previous
    return pdf, list(fetcher.refused)

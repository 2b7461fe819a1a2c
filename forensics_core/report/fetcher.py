"""The only way the PDF renderer may load a resource: ``data:`` URLs and the project's own template assets.

WeasyPrint fetches whatever the HTML names (images, stylesheets, fonts,
``<link rel="attachment">`` files to embed in the PDF). Evidence text is
escaped before it reaches the HTML, so it cannot name anything; this fetcher
is the second wall: a plugin template or an SVG figure that names
``file:///etc/passwd`` or a web address gets nothing.

A refusal is an ordinary exception, so WeasyPrint leaves the resource out
and carries on (one bad figure must not take the report down); every refused
URL is kept in :attr:`SafeFetcher.refused` for the caller to report. It
must not derive from WeasyPrint's ``FatalURLFetchingError``, a
``BaseException`` that would escape ``except Exception`` handlers.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote, urlsplit

from .weasy import URLFetcher, URLFetcherResponse


class RefusedURL(ValueError):
    """A resource outside what the report may load."""


class SafeFetcher(URLFetcher):
    """Fetch ``data:`` URLs, and ``file:`` URLs only inside ``assets_dir``.

    Parameters
    ----------
    assets_dir : Path or None
        The folder of the report templates; None allows no file at all.
    """

    def __init__(self, assets_dir: Path | None = None):
        super().__init__(allowed_protocols=("data",), allow_redirects=False, fail_on_errors=False)
        self._assets = assets_dir.resolve() if assets_dir is not None else None
        self.refused: list[str] = []

    def fetch(self, url: str, headers=None) -> URLFetcherResponse:
        scheme = url.split(":", 1)[0].lower() if ":" in url else ""
        if scheme == "data":
            return super().fetch(url, headers)
        if scheme == "file" and self._assets is not None:
            path = Path(unquote(urlsplit(url).path)).resolve()
            if path.is_file() and path.is_relative_to(self._assets):
                return URLFetcherResponse(url, body=path.read_bytes())
        self.refused.append(url)
        raise RefusedURL(f"the report may load only data: URLs and its own template assets, not {url[:80]!r}")

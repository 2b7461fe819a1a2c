"""The programs an XMP packet names: the creator tool and the editing history.

Adobe software and many others record themselves in XMP (ISO 16684-1):
``xmp:CreatorTool`` (the program that made the file; older files use the
``xap`` prefix) and, per saving step, ``stEvt:softwareAgent`` in the
``xmpMM:History`` sequence. Cameras write neither or their firmware. The
packet is read as Pillow exposes it (``Image.info["xmp"]`` for JPEG, PNG,
WebP) and searched with regular expressions rather than parsed as XML, so no
entity or external reference in hostile evidence is ever resolved.
"""

from __future__ import annotations

import contextlib
import html
import io
import re
from collections.abc import Callable

from PIL import Image

# Attribute form (tool="...") and element form (<tool>...</tool>), any prefix. The attribute form starts at the
# name itself: an optional "\w+:" before it would be tried, and backtracked, at every position of a long token,
# which made one 64 KB word take 10 s (quadratic); the element form's prefix is bounded.
_AGENT = re.compile(
    rb"""(CreatorTool|softwareAgent)\s*=\s*(?:"([^"]{0,200})"|'([^']{0,200})')"""
    rb"""|<(?:\w{1,64}:)?(CreatorTool|softwareAgent)>([^<]{0,200})</""")
_MAX_AGENTS = 50


def xmp_agents(data: bytes, decoding: Callable = contextlib.nullcontext) -> list[tuple[str, str]]:
    """The distinct programs the file's XMP names, in order of appearance.

    Parameters
    ----------
    data : bytes
        The evidence file (read, never written).
    decoding : callable
        Context manager under which Pillow opens it
        (:meth:`forensics_core.Evidence.decoding`: the user's pixel limit,
        not Pillow's default).

    Returns
    -------
    list of (str, str)
        ``("creator", name)`` for ``CreatorTool``, ``("history", name)`` for a
        history ``softwareAgent``; at most ``_MAX_AGENTS``, empty when there is
        no readable XMP.
    """
    try:
        with decoding(), Image.open(io.BytesIO(data)) as img:
            packet = img.info.get("xmp") or b""
    except (OSError, ValueError, SyntaxError, EOFError, Image.DecompressionBombError):
        return []
    if isinstance(packet, str):
        packet = packet.encode("utf-8", "replace")
    agents: list[tuple[str, str]] = []
    for match in _AGENT.finditer(packet):
        tag = match.group(1) or match.group(4)
        raw = next(g for g in (match.group(2), match.group(3), match.group(5)) if g is not None)
        entry = ("creator" if tag == b"CreatorTool" else "history",
                 html.unescape(raw.decode("utf-8", "replace")).strip())
        if entry[1] and entry not in agents:
            agents.append(entry)
        if len(agents) >= _MAX_AGENTS:
            break
    return agents

"""Text from evidence (file names, metadata) made safe to show on a terminal or in a report."""

from __future__ import annotations


def visible(text: str) -> str:
    """``text`` with control and format characters shown as escapes instead of acting.

    Escape sequences would drive a terminal, a newline would split a result
    line, and a bidirectional override (U+202E) makes ``photo\\u202egpj.exe``
    read as ``photoexe.jpg``; each becomes ``\\xNN`` or ``\\uNNNN``.
    """
    return "".join(c if c.isprintable() else (f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}")
                   for c in text)

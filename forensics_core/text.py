"""Text from evidence (file names, metadata) made safe to show on a terminal or in a report."""

from __future__ import annotations

# Python holds each byte of a file name that is not UTF-8 as a lone
# surrogate, U+DC80 to U+DCFF for the bytes 0x80 to 0xFF (PEP 383).
_ESCAPED_BYTES = range(0xDC80, 0xDD00)


def _escaped(c: str) -> str:
    if ord(c) in _ESCAPED_BYTES:
        return f"\\x{ord(c) - 0xDC00:02x}"
    return f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}"


def visible(text: str) -> str:
    """``text`` with control and format characters shown as escapes instead of acting.

    Escape sequences would drive a terminal, a newline would split a result
    line, and a bidirectional override (U+202E) makes ``photo\\u202egpj.exe``
    read as ``photoexe.jpg``; each becomes ``\\xNN`` or ``\\uNNNN``. A byte
    of a file name that is not UTF-8 is shown as ``\\xNN`` too.
    """
    return "".join(c if c.isprintable() else _escaped(c) for c in text)


def decoded(name: str) -> str:
    """A file name or path as text that any file format can hold: its bytes that are not UTF-8 as ``\\xNN``.

    A name written on another system (Latin-1 ``Caf\\xe9.jpg`` from an
    unpacked archive) is a valid file name here, but text with its bytes
    (lone surrogates, PEP 383) cannot be written as UTF-8 JSON, HTML or PDF.
    Any other name is returned unchanged.
    """
    if not undecodable(name):
        return name
    return "".join(_escaped(c) if ord(c) in _ESCAPED_BYTES else c for c in name)


def undecodable(text: str) -> bool:
    """Whether ``text`` holds bytes that were not UTF-8 (a file name, an argument typed in another encoding)."""
    return any(ord(c) in _ESCAPED_BYTES for c in text)

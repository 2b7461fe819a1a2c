"""Files the tool reads besides the evidence: regular files only, read with a size limit.

A bundle's manifest and signature, its findings and PDF, certificates, keys
and trust stores come from wherever the user or a bundle points. A FIFO
would hang the read and a device such as ``/dev/zero`` would fill the
memory, so each file is opened without blocking, checked to be a regular
file on the open descriptor (no window between the check and the read in
which it could be swapped), and read up to its limit.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

#: Limits, bytes, by kind of file: far above any the tool writes, far below what exhausts the memory.
SMALL = 1 << 20
"""Certificates, keys, signatures."""
MANIFEST = 64 << 20
DOCUMENT = 1 << 30
"""findings.json and report.pdf."""


class FileRefused(OSError):
    """A file that is not a regular file or exceeds its limit; ``str()`` is one line for the user."""


def read_limited(path: Path, limit: int) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes.

    Raises
    ------
    FileRefused
        When it is a FIFO, a device, a socket or a directory, or larger than ``limit``.
    OSError
        When it cannot be opened (missing, no permission, name too long).
    """
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise FileRefused(f"{path} is not a regular file")
        if st.st_size > limit:
            raise FileRefused(f"{path} has {st.st_size:,} bytes, more than the {limit:,} accepted")
        data = f.read(limit + 1)
    if len(data) > limit:
        raise FileRefused(f"{path} grew beyond the {limit:,} bytes accepted while it was read")
    return data

"""Helpers on processes for tests that stop or kill commands (imported by tests as ``processes``)."""

from pathlib import Path


def alive(pid: int) -> bool:
    """Running, not merely waiting to be reaped (a zombie)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in status

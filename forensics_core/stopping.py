"""Ctrl-C and SIGTERM: raised where the command is, and recorded, so that a lost exception still stops it.

Python raises ``KeyboardInterrupt`` at whatever line runs when the signal
arrives. Where that line is inside code that swallows exceptions (C code
calling back into Python and clearing the error, a finaliser, an at-fork
callback), the exception is gone and the command goes on to exit 0 as if no
one had asked it to stop: a script, or a scheduler that sent SIGTERM, would
take the run for a finished one. The handlers here therefore also record the
signal, and :func:`check` raises it again at the places where stopping is
safe (between photos, before a photo's outputs are written, at the end of
the command).
"""

from __future__ import annotations

import os
import signal

_received: list[int] = []
_installed = False


class Terminated(BaseException):
    """SIGTERM (a scheduler, ``timeout``, ``docker stop``), met as Ctrl-C is: what is running is stopped, what is
    finished is kept (a batch writes its summary).

    Python's default for SIGTERM ends the process at once: detector children
    were left running. Not a ``KeyboardInterrupt``: CPython ends a process in
    which one was raised inside ``exec`` (as dataclasses and plugins' imports
    do) by SIGINT, whatever status it then exits with.
    """


def _interrupt(signum, frame) -> None:
    _received.append(signum)
    raise KeyboardInterrupt


def _terminate(signum, frame) -> None:
    # A scheduler may send SIGTERM again while the first is being handled: raised inside that handling, it
    # escaped as a traceback, and arriving once Python had restored the default handler at exit, it killed the
    # process. The command is already stopping, so later ones are ignored (SIGKILL still ends it).
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    _received.append(signum)
    raise Terminated()


def _in_child() -> None:
    # A forked detector or worker is ended by its parent, which may use
    # SIGTERM (multiprocessing does at exit): there SIGTERM must end it. What
    # the parent was asked before the fork is the parent's to answer.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _received.clear()


def install() -> None:
    """Handle Ctrl-C and SIGTERM as described above; a signal the caller ignores (``nohup``) stays ignored.

    Only where the platform forks (``os.register_at_fork``), as the rest of
    containment assumes.
    """
    global _installed
    if not hasattr(os, "register_at_fork") or _installed:
        return
    _installed = True
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _interrupt)
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminate)
    os.register_at_fork(after_in_child=_in_child)


def check() -> None:
    """Raise ``KeyboardInterrupt`` or :class:`Terminated` again if Ctrl-C or SIGTERM came, whether or not it was lost."""
    if signal.SIGTERM in _received:
        raise Terminated()
    if _received:
        raise KeyboardInterrupt

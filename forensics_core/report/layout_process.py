"""The PDF's layout in a process of its own, started before the detectors run.

Importing WeasyPrint and its first layout (fontconfig, Pango's font map, the
fonts read from disk) cost about 0.5 s before the report's own pages are laid
out (the bundled camera photo's PDF: 1.67 s laid out cold in the command,
1.13 s warm; benchmarks/report_stages.py). The detectors seldom keep every
core busy, so a layout process forked when a photo's analysis starts spends
that time while they run, and the report, once its HTML is made, is laid out
warm. The process is kept for the photos that follow (``batch``), and started
again if it ended.

With it, the analysing process never imports WeasyPrint: the detectors it
forks do not inherit Pango's state, and a crash in the layout costs that
photo's report, not the run. Where it cannot be started, the PDF is laid out
in the analysing process, as before.
"""

from __future__ import annotations

import faulthandler
import gc
import multiprocessing
import os
import signal
import sys
import threading
from typing import Any

from ..containment import can_fork, die_with_parent, one_line, signals_held

LAYOUT_TIMEOUT_S = 600.0
"""A report that takes longer than this to lay out is given up: a hung layout must not hold the run for ever."""

#: Loads the report's fonts (its stylesheet names these first) and sets up fontconfig and Pango.
_WARM_UP = ('<html><body style="font-family: \'DejaVu Sans\'"><h1>Warm-up</h1><p>Text <b>bold</b> <i>italic</i> '
            '<code style="font-family: \'DejaVu Sans Mono\'">mono</code></p><table><tr><th>a</th><td>b</td></tr>'
            '</table></body></html>')


class LayoutError(RuntimeError):
    """The layout process failed on a report, or ended; the message is one line."""


def _serve(conn: Any, parent: int) -> None:
    die_with_parent(parent)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    # Ctrl-C is the analysing process's to handle; this process ends with it.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    faulthandler.disable()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    from .pdf import lay_out

    lay_out(_WARM_UP)
    while True:
        try:
            html = conn.recv()
        except (EOFError, OSError):
            return
        try:
            conn.send(("value", lay_out(html)))
        except BaseException as exc:  # the caller reports it for this photo; the process serves the next one
            conn.send(("error", one_line(exc)))


class LayoutProcess:
    """A warm WeasyPrint in a forked child: :meth:`lay_out` sends a report's HTML and returns its PDF.

    Started on creation. Calls from several threads take turns.
    """

    def __init__(self) -> None:
        ctx = multiprocessing.get_context("fork")
        self._conn, child_end = ctx.Pipe(duplex=True)
        self._proc = ctx.Process(target=_serve, args=(child_end, os.getpid()), daemon=True)
        self._lock = threading.Lock()
        sys.stdout.flush()
        sys.stderr.flush()
        gc.freeze()
        try:
            with signals_held():
                self._proc.start()
        finally:
            gc.unfreeze()
            child_end.close()

    def alive(self) -> bool:
        return self._proc.is_alive()

    @property
    def pid(self) -> int | None:
        return self._proc.pid

    def lay_out(self, html: str, timeout_s: float = LAYOUT_TIMEOUT_S) -> tuple[bytes, list[str]]:
        """The PDF of ``html`` and the URLs the renderer refused, as :func:`.pdf.lay_out` gives them.

        Raises
        ------
        LayoutError
            When the layout raised, exceeded ``timeout_s`` or the process ended.
        """
        with self._lock:
            try:
                self._conn.send(html)
                if not self._conn.poll(timeout_s):
                    self.close()
                    raise LayoutError(f"the PDF layout took longer than {timeout_s:g} s")
                outcome = self._conn.recv()
            except (EOFError, OSError):
                self.close()
                raise LayoutError(f"the PDF layout process ended (exit code {self._proc.exitcode})") from None
        if outcome[0] == "error":
            raise LayoutError(f"the PDF layout failed: {outcome[1]}")
        return outcome[1]

    def close(self) -> None:
        self._conn.close()
        if self._proc.is_alive():
            self._proc.kill()
        self._proc.join(5)


_shared: LayoutProcess | None = None
_shared_lock = threading.Lock()


def started() -> LayoutProcess | None:
    """This process's layout process, started now if there is none running.

    None where it cannot be started (no ``fork``; a daemonic process, such as a
    Dask worker running detectors inline, may have no children; no resources):
    the PDF is then laid out in this process, as before.
    """
    global _shared
    if not can_fork():
        return None
    with _shared_lock:
        if _shared is None or not _shared.alive():
            try:
                _shared = LayoutProcess()
            except (AssertionError, OSError):
                _shared = None
        return _shared

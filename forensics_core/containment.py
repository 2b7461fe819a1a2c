"""Running plugin code contained: a forked child with a time limit, its output kept, its crash reported.

A hang is ended at the time limit, a crash (even ``os._exit`` or a segfault
in a C library) costs only that call, and whatever the code prints goes into
the result instead of onto the user's terminal. Where ``fork`` is
unavailable, a daemon thread with a time limit is the fallback.
"""

from __future__ import annotations

import faulthandler
import multiprocessing
import os
import sys
import tempfile
import threading
import traceback
from collections.abc import Callable
from typing import Any



class PluginFault(Exception):
    """A contained call that failed in its child (it raised, timed out or died); the message is already one line."""


def one_line(exc: BaseException) -> str:
    """``Type: message`` on one line, for findings and the terminal."""
    text = " ".join(str(exc).split())
    if isinstance(exc, PluginFault):
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def can_fork() -> bool:
    """Whether this platform can run calls in forked children."""
    return "fork" in multiprocessing.get_all_start_methods()


OUTPUT_LIMIT = 4000


def _child(call: Callable[[], Any], conn, sink: int) -> None:
    # A crash of the detector is reported in its finding; an inherited fault
    # handler would also dump the interpreter's state onto the user's terminal.
    faulthandler.disable()
    # What the detector or its libraries print (Python or C) goes to the
    # finding, not to the terminal the user reads one line per photo on.
    os.dup2(sink, 1)
    os.dup2(sink, 2)
    sys.stdout = open(1, "w", encoding="utf-8", errors="replace", closefd=False)
    sys.stderr = open(2, "w", encoding="utf-8", errors="replace", closefd=False)
    try:
        # One BLAS/OpenMP thread: a detector is one of several processes on
        # the machine's cores, and OpenBLAS threads spinning against each
        # other once made the cfa detector 400 times slower on a loaded machine.
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1):
            outcome = ("value", call())
    except BaseException as exc:
        outcome = ("error", one_line(exc), traceback.format_exc())
    try:
        conn.send(outcome)
    except Exception as exc:
        conn.send(("error", f"result could not be passed back: {one_line(exc)}", ""))
    finally:
        conn.close()


def run_forked(call: Callable[[], Any], timeout_s: float) -> tuple[tuple, str | None]:
    """The child's outcome, and what it printed (None when nothing)."""
    ctx = multiprocessing.get_context("fork")
    receiver, sender = ctx.Pipe(duplex=False)
    sys.stdout.flush()
    sys.stderr.flush()
    with tempfile.TemporaryFile() as sink:
        proc = ctx.Process(target=_child, args=(call, sender, sink.fileno()), daemon=True)
        proc.start()
        sender.close()
        try:
            if not receiver.poll(timeout_s):
                proc.kill()
                outcome: tuple = ("error", f"timed out after {timeout_s:g} s", "")
            else:
                try:
                    outcome = receiver.recv()
                except EOFError:
                    proc.join(5)
                    outcome = ("error", f"detector process died (exit code {proc.exitcode})", "")
        finally:
            receiver.close()
            proc.join(5)
            if proc.is_alive():
                proc.kill()
                proc.join()
        size = os.fstat(sink.fileno()).st_size
        sink.seek(0)
        text = sink.read(OUTPUT_LIMIT).decode("utf-8", "replace")
    if size > OUTPUT_LIMIT:
        text += f"... ({size:,} bytes in all)"
    return outcome, text or None


def run_threaded(call: Callable[[], Any], timeout_s: float) -> tuple:
    box: list[tuple] = []

    def target() -> None:
        try:
            box.append(("value", call()))
        except BaseException as exc:
            box.append(("error", one_line(exc), traceback.format_exc()))

    worker = threading.Thread(target=target, daemon=True, name="forensics-detector")
    worker.start()
    worker.join(timeout_s)
    if worker.is_alive():
        return ("error", f"timed out after {timeout_s:g} s (still running in the background)", "")
    return box[0]

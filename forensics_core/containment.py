"""Running plugin code contained: a forked child with a time limit, its output kept, its crash reported.

A hang is ended at the time limit, a crash (even ``os._exit`` or a segfault
in a C library) costs only that call, and whatever the code prints goes into
the result instead of onto the user's terminal. Where ``fork`` is
unavailable, a daemon thread with a time limit is the fallback.
"""

from __future__ import annotations

import ctypes
import faulthandler
import gc
import multiprocessing
import os
import signal
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable, Collection, Iterator
from contextlib import contextmanager
from multiprocessing.connection import wait
from typing import Any

from .defaults import PARALLEL_MAX_PIXELS


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
_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


HELD_SIGNALS = frozenset({signal.SIGINT, signal.SIGTERM})
"""What :func:`signals_held` holds back while a process forks."""


@contextmanager
def signals_held() -> Iterator[None]:
    """Fork inside this: Ctrl-C and SIGTERM wait until the fork is done.

    Arriving during a fork, their exception is raised in an at-fork callback
    (logging's lock), where Python prints it and drops it: the command went
    on as if no one had asked it to stop. The child starts with them held
    and releases them itself (``signal.pthread_sigmask(signal.SIG_UNBLOCK,
    HELD_SIGNALS)``); a signal that came meanwhile is the parent's.
    """
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, HELD_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def die_with_parent(parent: int) -> None:
    """Have the kernel end this child when the process that forked it ends (Linux; elsewhere nothing).

    A parent killed outright (SIGKILL, the out-of-memory killer) cannot end
    its children. They would then wait for ever: each holds, inherited, the
    reading end of the others' result pipes, so a result larger than a pipe
    holds never finishes being sent.
    """
    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return
    prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # it ended before the request was made
        os._exit(1)


def _child(call: Callable[[], Any], conn, sink: int, parent: int) -> None:
    die_with_parent(parent)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, HELD_SIGNALS)
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


class Child:
    """A call running in a forked child, with its time limit; started on creation.

    Several may run at once: :func:`wait_any` tells which have finished, and
    :meth:`collect` takes each one's outcome. The parent stays single-threaded
    while it forks, so no child inherits a lock another thread holds.
    """

    def __init__(self, call: Callable[[], Any], timeout_s: float) -> None:
        ctx = multiprocessing.get_context("fork")
        self.timeout_s = timeout_s
        self.receiver, sender = ctx.Pipe(duplex=False)
        sys.stdout.flush()
        sys.stderr.flush()
        self._sink = tempfile.TemporaryFile()
        self._proc = ctx.Process(target=_child, args=(call, sender, self._sink.fileno(), os.getpid()), daemon=True)
        # The child's garbage collector would otherwise walk, and so copy, every
        # page of objects it shares with the parent; frozen, they are skipped
        # there, and the parent takes them back at once.
        gc.freeze()
        try:
            with signals_held():
                self._proc.start()
        except BaseException:
            self.receiver.close()
            self._sink.close()
            raise
        finally:
            gc.unfreeze()
            # Only the child may hold the sending end: its death must read as
            # end-of-file here, which it would not if a later child inherited it.
            sender.close()
        self.started = time.monotonic()

    @property
    def deadline(self) -> float:
        """When the time limit ends, on :func:`time.monotonic`'s clock."""
        return self.started + self.timeout_s

    def wait(self) -> tuple[tuple, str | None]:
        """Wait for this child alone, then :meth:`collect` it."""
        self.receiver.poll(max(0.0, self.deadline - time.monotonic()))
        return self.collect()

    def collect(self) -> tuple[tuple, str | None]:
        """The child's outcome, and what it printed (None when nothing); a child still running is killed."""
        try:
            if not self.receiver.poll(0):
                self._proc.kill()
                outcome: tuple = ("error", f"timed out after {self.timeout_s:g} s", "")
            else:
                try:
                    outcome = self.receiver.recv()
                except EOFError:
                    self._proc.join(5)
                    outcome = ("error", f"detector process died (exit code {self._proc.exitcode})", "")
        finally:
            self.receiver.close()
            self._proc.join(5)
            if self._proc.is_alive():
                self._proc.kill()
                self._proc.join()
        with self._sink as sink:
            size = os.fstat(sink.fileno()).st_size
            sink.seek(0)
            text = sink.read(OUTPUT_LIMIT).decode("utf-8", "replace")
        if size > OUTPUT_LIMIT:
            text += f"... ({size:,} bytes in all)"
        return outcome, text or None


def wait_any(children: Collection[Child]) -> list[Child]:
    """The children that have finished or reached their time limit, waiting until there is at least one."""
    while True:
        now = time.monotonic()
        late = [c for c in children if c.deadline <= now]
        ready = wait([c.receiver for c in children], timeout=0 if late else min(c.deadline for c in children) - now)
        done = [c for c in children if c.receiver in ready or c.deadline <= time.monotonic()]
        if done:
            return done


def jobs_for(n_pixels: int, jobs: int) -> int:
    """How many contained calls run at once on a photo of ``n_pixels``.

    ``jobs``, or one where the platform cannot fork or the photo is larger
    than :data:`~forensics_core.defaults.PARALLEL_MAX_PIXELS`.
    """
    if not can_fork() or n_pixels > PARALLEL_MAX_PIXELS:
        return 1
    return max(1, jobs)


def run_forked(call: Callable[[], Any], timeout_s: float) -> tuple[tuple, str | None]:
    """The child's outcome, and what it printed (None when nothing)."""
    return Child(call, timeout_s).wait()


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

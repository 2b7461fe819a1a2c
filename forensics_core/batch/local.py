"""Local worker processes: one photo at a time each, a dead worker costs only its photo.

Workers are forked from the command once its plugins and key are loaded and
stay for the whole batch. The command knows which photo each worker holds,
so when one dies (killed, out of memory, a crash in native code) exactly that
photo is charged: it goes back to the end of the queue once, and the second
death makes it a failure. A new worker takes the dead one's place.

Each worker leads its own process group (with its detector children) and
watches a "lifeline" pipe whose writing end only the command holds: when the
command dies, even by SIGKILL, the pipe reads end-of-file and the worker
kills its group, so no orphan goes on writing into the output folder.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait

from ..containment import HELD_SIGNALS, signals_held
from .plan import Job
from .work import PhotoOutcome, Settings, process_photo

MAX_ATTEMPTS = 2
"""A photo whose worker died is tried again once."""
IDLE_S = 0.5
"""How often ``on_idle`` is called while every worker is busy."""


@dataclass(frozen=True)
class Finished:
    """A photo the pool is done with: its outcome and how many workers it took (None: not known)."""

    job: Job
    outcome: PhotoOutcome
    attempts: int | None


def _watch_lifeline(fd: int) -> None:
    while os.read(fd, 1):
        pass
    os.killpg(os.getpgrp(), signal.SIGKILL)


def _worker_main(conn: Connection, lifeline_read: int, lifeline_write: int, settings: Settings) -> None:
    signal.pthread_sigmask(signal.SIG_UNBLOCK, HELD_SIGNALS)
    os.close(lifeline_write)
    # Its own group keeps the terminal's Ctrl-C for the command, which then
    # stops the workers itself; and lets the lifeline end detector children too.
    os.setpgid(0, 0)
    threading.Thread(target=_watch_lifeline, args=(lifeline_read,), daemon=True, name="lifeline").start()
    while True:
        try:
            job = conn.recv()
        except EOFError:
            return
        if job is None:
            return
        conn.send(process_photo(job, settings))


def _death(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        hint = " (out of memory?)" if -exitcode == signal.SIGKILL else ""
        return f"killed by {name}{hint}"
    return f"exited with status {exitcode}"


class _Worker:
    def __init__(self, ctx, lifeline: tuple[int, int], settings: Settings):
        self.conn, child_conn = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_main, args=(child_conn, *lifeline, settings), name="forensics-batch")
        with signals_held():
            self.proc.start()
        child_conn.close()
        # Set here too, so that the group exists whichever of the two runs first.
        try:
            os.setpgid(self.proc.pid, self.proc.pid)
        except OSError:
            pass
        self.job: Job | None = None

    def kill(self) -> None:
        """End the worker and any detector child it left; safe on a worker that already died.

        The group is signalled before the worker is reaped: until then its
        process id, and so the group's, cannot be given to another process.
        """
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            self.proc.kill()
        self.proc.join()
        self.conn.close()


class LocalPool:
    """``workers`` forked worker processes, used as a context manager.

    Parameters
    ----------
    workers : int
    settings : Settings
        What every photo is analysed with; the plugins and the key are those
        set by :func:`forensics_core.batch.work.preload` before the pool starts.
    """

    def __init__(self, workers: int, settings: Settings):
        self.size = max(1, workers)
        self.settings = settings
        self._ctx = multiprocessing.get_context("fork")
        self._workers: list[_Worker] = []
        self._lifeline: tuple[int, int] | None = None

    def __enter__(self) -> LocalPool:
        self._lifeline = os.pipe()
        return self

    def __exit__(self, *exc) -> None:
        for worker in self._workers:
            if exc[0] is None:
                try:
                    worker.conn.send(None)
                except OSError:
                    pass
                worker.proc.join(10)
                if worker.proc.exitcode is not None:  # ended on its own, and reaped: its id may be reused
                    worker.conn.close()
                    continue
            worker.kill()
        self._workers.clear()
        if self._lifeline is not None:
            for fd in self._lifeline:
                os.close(fd)
            self._lifeline = None

    def describe(self) -> str:
        return f"{self.size} local worker process{'es' if self.size != 1 else ''}"

    def run(self, jobs: Sequence[Job], on_idle: Callable[[], None] | None = None) -> Iterator[Finished]:
        """Analyse ``jobs``; yield each as it is finished, in completion order.

        ``on_idle`` is called every :data:`IDLE_S` seconds without news (the
        progress display refreshes from this thread: a second thread in this
        process would be forked into new workers in whatever state it was).
        """
        pending = deque(jobs)
        attempts: dict[Job, int] = {}
        while pending or any(w.job is not None for w in self._workers):
            while pending and len(self._workers) < min(self.size, len(pending) + self._busy()):
                self._workers.append(_Worker(self._ctx, self._lifeline, self.settings))
            for worker in self._workers:
                if worker.job is None and pending:
                    job = pending.popleft()
                    try:
                        worker.conn.send(job)
                    except OSError:
                        pending.appendleft(job)
                        continue
                    worker.job = job
                    attempts[job] = attempts.get(job, 0) + 1
            ready = set(wait([w.conn for w in self._workers if w.job is not None]
                             + [w.proc.sentinel for w in self._workers], timeout=IDLE_S))
            if not ready and on_idle is not None:
                on_idle()
            for worker in list(self._workers):
                if worker.conn in ready:
                    try:
                        outcome = worker.conn.recv()
                    except (EOFError, OSError):
                        pass  # it died: handled below
                    else:
                        job, worker.job = worker.job, None
                        yield Finished(job, outcome, attempts[job])
                        continue
                elif worker.proc.sentinel not in ready:
                    continue
                worker.kill()
                self._workers.remove(worker)
                job = worker.job
                if job is None:
                    continue
                if attempts[job] < MAX_ATTEMPTS:
                    pending.append(job)
                else:
                    reason = (f"the worker analysing it died {attempts[job]} times; the last was "
                              f"{_death(worker.proc.exitcode)}")
                    yield Finished(job, PhotoOutcome(error=reason), attempts[job])

    def _busy(self) -> int:
        return sum(w.job is not None for w in self._workers)

"""The same work on an existing Dask distributed cluster (``--scheduler tcp://HOST:PORT``).

Assumption: the command and every worker see the inputs, the output folder
and the signing key under the same paths (a shared file system), and every
worker has forensics and the same plugins installed. Only the job (paths and
the hash) and the settings travel; workers read the photos and write the
outputs themselves, and load the signing key from its path with the password
from their own environment (``FORENSICS_KEY_PASSWORD``), so no private key
crosses the network.

A photo whose worker dies is rescheduled by the cluster itself, up to the
scheduler's ``distributed.scheduler.allowed-failures`` times, then recorded
as failed. The cluster charges every task the dead worker held, so for the
local workers' behaviour (only the photo that killed the worker is charged,
and it is retried once) start workers with one thread each (``dask worker
--nthreads 1 --nworkers N``: a photo's detectors fork children, which
threads make unsafe anyway) and the scheduler with
``DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES=1`` and
``DASK_DISTRIBUTED__SCHEDULER__WORKER_SATURATION=1.0`` (no task queued on a
busy worker). A finished photo whose result was lost with its worker is
computed again; its outputs are rewritten whole.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Sequence

from ..plugins import one_line
from .local import IDLE_S, Finished
from .plan import Job
from .work import PhotoOutcome, Settings, process_photo

CONNECT_TIMEOUT_S = 20


class ClusterError(Exception):
    """The scheduler cannot be reached; the message is one line."""


class DaskPool:
    """Run the photos as tasks on the cluster whose scheduler is at ``address``; a context manager."""

    def __init__(self, address: str, settings: Settings):
        self.address = address
        self.settings = settings
        self.client = None
        self.allowed_failures: int | None = None
        self._futures: list = []

    def __enter__(self) -> DaskPool:
        from distributed import Client

        # A result lost with a dead worker is recomputed by the cluster; its
        # warnings would break the one-line-per-failure output.
        logging.getLogger("distributed").setLevel(logging.ERROR)
        try:
            self.client = Client(self.address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, ValueError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {self.address}: {exc}") from None
        try:
            self.allowed_failures = int(self.client.run_on_scheduler(_allowed_failures))
        except Exception:  # the figure is informative only
            self.allowed_failures = None
        return self

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            if self._futures:
                self.client.cancel(self._futures)
            self.client.close()
            self.client = None

    def describe(self) -> str:
        workers = len(self.client.scheduler_info(n_workers=-1).get("workers", {})) if self.client else 0
        return f"Dask cluster {self.address} ({workers} worker{'s' if workers != 1 else ''})"

    def run(self, jobs: Sequence[Job], on_idle: Callable[[], None] | None = None) -> Iterator[Finished]:
        """Submit every job; yield each as it is finished, in completion order.

        The cluster does not say how many workers a finished photo took, so
        ``attempts`` is None except for photos that killed every worker they met.
        """
        from distributed import wait
        from distributed.scheduler import KilledWorker

        by_future = {self.client.submit(process_photo, job, self.settings, pure=False): job for job in jobs}
        self._futures = list(by_future)
        pending = set(by_future)
        attempts = self.allowed_failures + 1 if self.allowed_failures is not None else None
        died = (f"the workers analysing it died {attempts} times" if attempts is not None
                else "the workers analysing it kept dying until the cluster gave it up")
        while pending:
            try:
                with self.client.as_current():
                    done, pending = wait(pending, timeout=IDLE_S, return_when="FIRST_COMPLETED")
            except TimeoutError:
                if on_idle is not None:
                    on_idle()
                continue
            for future in done:
                job = by_future[future]
                try:
                    finished = Finished(job, future.result(), None)
                except KilledWorker:
                    finished = Finished(job, PhotoOutcome(error=died), attempts)
                except Exception as exc:
                    finished = Finished(job, PhotoOutcome(error=f"the cluster could not run it: {one_line(exc)}"), None)
                future.release()
                yield finished
        self._futures = []


def _allowed_failures(dask_scheduler) -> int:
    return dask_scheduler.allowed_failures

"""``forensics batch``: many photos, local worker processes or a Dask cluster, resumable.

Stages, one module each:

``inputs``   find the photos under the inputs and hash them;
``plan``     name each photo's output folder (stable across reruns), find
             finished photos and duplicates;
``resume``   what counts as finished, leftovers of a killed run, the lock;
``work``     what a worker does for one photo (shared with ``analyze``
             through :func:`forensics_core.pipeline.examine_photo`);
``local``    local worker processes, a dead worker retried once;
``cluster``  the same work as tasks on a Dask distributed cluster;
``summary``  ``summary.json`` and ``summary.csv``;
``index``    ``index.html``, the batch on one page, a row per photo;
``runner``   the whole run, with the progress bar and the end tables.
"""

from .plan import Job
from .runner import BatchError, BatchRequest, BatchResult, default_workers, print_summary, run_batch
from .work import PhotoOutcome, Settings

__all__ = ["BatchError", "BatchRequest", "BatchResult", "Job", "PhotoOutcome", "Settings", "default_workers",
           "print_summary", "run_batch"]

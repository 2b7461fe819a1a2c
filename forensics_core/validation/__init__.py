"""Known error rates: run detectors over photos of known origin and record how often they err.

``forensics validate SUITE --out DIR`` (see :mod:`.command`) writes
``validation.json`` (:class:`ValidationRecord`) and ``validation.html``;
the report's "Known error rates" section reads such a record.

The package's names are imported from their modules when first used, so that
reading a record (the report does) or registering ``forensics validate``
loads neither the analysis nor the statistics.
"""

from importlib import import_module

from ..defaults import DEFAULT_COUNT, DEFAULT_SEED

_LAZY = {
    "Case": "cases", "Suite": "cases", "SuiteError": "cases", "folder_suite": "cases", "read_suite": "cases",
    "ValidationRecord": "record", "read_record": "record", "shipped_record": "record",
    "default_workers": "runner",
    "LENS_SPLICES": "lens_splices", "lens_splices_suite": "lens_splices",
    "INNOCENT_PROCESSING": "innocent_processing", "innocent_processing_suite": "innocent_processing",
    "REALISTIC": "realistic", "realistic_suite": "realistic",
    "RECORD_NAME": "run", "SYNTHETIC": "run", "synthetic_suite": "run", "validate": "run",
}


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["DEFAULT_COUNT", "DEFAULT_SEED", *sorted(_LAZY)]

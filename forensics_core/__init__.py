"""forensics: examine a photo for splicing and record findings an examiner can defend.

Public API for users and plugin authors. Plugins import from here only.
"""

from importlib.metadata import PackageNotFoundError, version

import pluggy

from .evidence import Evidence, EvidenceError, load_evidence
from .findings import (
    DetectorFinding,
    DetectorResult,
    DetectorSpec,
    EvidenceInfo,
    Findings,
    MetadataTag,
    Status,
    Verdict,
    VerdictLabel,
)
from .hookspecs import PROJECT
from .synthetic import SyntheticCase

try:
    __version__ = version("forensics")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

hookimpl = pluggy.HookimplMarker(PROJECT)
"""Decorator for a plugin's hook implementations."""

ENTRY_POINT_GROUP = "forensics.plugins"
"""Entry-point group under which bundled and third-party plugins are found."""

from .analysis import analyze  # noqa: E402  (needs hookimpl defined first)

__all__ = [
    "ENTRY_POINT_GROUP",
    "DetectorFinding",
    "DetectorResult",
    "DetectorSpec",
    "Evidence",
    "EvidenceError",
    "EvidenceInfo",
    "Findings",
    "MetadataTag",
    "Status",
    "SyntheticCase",
    "Verdict",
    "VerdictLabel",
    "__version__",
    "analyze",
    "hookimpl",
    "load_evidence",
]

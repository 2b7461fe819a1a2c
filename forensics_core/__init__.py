"""forensics: examine a photo for splicing and record findings an examiner can defend.

Public API for users and plugin authors. Plugins import from here only.
"""

import warnings
from importlib.metadata import PackageNotFoundError, version

# pyHanko imports cryptography's DSA key type at module level, and cryptography 51 warns on that import: a line on
# stderr for every signed report or verification, which breaks "one line per bad input" and says nothing about this
# run (forensics never makes or accepts DSA keys: signing.py refuses them). Only that warning, only from pyHanko.
warnings.filterwarnings("ignore", message=r"DSA is deprecated", module=r"pyhanko(\.|$)")

from .detector import Deferred, Detector
from .contracts import (
    ATTRIBUTION_KEY,
    PROCESSING_KEY,
    RADIAL_DISTORTION_KEY,
    RADIAL_RESAMPLING_KEY,
    Processing,
    RadialDistortion,
    RadialResampling,
    SourceAttribution,
)
from .findings import (
    HEADLINE_WORDS,
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
from .hookspecs import hookimpl
from .reading import SMALL, FileRefused, read_limited

try:
    __version__ = version("forensics")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

ENTRY_POINT_GROUP = "forensics.plugins"
"""Entry-point group under which bundled and third-party plugins are found."""

# Names whose modules load numpy and Pillow (or, for `analyze`, the analysis
# runner, fusion and calibration), imported when first used: a plugin's
# declarations, `forensics --version` and `forensics plugins` need none of them.
_LAZY = {
    "EmbeddedThumbnail": "thumbnail",
    "Evidence": "evidence",
    "EvidenceError": "evidence",
    "load_evidence": "evidence",
    "ReferenceSet": "reference",
    "ReferenceError": "reference",
    "load_references": "reference",
    "SyntheticCase": "synthetic",
    "box_sums": "integral",
    "integral_image": "integral",
    "grey_jpeg": "synthetic",
    "grey_shapes": "synthetic",
    "paste_ellipse": "synthetic",
    "analyze": "analysis",
}


def __getattr__(name: str):
    if name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ATTRIBUTION_KEY",
    "ENTRY_POINT_GROUP",
    "FileRefused",
    "SMALL",
    "read_limited",
    "Deferred",
    "Detector",
    "DetectorFinding",
    "DetectorResult",
    "HEADLINE_WORDS",
    "DetectorSpec",
    "EmbeddedThumbnail",
    "Evidence",
    "EvidenceError",
    "EvidenceInfo",
    "Findings",
    "MetadataTag",
    "PROCESSING_KEY",
    "Processing",
    "RADIAL_DISTORTION_KEY",
    "RADIAL_RESAMPLING_KEY",
    "RadialDistortion",
    "RadialResampling",
    "ReferenceError",
    "SourceAttribution",
    "ReferenceSet",
    "Status",
    "SyntheticCase",
    "Verdict",
    "VerdictLabel",
    "__version__",
    "analyze",
    "box_sums",
    "grey_jpeg",
    "grey_shapes",
    "hookimpl",
    "integral_image",
    "load_evidence",
    "load_references",
    "paste_ellipse",
]

"""What the provenance detector declares: name, version, literature, parameters.

Kept apart from the method so that listing the plugins (``forensics plugins``,
``--help``) imports none of its numerical code.
"""

from __future__ import annotations

from typing import Any

from forensics_core import DetectorSpec

NAME = "provenance"
VERSION = "1.1.0"
REFERENCES = (
    "Coalition for Content Provenance and Authenticity, C2PA Technical Specification 2.1, 2024.",
    "Content Authenticity Initiative, c2pa-python (bindings of the c2pa-rs reference implementation).",
)
DEFAULT_PARAMS: dict[str, Any] = {"trust_anchors_file": "", "read_sidecar": True, "max_sidecar_bytes": 50_000_000}
SPEC = DetectorSpec(
    name=NAME,
    version=VERSION,
    description="Reads and validates C2PA Content Credentials (signatures, the hash binding the manifest to the "
                "content, the signer, declared actions, ingredients and digital source type).",
    references=REFERENCES,
    default_params=DEFAULT_PARAMS,
    calibrated_on="score",
)

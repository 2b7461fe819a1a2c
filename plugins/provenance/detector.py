"""The provenance detector: C2PA Content Credentials, validated offline.

Valid credentials prove that the content is unchanged since the signer
signed it, and what the signer declared (the capture device or the editing
program, its actions and ingredients); they do not prove that the scene was
real or that the signer is honest, and without a trust list the signer's
identity is only what its certificate says. A hard-binding hash that no
longer matches shows a change after signing, which may be an edit of the
content or only of its metadata. No credentials says nothing either way:
most photos carry none. The finding states no p-value (there is no
validation data with credentials yet); its ``score`` is 1 for a broken
binding or claim, 0.5 for valid credentials that declare an edit, a
composition or a generative source, 0 for valid credentials of a capture.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import asdict
from importlib.metadata import version
from pathlib import Path
from typing import Any

import c2pa

from forensics_core import DetectorResult, Evidence, Status

from .credentials import AI_SOURCE_TYPES, Credentials, read

# Actions after which the content is no longer what was captured (C2PA 2.1, 18.4).
EDITS = ("c2pa.edited", "c2pa.filtered", "c2pa.color_adjustments", "c2pa.cropped", "c2pa.resized",
         "c2pa.drawing", "c2pa.placed", "c2pa.removed", "c2pa.orientation", "c2pa.converted", "c2pa.transcoded",
         "c2pa.repackaged", "c2pa.redacted", "c2pa.edited.metadata")



def _sidecar(evidence: Evidence, params: Mapping[str, Any]) -> tuple[bytes | None, str | None]:
    path = evidence.path.with_suffix(".c2pa")
    if not params["read_sidecar"] or not path.is_file() or path.stat().st_size > int(params["max_sidecar_bytes"]):
        return None, None
    data = path.read_bytes()
    return data, hashlib.sha256(data).hexdigest()


def _summary(cred: Credentials, edited: list[str]) -> tuple[str, float]:
    who = cred.signer.get("common_name") or "an unnamed signer"
    by = f"signed by {who} (issuer {cred.signer.get('issuer') or 'not stated'}), made by {cred.claim_generator}"
    if cred.binding_broken or cred.integrity_broken:
        what = "the content's hash no longer matches the one signed" if cred.binding_broken else \
            "the claim no longer matches its signature"
        return (f"Content Credentials {by}, but {what}: the file changed after it was signed (its content, or "
                f"only its metadata).", 1.0)
    trust = "signer on the examiner's trust list" if cred.state == "Trusted" else \
        "signer identity not checked against a trust list"
    ai = [t for t in cred.source_types if t in AI_SOURCE_TYPES]
    declared = []
    if edited:
        declared.append(f"edits ({', '.join(edited[:4])})")
    if ai:
        declared.append(f"a generative source ({', '.join(ai)})")
    if declared:
        return (f"Valid Content Credentials ({trust}), {by}. They declare {' and '.join(declared)}: by the signer's "
                f"own account the content is not as captured.", 0.5)
    return (f"Valid Content Credentials ({trust}), {by}: the content is unchanged since it was signed. This does not "
            f"show that the scene was real or that the signer is honest.", 0.0)


def analyse(evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
    """Read and validate the photo's Content Credentials.

    Returns
    -------
    DetectorResult
        ``inconclusive`` without credentials, or when the manifest store
        cannot be parsed; otherwise ``ok`` with the score of the module
        docstring and no p-value.
    """
    sidecar, sidecar_sha = _sidecar(evidence, params)
    anchors_file = str(params["trust_anchors_file"])
    anchors = Path(anchors_file).read_text(encoding="ascii") if anchors_file else None
    details: dict[str, Any] = {"c2pa": f"{version('c2pa-python')} (c2pa-rs {c2pa.sdk_version()})",
                               "sidecar_sha256": sidecar_sha,
                               "trust_anchors_sha256": anchors and hashlib.sha256(anchors.encode()).hexdigest()}
    try:
        cred = read(evidence.data, evidence.info.format, sidecar, anchors)
    except c2pa.C2paError as exc:
        details["error"] = str(exc).splitlines()[0][:300] if str(exc) else type(exc).__name__
        return DetectorResult(Status.INCONCLUSIVE, "Inconclusive: the file carries a C2PA manifest store that cannot "
                              f"be read ({details['error']}).", details=details)
    if cred is None:
        return DetectorResult(Status.INCONCLUSIVE, "Inconclusive: no Content Credentials. Most photos carry none; "
                              "their absence says nothing about the content.", details=details)
    edited = sorted({a["action"] for a in cred.actions if a["action"] in EDITS})
    summary, score = _summary(cred, edited)
    details.update(credentials=asdict(cred), edits=edited)
    return DetectorResult(Status.OK, summary, score=score, details=details)

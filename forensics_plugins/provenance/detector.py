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
Credentials are called valid only when the C2PA SDK's own validation state
is ``Valid`` or ``Trusted``; an expired, revoked or otherwise invalid
signing credential with an intact binding makes the finding inconclusive
(the signature cannot vouch for the content, nor show it changed).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import asdict
from importlib.metadata import version
from pathlib import Path
from typing import TYPE_CHECKING, Any

import c2pa

from forensics_core import HEADLINE_WORDS, SMALL, Detector, DetectorFinding, DetectorResult, Evidence, Status, read_limited

from .credentials import AI_SOURCE_TYPES, Credentials, read
from .spec import SPEC

if TYPE_CHECKING:
    from forensics_core.report import ReportSection

# Actions after which the content is no longer what was captured (C2PA 2.1, 18.4).
EDITS = ("c2pa.edited", "c2pa.filtered", "c2pa.color_adjustments", "c2pa.cropped", "c2pa.resized",
         "c2pa.drawing", "c2pa.placed", "c2pa.removed", "c2pa.orientation", "c2pa.converted", "c2pa.transcoded",
         "c2pa.repackaged", "c2pa.redacted", "c2pa.edited.metadata")


def _sidecar(evidence: Evidence, params: Mapping[str, Any]) -> tuple[bytes | None, str | None]:
    path = evidence.path.with_suffix(".c2pa")
    if not params["read_sidecar"]:
        return None, None
    try:
        data = read_limited(path, int(params["max_sidecar_bytes"]))
    except OSError:
        return None, None
    return data, hashlib.sha256(data).hexdigest()


def _codes(codes: list[str]) -> str:
    return ", ".join(codes[:4]) + (f" and {len(codes) - 4} more" if len(codes) > 4 else "")


def _summary(cred: Credentials, edited: list[str]) -> tuple[str, float | None]:
    """The finding's sentence and score; score None when the credentials cannot vouch for the content either way."""
    who = cred.signer.get("common_name") or "an unnamed signer"
    by = f"signed by {who} (issuer {cred.signer.get('issuer') or 'not stated'}), made by {cred.claim_generator}"
    codes = [f["code"] for f in cred.failures if f["code"] != "signingCredential.untrusted"]
    codes += [c for d in cred.ingredient_failures for c in d["codes"] if c not in codes]
    if cred.binding_broken or cred.integrity_broken:
        what = ("the content's hash no longer matches the one signed" if cred.binding_broken else
                "the claim or its assertions no longer match what was signed")
        return (f"Invalid Content Credentials {by}: {what} ({_codes(codes)}). The file changed after it was signed "
                f"(its content, or only its metadata or manifest); what changed, and whether content was "
                f"inserted, moved or removed, the credentials cannot say.", 1.0)
    if cred.state not in ("Valid", "Trusted"):
        problems = cred.credential_failures or codes or ["no failure code given but an untrusted signer"]
        return (f"Invalid Content Credentials {by}: the C2PA SDK does not validate them ({_codes(problems)}). The "
                f"signature cannot vouch for the content; that alone is no evidence that the content changed.", None)
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


def _headline(cred: Credentials, edited: list[str]) -> str:
    """The finding in one sentence for page 1; the signer is named when the sentence stays short enough."""
    who = cred.signer.get("common_name")
    if cred.binding_broken or cred.integrity_broken:
        told = "Invalid Content Credentials{}: the file changed after it was signed."
    elif cred.state not in ("Valid", "Trusted"):
        told = "Inconclusive: the C2PA SDK does not validate the Content Credentials{}."
    elif edited or [t for t in cred.source_types if t in AI_SOURCE_TYPES]:
        told = "Valid Content Credentials{} declare edits or a generative source: not as captured, by the signer's account."
    else:
        told = ("Valid Content Credentials{}: the content is unchanged since signing, which does not show the scene "
                "was real.")
    named = told.format(f" signed by {who}") if who else told.format("")
    return named if len(named.split()) <= HEADLINE_WORDS else told.format("")


def _ingredients_text(cred: Credentials) -> str:
    bad = cred.ingredient_failures
    if not bad:
        return ""
    return (f" {len(bad)} ingredient(s) carry credentials that fail validation ({_codes(bad[0]['codes'])}): what "
            f"they declare of the ingredient's own history cannot be relied on.")


def _read(evidence: Evidence, sidecar: bytes | None, anchors: str | None) -> tuple[Credentials | None, str | None]:
    """One manifest store (the file's own, or the sidecar's when given) and the error that kept it unread, if any."""
    try:
        return read(evidence.data, evidence.info.format, sidecar, anchors), None
    except c2pa.C2paError as exc:
        return None, str(exc).splitlines()[0][:300] if str(exc) else type(exc).__name__


def _beside(side: Credentials | None, error: str | None) -> str:
    """What the sidecar beside a photo with its own store holds, as a sentence (empty without one)."""
    if error:
        return f" The .c2pa file beside the photo cannot be read ({error}); that is a fault of that file, not of the photo."
    if side is None:
        return ""
    state = "validates" if side.state in ("Valid", "Trusted") and not side.binding_broken else \
        f"does not validate against the photo ({_codes([f['code'] for f in side.failures] or [side.state])})"
    return f" The .c2pa file beside the photo holds another manifest store, which {state}."


class Provenance(Detector):
    """The Content Credentials (C2PA) the file carries, validated, and what they say was done.

    References
    ----------
    .. [1] Coalition for Content Provenance and Authenticity, C2PA technical
       specification 2.1, 2024.

    Examples
    --------
    Most photos carry none, and their absence is no finding:

    >>> from forensics_core import load_evidence
    >>> from forensics_plugins.provenance.spec import DEFAULT_PARAMS
    >>> Provenance().analyze(load_evidence("tests/data/calibration/left01.jpg"), DEFAULT_PARAMS).score is None
    True
    """

    spec = SPEC

    def analyze(self, evidence: Evidence, params: Mapping[str, Any]) -> DetectorResult:
        """Read and validate the photo's Content Credentials, those it embeds and those of a sidecar beside it.

        The embedded store, when there is one, is the finding's; a ``.c2pa``
        sidecar is validated against the same bytes beside it, never instead of
        it, and a sidecar that cannot be read is reported as such.

        Returns
        -------
        DetectorResult
            ``inconclusive`` without credentials, when the store cannot be read
            or when the SDK does not validate credentials whose binding holds
            (an expired or revoked signer); otherwise ``ok`` with the score of
            the module docstring and no p-value.
        """
        sidecar, sidecar_sha = _sidecar(evidence, params)
        anchors_file = str(params["trust_anchors_file"])
        try:
            anchors = read_limited(Path(anchors_file), SMALL).decode("ascii") if anchors_file else None
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"the trust anchors file cannot be used: {exc}") from None
        details: dict[str, Any] = {"c2pa": f"{version('c2pa-python')} (c2pa-rs {c2pa.sdk_version()})",
                                   "sidecar_sha256": sidecar_sha,
                                   "trust_anchors_sha256": anchors and hashlib.sha256(anchors.encode()).hexdigest()}
        own, own_error = _read(evidence, None, anchors)
        side, side_error = _read(evidence, sidecar, anchors) if sidecar is not None else (None, None)
        if side_error:
            details["sidecar_error"] = side_error
        if own_error:
            details["error"] = own_error
            return DetectorResult(Status.INCONCLUSIVE, "Inconclusive: the file carries a C2PA manifest store that cannot "
                                  f"be read ({own_error}).{_beside(side, side_error)}", details=details,
                                  headline="Inconclusive: the file's C2PA manifest store cannot be read.")
        cred = own or side
        if cred is None:
            tail = (f" The .c2pa file beside it cannot be read ({side_error}); that is a fault of that file, not of the "
                    "photo.") if side_error else ""
            return DetectorResult(Status.INCONCLUSIVE, "Inconclusive: no Content Credentials. Most photos carry none; "
                                  f"their absence says nothing about the content.{tail}", details=details,
                                  headline="Inconclusive: no Content Credentials in the file; most photos carry none.")
        edited = sorted({a["action"] for a in cred.actions if a["action"] in EDITS})
        summary, score = _summary(cred, edited)
        summary += _ingredients_text(cred) + (_beside(side, side_error) if own is not None else "")
        details.update(credentials=asdict(cred), edits=edited)
        if own is not None and side is not None:
            details["sidecar_credentials"] = asdict(side)
        headline = _headline(cred, edited)
        if score is None:
            return DetectorResult(Status.INCONCLUSIVE, f"Inconclusive: {summary}", details=details, headline=headline)
        return DetectorResult(Status.OK, summary, score=score, details=details, headline=headline)

    def report_section(self, finding: DetectorFinding, evidence: Evidence) -> ReportSection | None:
        """The manifest chain, its signers and actions; where they were looked for when the file carries none."""
        from .section import absent_section, report_section

        if "credentials" in finding.details:
            return report_section(finding, evidence)
        return absent_section(finding) if finding.status is Status.INCONCLUSIVE else None

"""Reading and validating C2PA Content Credentials with c2pa-python (the Content Authenticity Initiative's bindings).

The reader never goes to the network: fetching remote manifests and OCSP
responses is switched off, so a hostile manifest cannot make the tool call
out and the result depends on the file alone (and on the trust anchors the
examiner supplies).

References
----------
.. [1] C2PA Technical Specification 2.1, Coalition for Content Provenance
   and Authenticity, 2024 (sections 15, validation, and 18, actions).
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from typing import Any

import c2pa

MIME_TYPES = {"JPEG": "image/jpeg", "MPO": "image/jpeg", "PNG": "image/png", "TIFF": "image/tiff",
              "WEBP": "image/webp", "HEIF": "image/heif", "AVIF": "image/avif"}
# Codes of the C2PA validation status that mean the content changed after
# signing: the hard binding no longer matches (spec section 15.2).
_BINDING = ("assertion.dataHash.mismatch", "assertion.bmffHash.mismatch", "assertion.boxesHash.mismatch",
            "assertion.collectionHash.mismatch")
# Codes about the signer's credential and time stamp, not the claim: the
# signature cannot vouch for the content, which is not shown to have changed.
# Without the examiner's trust anchors every signer is "untrusted", which the
# SDK still calls Valid.
_CREDENTIAL_PREFIXES = ("signingCredential.", "timeStamp.")
_UNTRUSTED = "signingCredential.untrusted"
AI_SOURCE_TYPES = ("trainedAlgorithmicMedia", "compositeWithTrainedAlgorithmicMedia", "algorithmicMedia",
                   "compositeSynthetic")


@dataclass(frozen=True)
class Credentials:
    """What the manifest store says and how it validated.

    Attributes
    ----------
    state : str
        The SDK's own validation state: ``Invalid``, ``Valid`` (signatures
        and bindings hold, signer not on a trust list) or ``Trusted``. The
        finding never calls credentials valid that the SDK does not.
    binding_broken, integrity_broken : bool
        A hard-binding hash no longer matches the content; the claim, its
        assertions or its signature do not match themselves (every failure
        code of the active manifest that is not about the binding or the
        signer's credential).
    failures : list of dict
        Every failure code of the active manifest with its explanation.
    credential_failures : list of str
        Failure codes about the signing credential or time stamp (expired,
        revoked, invalid), but ``signingCredential.untrusted``.
    ingredient_failures : list of dict
        ``ingredient`` (the ingredient assertion's URI) and ``codes``: each
        ingredient whose own credentials fail validation.
    manifests : int
        Manifests in the store (the active one and its ingredients').
    claim_generator : str
    signer : dict
        ``issuer``, ``common_name``, ``cert_serial_number``, ``alg``,
        ``time`` as the signature states them.
    actions : list of dict
        ``action``, ``softwareAgent``, ``when``, ``digitalSourceType``.
    ingredients : list of dict
        ``title``, ``relationship``, ``format``.
    source_types : list of str
        Every digital source type named (IPTC vocabulary, last path part).
    sidecar : bool
        Read from a ``.c2pa`` file beside the photo.
    """

    state: str
    binding_broken: bool
    integrity_broken: bool
    failures: list[dict[str, str]]
    manifests: int
    claim_generator: str
    signer: dict[str, Any]
    actions: list[dict[str, Any]]
    ingredients: list[dict[str, Any]]
    source_types: list[str] = field(default_factory=list)
    sidecar: bool = False
    credential_failures: list[str] = field(default_factory=list)
    ingredient_failures: list[dict[str, Any]] = field(default_factory=list)


def _context(trust_anchors: str | None) -> c2pa.Context:
    settings: dict[str, Any] = {"verify": {"remote_manifest_fetch": False, "ocsp_fetch": False}}
    if trust_anchors:
        settings["trust"] = {"trust_anchors": trust_anchors}
    return c2pa.Context.from_json(json.dumps(settings))


def _generator(manifest: dict[str, Any]) -> str:
    info = manifest.get("claim_generator_info") or []
    names = [" ".join(str(i.get(k, "")) for k in ("name", "version")).strip() for i in info if isinstance(i, dict)]
    return "; ".join(n for n in names if n) or str(manifest.get("claim_generator") or "not stated")


def _actions(manifest: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for assertion in manifest.get("assertions") or []:
        if str(assertion.get("label", "")).startswith("c2pa.actions"):
            for a in (assertion.get("data") or {}).get("actions") or []:
                agent = a.get("softwareAgent")
                out.append({"action": str(a.get("action", "")),
                            "softwareAgent": agent.get("name") if isinstance(agent, dict) else agent,
                            "when": a.get("when"),
                            "digitalSourceType": str(a.get("digitalSourceType") or "").rsplit("/", 1)[-1] or None})
    return out


def _ingredient_failures(ingredient: dict[str, Any]) -> list[str]:
    """The failure codes an ingredient's own credentials had when it was taken in, as its assertion records them.

    Older manifests list them as ``validation_status``, newer ones as
    ``validation_results``; a missing signer trust is not counted.
    """
    listed = ingredient.get("validation_status") or []
    recorded = ((ingredient.get("validation_results") or {}).get("activeManifest") or {}).get("failure") or []
    return sorted({str(f.get("code", "")) for f in [*listed, *recorded] if isinstance(f, dict)} - {_UNTRUSTED})


def read(data: bytes, fmt: str, sidecar: bytes | None = None, trust_anchors: str | None = None) -> Credentials | None:
    """The Content Credentials of a file's bytes, or None when it carries none.

    Parameters
    ----------
    data : bytes
        The evidence bytes (those that were hashed).
    fmt : str
        ``EvidenceInfo.format``.
    sidecar : bytes, optional
        A detached manifest store (``photo.c2pa``) to validate against
        ``data`` instead of the store embedded in it: read the two apart.
    trust_anchors : str, optional
        PEM certificates the examiner trusts as roots; without them a valid
        signature is ``Valid`` but never ``Trusted``.

    Raises
    ------
    c2pa.C2paError
        When the store is present but cannot be parsed.
    """
    mime = MIME_TYPES.get(fmt)
    if mime is None:
        return None
    reader = c2pa.Reader.try_create(mime, io.BytesIO(data), sidecar, context=_context(trust_anchors))
    if reader is None:
        return None
    with reader:
        store = json.loads(reader.json())
        state = str(reader.get_validation_state() or "Invalid")
        results = reader.get_validation_results() or {}
    active = (store.get("manifests") or {}).get(store.get("active_manifest") or "", {})
    failures = [{"code": str(f.get("code", "")), "explanation": str(f.get("explanation", ""))}
                for f in (results.get("activeManifest") or {}).get("failure") or []]
    codes = {f["code"] for f in failures}
    credential = {c for c in codes if c.startswith(_CREDENTIAL_PREFIXES)}
    deltas = [{"ingredient": str(d.get("ingredientAssertionURI", "")),
               "codes": sorted({str(f.get("code", "")) for f in (d.get("validationDeltas") or {}).get("failure") or []}
                               - {_UNTRUSTED})}
              for d in results.get("ingredientDeltas") or [] if isinstance(d, dict)]
    # Only what the SDK itself calls invalid is read as a claim that no longer matches: a failure of the active
    # manifest that is neither the binding nor the signer's credential, or of an ingredient validated now.
    delta_codes = {c for d in deltas for c in d["codes"]}
    structural = (codes - credential - set(_BINDING)) | delta_codes if state not in ("Valid", "Trusted") else set()
    actions = _actions(active)
    types = [a["digitalSourceType"] for a in actions if a["digitalSourceType"]]
    ingredients = [{"title": i.get("title"), "relationship": i.get("relationship"), "format": i.get("format")}
                   for i in active.get("ingredients") or []]
    deltas += [{"ingredient": str(i.get("title") or "untitled"), "codes": _ingredient_failures(i)}
               for i in active.get("ingredients") or [] if isinstance(i, dict)]
    signature = active.get("signature_info") or {}
    return Credentials(
        state=state, binding_broken=bool(codes & set(_BINDING)), integrity_broken=bool(structural),
        failures=failures, manifests=len(store.get("manifests") or {}), claim_generator=_generator(active),
        signer={k: signature.get(k) for k in ("issuer", "common_name", "cert_serial_number", "alg", "time")},
        actions=actions, ingredients=ingredients, source_types=sorted(set(types)), sidecar=sidecar is not None,
        credential_failures=sorted(credential - {_UNTRUSTED}), ingredient_failures=[d for d in deltas if d["codes"]])

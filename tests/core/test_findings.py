"""Findings: schema, round trip, determinism."""

import json

from plugin_hosts import fixture_host

from forensics_core import Findings, analyze
from forensics_core.findings import DetectorResult, MalformedResult, Status, check_result

VOLATILE = {"created", "hashed_at", "elapsed_s"}


def strip_volatile(doc):
    if isinstance(doc, dict):
        return {k: strip_volatile(v) for k, v in doc.items() if k not in VOLATILE}
    if isinstance(doc, list):
        return [strip_volatile(v) for v in doc]
    return doc


def test_same_input_and_parameters_give_identical_findings(photo):
    runs = [json.loads(analyze(photo, host=fixture_host("good", "raising")).to_json()) for _ in range(2)]
    assert strip_volatile(runs[0]) == strip_volatile(runs[1])


def test_findings_validate_and_round_trip(photo, validate):
    result = analyze(photo, host=fixture_host("good"), case_id="K-7")
    doc = validate(result)
    again = Findings.from_dict(doc)
    assert again.to_dict() == result.to_dict()


def test_numpy_details_are_converted_and_nan_refused():
    import numpy as np

    ok = check_result(DetectorResult(Status.OK, "Fine.", score=np.float64(0.25), details={"a": np.arange(3)}))
    assert ok.details == {"a": [0, 1, 2]} and ok.score == 0.25
    for bad in ({"z": float("inf")}, {1: "non-string key"}, {"o": object()}):
        try:
            check_result(DetectorResult(Status.OK, "Bad.", details=bad))
        except MalformedResult:
            continue
        raise AssertionError(f"accepted {bad}")

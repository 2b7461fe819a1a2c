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


def test_the_radial_distortion_contract_reads_only_a_complete_record_of_an_ok_finding():
    from forensics_core import RADIAL_DISTORTION_KEY, DetectorFinding, RadialDistortion, Status

    model = RadialDistortion(k1=0.05, k1_stderr=0.004, k2=0.0, k2_stderr=0.003, cx=0.01, cx_stderr=0.02, cy=0.0,
                             cy_stderr=0.02, cx_px=12.0, cy_px=0.0, sigma_px=0.3, n_lines_explained=30,
                             n_lines_informative=31)

    def finding(details, status=Status.OK):
        return DetectorFinding(name="lens_distortion", version="1", plugin="lens_distortion", status=status,
                               summary="s", score=None, p_value=None, nfa=None, details=details, parameters={},
                               elapsed_s=0.1)

    assert RadialDistortion.from_finding(finding({RADIAL_DISTORTION_KEY: model.to_details()})) == model
    assert RadialDistortion.from_finding(finding({RADIAL_DISTORTION_KEY: model.to_details()},
                                                 Status.INCONCLUSIVE)) is None
    partial = {k: v for k, v in model.to_details().items() if k != "k2_stderr"}
    assert RadialDistortion.from_finding(finding({RADIAL_DISTORTION_KEY: partial})) is None
    assert RadialDistortion.from_finding(finding({RADIAL_DISTORTION_KEY: {**model.to_details(), "k1": "x"}})) is None
    assert RadialDistortion.from_finding(None) is None

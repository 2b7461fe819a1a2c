"""A detector registered by a fixture plugin as Deferred: this module is imported only when it first runs."""

from forensics_core import Detector, DetectorResult, DetectorSpec, Status

SPEC = DetectorSpec("deferred", "1.0", "Imported when it first runs.", default_params={"level": 1})


class Lazy(Detector):
    spec = SPEC

    def analyze(self, evidence, params, prior):
        return DetectorResult(Status.OK, "Ran after its import.", score=0.0, details={"prior": sorted(prior)})


class Mismatched(Detector):
    spec = DetectorSpec("other_name", "1.0", "Not the spec registered.")

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, "Never run.")

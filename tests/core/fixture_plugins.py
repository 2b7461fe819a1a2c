"""Plugins that misbehave on purpose, loaded through real entry points by the tests."""

import os
import time

from forensics_core import Detector, DetectorResult, DetectorSpec, Status, Verdict, VerdictLabel, hookimpl


class _Detector(Detector):
    """A fixture plugin that is also the one detector it registers."""

    name = "base"

    @property
    def spec(self):
        return DetectorSpec(self.name, "1.0", f"Test detector {self.name}.", default_params={"level": 1})

    @hookimpl
    def forensics_register_detectors(self, register):
        register(self)


class Good(_Detector):
    name = "good"

    def analyze(self, evidence, params):
        mean = float(evidence.luma.mean())
        return DetectorResult(Status.OK, f"Mean luma {mean:.3f}.", score=0.1, p_value=0.5,
                              details={"mean_luma": mean, "level": params["level"]})


class Reader(_Detector):
    """Reads the finding of ``good`` (declared in ``uses``), as the metadata detector reads the lens one."""

    spec = DetectorSpec("reader", "1.0", "Reads good's finding.", uses=("good",))

    def analyze(self, evidence, params, prior):
        seen = {name: f.details.get("mean_luma") for name, f in prior.items()}
        return DetectorResult(Status.OK, "Observed.", score=0.0, details={"seen": seen})


REGISTERED: list[int] = []


class Registering(_Detector):
    """Notes each registration; its finding says which the main process had made before the fork."""

    name = "registering"

    @hookimpl
    def forensics_register_detectors(self, register):
        REGISTERED.append(os.getpid())
        register(self)

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, "Registered.", score=0.0, details={"registered": list(REGISTERED)})


class Raising(_Detector):
    name = "raising"

    def analyze(self, evidence, params):
        raise RuntimeError("boom in the detector")


class Hanging(_Detector):
    name = "hanging"

    def analyze(self, evidence, params):
        time.sleep(600)


class Garbage(_Detector):
    name = "garbage"

    def analyze(self, evidence, params):
        return {"score": "very high"}


class OutOfRange(_Detector):
    name = "out_of_range"

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, "Too sure.", score=1.7, details={"x": float("nan")})


class Crashing(_Detector):
    name = "crashing"

    def analyze(self, evidence, params):
        import os
        import signal

        os.kill(os.getpid(), signal.SIGSEGV)


class Mutating(_Detector):
    name = "mutating"

    def analyze(self, evidence, params):
        evidence.pixels[0, 0] = 0
        return DetectorResult(Status.OK, "Wrote to the evidence.")


class FileWriter(_Detector):
    name = "file_writer"

    def analyze(self, evidence, params):
        with open(evidence.path, "ab") as fh:
            fh.write(b"\0")
        return DetectorResult(Status.OK, "Appended a byte to the evidence file.")


class Chatty(_Detector):
    name = "chatty"

    def analyze(self, evidence, params):
        import sys
        import warnings

        for i in range(200_000):
            print(f"line {i}")
        warnings.warn("a library complains")
        sys.stderr.write("to stderr\n")
        return DetectorResult(Status.OK, "Printed a lot.", score=0.1)


class DeferredPlugin:
    """Registers a detector by its spec and the import path of its class (the module is not imported here)."""

    def __init__(self, target, spec=None):
        self.target, self.spec = target, spec

    @hookimpl
    def forensics_register_detectors(self, register):
        from forensics_core import Deferred

        spec = self.spec or DetectorSpec("deferred", "1.0", "Imported when it first runs.", default_params={"level": 1})
        register(Deferred(spec, self.target))


class BadRegistration:
    @hookimpl
    def forensics_register_detectors(self, register):
        raise ValueError("cannot register")


class Typo:
    @hookimpl
    def forensics_analyse(self, detector, evidence, params):
        return None


class WrongArgs:
    @hookimpl
    def forensics_fuse(self, policy, verdicts):
        return None


class ApiOne:
    """A plugin written for plugin API 1: specs returned, a name-routing analyse hook."""

    @hookimpl
    def forensics_register_detectors(self):
        return [DetectorSpec("api_one", "1.0", "Old style.")]

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        return None


class ApiOneSpecs:
    """Returns its specs as plugin API 1 did, and implements nothing else."""

    @hookimpl
    def forensics_register_detectors(self):
        return [DetectorSpec("api_one_specs", "1.0", "Old style.")]


class NotADetector:
    @hookimpl
    def forensics_register_detectors(self, register):
        register(DetectorSpec("spec_only", "1.0", "A spec is not a detector."))


class TwoNames:
    """Registers two detectors, the second of which clashes with the first: neither is kept."""

    @hookimpl
    def forensics_register_detectors(self, register):
        register(Good())
        register(Good())


class RaisingFusion:
    @hookimpl
    def forensics_fuse(self, policy, findings):
        raise RuntimeError("fusion broke")


FUSED: list[str] = []


class _Fusion:
    """Implements the policy ``first``, noting each call."""

    name = "base"

    def verdict(self, policy):
        FUSED.append(self.name)
        if policy != "first":
            return None
        return Verdict(VerdictLabel.INCONCLUSIVE, None, f"Decided by {self.name}.", policy)


class EarlyFusion(_Fusion):
    name = "early_fusion"

    @hookimpl
    def forensics_fuse(self, policy):
        return self.verdict(policy)


class LateFusion(_Fusion):
    name = "late_fusion"

    @hookimpl
    def forensics_fuse(self, policy):
        return self.verdict(policy)


class FirstFusion(_Fusion):
    name = "first_fusion"

    @hookimpl(tryfirst=True)
    def forensics_fuse(self, policy):
        return self.verdict(policy)


class MetadataHanging:
    @hookimpl
    def forensics_extract_metadata(self, evidence):
        time.sleep(3600)


class Metadata:
    @hookimpl
    def forensics_extract_metadata(self, evidence):
        return {"bytes": len(evidence.data)}


good, reader, raising, hanging, garbage = Good(), Reader(), Raising(), Hanging(), Garbage()
registering = Registering()
metadata_hanging = MetadataHanging()
out_of_range, crashing, mutating, file_writer, chatty = OutOfRange(), Crashing(), Mutating(), FileWriter(), Chatty()
bad_registration, typo, wrong_args, raising_fusion, metadata = BadRegistration(), Typo(), WrongArgs(), RaisingFusion(), Metadata()
api_one, api_one_specs, not_a_detector, two_names = ApiOne(), ApiOneSpecs(), NotADetector(), TwoNames()
early_fusion, late_fusion, first_fusion = EarlyFusion(), LateFusion(), FirstFusion()
deferred = DeferredPlugin("fixture_deferred:Lazy")
deferred_mismatched = DeferredPlugin("fixture_deferred:Mismatched",
                                     DetectorSpec("deferred_mismatched", "1.0", "Its class says otherwise."))

"""Plugins that misbehave on purpose, loaded through real entry points by the tests."""

import os
import time

from forensics_core import DetectorResult, DetectorSpec, Status, hookimpl


class _Detector:
    name = "base"

    @hookimpl
    def forensics_register_detectors(self):
        return [DetectorSpec(self.name, "1.0", f"Test detector {self.name}.", default_params={"level": 1})]


class Good(_Detector):
    name = "good"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        mean = float(evidence.luma.mean())
        return DetectorResult(Status.OK, f"Mean luma {mean:.3f}.", score=0.1, p_value=0.5,
                              details={"mean_luma": mean, "level": params["level"]})


class Reader:
    """Reads the finding of ``good`` (declared in ``uses``), as the metadata detector reads the lens one."""

    @hookimpl
    def forensics_register_detectors(self):
        return [DetectorSpec("reader", "1.0", "Reads good's finding.", uses=("good",))]

    @hookimpl
    def forensics_analyze(self, detector, evidence, params, prior):
        seen = {name: f.details.get("mean_luma") for name, f in prior.items()}
        return DetectorResult(Status.OK, "Observed.", score=0.0, details={"seen": seen})


PREPARED: list[int] = []


class Preparing(_Detector):
    """Notes each ``forensics_prepare`` call; its finding says which the main process had made before the fork."""

    name = "preparing"

    @hookimpl
    def forensics_prepare(self):
        PREPARED.append(os.getpid())

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        return DetectorResult(Status.OK, "Prepared.", score=0.0, details={"prepared": list(PREPARED)})


class Raising(_Detector):
    name = "raising"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        raise RuntimeError("boom in the detector")


class Hanging(_Detector):
    name = "hanging"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        time.sleep(600)


class Garbage(_Detector):
    name = "garbage"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        return {"score": "very high"}


class OutOfRange(_Detector):
    name = "out_of_range"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        return DetectorResult(Status.OK, "Too sure.", score=1.7, details={"x": float("nan")})


class Crashing(_Detector):
    name = "crashing"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        import os
        import signal

        os.kill(os.getpid(), signal.SIGSEGV)


class Mutating(_Detector):
    name = "mutating"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        evidence.pixels[0, 0] = 0
        return DetectorResult(Status.OK, "Wrote to the evidence.")


class FileWriter(_Detector):
    name = "file_writer"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        with open(evidence.path, "ab") as fh:
            fh.write(b"\0")
        return DetectorResult(Status.OK, "Appended a byte to the evidence file.")


class Chatty(_Detector):
    name = "chatty"

    @hookimpl
    def forensics_analyze(self, detector, evidence, params):
        import sys
        import warnings

        for i in range(200_000):
            print(f"line {i}")
        warnings.warn("a library complains")
        sys.stderr.write("to stderr\n")
        return DetectorResult(Status.OK, "Printed a lot.", score=0.1)


class BadRegistration:
    @hookimpl
    def forensics_register_detectors(self):
        raise ValueError("cannot register")


class Typo:
    @hookimpl
    def forensics_analyse(self, detector, evidence, params):
        return None


class WrongArgs:
    @hookimpl
    def forensics_analyze(self, detector, evidence, parameters):
        return None


class RaisingFusion:
    @hookimpl
    def forensics_fuse(self, policy, findings):
        raise RuntimeError("fusion broke")


class MetadataHanging:
    @hookimpl
    def forensics_extract_metadata(self, evidence):
        time.sleep(3600)


class Metadata:
    @hookimpl
    def forensics_extract_metadata(self, evidence):
        return {"bytes": len(evidence.data)}


good, reader, raising, hanging, garbage = Good(), Reader(), Raising(), Hanging(), Garbage()
preparing = Preparing()
metadata_hanging = MetadataHanging()
out_of_range, crashing, mutating, file_writer, chatty = OutOfRange(), Crashing(), Mutating(), FileWriter(), Chatty()
bad_registration, typo, wrong_args, raising_fusion, metadata = BadRegistration(), Typo(), WrongArgs(), RaisingFusion(), Metadata()

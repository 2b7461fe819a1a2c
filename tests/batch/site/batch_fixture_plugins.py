"""Test-only plugins for the batch tests, found through the entry points of the
``batch_fixtures`` distribution beside this file (put this folder on PYTHONPATH).

``steady``: a detector that takes ``seconds`` and reports the mean luma; its
report section takes ``report_seconds``.
``killer``: kills the worker that analyses a photo whose name contains
``$BATCH_TEST_KILL``, after noting the attempt in ``$BATCH_TEST_LOG``. Its
metadata hook runs contained, in a child the worker forks, so the worker is
that child's parent.
"""

import os
import signal
import time

from forensics_core import Detector, DetectorResult, DetectorSpec, Status, hookimpl


class Steady(Detector):
    spec = DetectorSpec("steady", "1.0.0", "Test detector: mean luma after a fixed delay.",
                        default_params={"seconds": 0.0, "report_seconds": 0.0})

    @hookimpl
    def forensics_register_detectors(self, register):
        register(self)

    def analyze(self, evidence, params):
        time.sleep(float(params["seconds"]))
        mean = float(evidence.luma.mean())
        return DetectorResult(Status.OK, f"Mean luma {mean:.3f}.", score=mean, p_value=0.5,
                              details={"mean_luma": mean})

    def report_section(self, finding, evidence):
        time.sleep(float(finding.parameters["report_seconds"]))
        return None


class Killer:
    @hookimpl
    def forensics_extract_metadata(self, evidence):
        target = os.environ.get("BATCH_TEST_KILL")
        log = os.environ.get("BATCH_TEST_LOG")
        if log:
            with open(log, "a") as fh:
                fh.write(f"{evidence.info.name} {os.getpid()}\n")
        if target and target in evidence.info.name:
            os.kill(os.getppid(), signal.SIGKILL)
        return None


steady, killer = Steady(), Killer()

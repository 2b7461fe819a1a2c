"""The Examples sections of the main public functions run as written (from the repository's root)."""

import doctest
import importlib
import os
from pathlib import Path

import pytest

import forensics_core.analysis
import forensics_core.contracts
import forensics_core.evidence
import forensics_core.report.images
import forensics_core.validation.realistic
import forensics_core.verify

ROOT = Path(__file__).resolve().parents[2]

NUMERICAL = ([f"forensics_plugins.lens_distortion.{m}" for m in ("edges", "lines", "k1", "consistency", "regions")]
             + [f"forensics_plugins.prnu.{m}" for m in ("alignment", "pce", "residual")])
DETECTORS = [f"forensics_plugins.{p}.detector" for p in ("cfa", "copy_move", "dq", "jpeg_grid", "lens_distortion",
                                                          "metadata", "noise", "provenance", "prnu")]


@pytest.mark.parametrize("module", [forensics_core.analysis, forensics_core.evidence, forensics_core.report.images,
                                    forensics_core.contracts, forensics_core.verify,
                                    forensics_core.validation.realistic]
                         + [importlib.import_module(m) for m in NUMERICAL + DETECTORS], ids=lambda m: m.__name__)
def test_examples_run(module, monkeypatch):
    monkeypatch.chdir(ROOT)
    assert os.path.isfile("tests/data/calibration/left01.jpg")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0

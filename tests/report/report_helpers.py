"""Helpers of the report tests: the CLI, hostile evidence, bundles made through the Python API."""

import os
import subprocess
import sys
from importlib.metadata import EntryPoint
from pathlib import Path

from PIL import Image

from forensics_core import ENTRY_POINT_GROUP
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.evidence import load_evidence
from forensics_core.output import write_findings
from forensics_core.plugins import PluginHost
from forensics_core.report.bundle import write_bundle
from forensics_core.report.render import ReportOptions

FORENSICS = [sys.executable, "-m", "forensics_core"]
HOSTILE_EXIF = {
    0x010F: "<script>alert('make')</script>",                        # Make
    0x0110: '<img src="file:///etc/passwd">',                        # Model
    0x0131: '<link rel="attachment" href="file:///etc/hostname">',   # Software
    0x010E: "</style><script>alert(1)</script>{{ 7*7 }}",            # ImageDescription
}


def run(*args, env=None, input=None):
    return subprocess.run([*FORENSICS, *map(str, args)], capture_output=True, text=True, input=input,
                          env={**os.environ, **(env or {})}, timeout=300)


def report_host(*names: str) -> PluginHost:
    """A host with the named plugins of report_fixture_plugins, loaded through real entry points."""
    host = PluginHost(allow=None, deny=())
    for name in names:
        host.load_entry_point(EntryPoint(name, f"report_fixture_plugins:{name}", ENTRY_POINT_GROUP))
    return host


def hostile_jpeg(path: Path, size=(320, 240)) -> Path:
    """A JPEG whose EXIF strings carry markup, made here with Pillow."""
    img = Image.new("RGB", size, (90, 120, 150))
    exif = Image.Exif()
    for tag, value in HOSTILE_EXIF.items():
        exif[tag] = value
    img.save(path, "JPEG", exif=exif.tobytes(), quality=90)
    return path


def make_bundle(evidence_path: Path, folder: Path, key, plugins=("sectioned", "no_section"), **report) -> Path:
    """Analyse with the fixture plugins and write a signed bundle through the Python API."""
    host = report_host(*plugins)
    evidence = load_evidence(evidence_path)
    findings = analyze_evidence(evidence, host, Options(case_id="2024/117", examiner="Dr. Ada Examiner",
                                                        isolation="inline"))
    write_findings(findings, folder)
    write_bundle(findings, evidence, folder, key, host=host, options=ReportOptions(exhibit_id="EX-7", **report),
                 organisation="Forensic Lab")
    return folder


def pdf_pages_text(pdf: Path) -> list[str]:
    """The text of each page, as poppler's pdftotext lays it out."""
    out = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True, text=True, check=True)
    return out.stdout.split("\f")[:-1]

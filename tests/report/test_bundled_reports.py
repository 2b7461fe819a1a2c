"""The bundled photos' reports stay short enough to read: at most 16 pages and 1.5 MB each (issue 40)."""

import os
import subprocess
import sys

import pytest

MAX_PAGES = 16
MAX_BYTES = 1.5 * 1024 * 1024


@pytest.mark.parametrize("photo", ["calibration/left01.jpg", "exif/87_OSError.jpg"])
def test_a_bundled_photo_s_report_has_at_most_16_pages(photo, data_dir, tmp_path):
    done = subprocess.run([sys.executable, "-m", "forensics_core", "analyze", str(data_dir / photo), "--out",
                           str(tmp_path / "out"), "--case-id", "DEMO-1", "--exhibit-id", "1"],
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "FORENSICS_HOME": str(tmp_path / "home")})
    assert done.returncode == 0, done.stderr
    (pdf,) = (tmp_path / "out").rglob("report.pdf")
    info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True, check=True).stdout
    pages = int(next(line.split()[-1] for line in info.splitlines() if line.startswith("Pages:")))
    assert pages <= MAX_PAGES and pdf.stat().st_size <= MAX_BYTES, (pages, pdf.stat().st_size)

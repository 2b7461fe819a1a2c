"""A seeded fuzz run: mutated headers of real JPEG, PNG and TIFF files through ``forensics analyze --format json``.

``FORENSICS_FUZZ_COUNT`` sets the number of mutants (default 200, which fits
the suite's time budget; the issue's run of 2,000 is the same test with
``FORENSICS_FUZZ_COUNT=2000``).
"""

import hashlib
import io
import os
import subprocess
import sys

import numpy as np
from PIL import Image

COUNT = int(os.environ.get("FORENSICS_FUZZ_COUNT", "200"))


def _bases(data_dir):
    bases = [(p.stem, p.suffix, p.read_bytes()) for p in sorted((data_dir / "exif").glob("*.jpg"))]
    with Image.open(data_dir / "exif" / "Canon_40D.jpg") as img:
        rgb = img.convert("RGB")
    for fmt, suffix in (("PNG", ".png"), ("TIFF", ".tif")):
        buf = io.BytesIO()
        rgb.save(buf, fmt)
        bases.append(("canon", suffix, buf.getvalue()))
    return bases


def test_mutated_headers_give_findings_or_one_line_each_and_leave_the_files_unchanged(tmp_path, data_dir):
    rng = np.random.default_rng(2026)
    bases = _bases(data_dir)
    photos, hashes = [], {}
    for k in range(COUNT):
        stem, suffix, data = bases[k % len(bases)]
        mutant = bytearray(data)
        for _ in range(int(rng.integers(1, 6))):
            mutant[int(rng.integers(0, min(len(mutant), 2048)))] = int(rng.integers(0, 256))
        path = tmp_path / f"{k:04d}_{stem}{suffix}"
        path.write_bytes(bytes(mutant))
        photos.append(path)
        hashes[path] = hashlib.sha256(mutant).hexdigest()
    done = subprocess.run([sys.executable, "-m", "forensics_core", "analyze", *map(str, photos), "--out",
                           str(tmp_path / "out"), "--format", "json", "--detectors", "metadata"],
                          capture_output=True, text=True, timeout=60 + 3 * COUNT)
    assert done.returncode in (0, 1)
    errors = done.stderr.strip().splitlines()
    assert all(line.startswith("forensics: error: ") for line in errors), [e for e in errors if "error" not in e][:5]
    assert not [e for e in errors if "internal error" in e], errors[:5]
    refused = {line.split(": ")[2] for line in errors}
    analysed = {line.split(": ")[0] for line in done.stdout.strip().splitlines()}
    assert len(refused) + len(analysed) == COUNT
    assert all(hashlib.sha256(p.read_bytes()).hexdigest() == h for p, h in hashes.items())

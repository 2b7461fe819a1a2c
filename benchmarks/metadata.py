"""Time and peak memory of the metadata detector on a 4000 x 3000 photo.

Usage: ``python benchmarks/metadata.py [--runs 5] [--size 4000x3000]``

A synthetic authentic photo (the lens benchmark's scene, rendered with the
distortion lensfun gives the Canon PowerShot SX60 HS at 6 mm) is saved once
into ``benchmarks/out/`` as JPEG quality 90 with camera EXIF: make, model,
dates, dimensions, focal length and a 160 x 120 IFD1 thumbnail, so every
check runs in full, including the lensfun lookup and the comparison with a
lens finding. Each run then analyses it in a fresh process, so import costs
and memory of one run do not leak into the next. Printed: the median and
range over the runs of each stage (decode = intake with hashing; the
detector's own stages as it records them; the report section with its
figures) and of the peak resident memory of
the analysing process (``VmHWM``, including the interpreter and libraries,
measured separately as ``baseline``). Target (issue 5): <= 3 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import io
import struct
from pathlib import Path

from harness import OUT, fresh_runs, parse_size, print_stages


_CHILD = r"""
from forensics_core import DetectorFinding, Status
from forensics_core.evidence import load_evidence
from forensics_plugins.metadata.detector import Metadata
from forensics_plugins.metadata.spec import DEFAULT_PARAMS, NAME, VERSION
from forensics_plugins.metadata.section import report_section
base = hwm_mb()
lens = DetectorFinding(name="lens_distortion", version="0.1.0", plugin="lens_distortion", status=Status.OK,
                       summary="benchmark", score=None, p_value=None, nfa=None,
                       details={"global_model": {"k1": 0.1, "k1_stderr": 0.002, "k2": 0.0, "k2_stderr": 0.002}},
                       parameters={}, elapsed_s=0.0)
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
t1 = time.perf_counter()
result = Metadata().analyze(ev, DEFAULT_PARAMS, {"lens_distortion": lens})
t2 = time.perf_counter()
finding = DetectorFinding(name=NAME, version=VERSION, plugin="metadata", status=result.status,
                          summary=result.summary, score=result.score, p_value=None, nfa=None, details=result.details,
                          parameters=dict(DEFAULT_PARAMS), elapsed_s=t2 - t1)
section = report_section(finding, ev)
t3 = time.perf_counter()
stages = {"decode+hash": t1 - t0, **result.details["elapsed_s"], "detector total": t2 - t1,
          "report section": t3 - t2}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "status": result.status.value,
                  "outcomes": {c["id"]: c["outcome"] for c in result.details["checks"]}}))
"""


def _exif_with_thumbnail(size: tuple[int, int], thumbnail: bytes) -> bytes:
    """Camera EXIF for the photo, with IFD1 pointing at ``thumbnail`` (Pillow does not write IFD1)."""
    from PIL import ExifTags, Image, TiffImagePlugin

    exif = Image.Exif()
    exif[ExifTags.Base.Make] = "Canon"
    exif[ExifTags.Base.Model] = "Canon PowerShot SX60 HS"
    exif[ExifTags.Base.DateTime] = "2024:05:01 10:00:00"
    sub = exif.get_ifd(ExifTags.IFD.Exif)
    sub[ExifTags.Base.DateTimeOriginal] = "2024:05:01 10:00:00"
    sub[ExifTags.Base.ExifImageWidth], sub[ExifTags.Base.ExifImageHeight] = size
    sub[ExifTags.Base.FocalLength] = TiffImagePlugin.IFDRational(6, 1)
    tiff = bytearray(exif.tobytes()[6:])
    (ifd0,) = struct.unpack_from(">I", tiff, 4)
    (n,) = struct.unpack_from(">H", tiff, ifd0)
    tiff += b"\x00" * (len(tiff) % 2)
    struct.pack_into(">I", tiff, ifd0 + 2 + 12 * n, len(tiff))
    start = len(tiff) + 2 + 3 * 12 + 4
    tiff += struct.pack(">H", 3)
    tiff += struct.pack(">HHIHH", 0x0103, 3, 1, 6, 0)
    tiff += struct.pack(">HHII", 0x0201, 4, 1, start)
    tiff += struct.pack(">HHII", 0x0202, 4, 1, len(thumbnail))
    tiff += struct.pack(">I", 0) + thumbnail
    return b"Exif\x00\x00" + bytes(tiff)


def photo(size: tuple[int, int]) -> Path:
    path = OUT / f"metadata_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        from PIL import Image

        from forensics_plugins.lens_distortion.photo import render_authentic
        from forensics_plugins.metadata.conversion import predict, unit_scale
        from forensics_plugins.metadata.lensdb import lookup

        lens = lookup("Canon", "Canon PowerShot SX60 HS", None, 6.0).data
        s = unit_scale(max(size) / min(size), lens.calibration_aspect, lens.calibration_crop, lens.camera_crop)
        model = predict(lens.model, lens.terms, size[0], size[1], s)
        synth = render_authentic(7, size=size, k1=model.k1, k2=model.k2, jpeg_quality=None)
        img = Image.fromarray(synth.image)
        thumb = io.BytesIO()
        img.resize((160, 120), Image.Resampling.BILINEAR).save(thumb, "JPEG", quality=80)
        OUT.mkdir(parents=True, exist_ok=True)
        img.save(path, "JPEG", quality=90, exif=_exif_with_thumbnail(size, thumb.getvalue()))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = parse_size(args.size)
    target = photo(size)
    runs = fresh_runs(_CHILD, target, args.runs)
    print(f"metadata on {target.name} ({size[0]}x{size[1]}), {args.runs} runs, status {runs[0]['status']}")
    print("outcomes: " + ", ".join(f"{k} {v}" for k, v in runs[0]["outcomes"].items()))
    print_stages(runs)


if __name__ == "__main__":
    main()

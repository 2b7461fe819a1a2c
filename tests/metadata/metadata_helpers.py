"""Build JPEGs with chosen EXIF (including an IFD1 thumbnail) for the metadata tests."""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np
from PIL import ExifTags, Image, TiffImagePlugin

from forensics_core.evidence import Evidence, load_evidence
from forensics_core.findings import EvidenceInfo, ExifSummary, RawTag
from forensics_core.thumbnail import read_thumbnail

DATA = Path(__file__).resolve().parents[1] / "data"

IFD0_TAGS = {"make": 0x010F, "model": 0x0110, "software": 0x0131, "datetime": 0x0132, "orientation": 0x0112}
EXIF_TAGS = {"datetime_original": 0x9003, "exif_width": 0xA002, "exif_height": 0xA003, "focal": 0x920A,
             "focal35": 0xA405, "lens_model": 0xA434}


def photo(size: tuple[int, int] = (640, 480), source: str = "canon_hdr_NO.jpg") -> Image.Image:
    """A real photo, resized to ``size`` (W, H): content other detectors see as ordinary."""
    with Image.open(DATA / "exif" / source) as img:
        return img.convert("RGB").resize(size, Image.Resampling.LANCZOS)


def camera_thumbnail(img: Image.Image, size: tuple[int, int] = (160, 120), quality: int = 80) -> bytes:
    """A thumbnail made as cameras make one: decimated with little filtering, letterboxed in black, JPEG."""
    scale = min(size[0] / img.width, size[1] / img.height)
    inner = (max(1, round(img.width * scale)), max(1, round(img.height * scale)))
    frame = Image.new("RGB", size, (0, 0, 0))
    frame.paste(img.convert("RGB").resize(inner, Image.Resampling.BILINEAR),
                ((size[0] - inner[0]) // 2, (size[1] - inner[1]) // 2))
    buf = io.BytesIO()
    frame.save(buf, "JPEG", quality=quality)
    return buf.getvalue()


def exif_bytes(**tags) -> bytes:
    """``Exif\\0\\0`` + TIFF holding the given tags (names as in :data:`IFD0_TAGS`, :data:`EXIF_TAGS`)."""
    exif = Image.Exif()
    sub = exif.get_ifd(ExifTags.IFD.Exif)
    for name, value in tags.items():
        if value is None:
            continue
        if name in IFD0_TAGS:
            exif[IFD0_TAGS[name]] = value
        elif name == "focal":
            sub[EXIF_TAGS[name]] = TiffImagePlugin.IFDRational(round(value * 1000), 1000)
        else:
            sub[EXIF_TAGS[name]] = value
    return exif.tobytes()


def with_thumbnail(exif: bytes, thumb: bytes, *, offset: int | None = None, length: int | None = None,
                   ifd1_offset: int | None = None) -> bytes:
    """Append IFD1 pointing at ``thumb`` to an EXIF block; ``offset``/``length``/``ifd1_offset`` may lie."""
    assert exif.startswith(b"Exif\x00\x00")
    tiff = bytearray(exif[6:])
    endian = "<" if tiff[:2] == b"II" else ">"
    (ifd0,) = struct.unpack_from(endian + "I", tiff, 4)
    (n,) = struct.unpack_from(endian + "H", tiff, ifd0)
    if len(tiff) % 2:
        tiff += b"\x00"
    ifd1 = len(tiff)
    struct.pack_into(endian + "I", tiff, ifd0 + 2 + 12 * n, ifd1 if ifd1_offset is None else ifd1_offset)
    data_at = ifd1 + 2 + 3 * 12 + 4
    entries = [(0x0103, 3, 1, struct.pack(endian + "HH", 6, 0)),
               (0x0201, 4, 1, struct.pack(endian + "I", data_at if offset is None else offset)),
               (0x0202, 4, 1, struct.pack(endian + "I", len(thumb) if length is None else length))]
    tiff += struct.pack(endian + "H", len(entries))
    for tag, typ, count, value in entries:
        tiff += struct.pack(endian + "HHI", tag, typ, count) + value
    tiff += struct.pack(endian + "I", 0) + thumb
    return b"Exif\x00\x00" + bytes(tiff)


def jpeg(img: Image.Image, exif: bytes | None = None, quality: int = 92, **save) -> bytes:
    """``img`` as JPEG bytes carrying the raw ``exif`` block."""
    buf = io.BytesIO()
    kwargs = {"quality": quality, **save}
    if exif is not None:
        kwargs["exif"] = exif
    img.save(buf, "JPEG", **kwargs)
    return buf.getvalue()


def evidence_from(data: bytes, tmp_path: Path, name: str = "photo.jpg") -> Evidence:
    """Take ``data`` in through the core's intake, as ``forensics analyze`` would."""
    path = tmp_path / name
    path.write_bytes(data)
    return load_evidence(path)


def info(width: int = 640, height: int = 480, fmt: str = "JPEG", **exif) -> EvidenceInfo:
    """An EvidenceInfo with the given EXIF summary fields, for checks that read tags only."""
    raw = exif.pop("raw", None)
    if raw is None:
        # One tag per given field: the checks only count them.
        raw = [RawTag("IFD0", 0, name, str(v)) for name, v in exif.items() if v is not None]
    summary = ExifSummary(**exif, raw=list(raw))
    return EvidenceInfo(path="/nonexistent", name="x.jpg", size=0, sha256="", sha512="", md5="", hashed_at="",
                        format=fmt, width=width, height=height, mode="RGB", orientation=exif.get("orientation"),
                        icc_profile=False, quantization_tables={}, exif=summary)


def fake_evidence(data: bytes, pixels: np.ndarray, evidence_info: EvidenceInfo) -> Evidence:
    """Evidence with arbitrary (possibly hostile) bytes, for inputs the intake would refuse; its thumbnail read
    from ``data`` as the intake reads it."""
    px = np.ascontiguousarray(pixels)
    px.flags.writeable = False
    return Evidence(info=evidence_info, data=data, pixels=px, thumbnail=read_thumbnail(data, evidence_info.format))

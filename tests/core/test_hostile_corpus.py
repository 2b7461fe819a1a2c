"""A hostile corpus made here (over 100 files): every one gets findings or one line, nothing escapes or hangs."""

import hashlib
import io
import struct
import subprocess
import sys
import zlib

import numpy as np
from PIL import Image


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _save(img: Image.Image, fmt: str, **kw) -> bytes:
    buf = io.BytesIO()
    img.save(buf, fmt, **kw)
    return buf.getvalue()


def hostile_files(data_dir) -> dict[str, bytes]:
    """Name -> bytes; each name's suffix is what a user would see."""
    rng = np.random.default_rng(7)
    real = (data_dir / "exif" / "Canon_40D.jpg").read_bytes()
    small = Image.fromarray((rng.random((48, 64, 3)) * 255).astype(np.uint8))
    files: dict[str, bytes] = {
        "empty.jpg": b"", "one_byte.jpg": b"\xff", "text.jpg": b"hello, not a photo\n", "html.png": b"<html></html>",
        "pdf.tif": b"%PDF-1.7\n%\xe2\xe3\n", "zip.jpg": b"PK\x03\x04" + bytes(40), "soi_only.jpg": b"\xff\xd8",
        "soi_eoi.jpg": b"\xff\xd8\xff\xd9", "png_sig_only.png": b"\x89PNG\r\n\x1a\n", "tiff_sig_only.tif": b"II*\x00",
        "gif.jpg": _save(small, "GIF"), "bmp.jpg": _save(small, "BMP"),
        "png_bomb_header.png": b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", 100000, 100000, 8, 0, 0, 0, 0))
        + _png_chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + _png_chunk(b"IEND", b""),
        "png_zero_size.png": b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", 0, 0, 8, 0, 0, 0, 0))
        + _png_chunk(b"IEND", b""),
        "zero_padded.jpg": real + bytes(4096 - len(real) % 4096), "data_after_eoi.jpg": real + b"trailing data" * 50,
        "two_jpegs.jpg": real + real, "wide.png": _save(Image.new("L", (4000, 1)), "PNG"),
        "tall.png": _save(Image.new("L", (1, 4000)), "PNG"),
    }
    for mode in ("1", "L", "LA", "P", "RGB", "RGBA", "I", "I;16", "F", "CMYK", "YCbCr"):
        img = small.convert(mode) if mode not in ("I;16",) else small.convert("L").convert("I;16")
        for fmt, suffix in (("PNG", "png"), ("TIFF", "tif"), ("JPEG", "jpg")):
            try:
                files[f"mode_{mode.replace(';', '_')}.{suffix}"] = _save(img, fmt)
            except (OSError, ValueError, KeyError):
                continue
    for size in ((1, 1), (2, 3), (7, 9), (8, 8), (17, 5)):
        files[f"tiny_{size[0]}x{size[1]}.jpg"] = _save(small.resize(size), "JPEG")
    for cut in (3, 20, 100, 300, 600, 1000, 2000, 4000, len(real) // 2, len(real) - 2):
        files[f"cut_{cut}.jpg"] = real[:cut]
    progressive = _save(small, "JPEG", progressive=True)
    for cut in (200, 400, len(progressive) - 10):
        files[f"progressive_cut_{cut}.jpg"] = progressive[:cut]
    frames = [small.rotate(a) for a in (0, 90, 180)]
    files["apng.png"] = _save(frames[0], "PNG", save_all=True, append_images=frames[1:])
    files["pages.tif"] = _save(frames[0], "TIFF", save_all=True, append_images=frames[1:])
    files["webp.webp"] = _save(small, "WEBP")
    files["avif.avif"] = _save(small, "AVIF")
    for i in range(40):
        mutant = bytearray(real)
        start = real.find(b"Exif\x00\x00") + 6
        for _ in range(3):
            mutant[start + int(rng.integers(0, 400))] = int(rng.integers(0, 256))
        files[f"exif_mutant_{i:02d}.jpg"] = bytes(mutant)
    return files


def test_a_hostile_corpus_gives_findings_or_one_line_each(tmp_path, data_dir):
    files = hostile_files(data_dir)
    assert len(files) >= 100
    folder = tmp_path / "in"
    folder.mkdir()
    hashes = {}
    for name, data in files.items():
        (folder / name).write_bytes(data)
        hashes[name] = hashlib.sha256(data).hexdigest()
    paths = sorted(folder.iterdir())
    done = subprocess.run([sys.executable, "-m", "forensics_core", "analyze", *map(str, paths), "--out",
                           str(tmp_path / "out"), "--format", "json", "--timeout", "60"],
                          capture_output=True, text=True, timeout=1200)
    assert done.returncode in (0, 1)
    errors = done.stderr.strip().splitlines()
    assert all(line.startswith("forensics: error: ") for line in errors), [e for e in errors if "error:" not in e][:5]
    assert not [e for e in errors if "internal error" in e], errors
    analysed = {line.split(": ")[0] for line in done.stdout.strip().splitlines()}
    assert len(errors) + len(analysed) == len(files), (len(errors), len(analysed))
    assert all(hashlib.sha256((folder / n).read_bytes()).hexdigest() == h for n, h in hashes.items())
    for findings in (tmp_path / "out").rglob("findings.json"):
        assert '"status": "error"' not in findings.read_text(), findings

"""The quantisation-lattice reading of where the main grid is missing, on photos made here."""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status, load_evidence
from forensics_core.findings import check_result
from forensics_plugins.jpeg_grid import synth
from forensics_plugins.jpeg_grid.detector import JpegGrid
from forensics_plugins.jpeg_grid.spec import DEFAULT_PARAMS
from forensics_plugins.jpeg_grid.lattice import block_coefficients, estimate_steps
from forensics_plugins.jpeg_grid.luminance import luminance

SIZE = (384, 512)
# The pasted piece: rows, columns (off the 8x8 grid on purpose).
PIECE = (slice(131, 259), slice(203, 363))


def _scene(seed, source="coffee"):
    return synth.render_scene(np.random.default_rng(seed), SIZE, source)


def _saved(arr, fmt, **kw):
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format=fmt, **kw)
    return buf.getvalue()


def _decoded(arr, quality):
    return np.asarray(Image.open(io.BytesIO(_saved(arr, "JPEG", quality=quality))).convert("RGB"))


def _pasted(base, seed):
    """``base`` with a never-compressed piece of another scene in PIECE; the truth mask."""
    out = base.copy()
    out[PIECE] = _scene(seed, "astronaut")[PIECE]
    mask = np.zeros(base.shape[:2], bool)
    mask[PIECE] = True
    return out, mask


def _analyse(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    return check_result(JpegGrid().analyze(load_evidence(path), DEFAULT_PARAMS))


def _hit_overlaps(result, mask):
    hits = [r for r in result.details["regions"] if r["meaningful"] and r["stage"] == "missing"]
    if not hits:
        return False
    x0, y0, x1, y1 = hits[0]["bbox_px"]
    # The region is a union of half-overlapping square windows: it covers the piece and some margin.
    inside = mask[y0:y1, x0:x1]
    return inside.sum() >= 0.8 * mask.sum() and inside.mean() >= 0.3


def test_steps_of_a_decoded_jpeg_are_its_quantisation_table(tmp_path):
    data = _saved(_scene(1), "JPEG", quality=70)
    table = np.asarray(Image.open(io.BytesIO(data)).quantization[0]).reshape(8, 8)
    png = _saved(np.asarray(Image.open(io.BytesIO(data)).convert("RGB")), "PNG")
    path = tmp_path / "d.png"
    path.write_bytes(png)
    lum = luminance(load_evidence(path))
    coef = block_coefficients(lum.fine, (0, 0))
    lat = estimate_steps(coef, np.ones(coef.shape[:2], bool), None)
    found = lat.steps > 0
    assert lat.n_frequencies >= 10
    assert np.array_equal(lat.steps[found], table[found])


def test_piece_never_compressed_in_a_png_from_a_jpeg_is_found(tmp_path):
    forged, mask = _pasted(_decoded(_scene(2), 75), 3)
    result = _analyse(tmp_path, "f.png", _saved(forged, "PNG"))
    assert result.status is Status.OK and result.details["lattice"]["applicable"]
    assert _hit_overlaps(result, mask), result.summary
    assert "off the quantisation steps" in result.summary


def test_png_from_a_jpeg_untouched_has_no_missing_region(tmp_path):
    result = _analyse(tmp_path, "a.png", _saved(_decoded(_scene(2), 75), "PNG"))
    assert result.details["lattice"]["applicable"]
    assert not any(r["meaningful"] for r in result.details["regions"]), result.summary


def test_piece_compressed_only_once_in_a_double_compressed_jpeg_is_found(tmp_path):
    forged, mask = _pasted(_decoded(_scene(4), 70), 5)
    result = _analyse(tmp_path, "f.jpg", _saved(forged, "JPEG", quality=95))
    assert result.details["lattice"]["applicable"] and result.details["lattice"]["reading"].startswith("earlier")
    assert _hit_overlaps(result, mask), result.summary


@pytest.mark.parametrize("first", [None, 70])
def test_untouched_jpeg_single_or_double_compressed_has_no_missing_region(tmp_path, first):
    arr = _scene(6) if first is None else _decoded(_scene(6), first)
    result = _analyse(tmp_path, "a.jpg", _saved(arr, "JPEG", quality=95))
    assert result.details["lattice"]["applicable"] is (first is not None), result.details["lattice"]
    assert not any(r["meaningful"] for r in result.details["regions"]), result.summary


def test_zero_own_missing_grid_test_stays_available(tmp_path):
    case = synth.make_uncompressed_paste(4, size=SIZE, quality=85)
    path = tmp_path / "m.png"
    path.write_bytes(case.data)
    result = check_result(JpegGrid().analyze(load_evidence(path), {**DEFAULT_PARAMS, "missing_method": "zero_q99"}))
    assert result.details["missing_tested"] and "lattice" not in result.details
    assert any(r["meaningful"] and r["stage"] == "missing" for r in result.details["regions"])


def test_a_second_compression_and_a_lossless_copy_are_named_as_processing_a_single_one_is_not(tmp_path):
    scene = _scene(3)
    once = _analyse(tmp_path, "once.jpg", _saved(scene, "JPEG", quality=75))
    twice = _analyse(tmp_path, "twice.jpg", _saved(_decoded(scene, 75), "JPEG", quality=95))
    png = _analyse(tmp_path, "copy.png", _saved(_decoded(scene, 75), "PNG"))
    assert once.details["processing"] is None
    assert twice.details["processing"]["kind"] == "recompression"
    assert "saved again as JPEG after an earlier JPEG compression" in twice.summary
    assert png.details["processing"]["kind"] == "lossless storage after JPEG compression"
    assert "processing, not a trace of a pasted piece" in png.summary

"""Memory (issue 16, item 14): the full-size float copies of a photo are made by bands, not all at once.

The target itself (at most 2.5 GB for a 100 MP photo, the whole process tree)
is measured by ``benchmarks/memory.py``; these tests pin the two changes that
reached it, counting numpy's allocations with tracemalloc on a 12 MP photo.
"""

import io
import tracemalloc

import numpy as np
from PIL import Image

from forensics_core.evidence import Evidence, load_evidence
from forensics_plugins.dq.coefficients import ZIGZAG, calibrated, read_luma


def _peak(fn):
    tracemalloc.start()
    try:
        result = fn()
        return result, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_luma_of_a_12_mp_colour_photo_holds_one_float_copy(tmp_path):
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, 256, (3000, 4000, 3), dtype=np.uint8)
    path = tmp_path / "big.png"
    Image.fromarray(pixels).save(path, compress_level=0)
    evidence = load_evidence(path)
    luma, peak = _peak(lambda: Evidence.luma.func(evidence))
    assert np.array_equal(luma, (pixels.astype(np.float64) @ np.array([0.299, 0.587, 0.114])) / 255.0)
    # All at once it was the float64 colour grid, three times the result, plus the result twice.
    assert peak < 1.5 * luma.nbytes, f"{peak / 1e6:.0f} MB for a {luma.nbytes / 1e6:.0f} MB result"


def test_dq_reads_a_12_mp_jpeg_without_a_full_float_copy():
    rng = np.random.default_rng(2)
    smooth = np.cumsum(rng.normal(0, 1, (3000, 4000)), axis=1) % 200 + 20
    buf = io.BytesIO()
    Image.fromarray(smooth.astype(np.uint8)).save(buf, format="JPEG", quality=85)
    coef = read_luma(buf.getvalue())
    frequencies = ZIGZAG[1:16]
    (unreliable, unquantised), peak = _peak(lambda: coef.scan(4.0, frequencies))
    full_float = 3000 * 4000 * 8
    # Decoding everything at once held at least four such copies.
    assert peak < 0.7 * full_float, f"{peak / 1e6:.0f} MB, a float copy of the photo is {full_float / 1e6:.0f} MB"
    top = coef.quantised[:40]
    decoded = coef.decoded(0, 40)
    rows, cols = np.divmod(frequencies, 8)
    assert np.array_equal(unquantised[:39], calibrated(decoded)[:, :, rows, cols])
    assert np.array_equal(unreliable[:40], coef.unreliable(decoded, 4.0)) and top.shape[0] == 40

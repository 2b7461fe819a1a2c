"""Quantisation tables: libjpeg's scaling, Pillow's table order, quality estimates, the check."""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_core.evidence import load_evidence
from forensics_plugins.metadata.quantisation import IJG_LUMA, estimate, ijg_tables, quantisation_check
from metadata_helpers import DATA, photo

MAKERS = ["canon", "apple", "fujifilm"]


def _tables(img: Image.Image, **save) -> dict[str, list[int]]:
    buf = io.BytesIO()
    img.save(buf, "JPEG", **save)
    with Image.open(io.BytesIO(buf.getvalue())) as back:
        return {str(k): list(v) for k, v in back.quantization.items()}


def test_libjpeg_scaling():
    luma, chroma = ijg_tables(50)
    assert np.array_equal(luma, IJG_LUMA)
    assert ijg_tables(100)[0].max() == 1 and ijg_tables(100)[1].max() == 1
    assert ijg_tables(75)[0][0] == 8  # (16 * 50 + 50) // 100
    assert ijg_tables(1)[0].max() == 255  # baseline clamp
    assert ijg_tables(np.arange(1, 101))[0].shape == (100, 64)


def test_pillow_gives_tables_in_natural_order():
    # Row 0 of Annex K's table is 16 11 10 16 24 40 51 61 in natural order;
    # zigzag order would start 16 11 12 14.
    tables = _tables(photo((64, 48)), quality=50)
    assert tables["0"][:8] == [16, 11, 10, 16, 24, 40, 51, 61]


@pytest.mark.parametrize("quality", [5, 30, 50, 75, 90, 95, 100])
def test_exact_ijg_quality_of_pillow_saves(quality):
    est = estimate(_tables(photo((64, 48)), quality=quality))
    assert est.standard_ijg and est.quality == quality and est.mean_abs_deviation == 0.0


def test_custom_tables_give_the_nearest_quality():
    luma, chroma = ijg_tables(80)
    custom = {"0": list(np.maximum(luma + np.resize([1, 0, 0, -1], 64), 1)), "1": list(chroma)}
    est = estimate(custom)
    assert not est.standard_ijg and est.quality == 80 and 0 < est.mean_abs_deviation < 1
    assert estimate({}) is None
    assert estimate({"0": [1, 2, 3]}) is None


def test_real_files():
    canon = load_evidence(DATA / "exif" / "Canon_40D.jpg").info
    est = estimate(canon.quantization_tables)
    assert est.standard_ijg and est.quality == 65  # re-saved by GIMP
    check, _ = quantisation_check(canon.quantization_tables, canon.format, canon.exif.make, MAKERS)
    assert check.outcome == "suspicious"
    nikon = load_evidence(DATA / "exif" / "87_OSError.jpg").info
    check, est = quantisation_check(nikon.quantization_tables, nikon.format, nikon.exif.make, MAKERS)
    assert check.outcome == "consistent" and not est.standard_ijg


def test_check_outcomes():
    ijg = _tables(photo((64, 48)), quality=85)
    assert quantisation_check(ijg, "JPEG", "Jolla", MAKERS)[0].outcome == "note"
    assert quantisation_check(ijg, "JPEG", None, MAKERS)[0].outcome == "note"
    assert quantisation_check(ijg, "JPEG", "Apple", MAKERS)[0].outcome == "suspicious"
    assert quantisation_check({}, "PNG", "Apple", MAKERS)[0].outcome == "not available"
    assert quantisation_check({}, "JPEG", "Apple", MAKERS)[0].outcome == "not available"

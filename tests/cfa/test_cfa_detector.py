"""The detector on hostile input, on photos without a trace, and its details."""

import io
import json

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status
from forensics_core.findings import check_result
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.detector import analyse, regions_mask
from forensics_plugins.cfa.spec import DEFAULT_PARAMS, SPEC


def _decoded(data: bytes) -> np.ndarray:
    arr = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))
    arr.flags.writeable = False
    return arr


@pytest.fixture(scope="module")
def pair():
    return synth.make_pair(21, (384, 448), algorithm="bilinear", shift=(1, 1), fraction=0.2)


RNG = np.random.default_rng(0)
HOSTILE = {
    "1x1": np.zeros((1, 1, 3), np.uint8),
    "7x9": RNG.integers(0, 256, (7, 9, 3), dtype=np.uint8),
    "greyscale": RNG.integers(0, 256, (200, 240), dtype=np.uint8),
    "grey+alpha": RNG.integers(0, 256, (200, 240, 2), dtype=np.uint8),
    "grey as rgb": np.repeat(RNG.integers(0, 256, (200, 240, 1), dtype=np.uint8), 3, axis=2),
    "rgba noise": RNG.integers(0, 256, (200, 240, 4), dtype=np.uint8),
    "16-bit noise": RNG.integers(0, 65536, (200, 240, 3), dtype=np.uint16),
    "int32": RNG.integers(0, 65536, (200, 240, 3)).astype(np.int32),
    "float": RNG.random((200, 240, 3)).astype(np.float32),
    "float nan": np.full((200, 240, 3), np.nan, np.float32),
    "flat colour": np.broadcast_to(np.array([30, 120, 200], np.uint8), (256, 256, 3)),
    "odd size": RNG.integers(0, 256, (257, 301, 3), dtype=np.uint8),
    "bool": np.zeros((200, 240, 3), bool),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_input_is_inconclusive_with_a_reason(name):
    px = np.array(HOSTILE[name])
    px.flags.writeable = False
    result = check_result(analyse(px, DEFAULT_PARAMS))
    assert result.status is Status.INCONCLUSIVE, result.summary
    assert result.summary.startswith("Inconclusive: ") and result.details["reason"]
    assert result.score is None and result.nfa is None


def test_spliced_photo_details_carry_what_the_report_needs(pair):
    _, spliced = pair
    result = check_result(analyse(spliced.rgb, DEFAULT_PARAMS))
    assert result.status is Status.OK
    d = result.details
    json.dumps(d, allow_nan=False)
    for key in ("image_shape", "block_px", "grid", "n_usable", "diagonal", "red_blue", "signature", "shift_votes",
                "pattern", "regions", "power", "n_tests", "thresholds", "elapsed_s", "min_log10_nfa"):
        assert key in d, key
    assert np.shape(d["shift_votes"]) == tuple(d["grid"])
    region = d["regions"][0]
    for key in ("id", "kind", "nfa", "log10_nfa", "bbox_px", "area_fraction", "blocks", "votes", "votes_against"):
        assert key in region, key
    assert region["kind"] == "red_blue" and region["nfa"] <= DEFAULT_PARAMS["nfa_threshold"]
    assert result.nfa == region["nfa"] and result.score == pytest.approx(1.0 - region["nfa"])
    mask = regions_mask(d, spliced.mask.shape)
    precision = (mask & spliced.mask).sum() / mask.sum()
    print(f"red/blue swap of {100 * spliced.mask.mean():.0f}%: NFA {region['nfa']:.2g}, precision {precision:.2f}")
    assert precision > 0.8


def test_authentic_photo_is_ok_without_regions_and_names_its_pattern(pair):
    authentic, _ = pair
    result = check_result(analyse(authentic.rgb, DEFAULT_PARAMS))
    assert result.status is Status.OK and not result.details["regions"]
    assert result.details["pattern"]["pattern"] == authentic.params["pattern"]
    assert result.details["diagonal"]["rate"] > 0.95
    assert result.score < 0.5


def test_same_input_same_result_and_pixels_untouched(pair):
    _, spliced = pair
    px = spliced.rgb.copy()
    px.flags.writeable = False
    a = analyse(px, DEFAULT_PARAMS)
    b = analyse(px, DEFAULT_PARAMS)
    a.details.pop("elapsed_s"), b.details.pop("elapsed_s")
    assert json.dumps(check_result(a).details) == json.dumps(check_result(b).details)
    assert np.array_equal(px, spliced.rgb)


@pytest.mark.parametrize("quality, resize", [(60, None), (None, 0.5), (None, 0.75)])
def test_strong_jpeg_or_resizing_is_inconclusive(pair, quality, resize):
    authentic, _ = pair
    data, _ = synth.encode(authentic.rgb, quality, resize)
    result = analyse(_decoded(data), DEFAULT_PARAMS)
    assert result.status is Status.INCONCLUSIVE, result.summary
    assert not result.details.get("regions")


def test_spec_declares_every_parameter():
    assert SPEC.name == "cfa" and SPEC.version == "1.4.0"
    assert set(SPEC.default_params) == set(DEFAULT_PARAMS)
    assert len(SPEC.references) >= 4

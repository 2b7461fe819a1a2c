"""The null on photos with what real camera pipelines add: sharpening, 4:2:0 JPEG, directional texture, colour.

Votes of real photos are not independent fair coins: neighbouring blocks vote
alike for reasons of content or processing. These tests build that dependence
(in vote grids, and in rendered photos through an unsharp mask, 4:2:0 JPEG
and strongly directional texture) and check that no region is flagged on an
authentic photo while a paste whose trace survives is still found.
"""

import io

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from forensics_core import Status
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.bayer import mosaic
from forensics_plugins.cfa.content_null import null_rates
from forensics_plugins.cfa.demosaic import demosaic
from forensics_plugins.cfa.detector import analyse, regions_mask
from forensics_plugins.cfa.spec import DEFAULT_PARAMS
from forensics_plugins.cfa.regions import Question, scan


def _camera_jpeg(rgb: np.ndarray, quality: int, amount: float = 0.8, sigma: float = 1.0) -> np.ndarray:
    """Unsharp mask (as camera firmware sharpens) then JPEG with 4:2:0 chroma, decoded."""
    x = rgb.astype(np.float64)
    sharp = x + amount * (x - ndimage.gaussian_filter(x, (sigma, sigma, 0)))
    img = Image.fromarray(np.clip(np.round(sharp), 0, 255).astype(np.uint8))
    out = io.BytesIO()
    img.save(out, format="JPEG", quality=quality, subsampling="4:2:0")
    return np.asarray(Image.open(io.BytesIO(out.getvalue())).convert("RGB"))


def _host_with_clump(agree):
    """Votes of a 60 x 80-block photo agreeing with its phase at ``agree``, and a clump voting 80 % against."""
    rng = np.random.default_rng(3)
    voting = rng.random((60, 80)) < 0.9
    disagree = rng.random(voting.shape) > agree
    clump = np.zeros(voting.shape, bool)
    clump[20:34, 30:48] = True
    disagree[clump] = rng.random(clump.sum()) < 0.8
    return voting, disagree, clump


def test_a_clump_without_the_photo_phase_around_it_is_not_a_region():
    """The photo's phase is barely shown (52 %, as on several camera JPEGs); a clump of 80 % against is not a paste."""
    voting, disagree, _ = _host_with_clump(0.52)
    assert not scan([Question("diagonal", disagree, voting)], 0.01).regions


def test_the_same_clump_in_a_photo_with_a_clear_phase_is_a_region():
    voting, disagree, clump = _host_with_clump(0.95)
    regions = scan([Question("diagonal", disagree, voting)], 0.01).regions
    assert regions and (regions[0].blocks & clump).sum() >= 0.8 * regions[0].blocks.sum()
    assert regions[0].ring_agree > 0.9 * regions[0].ring_votes


def test_a_colour_that_votes_against_everywhere_is_not_a_region():
    """A saturated colour whose blocks disagree wherever they are (a colour-dependent signature) flags nothing,
    while a patch of that colour disagreeing where the colour elsewhere agrees is still found."""
    rng = np.random.default_rng(5)
    shape = (48, 64)
    voting = rng.random(shape) < 0.9
    disagree = rng.random(shape) > 0.95
    chroma = rng.normal(size=shape + (2,)) * 0.1
    red = np.zeros(shape, bool)
    red[8:22, 6:24] = True
    red[30:42, 40:58] = True
    chroma[red, 0] += 2.0
    turned = disagree.copy()
    turned[red] = rng.random(red.sum()) < 0.85
    null = null_rates(turned, voting, chroma)
    assert null[red].mean() > 0.65 and null[~red].max() == 0.5
    assert not scan([Question("diagonal", turned, voting, null)], 0.01).regions
    pasted = disagree.copy()
    patch = np.zeros(shape, bool)
    patch[8:22, 6:24] = True
    pasted[patch] = rng.random(patch.sum()) < 0.85
    null = null_rates(pasted, voting, chroma)
    regions = scan([Question("diagonal", pasted, voting, null)], 0.01).regions
    assert regions and (regions[0].blocks & patch).sum() >= 0.8 * regions[0].blocks.sum()


def _directional_scene(rng, size):
    """Fine oriented texture (stripes near the sampling limit at a few angles, as gravel, fabric or brick joints)."""
    h, w = size
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    scene = np.zeros((h, w, 3))
    for angle, period, tint in ((0.3, 3.1, (1.0, 0.8, 0.6)), (1.9, 2.6, (0.6, 0.9, 1.0))):
        wave = 0.5 + 0.5 * np.sin(2 * np.pi * (x * np.cos(angle) + y * np.sin(angle)) / period)
        scene += 0.4 * wave[..., None] * np.array(tint)
    return np.clip(scene + 0.05 * rng.random((h, w, 1)), 0, 1)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_directional_texture_sharpened_jpeg_flags_nothing(seed):
    rng = np.random.default_rng(seed)
    scene = _directional_scene(rng, (384, 384))
    raw = mosaic(scene, "RGGB") + rng.normal(0, 0.01, scene.shape[:2])
    linear = np.clip(demosaic(np.clip(raw, 0, 1), "RGGB", "hamilton_adams"), 0, 1)
    rgb = np.round(linear ** (1 / 2.2) * 255).astype(np.uint8)
    result = analyse(_camera_jpeg(rgb, 92), DEFAULT_PARAMS)
    assert not result.details.get("regions"), result.summary


@pytest.fixture(scope="module")
def pairs():
    return [synth.make_pair(7000 + i, (384, 448), algorithm=("bilinear", "hamilton_adams")[i % 2], fraction=0.25)
            for i in range(6)]


@pytest.mark.slow
def test_sharpened_420_jpeg_originals_flag_nothing(pairs):
    for authentic, _ in pairs:
        result = analyse(_camera_jpeg(authentic.rgb, 90), DEFAULT_PARAMS)
        assert not result.details.get("regions"), result.summary


@pytest.mark.slow
def test_paste_found_where_the_trace_survives_sharpening_and_jpeg(pairs):
    found = 0
    for _, spliced in pairs:
        result = analyse(_camera_jpeg(spliced.rgb, 97, amount=0.5), DEFAULT_PARAMS)
        regions = result.details.get("regions") or []
        for r in regions:
            rm = regions_mask({"block_px": result.details["block_px"], "regions": [r]}, spliced.mask.shape)
            assert (rm & spliced.mask).sum() >= 0.5 * rm.sum(), "a region outside the paste"
        found += bool(regions) and result.status is Status.OK
    print(f"\npastes found after unsharp mask + JPEG 97 (4:2:0): {found}/{len(pairs)}")
    assert found >= len(pairs) // 2


def test_region_in_a_photo_too_weak_to_localise_a_tenth_is_set_aside():
    """After JPEG 75 the photo's own phase is too weak to localise a paste of 10 % of it: a region found anyway is
    reported as set aside, and the outcome is inconclusive, not a detection."""
    _, spliced = synth.make_pair(3001, (384, 384), algorithm="hamilton_adams")
    data, _ = synth.encode(spliced.rgb, 75, None)
    result = analyse(np.asarray(Image.open(io.BytesIO(data)).convert("RGB")), DEFAULT_PARAMS)
    assert result.status is Status.INCONCLUSIVE and not result.details["regions"]
    assert result.details["regions_set_aside"] and "set aside" in result.details["reason"]
    fraction = result.details["power"]["diagonal_outside_regions"]
    assert fraction is None or fraction > DEFAULT_PARAMS["max_detectable_fraction"]

"""Bayer geometry and the two demosaicing algorithms of the validation."""

import numpy as np
import pytest
from skimage.transform import downscale_local_mean

from forensics_plugins.cfa import bayer
from forensics_plugins.cfa.demosaic import ALGORITHMS, bilinear, demosaic, hamilton_adams


@pytest.fixture(scope="module")
def natural():
    import skimage.data

    return downscale_local_mean(skimage.data.astronaut() / 255.0, (2, 2, 1))


def _green_diagonal(pattern):
    return {(r + c) % 2 for r in range(2) for c in range(2) if bayer.colour_at(pattern, r, c) == "G"}


def test_shifts_move_green_or_swap_red_and_blue():
    for p in bayer.PATTERNS:
        assert bayer.shifted(p, 0, 0) == p
        for dy, dx in ((0, 1), (1, 0)):
            assert _green_diagonal(bayer.shifted(p, dy, dx)) != _green_diagonal(p)
        both = bayer.shifted(p, 1, 1)
        assert _green_diagonal(both) == _green_diagonal(p)
        assert both.index("R") == p.index("B")
    assert bayer.shifted("RGGB", 0, 1) == "GRBG"
    assert bayer.shifted("RGGB", 1, 0) == "GBRG"


def test_masks_sample_one_channel_per_pixel():
    for p in bayer.PATTERNS:
        m = bayer.masks(p, (5, 7))
        assert m.shape == (3, 5, 7)
        assert (m.sum(axis=0) == 1).all()
        assert m[1].sum() == sum(bayer.colour_at(p, r, c) == "G" for r in range(5) for c in range(7))
        assert bayer.colour_at(p, 3, 4) == "RGB"[np.argmax(m[:, 3, 4])]


def test_mosaic_keeps_the_sampled_channel():
    rgb = np.random.default_rng(0).random((6, 8, 3))
    raw = bayer.mosaic(rgb, "GBRG")
    assert raw[0, 0] == rgb[0, 0, 1] and raw[0, 1] == rgb[0, 1, 2] and raw[1, 0] == rgb[1, 0, 0]


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("pattern", bayer.PATTERNS)
def test_demosaicing_keeps_samples_and_constants(algorithm, pattern):
    rng = np.random.default_rng(1)
    rgb = rng.random((24, 30, 3))
    raw = bayer.mosaic(rgb, pattern)
    out = demosaic(raw, pattern, algorithm)
    m = bayer.masks(pattern, raw.shape)
    assert np.allclose(out[np.moveaxis(m, 0, -1)], rgb[np.moveaxis(m, 0, -1)])
    flat = np.ones((16, 16, 3)) * np.array([0.2, 0.5, 0.7])
    assert np.allclose(demosaic(bayer.mosaic(flat, pattern), pattern, algorithm), flat)


def test_edge_aware_beats_bilinear_on_a_photo(natural):
    psnr = {}
    for algorithm, fn in (("bilinear", bilinear), ("hamilton_adams", hamilton_adams)):
        out = fn(bayer.mosaic(natural, "RGGB"), "RGGB")
        err = (out - natural)[4:-4, 4:-4]
        psnr[algorithm] = -10 * np.log10(np.mean(err ** 2))
    print(f"PSNR on astronaut / 2: bilinear {psnr['bilinear']:.2f} dB, Hamilton-Adams {psnr['hamilton_adams']:.2f} dB")
    assert psnr["hamilton_adams"] > psnr["bilinear"] + 3.0
    assert psnr["bilinear"] > 25.0


def test_unknown_algorithm_is_refused():
    with pytest.raises(ValueError, match="unknown demosaicing"):
        demosaic(np.zeros((4, 4)), "RGGB", "ahd")

"""Stage 1 (residual features) and stage 2 (the phase votes) on controlled images."""

import numpy as np
import pytest

from forensics_plugins.cfa import bayer, synth
from forensics_plugins.cfa.demosaic import bilinear
from forensics_plugins.cfa.residuals import FEATURES, POSITIONS, block_features
from forensics_plugins.cfa.votes import SHIFTS, phase_votes


def _bilinear_noise(shape=(128, 160), pattern="RGGB", seed=0):
    rng = np.random.default_rng(seed)
    scene = 0.5 + 0.1 * rng.standard_normal(shape + (3,))
    return np.clip(np.round(bilinear(bayer.mosaic(scene, pattern), pattern) * 255), 0, 255).astype(np.uint8)


def _usable(f):
    return (f.clipped <= 0.25) & (f.activity >= 0.2)


def test_features_shape_centring_and_sampled_sites():
    img = _bilinear_noise()
    f = block_features(img, 16, 255.0, 0.05)
    assert f.features.shape == (8, 10, len(FEATURES), 4)
    assert np.allclose(f.features.sum(axis=3), 0, atol=1e-5)
    # Bilinear interpolation leaves the red samples the noisiest red pixels (RGGB: red at (0, 0)).
    red_cross = f.features[:, :, FEATURES.index(("R", "cross"))]
    assert (np.argmax(red_cross, axis=2) == POSITIONS.index((0, 0))).all()
    green = f.features[:, :, FEATURES.index(("G", "cross"))]
    assert (green[..., 1] > green[..., 0]).all() and (green[..., 2] > green[..., 3]).all()


def test_scale_and_dtype_do_not_change_features():
    img = _bilinear_noise()
    a = block_features(img, 16, 255.0, 0.05).features
    b = block_features(img.astype(np.uint16) * 257, 16, 65535.0, 0.05).features
    c = block_features(img.astype(np.float32) / 255.0, 16, 1.0, 0.05).features
    assert np.allclose(a, b, atol=1e-4) and np.allclose(a, c, atol=1e-4)


def test_clipping_is_measured():
    img = _bilinear_noise()
    img[:32] = 255
    f = block_features(img, 16, 255.0, 0.05)
    assert (f.clipped[:2] == 1.0).all() and (f.clipped[2:] < 0.5).all()


def test_read_only_input():
    img = _bilinear_noise()
    img.flags.writeable = False
    block_features(img, 16, 255.0, 0.05)


def test_odd_block_side_is_refused():
    with pytest.raises(ValueError, match="even"):
        block_features(np.zeros((32, 32, 3), np.uint8), 15, 255.0, 0.05)


@pytest.mark.parametrize("algorithm", ["bilinear", "hamilton_adams"])
def test_a_pasted_region_votes_for_its_shift(algorithm):
    """A region in the other diagonal's phase: its blocks mostly say so, the others do not."""
    photo = synth.make_photo(9, (384, 384), spliced=True, algorithm=algorithm, shift=(0, 1), fraction=0.3)
    f = block_features(photo.rgb, 16, 255.0, 0.05)
    v = phase_votes(f.features, f.colour, _usable(f), 0.05, 0.01)
    inside = photo.mask[8::16, 8::16] & _usable(f)
    outside = ~photo.mask[8::16, 8::16] & _usable(f)
    print(f"{algorithm}: diagonal disagreement inside {np.mean(v.t_diag[inside] < 0):.2f}, "
          f"outside {np.mean(v.t_diag[outside] < 0):.2f}")
    assert np.mean(v.t_diag[inside] < 0) > 0.6
    assert np.mean(v.t_diag[outside] < 0) < 0.1
    assert SHIFTS[int(np.bincount(v.shift_vote[inside], minlength=4).argmax())] in ((0, 1), (1, 0))


def test_votes_are_fair_coins_without_a_trace():
    """White noise carries no mosaic: the blocks must not agree on a phase."""
    rng = np.random.default_rng(3)
    agree = []
    for seed in range(6):
        img = rng.integers(0, 256, (256, 256, 3), dtype=np.uint8)
        f = block_features(img, 16, 255.0, 0.05)
        v = phase_votes(f.features, f.colour, _usable(f), 0.05, 0.01)
        agree.append(np.mean(v.t_diag[_usable(f)] > 0))
    print(f"agreement of blocks of white noise: {np.round(agree, 2)}")
    assert 0.4 < np.mean(agree) < 0.6

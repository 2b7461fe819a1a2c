"""Zero counts, flat blocks and votes against their definitions (ZERO, IPOL 2021)."""

import numpy as np
import pytest
from scipy.fft import dctn

from forensics_plugins.jpeg_grid.votes import NO_VOTE, grid_code, grid_origin, vote_map
from forensics_plugins.jpeg_grid.zeros import ZERO_THRESHOLD, dct_matrix, flat_blocks, zero_counts


def test_dct_matrix_is_the_orthonormal_dct_ii():
    d = dct_matrix()
    block = np.random.default_rng(0).normal(size=(8, 8))
    np.testing.assert_allclose(d @ block @ d.T, dctn(block, norm="ortho"), atol=1e-12)
    np.testing.assert_allclose(d @ d.T, np.eye(8), atol=1e-12)


@pytest.mark.parametrize("shape", [(8, 8), (19, 23), (70, 41)])
def test_zero_counts_match_a_direct_dct_at_every_position_without_dc(shape):
    rng = np.random.default_rng(sum(shape))
    # Smooth integer image plus a flat patch and a black one (DC zero): many coefficients near the threshold.
    img = np.round(np.cumsum(rng.normal(0, 1.5, shape), axis=1) + 100).astype(np.float32)
    img[: shape[0] // 2, : shape[1] // 3] = 77
    img[shape[0] // 2:, shape[1] // 2:] = 0
    z = zero_counts(img, strip=5)
    assert z.shape == (shape[0] - 7, shape[1] - 7)
    for y in range(shape[0] - 7):
        for x in range(shape[1] - 7):
            c = np.abs(dctn(img[y:y + 8, x:x + 8].astype(np.float64), norm="ortho")).ravel()[1:]
            # float32 arithmetic may flip a coefficient lying within 1e-4 of the threshold.
            lo, hi = (c < ZERO_THRESHOLD - 1e-4).sum(), (c < ZERO_THRESHOLD + 1e-4).sum()
            assert lo <= z[y, x] <= hi
    assert z.max() <= 63


def test_zero_counts_find_the_grid_of_a_quantised_image():
    rng = np.random.default_rng(3)
    d = dct_matrix()
    q = 12.0
    freq = np.add.outer(np.arange(8), np.arange(8))
    blocks = np.round(rng.normal(0, 1, (6, 6, 8, 8)) * 60 / (1 + freq) / q) * q
    img = np.einsum("ui,yxuv,vj->yixj", d, blocks, d).reshape(48, 48) + 128
    z = zero_counts(np.round(img).astype(np.float32))
    aligned = z[::8, ::8].mean()
    straddling = np.delete(np.delete(z, np.s_[::8], axis=0), np.s_[::8], axis=1).mean()
    assert aligned > 25 and aligned > straddling + 20


def test_zero_counts_refuse_images_smaller_than_a_block():
    with pytest.raises(ValueError):
        zero_counts(np.zeros((7, 40), np.float32))
    with pytest.raises(ValueError):
        flat_blocks(np.zeros((40, 7), np.float32))


def test_flat_blocks_match_the_definition():
    rng = np.random.default_rng(8)
    img = rng.integers(0, 3, (40, 45)).astype(np.float32)
    img[5:20, :] = np.arange(45)[None, :]            # every column constant: constant along y
    img[22:35, 10:30] = np.arange(13)[:, None] * 3   # every row constant: constant along x
    img[30:40, 33:45] = 255                          # clipped
    flat = flat_blocks(img)
    assert flat.shape == (33, 38)
    for y in range(33):
        for x in range(38):
            b = img[y:y + 8, x:x + 8]
            expected = bool((b == b[:, :1]).all() or (b == b[:1, :]).all())
            assert flat[y, x] == expected, (y, x)
    assert flat[5, 0] and flat[22, 10] and flat[30, 33] and not flat[0, 0]


def _brute_votes(z, flat):
    nh, nw = z.shape
    out = np.full((nh + 7, nw + 7), NO_VOTE, int)
    for y in range(7, nh):
        for x in range(7, nw):
            block = z[y - 7:y + 1, x - 7:x + 1]
            best = block.max()
            if (block == best).sum() > 1:
                continue
            j, i = np.unravel_index(np.argmax(block), block.shape)
            by, bx = y - 7 + j, x - 7 + i
            if not flat[by, bx]:
                out[y, x] = grid_code(bx, by)
    return out


@pytest.mark.parametrize("seed", [5, 6])
def test_votes_match_the_definition(seed):
    rng = np.random.default_rng(seed)
    z = rng.integers(0, 30, (33, 41)).astype(np.uint8)
    flat = rng.random(z.shape) < 0.2
    np.testing.assert_array_equal(vote_map(z, flat), _brute_votes(z, flat))


def test_ties_and_flat_blocks_cast_no_vote_and_a_grid_wins_its_pixels():
    z = np.zeros((41, 41), np.uint8)
    none = np.zeros(z.shape, bool)
    assert (vote_map(z, none) == NO_VOTE).all()
    z[3::8, 5::8] = 50
    v = vote_map(z, none)
    assert (v[7:34, 7:34] == grid_code(5, 3)).all()
    assert (v[:7] == NO_VOTE).all() and (v[:, -7:] == NO_VOTE).all()
    assert grid_origin(grid_code(5, 3)) == (5, 3)
    # The winning blocks flat (a sky on that grid): nobody votes, although they hold the most zeros.
    flat = np.zeros(z.shape, bool)
    flat[3::8, 5::8] = True
    assert (vote_map(z, flat) == NO_VOTE).all()
    with pytest.raises(ValueError):
        vote_map(z, flat[:-1])

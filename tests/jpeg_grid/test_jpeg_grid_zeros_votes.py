"""Zero counts and votes against direct computations on small images."""

import numpy as np
import pytest
from scipy.fft import dctn

from forensics_plugins.jpeg_grid.votes import (
    NO_VOTE,
    VOID,
    cell_tally,
    clipped_neighbourhood,
    grid_code,
    grid_origin,
    vote_map,
)
from forensics_plugins.jpeg_grid.zeros import dct_matrix, zero_counts


def test_dct_matrix_is_the_orthonormal_dct_ii():
    d = dct_matrix()
    block = np.random.default_rng(0).normal(size=(8, 8))
    np.testing.assert_allclose(d @ block @ d.T, dctn(block, norm="ortho"), atol=1e-12)
    np.testing.assert_allclose(d @ d.T, np.eye(8), atol=1e-12)


@pytest.mark.parametrize("shape", [(8, 8), (19, 23), (70, 41)])
def test_zero_counts_match_a_direct_dct_at_every_position(shape):
    rng = np.random.default_rng(sum(shape))
    # Smooth integer image plus a few flat patches: many coefficients near the thresholds.
    img = np.round(np.cumsum(rng.normal(0, 1.5, shape), axis=1) + 100).astype(np.float32)
    img[: shape[0] // 2, : shape[1] // 3] = 77
    z05, z2 = zero_counts(img, (0.5, 2.0), strip=5)
    assert z05.shape == z2.shape == (shape[0] - 7, shape[1] - 7)
    for y in range(shape[0] - 7):
        for x in range(shape[1] - 7):
            c = np.abs(dctn(img[y:y + 8, x:x + 8].astype(np.float64), norm="ortho"))
            # float32 arithmetic may flip a coefficient lying within 1e-4 of a threshold.
            for t, z in ((0.5, z05), (2.0, z2)):
                lo, hi = (c < t - 1e-4).sum(), (c < t + 1e-4).sum()
                assert lo <= z[y, x] <= hi


def test_zero_counts_find_the_grid_of_a_quantised_image():
    rng = np.random.default_rng(3)
    d = dct_matrix()
    q = 12.0
    freq = np.add.outer(np.arange(8), np.arange(8))
    blocks = np.round(rng.normal(0, 1, (6, 6, 8, 8)) * 60 / (1 + freq) / q) * q
    img = np.einsum("ui,yxuv,vj->yixj", d, blocks, d).reshape(48, 48) + 128
    z, _ = zero_counts(np.round(img).astype(np.float32), (0.5, 1.0))
    aligned = z[::8, ::8].mean()
    straddling = np.delete(np.delete(z, np.s_[::8], axis=0), np.s_[::8], axis=1).mean()
    assert aligned > 25 and aligned > straddling + 20


def test_zero_counts_refuse_images_smaller_than_a_block():
    with pytest.raises(ValueError):
        zero_counts(np.zeros((7, 40), np.float32), (0.5, 1.0))


def _brute_votes(z, excluded):
    nh, nw = z.shape
    out = np.full((nh + 7, nw + 7), NO_VOTE, int)
    for y in range(7, nh):
        for x in range(7, nw):
            best, arg, tie = -1, -1, False
            for j in range(8):
                for i in range(8):
                    g = grid_code(x - i, y - j)
                    if g == excluded:
                        continue
                    c = z[y - j, x - i]
                    if c > best:
                        best, arg, tie = c, g, False
                    elif c == best:
                        tie = True
            out[y, x] = NO_VOTE if tie else arg
    return out


@pytest.mark.parametrize("excluded", [None, 0, 37])
def test_votes_match_the_definition(excluded):
    z = np.random.default_rng(5).integers(0, 20, (33, 41)).astype(np.uint8)
    expected = _brute_votes(z, -1 if excluded is None else excluded)
    np.testing.assert_array_equal(vote_map(z, excluded), expected)


def test_ties_cast_no_vote_and_a_grid_wins_its_pixels():
    z = np.zeros((41, 41), np.uint8)
    assert (vote_map(z) == NO_VOTE).all()
    z[3::8, 5::8] = 50
    v = vote_map(z)
    inner = v[7:34, 7:34]
    assert (inner == grid_code(5, 3)).all()
    assert grid_origin(grid_code(5, 3)) == (5, 3)


def test_cell_tally_counts_every_vote_once():
    v = np.random.default_rng(1).integers(-1, 64, (50, 67)).astype(np.int8)
    hist, eligible = cell_tally(v, 8)
    assert hist.shape == (6, 8, 64) and eligible.shape == (6, 8)
    region = v[7:43, 7:60]  # pixels lying in 64 blocks: 7 <= y <= H - 8, 7 <= x <= W - 8
    assert eligible.sum() == region.size
    np.testing.assert_array_equal(hist.sum(axis=(0, 1)), np.bincount(region[region >= 0], minlength=64))


def test_pixels_near_clipping_do_not_vote_and_are_not_counted():
    y = np.full((40, 48), 128.0)
    y[20, 30] = 255.0
    void = clipped_neighbourhood(y)
    assert void[13:28, 23:38].all() and void.sum() == 15 * 15
    z = np.random.default_rng(2).integers(0, 9, (33, 41)).astype(np.uint8)
    v = vote_map(z, void=void)
    assert (v[void] == VOID).all() and not (v[~void] == VOID).any()
    hist, eligible = cell_tally(v, 8)
    assert eligible.sum() == ((v[7:33, 7:41] != VOID).sum())
    with pytest.raises(ValueError):
        vote_map(z, void=void[:-1])

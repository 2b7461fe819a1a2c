"""Binomial tails, ZERO's region growing and region NFA on vote maps built by hand."""

import math

import numpy as np
import pytest
from scipy import stats
from scipy.sparse.csgraph import connected_components

from forensics_plugins.jpeg_grid.nfa import log10_binomial_tail, nfa_text
from forensics_plugins.jpeg_grid.regions import (
    W, components, find_regions, log10_n_tests, min_region_pixels,
)
from forensics_plugins.jpeg_grid.votes import grid_code


@pytest.mark.parametrize("n, k, p", [(100, 5, 1 / 64), (1000, 40, 0.02), (50, 0, 0.1), (20, 20, 0.5)])
def test_tail_matches_scipy(n, k, p):
    expected = 0.0 if k == 0 else math.log10(stats.binom.sf(k - 1, n, p))
    assert log10_binomial_tail(n, k, p) == pytest.approx(expected, abs=1e-9)


def test_tail_beyond_double_range_is_a_finite_upper_bound():
    value = log10_binomial_tail(200_000, 150_000, 1 / 64)
    assert math.isfinite(value) and value < -300
    # Monotone in k, and never below the exact log of the first term.
    assert log10_binomial_tail(200_000, 150_001, 1 / 64) < value
    n, k, p = 200_000, 150_000, 1 / 64
    first = (math.lgamma(n + 1) - math.lgamma(k + 1) - math.lgamma(n - k + 1) + k * math.log(p)
             + (n - k) * math.log1p(-p)) / math.log(10)
    assert value >= first


def test_nfa_text():
    assert nfa_text(-1000) == "< 10^-1000"
    assert nfa_text(-12.34) == "10^-12.3"
    assert nfa_text(-1.0) == "0.1"


def _brute_partition(votes, grid):
    """Components of the pixels voting ``grid`` under |dx|, |dy| <= W, by an explicit adjacency matrix."""
    ys, xs = np.nonzero(votes == grid)
    adj = (np.abs(ys[:, None] - ys[None]) <= W) & (np.abs(xs[:, None] - xs[None]) <= W)
    return ys, xs, connected_components(adj, directed=False)[1]


@pytest.mark.parametrize("seed", range(6))
def test_components_are_zeros_region_growing(seed):
    rng = np.random.default_rng(seed)
    h, w = rng.integers(20, 80, 2)
    votes = np.where(rng.random((h, w)) < rng.uniform(0.01, 0.4), rng.integers(0, 4, (h, w)), -1).astype(np.int8)
    member = np.zeros(64, bool)
    member[[1, 2, 3]] = True
    labels, size, grid, bbox = components(votes, member)
    assert (labels[(votes < 1)] == -1).all()
    for g in (1, 2, 3):
        ys, xs, truth = _brute_partition(votes, g)
        got = labels[ys, xs]
        # Same partition: each true component maps to one label and back.
        assert len(set(zip(truth, got))) == len(set(truth)) == len(set(got))
        for k in set(got):
            sel = got == k
            assert size[k] == sel.sum() and grid[k] == g
            assert list(bbox[k]) == [xs[sel].min(), ys[sel].min(), xs[sel].max(), ys[sel].max()]


def test_reach_is_nine_pixels_across_and_down():
    votes = np.full((40, 60), -1, np.int8)
    votes[5, 5] = votes[14, 14] = 7        # 9 apart on both axes: one region
    votes[5, 40] = votes[5, 50] = 7        # 10 apart: two regions
    labels, size, _, _ = components(votes, np.arange(64) == 7)
    assert labels[5, 5] == labels[14, 14] and labels[5, 40] != labels[5, 50]
    assert sorted(size.tolist()) == [1, 1, 2]


def test_number_of_tests_and_smallest_region_are_zeros():
    log_nt = log10_n_tests((600, 800))
    assert log_nt == pytest.approx(math.log10((64 * 600 * 800) ** 2))
    assert min_region_pixels(log_nt) == math.ceil(64 * log_nt / math.log10(64))


def _votes_with_patch(rng, shape, patch, grid, density):
    """Votes at random over the other grids for 40 % of the pixels; ``density`` of votes for ``grid`` in ``patch``."""
    v = rng.integers(0, 64, shape).astype(np.int8)
    v[(rng.random(shape) < 0.6) | (v == grid)] = -1
    inside = np.zeros(shape, bool)
    inside[patch] = True
    v[inside & (rng.random(shape) < density)] = grid
    return v, inside


def test_a_patch_voting_for_one_grid_is_a_meaningful_region_with_its_extent():
    rng = np.random.default_rng(1)
    shape = (300, 400)
    g = grid_code(3, 6)
    votes, inside = _votes_with_patch(rng, shape, (slice(100, 200), slice(150, 300)), g, 0.3)
    log_nt = log10_n_tests(shape)
    labels, regions = find_regions(votes, np.arange(64) != 0, log_nt)
    assert regions and regions[0].grid == g and regions[0].log10_nfa < -20
    x0, y0, x1, y1 = regions[0].bbox
    assert abs(x0 - 150) <= 3 and abs(y0 - 100) <= 3 and abs(x1 - 299) <= 3 and abs(y1 - 199) <= 3
    assert inside[labels == regions[0].label].all()
    assert not any(r.log10_nfa < 0 for r in regions[1:])


def test_random_votes_give_no_meaningful_region():
    rng = np.random.default_rng(2)
    shape = (400, 500)
    votes = rng.integers(0, 64, shape).astype(np.int8)
    votes[rng.random(shape) < 0.5] = -1
    _, regions = find_regions(votes, np.ones(64, bool), log10_n_tests(shape))
    assert not any(r.log10_nfa < 0 for r in regions)

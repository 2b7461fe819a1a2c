"""Binomial tails and region growing on vote maps built by hand."""

import math

import numpy as np
import pytest
from scipy import stats

from forensics_plugins.jpeg_grid.detector import DEFAULT_PARAMS
from forensics_plugins.jpeg_grid.nfa import log10_binomial_tail, nfa_text
from forensics_plugins.jpeg_grid.regions import grow_regions, mirror_references
from forensics_plugins.jpeg_grid.votes import cell_tally, grid_code


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


def _votes_with_patch(rng, shape, patch, grid, density, background_grids=63):
    """Votes uniform over the other grids, and ``density`` of votes for ``grid`` inside ``patch``."""
    v = rng.integers(1, 1 + background_grids, shape).astype(np.int8)
    v[rng.random(shape) < 0.3] = -1
    inside = np.zeros(shape, bool)
    inside[patch] = True
    v[inside & (rng.random(shape) < density)] = grid
    return v, inside


def test_a_patch_voting_for_one_grid_is_found_with_its_extent():
    rng = np.random.default_rng(0)
    shape = (400, 480)
    patch = (slice(96, 296), slice(160, 400))
    v, inside = _votes_with_patch(rng, shape, patch, grid_code(3, 5), 0.15)
    hist, eligible = cell_tally(v)
    candidates = range(1, 64)
    found = grow_regions(hist, eligible, candidates, {g: 1 / 64 for g in candidates}, 6.0, DEFAULT_PARAMS)
    best = found[0]
    assert best.grid == grid_code(3, 5) and best.log10_nfa < -20
    tiles = inside[::8, ::8][: best.tiles.shape[0], : best.tiles.shape[1]]
    # The outline spreads by about two tiles (the growing window), see the section's limitations.
    assert (best.tiles & tiles).sum() / (best.tiles | tiles).sum() > 0.7


def test_uniform_votes_give_no_meaningful_region():
    rng = np.random.default_rng(1)
    v = rng.integers(0, 64, (400, 480)).astype(np.int8)
    hist, eligible = cell_tally(v)
    candidates = range(1, 64)
    found = grow_regions(hist, eligible, candidates, {g: 1 / 64 for g in candidates}, 6.0, DEFAULT_PARAMS)
    assert all(r.log10_nfa >= 0 for r in found)


def test_a_patch_explained_by_its_mirror_grid_is_not_meaningful():
    rng = np.random.default_rng(2)
    shape = (400, 480)
    patch = (slice(96, 296), slice(160, 400))
    v, inside = _votes_with_patch(rng, shape, patch, grid_code(0, 1), 0.1)
    # Content that favours the main grid's neighbour below favours the one above alike.
    v[inside & (rng.random(shape) < 0.1)] = grid_code(0, 7)
    hist, eligible = cell_tally(v)
    candidates = range(1, 64)
    refs = mirror_references(0, 2.0)
    found = grow_regions(hist, eligible, candidates, {g: 1 / 64 for g in candidates}, 6.0, DEFAULT_PARAMS,
                         use_ring=True, references=refs)
    assert all(r.log10_nfa >= -1 for r in found)


def test_mirror_references():
    refs = mirror_references(grid_code(2, 3), 2.0)
    assert len(refs) == 63 and grid_code(2, 3) not in refs
    # (2 + 1, 3 + 0) mirrors to (2 - 1, 3); it shares the main grid's row phase, so its factor applies.
    assert refs[grid_code(3, 3)] == ([grid_code(1, 3)], 2.0)
    assert refs[grid_code(3, 4)] == (sorted([grid_code(1, 4), grid_code(3, 2), grid_code(1, 2)]), 1.0)
    # The half-block shift is its own mirror image: nearest grids and its transpose instead.
    grids, factor = refs[grid_code(6, 3)]
    assert set(grids) == {grid_code(5, 3), grid_code(7, 3), grid_code(6, 2), grid_code(6, 4), grid_code(2, 7)}
    assert factor == 2.0

"""Stage 3: the a-contrario window scan on vote grids with known truth."""

import numpy as np

from forensics_plugins.cfa.regions import Question, count_tests, detectable_side, scan, window_sides


def test_window_sides_and_test_count():
    assert window_sides(20) == [2, 3, 4, 6, 8, 11, 16]
    assert count_tests(2, 2) == 1
    assert count_tests(32, 32) > count_tests(16, 16) > 0


def test_a_disagreeing_square_is_found_with_its_extent():
    rng = np.random.default_rng(0)
    ny, nx = 32, 40
    voting = rng.random((ny, nx)) < 0.9
    disagree = rng.random((ny, nx)) < 0.05
    truth = np.zeros((ny, nx), bool)
    truth[10:20, 5:17] = True
    disagree[truth] = rng.random(truth.sum()) < 0.9
    result = scan([Question("diagonal", disagree, voting)], 0.01)
    assert result.regions
    best = result.regions[0]
    iou = (best.blocks & truth).sum() / (best.blocks | truth).sum()
    print(f"square of 10 x 12 blocks, 90% disagreeing: NFA 10^{best.log10_nfa:.1f}, IoU {iou:.2f}")
    assert best.log10_nfa < -10 and iou > 0.7
    assert best.kind == "diagonal"


def test_fair_coins_give_no_region():
    found = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        voting = rng.random((24, 24)) < 0.8
        disagree = rng.random((24, 24)) < 0.5
        found += bool(scan([Question("diagonal", disagree, voting), Question("red_blue", ~disagree, voting)],
                           0.01).regions)
    assert found <= 1


def test_votes_of_a_neighbour_do_not_make_a_region():
    """Blocks next to a strong region inherit no NFA from windows that owe it to that region."""
    ny, nx = 24, 24
    voting = np.ones((ny, nx), bool)
    disagree = np.zeros((ny, nx), bool)
    disagree[4:14, 4:14] = True
    disagree[20, 20] = disagree[20, 21] = True
    result = scan([Question("diagonal", disagree, voting)], 0.01)
    assert len(result.regions) == 1
    assert result.regions[0].blocks[4:14, 4:14].all()


def test_detectable_side_shrinks_with_agreement():
    weak = detectable_side((40, 40), 0.7, 1.0, 100000, 0.01)
    strong = detectable_side((40, 40), 0.99, 1.0, 100000, 0.01)
    assert strong < weak
    assert detectable_side((10, 10), 0.51, 1.0, 100000, 0.01) is None

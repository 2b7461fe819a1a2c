"""Window sums from the integral image, against summing each window directly."""

import numpy as np
import pytest

from forensics_core import box_sums, integral_image


@pytest.mark.parametrize("dtype", [bool, np.int32, np.float32, np.float64])
def test_box_sums_are_the_sums_of_each_window(dtype):
    a = (np.random.default_rng(3).normal(size=(23, 31)) * 10).astype(dtype)
    got = box_sums(a, 6, 4)
    want = np.array([[a[y:y + 6, x:x + 6].sum(dtype=np.float64) for x in range(0, 31 - 6 + 1, 4)]
                     for y in range(0, 23 - 6 + 1, 4)])
    assert got.shape == want.shape == (5, 7)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
    # Counts stay exact integers; anything else is summed in float64.
    assert got.dtype == (np.int64 if np.dtype(dtype).kind in "biu" else np.float64)


def test_the_integral_image_has_a_leading_row_and_column_of_zeros():
    s = integral_image(np.ones((3, 4), dtype=bool))
    assert s.shape == (4, 5) and not s[0].any() and not s[:, 0].any() and s[3, 4] == 12

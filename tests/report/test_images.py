"""The one rule by which the report and every plugin figure show the photo."""

import numpy as np

from forensics_core.report import display_image


def test_a_dark_16_bit_photo_stays_dark_and_a_float_nan_is_black():
    dark = np.full((300, 400), 1000, np.uint16)
    img, factor = display_image(dark, 200)
    assert img.mode == "RGB" and img.size == (200, 150) and factor == 0.5
    assert np.asarray(img).max() == round(1000 / 65535 * 255)
    floats = np.full((10, 10, 3), 0.5, np.float32)
    floats[0, 0] = np.nan
    shown = np.asarray(display_image(floats, 100)[0])
    assert shown[0, 0].tolist() == [0, 0, 0] and shown[5, 5].tolist() == [128, 128, 128]


def test_dimming_maps_each_grey_level():
    grey = np.array([[0, 255]], np.uint8)
    img, factor = display_image(grey, 10, 0.6, 40)
    assert factor == 1.0 and np.asarray(img)[0, :, 0].tolist() == [40, 193]

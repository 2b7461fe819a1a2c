"""The IFD1 thumbnail against the image: picture area, comparison, the check under its own limits.

Reading the thumbnail from hostile bytes is the intake's (tests/core/test_thumbnail.py).
"""

import dataclasses
import io

import numpy as np
from PIL import Image, ImageFilter

from forensics_core.evidence import load_evidence
from forensics_core.thumbnail import read_thumbnail
from forensics_plugins.metadata.thumbnail import (
    ThumbnailThresholds,
    compare,
    content_box,
    monotone_fit,
    luma_of,
    thumbnail_check,
)
from metadata_helpers import DATA, camera_thumbnail, exif_bytes, jpeg, photo, with_thumbnail

LIMITS = ThumbnailThresholds(max_bytes=262144, max_pixels=1048576, aspect_tolerance=0.03, min_correlation=0.9,
                             blur_px=1.5, change_threshold=0.12, max_region_fraction=0.005)


def test_letterbox_bands_are_found():
    rng = np.random.default_rng(0)
    thumb = np.full((120, 160), 0.0)
    thumb[6:113] = rng.random((107, 160))  # a 3:2 picture in a 4:3 frame
    # The line next to each band is left out: JPEG ringing mixes it with the band.
    assert content_box(thumb, 1.5) == (0, 7, 160, 112)
    # Bands on all four sides (Nikon D70) and on one side only (Kodak DC280).
    boxed = np.full((120, 160), 0.0)
    boxed[10:110, 4:156] = rng.random((100, 152))
    assert content_box(boxed, 1.5) == (5, 11, 155, 109)
    one_sided = np.full((120, 160), 0.0)
    one_sided[13:] = rng.random((107, 160))
    assert content_box(one_sided, 1.5) == (0, 14, 160, 120)
    # Bands that are not uniform are picture, not letterbox.
    noisy = rng.random((120, 160))
    assert content_box(noisy, 1.5) == (0, 0, 160, 120)
    # A uniform dark sky is kept when removing it would spoil the framing.
    sky = rng.random((120, 160))
    sky[:20] = 0.02
    assert content_box(sky, 4 / 3) == (0, 0, 160, 120)


def test_monotone_fit_follows_a_tone_curve():
    x = np.random.default_rng(2).random(5000)
    y = x**0.6 + 0.01 * np.sin(40 * x)
    fit = monotone_fit(x, y)
    assert np.all(np.diff(fit[np.argsort(x)]) >= -1e-12)
    assert np.abs(fit - x**0.6).max() < 0.03


def test_matching_thumbnail():
    img = photo()
    cmp = compare(np.asarray(img), luma_of(Image.open(io.BytesIO(camera_thumbnail(img)))), 0.03, 1.5, 0.12)
    assert cmp.correlation > 0.99 and cmp.region_fraction < 0.001 and cmp.aspect_difference < 0.01


def test_local_edit_is_located():
    img = photo()
    thumb = luma_of(Image.open(io.BytesIO(camera_thumbnail(img))))
    edited = np.asarray(img).copy()
    edited[300:420, 60:220] = 255 - edited[300:420, 60:220]
    cmp = compare(edited, thumb, 0.03, 1.5, 0.12)
    assert cmp.region_fraction > 0.02
    # The edit spans thumbnail pixels x 15-55, y 75-105; the blur spreads it by about 3.
    x0, y0, x1, y1 = cmp.changed_box
    assert 12 <= x0 and 72 <= y0 and x1 <= 58 and y1 <= 108


def test_crop_and_rotation_change_the_aspect():
    img = photo()
    thumb = luma_of(Image.open(io.BytesIO(camera_thumbnail(img))))
    cropped = compare(np.asarray(img)[:, :500], thumb, 0.03, 1.5, 0.12)
    assert cropped.aspect_difference > cropped.aspect_tolerance and not cropped.rotated
    assert cropped.correlation < 0.95 or cropped.region_fraction > 0.003
    rotated = compare(np.rot90(np.asarray(img)), thumb, 0.03, 1.5, 0.12)
    assert rotated.rotated


def test_thumbnail_cropped_or_squeezed_by_the_camera():
    """Cameras crop their thumbnails a few per cent or squeeze them into a fixed frame: both match."""
    img = photo((960, 640))
    arr = np.asarray(img)
    inner = Image.fromarray(arr[32:608, 48:912])  # 90 % of each side, as the Olympus E-10 crops
    for thumb_img in (inner.resize((160, 107), Image.Resampling.BILINEAR),
                      img.resize((160, 120), Image.Resampling.BILINEAR)):
        cmp = compare(arr, luma_of(thumb_img), 0.03, 1.5, 0.12)
        assert cmp.correlation > 0.99 and cmp.region_fraction < 0.003
    x0, y0, x1, y1 = compare(arr, luma_of(inner.resize((160, 107))), 0.03, 1.5, 0.12).image_rect
    assert abs(x0 - 0.05) < 0.01 and abs(y0 - 0.05) < 0.01 and abs(x1 - 0.95) < 0.01 and abs(y1 - 0.95) < 0.01


def test_thumbnail_with_its_own_tone_curve_and_sharpening():
    img = photo((960, 640))
    arr = np.asarray(img)
    small = np.asarray(img.resize((160, 107), Image.Resampling.BILINEAR), dtype=np.float64) / 255
    rendered = Image.fromarray(np.uint8(255 * small**0.7 + 0.5))
    sharpened = rendered.filter(ImageFilter.UnsharpMask(radius=1, percent=120, threshold=0))
    cmp = compare(arr, luma_of(sharpened), 0.03, 1.5, 0.12)
    assert cmp.correlation > 0.98 and cmp.region_fraction < 0.003


def test_check_outcomes_on_real_files():
    canon = load_evidence(DATA / "exif" / "canon_hdr_NO.jpg")
    check, details = thumbnail_check(canon.thumbnail, canon.pixels, LIMITS)
    assert check.outcome == "consistent" and details["correlation"] > 0.99
    casio = load_evidence(DATA / "exif" / "35-empty.jpg")
    check, details = thumbnail_check(casio.thumbnail, casio.pixels, LIMITS)
    assert check.outcome == "suspicious" and details["correlation"] < 0.5
    nikon = load_evidence(DATA / "exif" / "87_OSError.jpg")
    check, details = thumbnail_check(nikon.thumbnail, nikon.pixels, LIMITS)
    assert check.outcome == "note" and "0 bytes" in check.observation and not details["present"]


def test_no_thumbnail_is_not_available():
    img = photo()
    check, details = thumbnail_check(read_thumbnail(jpeg(img, exif_bytes(make="Canon")), "JPEG"), np.asarray(img),
                                     LIMITS)
    assert check.outcome == "not available" and not details["present"] and "error" not in details


def test_the_checks_own_limits_refuse_as_the_parser_does():
    """Limits tighter than the intake's refuse its thumbnail with the parser's sentence, as a note."""
    img = photo()
    blob = camera_thumbnail(img)
    thumb = read_thumbnail(jpeg(img, with_thumbnail(exif_bytes(make="Canon"), blob)), "JPEG")
    assert thumb.error is None and thumb.size == (160, 120)
    small_bytes = dataclasses.replace(LIMITS, max_bytes=len(blob) - 1)
    check, details = thumbnail_check(thumb, np.asarray(img), small_bytes)
    assert check.outcome == "note" and not details["present"]
    assert details["error"] == f"IFD1 claims a {len(blob)}-byte thumbnail, more than the {len(blob) - 1} bytes accepted"
    small_pixels = dataclasses.replace(LIMITS, max_pixels=1000)
    check, details = thumbnail_check(thumb, np.asarray(img), small_pixels)
    assert check.outcome == "note" and details["error"] == "the thumbnail claims 160 x 120 pixels, outside the accepted 1 to 1000"

"""The innocent-processing suite, built from a small drawn corpus: determinism, chains, labels, recipes and the CLI."""

import hashlib

import numpy as np
import pytest
from PIL import Image
from test_lens_splices import (build_reading_only, draw_corpus, pixels, says_the_corpus_is_absent,
                               seed_decides_the_files, truth_rows)

from forensics_core.validation import SuiteError, folder_suite
from forensics_core.validation.innocent_processing import CHAINS, SuiteSize, build_innocent_processing

SIZE = SuiteSize(lens_correction=16, per_chain=1)
CAMERAS = {"acme": ("ACME", "ACME Model One", (480, 360)), "bravo": ("Bravo", "Bravo Two", (300, 420)),
           "opensfm_lund": ("", "", (400, 300))}
RESAMPLING_CHAINS = {"lens_correction", "rotation", "keystone", "resize_down", "resize_up"}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return draw_corpus(tmp_path_factory.mktemp("real"), CAMERAS, np.random.default_rng(5))


@pytest.fixture(scope="module")
def built(corpus, tmp_path_factory):
    return build_reading_only(build_innocent_processing, corpus, tmp_path_factory.mktemp("suite"), SIZE)


def test_the_same_seed_gives_the_same_files_and_another_seed_others(corpus, built, tmp_path):
    # Byte for byte: truth.csv, recipes.json and every photo.
    seed_decides_the_files(build_innocent_processing, corpus, built[0], SIZE, tmp_path)


def test_every_chain_is_there_and_every_photo_authentic(built):
    folder, _ = built
    rows = truth_rows(folder)
    kinds = [r["kind"] for r in rows]
    assert {k: kinds.count(k) for k in set(kinds)} == {c.name: 16 if c.name == "lens_correction" else 1 for c in CHAINS}
    suite = folder_suite(folder)
    assert len(suite.cases) == 26 and not any(c.spliced or c.mask for c in suite.cases)
    assert all(set(r) == {"file", "label", "kind", "jpeg_quality", "host", "interpolation", "subsampling"}
               for r in rows)
    for r in rows:
        assert (r["jpeg_quality"] == "" and r["subsampling"] == "") == (r["kind"] == "png_export")
        # Platforms pass photos within 1600 px, as all drawn ones are, through unresampled.
        assert bool(r["interpolation"]) == (r["kind"] in RESAMPLING_CHAINS)


def test_recipes_name_their_source_and_remake_the_sizes(built, corpus):
    folder, recipes = built
    assert {r["host"]["camera"] for r in recipes} == {"ACME Model One", "Bravo Two"}, "opensfm_lund is left out"
    for r in recipes:
        host = corpus / "authentic_buildings" / r["host"]["set"] / r["host"]["file"]
        assert hashlib.sha256(host.read_bytes()).hexdigest() == r["host"]["sha256"]
        with Image.open(folder / r["file"]) as img:
            assert list(img.size) == r["export"]["size"] and not img.getexif()
        assert r["export"]["size"] == processed_size(r["kind"], r["settings"], r["host"]["size"])
        if r["kind"] == "crop":
            assert r["settings"]["box"][0] % 8 and r["settings"]["box"][1] % 8
        if r["kind"] == "png_export":
            assert np.array_equal(pixels(folder / r["file"]), pixels(host))


def processed_size(kind, settings, size):
    if kind in ("rotation", "crop"):
        return settings["crop" if kind == "rotation" else "box"][2:]
    if kind in ("resize_down", "resize_up", "platform_reencode"):
        return settings["size"] or size
    return size


def test_lens_corrections_cover_every_interpolation_and_half_are_saved_at_98_or_more(built):
    _, recipes = built
    lens = [r for r in recipes if r["kind"] == "lens_correction"]
    assert {r["settings"]["interpolation"] for r in lens} == {"nearest", "linear", "cubic", "lanczos4"}
    assert sum(r["export"]["jpeg_quality"] >= 98 for r in lens) == len(lens) // 2
    assert all(-0.10 <= r["settings"]["k1"] <= -0.04 or 0.03 <= r["settings"]["k1"] <= 0.08 for r in lens)
    # Half fill the frame (an editor's crop-to-fill), half keep the camera matrix (cv2.undistort's default), each
    # with every interpolation and both quality sets.
    for fill in (True, False):
        some = [r for r in lens if r["settings"]["fill_frame"] is fill]
        assert len(some) == 8 and {r["settings"]["interpolation"] for r in some} == {"nearest", "linear", "cubic",
                                                                                      "lanczos4"}
        assert sum(r["export"]["jpeg_quality"] >= 98 for r in some) == 4


def test_a_corpus_of_downscaled_photos_alone_gives_nothing(corpus, tmp_path):
    only = tmp_path / "real" / "authentic_buildings"
    only.mkdir(parents=True)
    (only / "opensfm_lund").symlink_to(corpus / "authentic_buildings" / "opensfm_lund")
    with pytest.raises(SuiteError, match="no authentic_buildings"):
        build_innocent_processing(tmp_path / "real", tmp_path / "suite", seed=1, size=SIZE)


def test_the_cli_says_in_one_line_that_the_corpus_is_absent(tmp_path):
    says_the_corpus_is_absent("innocent-processing", tmp_path)

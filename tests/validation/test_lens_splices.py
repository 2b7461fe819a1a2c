"""The lens-splices suite, built from a small drawn corpus: determinism, masks, controls, recipes and the CLI."""

import csv
import hashlib
import json
import subprocess
import sys

import cv2
import numpy as np
import pytest
from PIL import Image

from forensics_core.validation import SuiteError, folder_suite
from forensics_core.validation.lens_splices import SuiteSize, build_lens_splices, read_corpus

SIZE = SuiteSize(other_camera=4, moved=3, rescaled=2, hosts=4)
CAMERAS = {"acme": ("ACME", "ACME Model One", (480, 360)), "opensfm_lund": ("", "", (400, 300))}


def facade(rng, size):
    """A grey facade of window frames and a grid: straight edges in two directions for LSD to find."""
    w, h = size
    img = np.tile(np.linspace(120, 180, w, dtype=np.float32), (h, 1))
    for x in range(int(rng.integers(20, 60)), w, int(rng.integers(70, 110))):
        cv2.line(img, (x, 0), (x, h - 1), 60, 3)
    for _ in range(6):
        x0, y0 = int(rng.integers(0, w // 2)), int(rng.integers(0, h // 2))
        cv2.rectangle(img, (x0, y0), (x0 + int(rng.integers(w // 5, w // 2)), y0 + int(rng.integers(h // 5, h // 2))),
                      float(rng.integers(0, 90)), 4)
    grey = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    return np.stack([grey, grey, (grey * 0.9).astype(np.uint8)], axis=-1)


def draw_corpus(root, cameras, rng):
    """Three drawn facades in each set of ``cameras`` (set: make, model, size), and a manipulated photo listed."""
    for name, (make, model, size) in cameras.items():
        folder = root / "authentic_buildings" / name
        folder.mkdir(parents=True)
        truth = ["file,label,mask,source,camera"]
        exif = ["file,bytes,make,model,focal_length_mm,focal_length_35mm,width,height,orientation,software,"
                "datetime_original,format,notes"]
        for i in range(3):
            Image.fromarray(facade(rng, size)).save(folder / f"{i}.jpg", quality=95)
            truth.append(f"{i}.jpg,authentic,,drawn,{model}")
            exif.append(f"{i}.jpg,0,{make},{model},4.3,35,{size[0]},{size[1]},1,,,JPEG,")
        truth.append("edited.jpg,manipulated,,drawn,")
        (folder / "truth.csv").write_text("\n".join(truth) + "\n")
        (folder / "exif.csv").write_text("\n".join(exif) + "\n")
    return root


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return draw_corpus(tmp_path_factory.mktemp("real"), CAMERAS, np.random.default_rng(7))


def digests(folder):
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def build_reading_only(build, corpus, folder, size):
    """``build`` (a suite's builder) with seed 11 into ``folder``, checking that the corpus is only read."""
    before = digests(corpus)
    recipes = build(corpus, folder, seed=11, size=size)
    assert digests(corpus) == before, "the corpus is only read"
    return folder, recipes


def seed_decides_the_files(build, corpus, folder, size, tmp_path):
    """The suite ``build`` made into ``folder`` with seed 11 again, byte for byte, and another with seed 12."""
    build(corpus, tmp_path / "again", seed=11, size=size)
    assert digests(tmp_path / "again") == digests(folder)
    build(corpus, tmp_path / "other", seed=12, size=size)
    assert (tmp_path / "other" / "recipes.json").read_text() != (folder / "recipes.json").read_text()


@pytest.fixture(scope="module")
def built(corpus, tmp_path_factory):
    return build_reading_only(build_lens_splices, corpus, tmp_path_factory.mktemp("suite"), SIZE)


def truth_rows(folder):
    with open(folder / "truth.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def pixels(path):
    with Image.open(path) as img:
        return np.asarray(img.convert("RGB"), dtype=float)


def test_the_same_seed_gives_the_same_files_and_another_seed_others(corpus, built, tmp_path):
    seed_decides_the_files(build_lens_splices, corpus, built[0], SIZE, tmp_path)


def test_cameras_are_named_from_exif_and_unnamed_sets_by_the_map(corpus):
    photos = read_corpus(corpus)
    assert {p.camera for p in photos} == {"ACME Model One", "iPhone 4S"}
    assert len(photos) == 6 and all(len(p.segments) for p in photos)


def test_kinds_counts_and_conditions_as_the_folder_suite_reads_them(built):
    folder, recipes = built
    rows = truth_rows(folder)
    kinds = [r["kind"] for r in rows]
    assert {k: kinds.count(k) for k in set(kinds)} == {"other_camera": 4, "moved": 3, "rescaled": 2, "control": 4}
    suite = folder_suite(folder)
    assert len(suite.cases) == 13 and sum(c.spliced for c in suite.cases) == 9
    assert all((c.mask is not None) == c.spliced for c in suite.cases)
    assert all(set(r) == {"file", "label", "mask", "kind", "jpeg_quality", "resized", "host", "donor",
                          "two_directions"} for r in rows)
    assert all(r["two_directions"] in ("yes", "no") for r in rows if r["label"] == "spliced")


def test_recipes_follow_the_kinds(built, corpus):
    _, recipes = built
    for r in recipes:
        host = corpus / "authentic_buildings" / r["host"]["set"] / r["host"]["file"]
        assert hashlib.sha256(host.read_bytes()).hexdigest() == r["host"]["sha256"]
        assert r["export"]["jpeg_quality"] in (85, 90, 92, 95, 98) and r["export"]["exif"] is False
        if r["kind"] == "control":
            assert r["seed"] is None and r["source"] is None
            continue
        assert isinstance(r["seed"], int) and r["region"]["edges"] >= 1
        change = abs(r["distance_from_centre"]["destination"] - r["distance_from_centre"]["source"])
        if r["kind"] == "other_camera":
            assert r["donor"]["camera"] != r["host"]["camera"]
            assert max(r["donor"]["resized_to"]) == max(r["host"]["size"])
            assert change >= 0.25 and r["destination"][2:] == r["source"][2:]
        elif r["kind"] == "moved":
            assert r["donor"] is None and change >= 0.25 and r["destination"][2:] == r["source"][2:]
        else:
            assert 0.7 <= r["scale"] <= 0.85 or 1.2 <= r["scale"] <= 1.4
            assert r["destination"][2] == round(r["source"][2] * r["scale"])


def test_masks_cover_the_pasted_rectangle_and_nothing_else_changed(built):
    folder, recipes = built
    controls = {r["host"]["file"] + r["host"]["set"]: r for r in recipes if r["kind"] == "control"}
    for r in recipes:
        if r["kind"] == "control":
            continue
        photo = pixels(folder / r["file"])
        with Image.open(folder / r["mask"]) as img:
            mask = np.asarray(img) > 0
        assert mask.shape == photo.shape[:2] and list(img.size) == r["export"]["size"]
        factor = r["export"]["resize"] or 1
        x, y, w, h = (round(v * factor) for v in r["destination"])
        rows, cols = np.nonzero(mask)
        assert abs(cols.min() - x) <= 1 and abs(rows.min() - y) <= 1
        assert abs(cols.max() + 1 - (x + w)) <= 1 and abs(rows.max() + 1 - (y + h)) <= 1
        assert mask.sum() == pytest.approx(w * h, rel=0.03)
        control = pixels(folder / controls[r["host"]["file"] + r["host"]["set"]]["file"])
        away = cv2.dilate(mask.astype(np.uint8), np.ones((33, 33), np.uint8)) == 0
        # JPEG blocks across the rectangle's edge change with it; farther away the forgery is its control.
        assert np.abs(photo - control)[away].mean() < 1.5
        assert np.abs(photo - control)[mask].mean() > 5


def test_each_host_has_one_control_saved_as_its_forgeries(built, corpus):
    folder, recipes = built
    controls = [r for r in recipes if r["kind"] == "control"]
    hosts = {(r["host"]["set"], r["host"]["file"]) for r in recipes if r["kind"] != "control"}
    assert sorted((c["host"]["set"], c["host"]["file"]) for c in controls) == sorted(hosts)
    for c in controls:
        siblings = [r for r in recipes if r["host"] == c["host"] and r is not c]
        assert all(s["export"] == c["export"] for s in siblings)
        assert c["label"] == "authentic" and c["mask"] is None
        original = pixels(corpus / "authentic_buildings" / c["host"]["set"] / c["host"]["file"])
        if c["export"]["resize"] is None:
            assert np.abs(pixels(folder / c["file"]) - original).mean() < 3


def test_a_corpus_of_one_camera_cannot_give_other_camera_cases(corpus, tmp_path):
    single = tmp_path / "real"
    (single / "authentic_buildings").mkdir(parents=True)
    (single / "authentic_buildings" / "acme").symlink_to(corpus / "authentic_buildings" / "acme")
    with pytest.raises(SuiteError, match="two cameras"):
        build_lens_splices(single, tmp_path / "suite", seed=1, size=SIZE)
    build_lens_splices(single, tmp_path / "suite", seed=1, size=SuiteSize(other_camera=0, moved=2, rescaled=1, hosts=2))
    assert json.loads((tmp_path / "suite" / "recipes.json").read_text())["size"]["other_camera"] == 0


def test_the_cli_says_in_one_line_that_the_corpus_is_absent(tmp_path):
    says_the_corpus_is_absent("lens-splices", tmp_path)


def says_the_corpus_is_absent(suite, tmp_path):
    """``forensics validate SUITE`` without its corpus: one line, exit 1, no traceback, nothing written."""
    absent = tmp_path / "no-corpus"
    run = subprocess.run([sys.executable, "-m", "forensics_core", "validate", suite, "--corpus", absent,
                          "--out", tmp_path / "o", "--detectors", "metadata"], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert run.stderr.count("\n") == 1 and f"the real corpus is absent ({absent})" in run.stderr
    assert not (tmp_path / "o").exists()

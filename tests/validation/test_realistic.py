"""The realistic suite, built from a small drawn corpus: determinism, kinds, masks, controls, recipes and the CLI."""

import json

import numpy as np
import pytest
from PIL import Image
from test_lens_splices import (build_reading_only, draw_corpus, pixels, says_the_corpus_is_absent,
                               seed_decides_the_files, truth_rows)

from forensics_core.calibration.fit import scene
from forensics_core.validation import folder_suite
from forensics_core.validation.cases import find_sets
from forensics_core.validation.realistic import CONTROL, KINDS, SuiteSize, build_realistic

SIZE = SuiteSize(per_kind=3)
CAMERAS = {"acme": ("ACME", "ACME Model One", (480, 360)), "bravo": ("Bravo", "Bravo Two", (400, 300)),
           "opensfm_lund": ("", "", (400, 300))}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return draw_corpus(tmp_path_factory.mktemp("real"), CAMERAS, np.random.default_rng(7))


@pytest.fixture(scope="module")
def built(corpus, tmp_path_factory):
    return build_reading_only(build_realistic, corpus, tmp_path_factory.mktemp("suite"), SIZE)


def test_the_same_seed_gives_the_same_files_and_another_seed_others(corpus, built, tmp_path):
    seed_decides_the_files(build_realistic, corpus, built[0], SIZE, tmp_path)


def test_every_kind_comes_with_as_many_controls_from_the_same_hosts(built):
    folder, _ = built
    rows = truth_rows(folder)
    kinds = [r["kind"] for r in rows]
    assert all(kinds.count(k) == SIZE.per_kind for k in KINDS)
    assert kinds.count(CONTROL) == len(KINDS) * SIZE.per_kind
    forged = {r["host"] for r in rows if r["kind"] != CONTROL}
    assert forged == {r["host"] for r in rows if r["kind"] == CONTROL}
    assert not any(r["host"].startswith("opensfm_lund/") for r in rows)
    assert all((r["label"] == "authentic") == (r["kind"] == CONTROL) for r in rows)
    assert all(r["donor"] and r["donor"].split("/")[0] != r["host"].split("/")[0] for r in rows if r["kind"] == "splice")


def test_masks_cover_an_object_like_region_where_the_photo_changed(built, corpus):
    folder, recipes = built
    for recipe in recipes:
        if recipe["kind"] == CONTROL or recipe["export"]["kind"] == "resized_jpeg":
            continue
        mask = np.asarray(Image.open(folder / recipe["mask"])) > 0
        share = mask.mean()
        assert 0.001 < share < 0.12, (recipe["name"], share)
        host = corpus / "authentic_buildings" / recipe["host"]["set"] / recipe["host"]["file"]
        change = np.abs(pixels(folder / recipe["file"]) - pixels(host)).mean(axis=2)
        # Inside the mask the content is another's; outside only the save changed it.
        assert change[mask].mean() > 2 * change[~mask].mean(), recipe["name"]


def test_recipes_name_their_sources_and_read_as_a_folder_suite(built):
    folder, recipes = built
    document = json.loads((folder / "recipes.json").read_text())
    assert document["suite"] == "realistic" and document["size"] == {"per_kind": SIZE.per_kind}
    assert {r["kind"] for r in recipes} == {*KINDS, CONTROL}
    for r in recipes:
        assert len(r["host"]["sha256"]) == 64
        assert r["export"]["kind"] in ("jpeg", "resized_jpeg", "png")
    moves = [r["forged"] for r in recipes if r["kind"] == "copy_move"]
    assert all(m["transform"] in ("move", "rotate", "scale") for m in moves)
    suite = folder_suite(folder)
    assert len(suite.cases) == len(recipes)
    assert sum(c.spliced for c in suite.cases) == len(KINDS) * SIZE.per_kind
    assert all(c.mask is not None for c in suite.cases if c.spliced)


def test_the_cli_says_in_one_line_that_the_corpus_is_absent(tmp_path):
    says_the_corpus_is_absent("realistic", tmp_path)


def test_a_forgery_and_its_control_are_saved_alike(built):
    _, recipes = built
    by_name = {r["name"]: r for r in recipes}
    for r in recipes:
        if r["kind"] == CONTROL:
            forgery = by_name[r["name"].removeprefix("control_")]
            assert forgery["host"] == r["host"]
            assert {k: v for k, v in forgery["export"].items() if k != "size"} == \
                   {k: v for k, v in r["export"].items() if k != "size"}


def test_each_case_is_in_its_hosts_scene_of_the_corpus_record(corpus, built):
    """Calibrators fitted on the corpus's record and this suite together leave a host and its cases out as one."""
    folder, _ = built
    host_scene = {}
    # Named as `forensics validate CORPUS` names a set's photos: set-prefixed file stems, the set as a condition.
    for set_name, set_folder in find_sets(corpus):
        if set_name.startswith("authentic_buildings/"):
            for row in truth_rows(set_folder):
                if row["label"] == "authentic":
                    name = f"{set_name.replace('/', '_')}__{row['file'].rsplit('.', 1)[0]}"
                    host_scene[f"{set_name.split('/', 1)[1]}/{row['file']}"] = scene(name, {"set": set_name})
    for c in folder_suite(folder).cases:
        assert scene(c.name, c.conditions) == host_scene[c.conditions["host"]]

"""prnu on photos of synthetic cameras made here: references, attribution, a piece from another camera, and
the reference material's path through the core (skipped without it, hashed and listed with it)."""

import json
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from forensics_core import Status, analyze, load_evidence, load_references
from forensics_core.cli import cli
from forensics_plugins.prnu.alignment import Peak, best_alignment, candidates, single_test_z
from forensics_plugins.prnu.detector import Prnu
from forensics_plugins.prnu.spec import DEFAULT_PARAMS

from . import camera

BOX = (256, 512, 512, 512)


@pytest.fixture(scope="module")
def refs(tmp_path_factory):
    return camera.references(tmp_path_factory.mktemp("prnu") / "refs", camera=1)


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    folder = tmp_path_factory.mktemp("prnu-photos")
    made = {"same": camera.photo(1, 5), "other": camera.photo(2, 5), "spliced": camera.spliced(1, 2, 5, BOX)}
    for name, data in made.items():
        (folder / f"{name}.jpg").write_bytes(data)
    return {name: folder / f"{name}.jpg" for name in made}


def _run(path, refs, **params):
    evidence = load_evidence(path)
    return Prnu().analyze(evidence, {**DEFAULT_PARAMS, **params}, load_references(refs, max_pixels=10 ** 8))


def test_the_reference_camera_is_found_in_its_photo_and_no_part_lacks_it(photos, refs):
    result = _run(photos["same"], refs)
    assert result.status is Status.OK, result.summary
    assert result.details["pce"] > 1000 and result.details["alignment"]["shift"] == [0, 0]
    assert result.details["local"]["regions"] == []
    assert result.details["reference"]["count"] == 8
    assert len(result.details["reference"]["files"]) == 8


def test_another_cameras_photo_does_not_carry_the_fingerprint(photos, refs):
    result = _run(photos["other"], refs)
    assert result.status is Status.INCONCLUSIVE
    assert abs(result.details["pce"]) < DEFAULT_PARAMS["min_pce"]
    assert "not found" in result.summary and "local" not in result.details


def test_a_piece_from_another_camera_is_localised(photos, refs):
    result = _run(photos["spliced"], refs)
    assert result.status is Status.OK and result.details["pce"] > 1000
    mask = np.zeros(camera.SHAPE, bool)
    y, x, h, w = BOX
    mask[y:y + h, x:x + w] = True
    found = Prnu().localize(type("F", (), {"details": result.details})(), camera.SHAPE)
    f1 = 2 * (found & mask).sum() / (found.sum() + mask.sum())
    # Measured: one region, x 576-960, y 320-704 inside the piece at x 512-1024, y 256-768 (F1 0.72): blocks half
    # over its edge are not flagged.
    assert len(result.details["local"]["regions"]) == 1 and f1 > 0.6, result.details["local"]["regions"]


def test_the_fingerprint_is_cached_per_reference_set(photos, refs):
    first = _run(photos["same"], refs)
    second = _run(photos["same"], refs)
    assert second.details["reference"]["cached"] is True
    assert first.details["pce"] == second.details["pce"]


def test_references_of_different_sizes_make_the_detector_inconclusive(photos, refs, tmp_path):
    mixed = tmp_path / "mixed"
    shutil.copytree(refs, mixed)
    shutil.copyfile(camera_file := photos["same"], mixed / "other_size.jpg")
    from PIL import Image

    Image.open(camera_file).crop((0, 0, 400, 300)).save(mixed / "other_size.jpg")
    result = _run(photos["same"], mixed)
    assert result.status is Status.INCONCLUSIVE and "differ in size" in result.summary


def test_alignments_follow_the_photos_size():
    assert candidates((512, 768), (512, 768)) == [(0, 1.0), (180, 1.0)]
    assert candidates((768, 512), (512, 768)) == [(90, 1.0), (270, 1.0)]
    assert (0, 0.5) in candidates((256, 384), (512, 768))
    assert candidates((600, 800), (512, 768)) == []
    one = Peak(100.0, (0, 0), 1)
    many = Peak(100.0, (3, 4), 10 ** 6)
    assert single_test_z(one) == pytest.approx(10.0)
    assert 0 < single_test_z(many) < 10.0


def test_a_crop_is_found_at_its_place(photos, refs):
    from forensics_plugins.prnu.cache import fingerprint_for
    from forensics_plugins.prnu.residual import test_residual

    fingerprint, _ = fingerprint_for(load_references(refs, max_pixels=10 ** 8), 3.0)
    pixels = load_evidence(photos["same"]).pixels[96:96 + 320, 160:160 + 480]
    residual, intensity = test_residual(np.ascontiguousarray(pixels))
    peak = best_alignment(intensity * residual, fingerprint.k)
    assert peak.shift == (96, 160) and peak.pce > 1000 and peak.rotation == 0


def test_without_references_prnu_is_skipped_and_nothing_else_changes(photo):
    alone = analyze(photo, ["noise"])
    both = analyze(photo, ["noise", "prnu"])
    prnu = both.detectors[1]
    assert prnu.status is Status.SKIPPED and "--reference" in prnu.summary
    assert both.references == []
    assert both.detectors[0].summary == alone.detectors[0].summary
    assert both.detectors[0].log10_lr == alone.detectors[0].log10_lr
    assert both.verdict.log10_lr == alone.verdict.log10_lr and both.verdict.label == alone.verdict.label


def test_the_cli_lists_the_references_and_runs_prnu_on_them(photos, refs, tmp_path, validate):
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["analyze", str(photos["same"]), "--out", str(out), "--format", "json",
                                      "--detectors", "prnu", "--reference", str(refs)])
    assert result.exit_code == 0, result.output
    doc = validate(json.loads((out / "same" / "findings.json").read_text()))
    assert [r["name"] for r in doc["references"]] == [f"ref_{i:02d}.jpg" for i in range(8)]
    assert all(len(r["sha256"]) == 64 for r in doc["references"])
    assert doc["parameters"]["reference"] == str(refs.resolve())
    assert doc["detectors"][0]["status"] == "ok"


def _folder(parent, files):
    folder = parent / "refs"
    folder.mkdir()
    for name in files:
        (folder / name).write_text("not a photo")
    return folder


@pytest.mark.parametrize("make, says", [
    (lambda d: d / "missing", "no such folder"),
    (lambda d: _folder(d, []), "no reference photo"),
    (lambda d: _folder(d, ["notes.txt"]), "notes.txt"),
])
def test_a_bad_reference_folder_gets_one_line_and_exit_2(photos, tmp_path, make, says):
    folder = make(tmp_path)
    result = CliRunner().invoke(cli, ["analyze", str(photos["same"]), "--out", str(tmp_path / "out"),
                                      "--format", "json", "--reference", str(folder)])
    assert result.exit_code == 2 and says in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_the_report_states_the_source_apart_and_lists_the_references(photos, refs, tmp_path):
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["analyze", str(photos["spliced"]), "--out", str(out), "--format", "json,html",
                                      "--detectors", "prnu,noise", "--reference", str(refs)])
    assert result.exit_code == 0, result.output
    html = (out / "spliced" / "report.html").read_text()
    assert "Source, a separate statement (prnu)" in html
    assert "Sensor fingerprint (PRNU)" in html and "Reference photos" in html
    assert (out / "spliced" / "prnu-references.csv").is_file()
    assert "--reference" in html
    doc = json.loads((out / "spliced" / "findings.json").read_text())
    prnu = doc["detectors"][0]
    assert prnu["details"]["attribution"]["log10_lr"] == prnu["details"]["attribution_log10_lr"]
    assert "prnu" not in doc["verdict"]["likelihood_ratio"]["uncalibrated"]

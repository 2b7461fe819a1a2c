"""noise on photos made here: one grain throughout, or a piece pasted with noisier or smoother grain."""

import numpy as np
import pytest

from forensics_core import Status, load_evidence
from forensics_plugins.noise.detector import NoiseLevel, regions_mask
from forensics_plugins.noise.spec import DEFAULT_PARAMS
from forensics_plugins.noise.synth import encode, paste, scene, synthetic_cases


def _evidence(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    return load_evidence(path)


def _best_share(result, mask):
    """Share of the best window's pixels that were pasted."""
    b = result.details["best"]
    return mask[8 * b["row"]:8 * (b["row"] + b["size"]), 8 * b["col"]:8 * (b["col"] + b["size"])].mean()


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("noise")
    return [(case, NoiseLevel().analyze(_evidence(tmp, case.name + case.suffix, case.data), DEFAULT_PARAMS))
            for case in synthetic_cases(3, 6)]


def test_pasted_grain_scores_higher_than_a_photo_of_one_grain(results):
    authentic = [r for c, r in results if not c.spliced]
    spliced = [r for c, r in results if c.spliced]
    assert all(r.status is Status.OK for r in authentic + spliced), [r.summary for r in authentic + spliced]
    assert all(r.p_value is None for r in authentic + spliced)
    # Measured (seed 3, 1024 x 768): authentic |deviation| up to 5.0 (scores up to 0.25), none listed at 6;
    # spliced deviations +6.5, +19.6, +20.6 (noisier), -15.5, -9.0, -4.3 (smoother), 5 of 6 listed.
    # Over seeds 0-4 (50 pairs): authentic at most 5.55, 41 of 50 spliced listed, AUC 0.95.
    top = max(r.score for r in authentic)
    assert top < 0.3 and not any(r.details["windows"] for r in authentic), [r.details["best"] for r in authentic]
    assert sum(bool(r.details["windows"]) and r.score > top for r in spliced) >= 4, [r.score for r in spliced]


def test_the_best_window_lies_on_the_pasted_piece(results):
    detected = [(c, r) for c, r in results if c.spliced and r.details["windows"]]
    assert len(detected) >= 4
    for case, r in detected:
        covered = (regions_mask(r.details, case.mask.shape) & case.mask).sum() / case.mask.sum()
        # Measured: best window 0.60-0.93 pasted; listed windows cover 0.36-1.0 of the piece (0.36: one window
        # listed on a large ellipse).
        assert _best_share(r, case.mask) > 0.5 and covered > 0.3, (case.name, _best_share(r, case.mask), covered)


def test_noisier_pieces_deviate_up_and_smoother_ones_down(results):
    spliced = [(c.conditions["kind"], r.details["best"]["deviation"]) for c, r in results if c.spliced]
    right = [(kind == "noise_noisier") == (dev > 0) for kind, dev in spliced]
    # Measured: all 6 right, noisier +6.5 to +20.6, smoother -4.3 to -15.5 (seeds 0-4: 49 of 50).
    assert all(right), spliced
    listed = [(c.conditions["kind"], r.details["best"]["deviation"]) for c, r in results
              if c.spliced and r.details["windows"]]
    assert all((kind == "noise_noisier") == (dev > 0) for kind, dev in listed), listed


def test_a_flat_sky_above_texture_with_one_grain_is_not_listed(tmp_path):
    # JPEG quantises a smooth sky's grain to silence and keeps more in texture; like content is compared with like.
    import cv2

    rng = np.random.default_rng(0)
    h, w = 480, 640
    img = np.empty((h, w), np.float32)
    y, x = np.mgrid[0:h // 2, 0:w].astype(np.float32)
    img[:h // 2] = 200 - 50 * y / (h // 2) + 10 * x / w
    field = cv2.GaussianBlur(rng.normal(0, 1, (h - h // 2, w)).astype(np.float32), (0, 0), 2.0)
    img[h // 2:] = 110 + 40 * field / field.std()
    img += rng.normal(0, 3.0, img.shape).astype(np.float32)
    r = NoiseLevel().analyze(_evidence(tmp_path, "sky.jpg", encode(np.clip(img, 8, 247), 90)), DEFAULT_PARAMS)
    # Measured: best deviation 2.45, nothing listed.
    assert r.status is Status.OK and r.details["windows"] == [], r.details["best"]
    assert abs(r.details["best"]["deviation"]) < 4


def test_a_tiny_photo_is_inconclusive_with_the_reason(tmp_path):
    rng = np.random.default_rng(1)
    r = NoiseLevel().analyze(_evidence(tmp_path, "tiny.jpg", encode(scene(rng, (64, 64), 3.0), 90)), DEFAULT_PARAMS)
    assert r.status is Status.INCONCLUSIVE and r.score is None and r.p_value is None
    assert r.details["valid_blocks"] == 64 and "256 are needed" in r.summary, r.summary


def test_a_picture_without_any_grain_is_inconclusive(tmp_path):
    from PIL import Image

    flat = np.full((400, 600), 128, np.uint8)
    flat[:, :300] = 255
    Image.fromarray(flat).save(tmp_path / "flat.png")
    r = NoiseLevel().analyze(load_evidence(tmp_path / "flat.png"), DEFAULT_PARAMS)
    assert r.status is Status.INCONCLUSIVE and r.score is None and "no noise to compare" in r.summary, r.summary


def test_same_photo_same_findings(tmp_path):
    rng = np.random.default_rng(4)
    spliced, _ = paste(scene(rng, (640, 480), 3.0), rng, "noisier", 3.0)
    data = encode(spliced, 90)
    a = NoiseLevel().analyze(_evidence(tmp_path, "a.jpg", data), DEFAULT_PARAMS)
    b = NoiseLevel().analyze(_evidence(tmp_path, "b.jpg", data), DEFAULT_PARAMS)
    a.details.pop("elapsed_s"), b.details.pop("elapsed_s")
    assert (a.score, a.details) == (b.score, b.details)


def test_through_the_plugin_host_a_jpeg_and_a_png_get_an_ok_finding_without_p_value(tmp_path):
    from PIL import Image

    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.plugins import PluginHost

    host = PluginHost.from_entry_points(allow=["noise"])
    assert host.detectors["noise"].spec.calibrated_on == "score"
    rng = np.random.default_rng(4)
    spliced, mask = paste(scene(rng, (640, 480), 3.0), rng, "noisier", 3.0)
    jpeg = _evidence(tmp_path, "spliced.jpg", encode(spliced, 90))
    (finding,) = analyze_evidence(jpeg, host, Options(detectors=["noise"], isolation="process")).detectors
    assert finding.status is Status.OK, finding.error or finding.summary
    # Measured: deviation +5.2 (score 0.26; at 640 x 480 a window's mean is measured on few blocks, so under
    # the listing threshold of 6), the best window on the piece.
    assert finding.p_value is None and finding.score > 0.2 and "noisier" in finding.summary, finding.summary
    assert _best_share(finding, mask) > 0.3, finding.details["best"]

    rng = np.random.default_rng(4)
    smoother, mask = paste(scene(rng, (640, 480), 3.0), rng, "smoother", 3.0)
    Image.fromarray(np.round(smoother).astype(np.uint8)).save(tmp_path / "spliced.png")
    png = load_evidence(tmp_path / "spliced.png")
    (found,) = analyze_evidence(png, host, Options(detectors=["noise"])).detectors
    assert found.status is Status.OK and found.p_value is None, found.error or found.summary
    # Measured: deviation -16.0 (score 0.80), the best window wholly pasted.
    assert found.details["best"]["deviation"] < -4 and _best_share(found, mask) > 0.5, found.details["best"]

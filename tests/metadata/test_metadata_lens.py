"""lensfun lookup, conversion to the project's (k1, k2), and the comparison with the lens detector."""

import lensfunpy
import numpy as np
import pytest

from forensics_core import RADIAL_DISTORTION_KEY, DetectorFinding, RadialDistortion, Status
from forensics_plugins.lens_distortion.geometry import undistort
from forensics_plugins.metadata.conversion import forward, inverse, predict, unit_scale
from forensics_plugins.metadata.lens_check import compare, lens_check
from forensics_plugins.metadata.lensdb import calibration_aspect, database, lookup, normalise_lens_text
from metadata_helpers import info

SX60 = ("Canon", "Canon PowerShot SX60 HS")
D70S = ("NIKON CORPORATION", "NIKON D70s")


def test_database_is_bundled_and_offline():
    db = database()
    assert len(db.cameras) > 500 and len(db.lenses) > 500


def test_lens_text_normalisation():
    assert normalise_lens_text("18.0-70.0 mm f/3.5-4.5") == "18-70mm f/3.5-4.5"
    assert normalise_lens_text("EF-S18-55mm f/3.5-5.6 IS") == "EF-S18-55mm f/3.5-5.6 IS"


def test_fixed_lens_compact():
    found = lookup(*SX60, None, 8.119)
    lens = found.data
    assert lens.lens_model.startswith("Canon PowerShot SX60 HS") and lens.model == "ptlens"
    assert lens.terms == pytest.approx((0.0, -0.0162908, 0.0), abs=1e-6)
    assert lens.calibration_aspect == pytest.approx(4 / 3) and lens.camera_crop == pytest.approx(5.61, abs=1e-3)


def test_interchangeable_lens_by_lens_model():
    lens = lookup(*D70S, "18.0-70.0 mm f/3.5-4.5", 18.0).data
    assert "18-70mm" in lens.lens_model and lens.calibration_aspect == 1.5  # lensfun's default 3:2
    assert lens.calibration_crop == pytest.approx(1.528, abs=1e-3)


@pytest.mark.parametrize("args, reason", [
    ((None, None, None, 5.0), "names no camera"),
    (("Apple", "iPhone 6", "iPhone 6 back camera 4.15mm f/2.2", 4.15), "not in the lensfun database"),
    (("NIKON", "COOLPIX P6000", None, 6.0), "no lens data"),
    (("Canon", "Canon EOS 40D", None, 135.0), "not identified"),
    ((*SX60, None, None), "no focal length"),
    ((*SX60, None, 900.0), "outside"),
])
def test_no_lens_data(args, reason):
    found = lookup(*args)
    assert found.data is None and reason in found.reason


def test_calibration_aspect_from_the_bundled_xml():
    assert calibration_aspect("Canon", "Canon PowerShot SX60 HS & compatibles") == pytest.approx(4 / 3)
    assert calibration_aspect("Nobody", "No such lens") == 1.5


def test_unit_scale():
    # Image and calibration sensor alike: lensfun's unit is half the shorter side.
    assert unit_scale(4 / 3, 4 / 3, 5.6, 5.6) == pytest.approx(4 / 3)
    assert unit_scale(1.5, 1.5, 1.0, 1.0) == pytest.approx(1.5)
    # A smaller sensor behind the same lens sees a smaller part of its image circle.
    assert unit_scale(1.5, 1.5, 1.0, 1.5) == pytest.approx(1.0)


@pytest.mark.parametrize("model, terms", [("poly3", (0.02,)), ("poly5", (-0.05, 0.01)),
                                          ("ptlens", (0.02, -0.06, 0.01))])
def test_forward_inverse_roundtrip(model, terms):
    r = np.linspace(0.0, 1.8, 50)
    rd, _ = forward(model, terms, r)
    assert np.allclose(inverse(model, terms, rd), r, atol=1e-10)


def test_folding_model_is_refused():
    assert predict("poly5", (-0.6, 0.0), 1500, 1000, 1.5) is None


def test_no_distortion_predicts_zero():
    p = predict("ptlens", (0.0, 0.0, 0.0), 4000, 3000, 4 / 3)
    assert abs(p.k1) < 1e-12 and abs(p.k2) < 1e-12 and p.magnification == pytest.approx(1.0)
    assert p.r_max == pytest.approx(1.25)


def test_prediction_straightens_what_lensfun_bends():
    """Points distorted by lensfun's model, undistorted by the project's fitted model, land where lensfun says."""
    lens = lookup(*D70S, "18.0-70.0 mm f/3.5-4.5", 18.0).data
    w, h = 3008, 2000
    s = unit_scale(w / h, lens.calibration_aspect, lens.calibration_crop, lens.camera_crop)
    p = predict(lens.model, lens.terms, w, h, s)
    rng = np.random.default_rng(0)
    pts = rng.uniform([-1, -h / w], [1, h / w], size=(500, 2))
    r_d = np.hypot(pts[:, 0], pts[:, 1])
    expected = pts * (inverse(lens.model, lens.terms, r_d * s) / s / r_d)[:, None]
    ours = undistort(pts, p.k1, p.k2) * p.magnification
    err_px = np.hypot(*(ours - expected).T) * w / 2
    assert np.sqrt(np.mean(err_px**2)) < 2 * p.fit_rms_px + 0.05
    assert p.k1 == pytest.approx(0.0853, abs=2e-3)


def _modifier_k(lens, crop, w, h, focal):
    """(k1, k2) fitted to lensfun's own Modifier output (lensfun's normalisation, not ours)."""
    mod = lensfunpy.Modifier(lens, crop, w, h)
    mod.initialize(focal, 4.0, 1000.0, 1.0, flags=lensfunpy.ModifyFlags.DISTORTION)
    coords = mod.apply_geometry_distortion().astype(np.float64)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    cx, cy, half = (w - 1) / 2, (h - 1) / 2, max(w, h) / 2
    r_u = np.hypot(x - cx, y - cy).ravel() / half
    r_d = np.hypot(coords[..., 0] - cx, coords[..., 1] - cy).ravel() / half
    keep = r_d > 0
    design = np.column_stack([r_d[keep], r_d[keep] ** 3, r_d[keep] ** 5])
    coef, *_ = np.linalg.lstsq(design, r_u[keep], rcond=None)
    return coef[1] / coef[0]


@pytest.mark.parametrize("camera, lens_text, focal, size, crop_scale", [
    (SX60, None, 8.119, (400, 300), 1.0),
    (SX60, None, 4.944, (450, 300), 1.0),    # image 3:2, calibration 4:3
    (SX60, None, 4.944, (400, 300), 1.5),    # smaller sensor than the calibration's
    (D70S, "18.0-70.0 mm f/3.5-4.5", 18.0, (450, 300), 1.0),
    (D70S, "18.0-70.0 mm f/3.5-4.5", 24.0, (300, 450), 1.0),  # portrait
])
def test_agrees_with_lensfuns_own_modifier(camera, lens_text, focal, size, crop_scale):
    db = database()
    cam = db.find_cameras(*camera, False)[0]
    lens_obj = (db.find_lenses(cam, None, "18-70mm f/3.5-4.5", False) if lens_text else db.find_lenses(cam))[0]
    lens = lookup(*camera, lens_text, focal).data
    w, h = size
    crop = lens.camera_crop * crop_scale
    s = unit_scale(max(w, h) / min(w, h), lens.calibration_aspect, lens.calibration_crop, crop)
    ours = predict(lens.model, lens.terms, w, h, s).k1
    theirs = _modifier_k(lens_obj, crop, w, h, focal)
    print(f"{camera[1]} {focal} mm {w}x{h} crop x{crop_scale}: ours {ours:+.4f}, lensfun Modifier {theirs:+.4f}")
    assert ours == pytest.approx(theirs, abs=0.004)


def _lens_finding(k1=None, se=0.005, status=Status.OK, k2_stderr=0.01):
    model = None if k1 is None else RadialDistortion(
        k1=k1, k1_stderr=se, k2=0.0, k2_stderr=k2_stderr, cx=0.0, cx_stderr=0.01, cy=0.0, cy_stderr=0.01, cx_px=0.0,
        cy_px=0.0, sigma_px=0.3, n_lines_explained=20, n_lines_informative=20).to_details()
    return DetectorFinding(name="lens_distortion", version="0.1.0", plugin="lens_distortion", status=status,
                           summary="s", score=None, p_value=None, nfa=None,
                           details={RADIAL_DISTORTION_KEY: model}, parameters={}, elapsed_s=0.1)


def _d70s_info(**extra):
    fields = dict(make=D70S[0], model=D70S[1], lens_model="18.0-70.0 mm f/3.5-4.5", focal_length_mm=18.0,
                  exif_image_width=3008, exif_image_height=2000)
    fields.update(extra)
    return info(3008, 2000, **fields)


def test_comparison_outcomes():
    evidence_info = _d70s_info()
    predicted = compare(evidence_info, None, False, 0.02, 0.01, 64).prediction.k1
    cases = {
        "agrees": _lens_finding(predicted + 0.015),
        "disagrees": _lens_finding(predicted + 0.06),
        "lens detector did not measure k1": _lens_finding(None),
    }
    for outcome, finding in cases.items():
        cmp = compare(evidence_info, finding, False, 0.02, 0.01, 64)
        assert cmp.outcome == outcome
        check = lens_check(cmp, 0.02, 0.01)
        assert check.outcome == {"agrees": "consistent", "disagrees": "note"}.get(outcome, "not available")
    for status in (Status.ERROR, Status.INCONCLUSIVE):
        other = compare(evidence_info, _lens_finding(predicted, status=status), False, 0.02, 0.01, 64)
        assert other.outcome == "lens detector did not measure k1" and status.value in other.reason
    assert "did not run" in compare(evidence_info, None, False, 0.02, 0.01, 64).reason
    # Within the tolerance but far in standard errors: still agrees (the tolerance is for lensfun's blind spots).
    tight = compare(evidence_info, _lens_finding(predicted + 0.018, se=0.001), False, 0.02, 0.01, 64)
    assert tight.outcome == "agrees" and tight.z > 10


def test_a_one_term_measurement_is_compared_with_the_one_term_prediction():
    """k2 held at zero (k2 = 0 +- 0) is the lens detector's one-term k1: lensfun's one-term fit is its truth."""
    evidence_info = _d70s_info()
    prediction = compare(evidence_info, None, False, 0.02, 0.01, 64).prediction
    assert abs(prediction.k1 - prediction.k1_one_term) > 0.02
    one = compare(evidence_info, _lens_finding(prediction.k1_one_term, k2_stderr=0.0), False, 0.02, 0.01, 64)
    assert one.difference == pytest.approx(0.0) and one.outcome == "agrees"
    assert "one-term k1" in lens_check(one, 0.02, 0.01).observation
    two = compare(evidence_info, _lens_finding(prediction.k1_one_term), False, 0.02, 0.01, 64)
    assert two.difference == pytest.approx(prediction.k1_one_term - prediction.k1)


def test_prediction_does_not_apply():
    resized = compare(_d70s_info(), _lens_finding(0.0), True, 0.02, 0.01, 64)
    assert resized.outcome == "prediction does not apply" and "resized or cropped" in resized.reason
    zoomed = compare(_d70s_info(focal_length_35mm=54.0), _lens_finding(0.0), False, 0.02, 0.01, 64)
    assert zoomed.outcome == "prediction does not apply" and "crop factor" in zoomed.reason
    fine = compare(_d70s_info(focal_length_35mm=27.0), _lens_finding(0.0), False, 0.02, 0.01, 64)
    assert fine.outcome != "prediction does not apply"
    unknown = compare(info(make="Jolla", model="Jolla", focal_length_mm=4.0), None, False, 0.02, 0.01, 64)
    assert unknown.outcome == "no lens data" and lens_check(unknown, 0.02, 0.01).outcome == "not available"

"""Validation with fixed seeds: measured rates of the thumbnail check and of the lens comparison.

Run with ``pytest -s tests/metadata/test_metadata_validation.py`` to see the figures.
"""

import io

import numpy as np
import pytest
from PIL import Image
from scipy.special import ndtri

from forensics_core import DetectorFinding
from forensics_core.evidence import load_evidence
from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS as LENS_PARAMS
from forensics_plugins.lens_distortion.detector import analyse as lens_analyse
from forensics_plugins.lens_distortion.photo import render_authentic
from forensics_plugins.metadata.conversion import predict, unit_scale
from forensics_plugins.metadata.detector import thresholds
from forensics_plugins.metadata.spec import DEFAULT_PARAMS
from forensics_plugins.metadata.lens_check import compare
from forensics_plugins.metadata.lensdb import lookup
from forensics_core.thumbnail import read_thumbnail
from forensics_plugins.metadata.thumbnail import thumbnail_check
from metadata_helpers import DATA, camera_thumbnail, exif_bytes, info, jpeg, with_thumbnail

pytestmark = pytest.mark.slow

LIMITS = thresholds(DEFAULT_PARAMS)
SPLICE_SIDES = (0.06, 0.08, 0.10, 0.15)
SPLICES_PER_SIZE = 8


def _photo(name, size=None):
    with Image.open(DATA / "exif" / name) as img:
        out = img.convert("RGB")
    return out.resize(size, Image.Resampling.LANCZOS) if size else out


def _decoded(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as img:
        return np.asarray(img.convert("RGB"))


def test_thumbnail_false_alarms_and_detection():
    """Splices the thumbnail did not follow, against re-saves and real camera files.

    Four real photos (about 0.8 MP; one portrait, so its thumbnail is
    pillarboxed) get a camera-style thumbnail; spliced versions paste a block
    of another of the photos, of the given fraction of each side, at a random
    place, and are re-saved at quality 90 with the original EXIF (as editors
    that copy EXIF do). Negatives: the untouched photos re-saved at quality 75
    and 95, and the real camera files of tests/data whose thumbnail is intact.
    """
    bases = {
        "canon_hdr_NO": _photo("canon_hdr_NO.jpg", (1024, 768)),
        "87_OSError": _photo("87_OSError.jpg", (744, 1120)),
        "35-empty": _photo("35-empty.jpg", (1082, 813)),
        "nikon-e950": _photo("nikon-e950.jpg"),
    }
    names = list(bases)
    rng = np.random.default_rng(20240605)
    negatives, detected = [], {s: [] for s in SPLICE_SIDES}
    for name in ("canon_hdr_NO.jpg", "nikon-e950.jpg", "Canon_40D.jpg", "BlueSquare.jpg"):
        ev = load_evidence(DATA / "exif" / name)
        check, _ = thumbnail_check(ev.thumbnail, ev.pixels, LIMITS)
        negatives.append((name, check.outcome))
    for i, (name, img) in enumerate(bases.items()):
        block = with_thumbnail(exif_bytes(make="Canon", model="Canon PowerShot SX60 HS"), camera_thumbnail(img))
        for quality in (75, 95):
            data = jpeg(img, block, quality=quality)
            check, _ = thumbnail_check(read_thumbnail(data, "JPEG"), _decoded(data), LIMITS)
            negatives.append((f"{name} re-saved q{quality}", check.outcome))
        arr = np.asarray(img)
        h, w = arr.shape[:2]
        donor = np.asarray(bases[names[(i + 1) % len(names)]].resize((w, h)))
        for side in SPLICE_SIDES:
            bw, bh = int(w * side), int(h * side)
            for _ in range(SPLICES_PER_SIZE):
                x, y = rng.integers(0, w - bw), rng.integers(0, h - bh)
                dx, dy = rng.integers(0, w - bw), rng.integers(0, h - bh)
                spliced = arr.copy()
                spliced[y:y + bh, x:x + bw] = donor[dy:dy + bh, dx:dx + bw]
                data = jpeg(Image.fromarray(spliced), block, quality=90)
                check, _ = thumbnail_check(read_thumbnail(data, "JPEG"), _decoded(data), LIMITS)
                detected[side].append(check.outcome == "suspicious")
    false_alarms = [n for n, outcome in negatives if outcome == "suspicious"]
    print(f"\nthumbnail check: false alarms {len(false_alarms)} of {len(negatives)} negatives {false_alarms}")
    for side, hits in detected.items():
        print(f"  splice {100 * side:.0f}% of each side ({100 * side * side:.2f}% of the area): detected "
              f"{sum(hits)} of {len(hits)} ({100 * np.mean(hits):.0f}%)")
    assert not false_alarms
    assert all(outcome == "consistent" for _, outcome in negatives)
    assert np.mean(detected[0.15]) >= 0.9
    assert np.mean(detected[0.10]) >= 0.75


# (camera, EXIF lens model, focal length in mm, image size): lensfun lenses with clear and with
# slight distortion, landscape and portrait, 4:3 and 3:2.
LENS_CASES = [
    (("Canon", "Canon PowerShot SX60 HS"), None, 4.944, (1600, 1200)),
    (("Canon", "Canon PowerShot SX60 HS"), None, 6.0, (1600, 1200)),
    (("Canon", "Canon PowerShot SX60 HS"), None, 8.119, (1600, 1200)),
    (("NIKON CORPORATION", "NIKON D70s"), "18.0-70.0 mm f/3.5-4.5", 18.0, (1500, 1000)),
    (("NIKON CORPORATION", "NIKON D70s"), "18.0-70.0 mm f/3.5-4.5", 24.0, (1000, 1500)),
]
# The EXIF of a mismatched case names the same camera at another focal length.
WRONG_FOCAL = {4.944: 14.5, 6.0: 50.0, 8.119: 4.944, 18.0: 50.0, 24.0: 18.0}


def _info(camera, lens_text, focal, size):
    w, h = size
    return info(w, h, make=camera[0], model=camera[1], lens_model=lens_text, focal_length_mm=focal,
                exif_image_width=w, exif_image_height=h)


def test_lens_comparison_on_rendered_photos():
    """The lens detector measures photos rendered through the named lens's lensfun distortion.

    Each photo is a synthetic authentic scene (lens_distortion.photo) rendered
    with the (k1, k2) that lensfun predicts for the lens at that focal length
    and saved as JPEG quality 92. Matched: the EXIF names that focal length
    (expected "agrees"). Mismatched: it names another, whose prediction differs
    (expected "disagrees" when the difference exceeds the tolerance clearly).
    """
    tol, alpha = DEFAULT_PARAMS["lens_k1_tolerance"], DEFAULT_PARAMS["lens_alpha"]
    rows, matched, mismatched = [], [], []
    for seed, (camera, lens_text, focal, size) in enumerate(LENS_CASES):
        lens = lookup(*camera, lens_text, focal).data
        w, h = size
        s = unit_scale(max(w, h) / min(w, h), lens.calibration_aspect, lens.calibration_crop, lens.camera_crop)
        truth = predict(lens.model, lens.terms, w, h, s)
        synth = render_authentic(seed + 11, size=size, k1=truth.k1, k2=truth.k2, jpeg_quality=92)
        luma = np.asarray(Image.open(io.BytesIO(synth.jpeg_bytes)).convert("L"), dtype=np.float64) / 255
        measured = lens_analyse(luma, LENS_PARAMS)
        finding = DetectorFinding(name="lens_distortion", version="0.1.0", plugin="lens_distortion",
                                  status=measured.status, summary=measured.summary, score=None, p_value=None,
                                  nfa=None, details=measured.details, parameters={}, elapsed_s=0.0)
        good = compare(_info(camera, lens_text, focal, size), finding, False, tol, alpha, 64)
        bad = compare(_info(camera, lens_text, WRONG_FOCAL[focal], size), finding, False, tol, alpha, 64)
        matched.append(good.outcome)
        # The detector publishes the one-term k1 with its real-photo error: a wrong focal length is
        # expected to show where lensfun's one-term predictions differ by clearly more than the
        # tolerance plus the critical number of standard errors, and not where clearly less.
        margin = (abs(bad.prediction.k1_one_term - good.prediction.k1_one_term) - tol) / good.measured["k1_stderr"]
        z_crit = float(-ndtri(alpha / 2))
        if abs(margin - z_crit) > 1.5:
            mismatched.append((bad.outcome, "disagrees" if margin > z_crit else "agrees"))
        rows.append((camera[1], focal, size, truth.k1, good.measured, good.outcome, WRONG_FOCAL[focal],
                     bad.prediction.k1, bad.outcome))
    print("\nlens comparison (k1 in the project's units):")
    for cam, f, size, k1, m, out, wf, wk1, wout in rows:
        print(f"  {cam} {f:g} mm {size[0]}x{size[1]}: lensfun k1 {k1:+.4f}, measured {m['k1']:+.4f} ± "
              f"{m['k1_stderr']:.4f} -> {out}; EXIF saying {wf:g} mm (k1 {wk1:+.4f}) -> {wout}")
    n_agree = sum(o == "agrees" for o in matched)
    n_right = sum(o == e for o, e in mismatched)
    print(f"  matched EXIF: {n_agree} of {len(matched)} agree; mismatched EXIF: {n_right} of {len(mismatched)} "
          f"as expected ({sum(e == 'disagrees' for _, e in mismatched)} expected to disagree)")
    assert n_agree == len(matched)
    assert n_right == len(mismatched)
    assert any(e == "disagrees" for _, e in mismatched)

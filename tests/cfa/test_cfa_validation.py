"""Validation on synthetic raw-like photos: region found, false regions, and what erases the trace.

Each pair is an authentic photo (a dead-leaves scene through a Bayer sensor,
demosaiced by bilinear interpolation or Hamilton-Adams) and the same photo
with 10-30% of it replaced by another scene shot with the same camera model
with its mosaic shifted by one pixel in x, y or both (so its pattern differs).
Seeds are fixed; the decision threshold is the detector's default NFA <= 0.01,
set before these seeds were drawn.

*Found*: some flagged region lies at least half inside the pasted mask
(precision >= 0.5, measured on its blocks' pixels). *False region*: any
flagged region of an authentic photo, or a flagged region of a spliced photo
lying mostly outside the mask. Run with ``pytest -s`` to see the figures.
"""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_core import Status
from forensics_plugins.cfa import synth
from forensics_plugins.cfa.detector import analyse, regions_mask
from forensics_plugins.cfa.spec import DEFAULT_PARAMS

pytestmark = pytest.mark.slow

N_PAIRS = 40
SIZE = (512, 512)
SMALL = (384, 384)


def _pixels(rgb: np.ndarray, quality=None, resize=None) -> np.ndarray:
    data, _ = synth.encode(rgb, quality, resize)
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


def _score(result, mask):
    """(found, false regions, IoU of the union of regions) of one spliced result; mask None for authentic."""
    regions = result.details.get("regions") or []
    if mask is None:
        return False, len(regions), None
    found, false = False, 0
    for r in regions:
        rm = regions_mask({"block_px": result.details["block_px"], "regions": [r]}, mask.shape)
        if (rm & mask).sum() >= 0.5 * rm.sum():
            found = True
        else:
            false += 1
    union = regions_mask(result.details, mask.shape)
    return found, false, float((union & mask).sum() / (union | mask).sum())


def _run(pairs, quality=None, resize=None):
    rows = []
    for authentic, spliced in pairs:
        for photo in (authentic, spliced):
            mask = synth.resized_mask(photo.mask, resize) if photo.mask is not None else None
            result = analyse(_pixels(photo.rgb, quality, resize), DEFAULT_PARAMS)
            found, false, iou = _score(result, mask)
            rows.append({"spliced": mask is not None, "status": result.status, "found": found, "false": false,
                         "iou": iou, "demosaic": photo.params["demosaic"],
                         "shift": tuple(photo.params.get("shift", ())),
                         "named": (result.details.get("pattern") or {}).get("pattern"),
                         "pattern": photo.params["pattern"]})
    return rows


def _report(title, rows):
    auth = [r for r in rows if not r["spliced"]]
    spl = [r for r in rows if r["spliced"]]
    found = np.mean([r["found"] for r in spl])
    false_auth = np.mean([r["false"] > 0 for r in auth])
    inconclusive = {k: np.mean([r["status"] is Status.INCONCLUSIVE for r in v]) for k, v in
                    (("authentic", auth), ("spliced", spl))}
    print(f"\n{title}: {len(auth)} authentic, {len(spl)} spliced")
    print(f"  region found {found:.3f} ({sum(r['found'] for r in spl)}/{len(spl)}); median IoU "
          f"{np.median([r['iou'] for r in spl]):.2f}")
    print(f"  authentic with a false region {false_auth:.3f} ({sum(r['false'] > 0 for r in auth)}/{len(auth)}); "
          f"false regions in spliced photos {sum(r['false'] for r in spl)}")
    print(f"  inconclusive: authentic {inconclusive['authentic']:.2f}, spliced {inconclusive['spliced']:.2f}")
    named = [r for r in auth if r["named"]]
    print(f"  Bayer pattern of the authentic photos named {len(named)}/{len(auth)}, of which wrong "
          f"{sum(r['named'] != r['pattern'] for r in named)}")
    for alg in ("bilinear", "hamilton_adams"):
        for shift in synth.SHIFTS:
            sel = [r for r in spl if r["demosaic"] == alg and r["shift"] == shift]
            if sel:
                print(f"    {alg:<15} shift {shift}: found {sum(r['found'] for r in sel)}/{len(sel)}")
    return found, false_auth, sum(r["false"] for r in spl)


@pytest.fixture(scope="module")
def png_pairs():
    return [synth.make_pair(1000 + i, SIZE, algorithm=("bilinear", "hamilton_adams")[i % 2]) for i in range(N_PAIRS)]


def test_png_region_found_and_false_regions(png_pairs):
    rows = _run(png_pairs)
    found, false_auth, false_spl = _report(f"PNG {SIZE[1]}x{SIZE[0]}", rows)
    assert found >= 0.8
    assert false_auth <= 0.05
    assert false_spl <= 0.05 * N_PAIRS
    named = [r for r in rows if not r["spliced"] and r["named"]]
    assert len(named) >= 0.8 * N_PAIRS and all(r["named"] == r["pattern"] for r in named)


def test_jpeg_95_keeps_the_trace(png_pairs):
    rows = _run(png_pairs[:16], quality=95)
    found, false_auth, false_spl = _report(f"JPEG 95 {SIZE[1]}x{SIZE[0]}", rows)
    assert found >= 0.75
    assert false_auth <= 0.07 and false_spl <= 1
    assert all(r["named"] in (None, r["pattern"]) for r in rows if not r["spliced"])


@pytest.mark.parametrize("quality, resize", [(75, None), (None, 0.75)])
def test_strong_jpeg_and_resizing_give_no_false_region(quality, resize):
    pairs = [synth.make_pair(3000 + i, SMALL, algorithm=("bilinear", "hamilton_adams")[i % 2]) for i in range(8)]
    rows = _run(pairs, quality=quality, resize=resize)
    _, false_auth, false_spl = _report(f"JPEG {quality} / resize {resize} {SMALL[1]}x{SMALL[0]}", rows)
    assert false_auth == 0 and false_spl == 0
    assert np.mean([r["status"] is Status.INCONCLUSIVE for r in rows if not r["spliced"]]) >= 0.5


def test_donor_from_another_camera_is_measured():
    """A donor with other camera settings (and half the time the other algorithm): reported, not a target."""
    pairs = [synth.make_pair(4000 + i, SMALL, algorithm=("bilinear", "hamilton_adams")[i % 2], donor_camera="other",
                             donor_algorithm=("bilinear", "hamilton_adams")[(i // 2) % 2]) for i in range(12)]
    _, false_auth, _ = _report(f"donor from another camera {SMALL[1]}x{SMALL[0]}", _run(pairs))
    assert false_auth <= 1 / 12

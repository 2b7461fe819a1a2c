"""The JPEG grid detector on whole files: grids, regions, hostile input, determinism."""

import io
import json

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from forensics_core import DetectorFinding, EvidenceError, Processing, RadialResampling, Status, load_evidence
from forensics_core.findings import check_result
from forensics_plugins.jpeg_grid import synth
from forensics_plugins.jpeg_grid.detector import JpegGrid, ijg_quality
from forensics_plugins.jpeg_grid.spec import DEFAULT_PARAMS
from forensics_plugins.jpeg_grid.figures import tiles_mask
from forensics_plugins.jpeg_grid.luminance import luminance

SIZE = (256, 320)


def _file(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _region_mask(region, details):
    cell = details["map"]["cell_px"]
    tiles = tiles_mask(region["tiles_rle"], tuple(details["map"]["tiles_shape"]))
    return np.kron(tiles, np.ones((cell, cell), bool))


def _iou(region, details, truth):
    m = _region_mask(region, details)
    t = truth[: m.shape[0], : m.shape[1]]
    return (m & t).sum() / ((m | t).sum() + (truth.sum() - t.sum()))


@pytest.fixture(scope="module")
def scene():
    return synth.render_scene(np.random.default_rng(4), SIZE, "coffee")


def test_single_compression_main_grid_at_origin_and_no_region(tmp_path, scene):
    ev = load_evidence(_file(tmp_path, "a.jpg", synth.jpeg_bytes(scene, 85)))
    result = check_result(JpegGrid().analyze(ev, DEFAULT_PARAMS))
    d = result.details
    assert result.status is Status.OK, result.summary
    assert d["main_grid"]["origin"] == [0, 0] and d["main_grid"]["log10_nfa"] < -100
    assert not d["cropped"]
    assert not any(r["meaningful"] for r in d["regions"])
    assert result.nfa == 1.0 and result.score == 0.0
    assert d["luminance"]["source"] == "jpeg_y"
    assert d["jpeg_quality_estimate"] == 85


def test_crop_moves_the_main_grid_and_is_reported_but_not_a_splice(tmp_path, scene):
    decoded = synth.decode_cropped(synth.jpeg_bytes(scene, 80))
    buf = io.BytesIO()
    Image.fromarray(decoded[5:, 3:]).save(buf, format="PNG")
    result = JpegGrid().analyze(load_evidence(_file(tmp_path, "c.png", buf.getvalue())), DEFAULT_PARAMS)
    d = result.details
    assert result.status is Status.OK
    assert d["main_grid"]["origin"] == [5, 3] and d["cropped"] and d["lattice"]["origin"] == [5, 3]
    assert "cropped" in result.summary
    assert not any(r["meaningful"] for r in d["regions"]) and result.nfa == 1.0
    assert d["luminance"]["source"] == "luma" and d["jpeg_quality_estimate"] is None


def test_crop_saved_again_as_jpeg_does_not_make_the_files_own_grid_foreign(tmp_path):
    # Cropped off-grid, then saved at quality 98: the first compression stays the main grid, and the
    # file's own grid (0, 0), which every pixel went through, outvotes it over much of the frame.
    scene = synth.render_scene(np.random.default_rng(1), (600, 800), synth.SOURCES[1])
    cropped = synth.decode_cropped(synth.jpeg_bytes(scene, 76))[5:, 3:]
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "r.jpg", _jpeg(cropped, quality=98))),
                                  DEFAULT_PARAMS))
    d = result.details
    assert result.status is Status.OK and d["main_grid"]["origin"] == [5, 3] and d["cropped"]
    assert not any(r["meaningful"] for r in d["regions"]) and result.nfa == 1.0


@pytest.mark.parametrize("kind, final_quality", [("splice", 100), ("copy_move", 98)])
def test_region_on_a_shifted_grid_is_found(tmp_path, kind, final_quality):
    case = synth.make_spliced(21, kind, size=(384, 512), quality=85, paste_quality=80, final_quality=final_quality,
                              shift=(3, 6))
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "s.jpg", case.data)), DEFAULT_PARAMS))
    d = result.details
    hits = [r for r in d["regions"] if r["meaningful"]]
    assert result.status is Status.OK and hits, result.summary
    best = hits[0]
    assert best["grid"] == [3, 6]
    assert _iou(best, d, case.mask) >= 0.5
    assert result.nfa < 1e-10 and result.score > 0.99
    for key in ("id", "stage", "grid", "bbox_px", "area_px", "pixels", "density", "log10_nfa", "tiles_rle"):
        assert key in best


@pytest.mark.parametrize("method", ["lattice", "zero_q99"])
def test_region_missing_the_main_grid_is_found(tmp_path, method):
    case = synth.make_uncompressed_paste(4, size=(384, 512), quality=85)
    ev = load_evidence(_file(tmp_path, "m.png", case.data))
    assert not any(r["meaningful"] for r in JpegGrid().analyze(ev, {**DEFAULT_PARAMS, "missing_grid": False}).details["regions"])
    result = check_result(JpegGrid().analyze(ev, {**DEFAULT_PARAMS, "missing_method": method}))
    assert result.details["missing_tested"]
    hits = [r for r in result.details["regions"] if r["meaningful"]]
    assert result.status is Status.OK and hits, result.summary
    assert hits[0]["stage"] == "missing" and hits[0]["grid"] == [0, 0]
    assert _iou(hits[0], result.details, case.mask) >= (0.5 if method == "zero_q99" else 0.3)


def test_never_compressed_is_inconclusive_not_clean(tmp_path):
    data, _ = synth.make_never_compressed(2, size=SIZE)
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "n.png", data)), DEFAULT_PARAMS))
    assert result.status is Status.INCONCLUSIVE
    assert result.score is None and result.nfa is None and result.p_value is None
    assert "never JPEG-compressed" in result.summary
    assert result.details["main_grid"]["log10_nfa"] >= 0
    assert not any(r["meaningful"] for r in result.details["regions"])


def _texture(rng, shape, smooth=2.0, contrast=40.0):
    """Natural-looking grey texture: smoothed noise at two scales, with straight and curved edges."""
    h, w = shape
    fine = ndimage.gaussian_filter(rng.normal(0, 1, shape), smooth)
    coarse = ndimage.gaussian_filter(rng.normal(0, 1, shape), 8 * smooth)
    yy, xx = np.mgrid[:h, :w]
    edges = 30.0 * (xx > 0.37 * w) - 25.0 * ((yy - 0.6 * h) ** 2 + (xx - 0.3 * w) ** 2 < (0.2 * h) ** 2)
    img = 120 + contrast * fine / fine.std() + 2 * contrast * coarse / coarse.std() + edges
    return np.clip(img, 0, 255)


def _rgb(grey, rng):
    tint = np.array([1.0, 0.97, 0.9])
    return np.clip(grey[..., None] * tint + rng.normal(0, 1.0, grey.shape + (3,)), 0, 255).round().astype(np.uint8)


def test_jpeg_piece_pasted_into_a_never_compressed_image_is_a_foreign_region(tmp_path):
    rng = np.random.default_rng(11)
    host = _rgb(_texture(rng, (512, 768)), rng)
    donor = _rgb(_texture(rng, (384, 512), smooth=1.5), rng)
    piece = synth.decode_cropped(synth.jpeg_bytes(donor, 80))
    mask = np.zeros(host.shape[:2], bool)
    # Pasted 3 columns and 5 rows off the host's (absent) grid: the piece keeps its grid at (3, 5).
    mask[101:165, 363:459] = True
    forged = host.copy()
    forged[mask] = piece[96:160, 160:256].reshape(-1, 3)
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "p.png", _png(forged))), DEFAULT_PARAMS))
    d = result.details
    hits = [r for r in d["regions"] if r["meaningful"]]
    assert result.status is Status.OK and hits, result.summary
    # A piece of 1.6 % of the frame: too small for its grid to be significant over the whole image.
    assert not d["main_grid"]["significant"] and not d["cropped"] and not d["missing_tested"], d["main_grid"]
    assert hits[0]["stage"] == "foreign" and hits[0]["grid"] == [3, 5]
    assert _iou(hits[0], d, mask) >= 0.5
    assert hits[0]["log10_nfa"] < -10 and result.nfa == pytest.approx(10 ** hits[0]["log10_nfa"])
    assert "the rest of the photo lacks" in result.summary


@pytest.mark.parametrize("quality", [85, 95])
def test_flat_sky_and_saturated_areas_give_no_region(tmp_path, quality):
    rng = np.random.default_rng(quality)
    h, w = 480, 640
    grey = _texture(rng, (h, w))
    yy, xx = np.mgrid[:h, :w]
    sky = yy < 0.35 * h
    grey[sky] = 150 + 90 * (1 - yy[sky] / (0.35 * h))   # a sky brightening upwards, clipped at the top
    grey[:60] = 255
    grey[(yy > 0.8 * h) & (xx < 0.4 * w)] = 0             # crushed shadows
    grey[(yy > 0.5 * h) & (xx > 0.75 * w)] = 255           # blown highlight
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "s.jpg", _jpeg(_rgb(grey, rng), quality=quality))),
                                  DEFAULT_PARAMS))
    d = result.details
    assert result.status is Status.OK and d["main_grid"]["origin"] == [0, 0]
    assert not any(r["meaningful"] for r in d["regions"]), d["regions"][:1]
    assert result.nfa == 1.0 and not d["missing_tested"]


def test_same_input_same_result(tmp_path):
    case = synth.make_spliced(5, "splice", size=SIZE, final_quality=97)
    ev = load_evidence(_file(tmp_path, "d.jpg", case.data))
    first = check_result(JpegGrid().analyze(ev, DEFAULT_PARAMS))
    second = check_result(JpegGrid().analyze(ev, DEFAULT_PARAMS))
    strip = lambda d: {k: v for k, v in d.items() if k != "elapsed_s"}  # noqa: E731
    assert json.dumps(strip(first.details), sort_keys=True) == json.dumps(strip(second.details), sort_keys=True)
    assert (first.status, first.summary, first.nfa) == (second.status, second.summary, second.nfa)


def test_pixels_and_bytes_are_left_untouched(tmp_path, scene):
    ev = load_evidence(_file(tmp_path, "u.jpg", synth.jpeg_bytes(scene, 90)))
    before = (ev.pixels.copy(), bytes(ev.data))
    JpegGrid().analyze(ev, DEFAULT_PARAMS)
    assert np.array_equal(ev.pixels, before[0]) and ev.data == before[1]
    assert not ev.pixels.flags.writeable


def _png(arr, mode=None):
    buf = io.BytesIO()
    img = Image.fromarray(arr) if mode is None else Image.fromarray(arr).convert(mode)
    img.save(buf, format="PNG")
    return buf.getvalue()


def _jpeg(arr, **kw):
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="JPEG", **kw)
    return buf.getvalue()


def _with_segment(jpeg, segment):
    """``jpeg`` with ``segment`` inserted right after SOI."""
    return jpeg[:2] + segment + jpeg[2:]


def _hostile(scene):
    grey = scene[..., 1]
    cmyk = io.BytesIO()
    Image.fromarray(scene).convert("CMYK").save(cmyk, format="JPEG", quality=90)
    good = _jpeg(scene, quality=90)
    return {
        "1x1.png": _png(np.zeros((1, 1, 3), np.uint8)),
        "7x9.jpg": _jpeg(np.full((9, 7, 3), 120, np.uint8)),
        "31x200.jpg": _jpeg(np.zeros((31, 200, 3), np.uint8)),
        "grey.jpg": _jpeg(grey, quality=80),
        "16bit.png": _png((grey.astype(np.uint16) * 257)),
        "rgba.png": _png(np.dstack([scene, np.full(grey.shape, 200, np.uint8)])),
        "palette.png": _png(scene, "P"),
        "cmyk.jpg": cmyk.getvalue(),
        "flat.jpg": _jpeg(np.full((200, 200, 3), 255, np.uint8), quality=75),
        # Malformed marker segments the decoder skips: EXIF of garbage, an empty comment, a short APP0.
        "exif_garbage.jpg": _with_segment(good, b"\xff\xe1\x00\x10Exif\x00\x00garbage!"),
        "comment_empty.jpg": _with_segment(good, b"\xff\xfe\x00\x02"),
        "app0_short.jpg": _with_segment(good, b"\xff\xe0\x00\x04JF"),
        # Malformed segments the intake refuses: a length running past the data, a DQT of garbage.
        "bad_app.jpg": _with_segment(good, b"\xff\xef\x00\x40garbage"),
        "bad_dqt.jpg": _with_segment(good, b"\xff\xdb\x00\x05\x7f\x01\x02"),
        "truncated.jpg": good[: len(good) // 2],
    }


def test_hostile_inputs_give_a_result_or_a_refused_intake(tmp_path, scene):
    statuses = {}
    for name, data in _hostile(scene).items():
        try:
            ev = load_evidence(_file(tmp_path, name, data))
        except EvidenceError as exc:
            statuses[name] = f"refused: {exc}"
            continue
        result = check_result(JpegGrid().analyze(ev, DEFAULT_PARAMS))
        assert result.status in (Status.OK, Status.INCONCLUSIVE, Status.SKIPPED), name
        if result.status is not Status.OK:
            assert result.summary.startswith("Inconclusive") and result.score is None, name
        statuses[name] = result.status.value
    print(statuses)
    assert statuses["1x1.png"] == statuses["7x9.jpg"] == statuses["31x200.jpg"] == "inconclusive"
    for name in ("grey.jpg", "exif_garbage.jpg", "comment_empty.jpg", "app0_short.jpg"):
        assert statuses[name] == "ok", name
    assert statuses["flat.jpg"] == "inconclusive"
    for name in ("16bit.png", "rgba.png", "palette.png"):
        assert statuses[name] == "inconclusive", name


def test_greyscale_and_cmyk_jpegs_use_the_right_channel(tmp_path, scene):
    grey = load_evidence(_file(tmp_path, "g.jpg", _jpeg(scene[..., 0], quality=80)))
    assert luminance(grey).source == "jpeg_grey"
    cmyk = io.BytesIO()
    Image.fromarray(scene).convert("CMYK").save(cmyk, format="JPEG", quality=90)
    lum = luminance(load_evidence(_file(tmp_path, "k.jpg", cmyk.getvalue())))
    assert lum.source == "luma" and lum.table is not None


def test_decoded_y_is_the_decoder_output(tmp_path, scene):
    data = synth.jpeg_bytes(scene, 90)
    ev = load_evidence(_file(tmp_path, "y.jpg", data))
    lum = luminance(ev)
    img = Image.open(io.BytesIO(data))
    img.draft("YCbCr", img.size)
    np.testing.assert_array_equal(lum.y, np.asarray(img)[..., 0])
    # The luma of the decoded RGB differs by colour conversion rounding.
    assert np.abs(lum.y - ev.luma * 255).max() > 0.5


def test_ijg_quality_estimate():
    for q in (50, 75, 90, 100):
        data = _jpeg(np.zeros((16, 16, 3), np.uint8), quality=q)
        table = np.asarray(Image.open(io.BytesIO(data)).quantization[0], dtype=float).reshape(8, 8)
        assert ijg_quality(table) == q
    assert ijg_quality(None) is None


def _lens_corrected(rgb: np.ndarray, k1: float) -> np.ndarray:
    """``rgb`` remapped by OpenCV's undistortion with one radial term about the centre, as an editor's lens correction."""
    import cv2

    h, w = rgb.shape[:2]
    camera = np.array([[0.9 * w, 0.0, (w - 1) / 2], [0.0, 0.9 * w, (h - 1) / 2], [0.0, 0.0, 1.0]])
    return cv2.undistort(rgb, camera, np.array([k1, 0.0, 0.0, 0.0]), None, camera)


def _pasted_piece_is_found(tmp_path, rng, host: np.ndarray, grid: tuple[int, int], box: tuple[slice, slice]):
    """``host`` with a piece of another JPEG compressed on ``grid`` pasted at ``box``, saved at quality 98: the
    piece is the strongest foreign region, on its grid. Returns the result."""
    shape = host.shape[:2]
    donor = synth.decode_cropped(synth.jpeg_bytes(synth.render_scene(rng, shape, "coffee"), 80, grid), grid)
    pasted = host.copy()
    pasted[box] = donor[box]
    spliced = JpegGrid().analyze(load_evidence(_file(tmp_path, "spliced.jpg", synth.jpeg_bytes(pasted, 98))), DEFAULT_PARAMS)
    foreign = [r for r in spliced.details["regions"] if r["meaningful"]]
    assert foreign and foreign[0]["grid"] == list(grid) and foreign[0]["stage"] == "foreign"
    assert spliced.nfa < 1e-6
    return spliced


def test_lens_correction_is_named_processing_and_a_piece_pasted_into_it_is_still_found(tmp_path):
    """A camera JPEG lens-corrected and saved at quality 98 keeps its first grid shifted along each radius.

    That is processing, not a paste: no region is reported as compressed on
    another grid, and the finding names the radial resampling. A piece of
    another JPEG pasted near the centre's left, on a grid shifted by (3, 5)
    (not along its radius), is still reported as foreign.
    """
    rng = np.random.default_rng(38)
    first = synth.decode_cropped(synth.jpeg_bytes(synth.render_scene(rng, (1200, 1600), "astronaut"), 85))
    corrected = _lens_corrected(first, -0.08)
    result = JpegGrid().analyze(load_evidence(_file(tmp_path, "corrected.jpg", synth.jpeg_bytes(corrected, 98))), DEFAULT_PARAMS)
    processing = result.details["processing"]
    assert processing and processing["kind"] == "radial resampling" and processing["radial"]["n_regions"] >= 2
    assert result.details["n_meaningful"] == 0 and result.nfa == 1.0
    assert "radial warp about its centre" in result.summary and "processing" in result.summary
    check_result(result)
    finding = DetectorFinding(name="jpeg_grid", version="2", plugin="jpeg_grid", status=result.status,
                              summary=result.summary, score=result.score, p_value=None, nfa=result.nfa,
                              details=result.details, parameters={}, elapsed_s=0.0)
    assert Processing.from_finding(finding) == Processing(
        "radial resampling", "resampled by a radial warp about its centre after a first JPEG compression, as lens "
        "correction does")
    # The warp itself is published for the cfa detector, whose mosaic it moves too.
    warp = RadialResampling.from_finding(finding)
    assert warp is not None and [warp.a, warp.b] == processing["radial"]["profile_terms_px"]
    corner = warp.displacement(np.array([0.0]), np.array([0.0]), corrected.shape[:2])
    assert (corner[0][0] < 0) == (processing["radial"]["direction"] == "outwards")

    _pasted_piece_is_found(tmp_path, rng, corrected, (3, 5), (slice(450, 750), slice(350, 650)))


def test_crop_after_compression_is_named_processing_and_a_piece_pasted_into_it_is_still_found(tmp_path):
    """A JPEG cropped off its grid and saved again at quality 98 keeps its first grid, moved, all over the frame.

    That grid, (3, 5) after cutting 5 columns and 3 rows, is the photo's
    history: its region is explained as a crop, and the finding names the
    processing. A piece of another JPEG pasted into the same photo on the
    grid (6, 2) is still reported as foreign.
    """
    rng = np.random.default_rng(39)
    first = synth.decode_cropped(synth.jpeg_bytes(synth.render_scene(rng, (900, 1200), synth.SOURCES[0]), 80))
    cropped = np.ascontiguousarray(first[3:, 5:])
    result = check_result(JpegGrid().analyze(load_evidence(_file(tmp_path, "cropped.jpg", synth.jpeg_bytes(cropped, 98))),
                                  DEFAULT_PARAMS))
    d = result.details
    assert d["main_grid"]["origin"] == [0, 0] and d["processing"]["kind"] == "crop after compression"
    assert d["processing"]["crop"]["grid"] == [3, 5]
    assert [r["stage"] for r in d["regions"]] == ["cropped"] and d["n_meaningful"] == 0 and result.nfa == 1.0
    assert "cropped off the block grid" in result.summary

    spliced = _pasted_piece_is_found(tmp_path, rng, cropped, (6, 2), (slice(300, 560), slice(400, 700)))
    assert spliced.details["processing"]["crop"]["grid"] == [3, 5]

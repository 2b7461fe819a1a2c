"""Synthetic scene generator: determinism, truth geometry, splices, files and command."""

import io
import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from forensics_plugins.lens_distortion.command import synth_command
from forensics_plugins.lens_distortion.geometry import norm_scale, to_normalised, undistort
from forensics_plugins.lens_distortion.photo import render_authentic
from forensics_plugins.lens_distortion.render import render_scene
from forensics_plugins.lens_distortion.scene import ConvexPolygon, Scene
from forensics_plugins.lens_distortion.splice import SPLICE_KINDS, generate, make_splice
from forensics_plugins.lens_distortion.truth import write

SIZE = (400, 300)
SHAPE = (SIZE[1], SIZE[0])
LOSSLESS = {"jpeg_quality": None, "resize": None}


def _line_rms(points_norm: np.ndarray) -> float:
    """RMS distance of points (N, 2) to their total-least-squares line."""
    centred = points_norm - points_norm.mean(axis=0)
    return float(np.linalg.svd(centred, compute_uv=False)[-1] / np.sqrt(len(points_norm)))


def _chord(points: np.ndarray) -> float:
    return float(np.hypot(*(points[-1] - points[0])))


@pytest.fixture(scope="module")
def splices():
    return {kind: make_splice(kind, 11, SIZE, 0.1, **LOSSLESS) for kind in SPLICE_KINDS}


def test_same_seed_same_bytes_other_seed_other_image():
    a = render_authentic(3, SIZE)
    b = render_authentic(3, SIZE)
    c = render_authentic(4, SIZE)
    assert a.jpeg_bytes == b.jpeg_bytes
    assert np.array_equal(a.image, b.image)
    assert np.mean(a.image != c.image) > 0.5
    s1, s2 = make_splice("other_zoom", 3, SIZE), make_splice("other_zoom", 3, SIZE)
    assert s1.jpeg_bytes == s2.jpeg_bytes and np.array_equal(s1.mask, s2.mask)


@pytest.mark.parametrize(
    ("k1", "k2", "centre"), [(0.1, 0.0, (0.0, 0.0)), (-0.08, 0.0, (0.0, 0.0)), (0.15, -0.03, (0.04, -0.02))]
)
def test_truth_edges_are_straight_after_undistortion(k1, k2, centre):
    img = render_authentic(5, SIZE, k1, k2, centre, **LOSSLESS)
    assert len(img.lines_px) >= 10
    long_lines = [p for p in img.lines_px if _chord(p) >= SHAPE[0] / 3]
    assert len(long_lines) >= 4
    for p in img.lines_px:
        rms_px = _line_rms(undistort(to_normalised(p, SHAPE), k1, k2, centre)) * norm_scale(SHAPE)
        assert rms_px < 0.01
        assert np.all((p >= 0) & (p <= [SIZE[0] - 1, SIZE[1] - 1]))


@pytest.mark.parametrize("seed", range(4))
def test_scenes_have_long_edges_across_the_frame(seed):
    img = render_authentic(seed, SIZE, 0.1, **LOSSLESS)
    long_lines = [p for p in img.lines_px if _chord(p) >= SHAPE[0] / 3]
    thirds = {int(3 * p[len(p) // 2, 0] / SIZE[0]) for p in long_lines}
    assert thirds == {0, 1, 2}
    radii = [np.hypot(*to_normalised(p[len(p) // 2 : len(p) // 2 + 1], SHAPE)[0]) for p in long_lines]
    assert max(radii) > 0.6 and max(radii) - min(radii) > 0.25  # near and far from the centre


def test_truth_edges_lie_on_image_edges():
    img = render_authentic(6, SIZE, 0.1, noise=0.0, **LOSSLESS)
    luma = img.image.astype(np.float64) @ [0.299, 0.587, 0.114]
    gy, gx = np.gradient(luma)
    grad = np.hypot(gx, gy)
    pts = np.round(np.concatenate(img.lines_px)).astype(int)
    assert np.median(grad[pts[:, 1], pts[:, 0]]) > 10 * np.median(grad) + 5.0


def _edge_columns(image: np.ndarray) -> np.ndarray:
    """Sub-pixel column of a dark-to-bright step in each row, from the bright area.

    Area is conserved by pixel integration and by any blur, so a step at
    column ``e`` leaves ``W - 0.5 - e`` of brightness in its row whatever its
    sub-pixel phase.
    """
    return image.shape[1] - 0.5 - image[..., 0].astype(np.float64).sum(axis=1)


def _expected_columns(a: float, tilt: float, k1: float) -> np.ndarray:
    """Distorted image of the line x_u = a + tilt * y_u, per row (paper eq. 4).

    Substituting p_u = p_d (1 + k1 r_d^2) gives, in each row y, the cubic
    (x - tilt y)(1 + k1 x^2 + k1 y^2) = a, solved independently of geometry.distort.
    """
    scale = norm_scale(SHAPE)
    ys = (np.arange(SHAPE[0]) - (SHAPE[0] - 1) / 2.0) / scale
    xs = []
    for y in ys:
        roots = np.roots([k1, -k1 * tilt * y, 1.0 + k1 * y * y, -tilt * y * (1.0 + k1 * y * y) - a])
        real = roots[np.abs(roots.imag) < 1e-9].real
        xs.append(real[np.argmin(np.abs(real - a - tilt * y))])
    return np.array(xs) * scale + (SHAPE[1] - 1) / 2.0


@pytest.mark.parametrize(("k1", "tilt"), [(0.1, 0.0), (0.1, 0.35), (0.0, 0.0)])
def test_edge_near_border_bows_by_the_model_sagitta(k1, tilt):
    a = 0.6
    outline = np.array([[a - 3.0 * tilt, -3.0], [5.0, -3.0], [5.0, 3.0], [a + 3.0 * tilt, 3.0]])
    scene = Scene(np.zeros(3), 0.0, (ConvexPolygon(outline, np.ones(3), 0.0),), texture_seed=0)
    measured = _edge_columns(render_scene(scene, SIZE, k1, blur=0.7).image)
    expected = _expected_columns(a, tilt, k1)
    inner = slice(2, -2)  # the blur's border mode flattens the outermost rows
    assert np.max(np.abs(measured[inner] - expected[inner])) < 0.005
    chord = np.interp(SHAPE[0] // 2, [2, SHAPE[0] - 3], expected[[2, -3]])
    sagitta = expected[SHAPE[0] // 2] - chord
    measured_sagitta = measured[SHAPE[0] // 2] - np.interp(SHAPE[0] // 2, [2, SHAPE[0] - 3], measured[[2, -3]])
    assert abs(measured_sagitta - sagitta) < 0.005
    if k1:
        assert sagitta > 4.0  # barrel: the middle bulges away from the centre by about 5 px
    else:
        assert abs(measured_sagitta) < 0.005


def _mask_at(mask: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Mask value at the pixel nearest each point (N, 2)."""
    idx = np.round(points).astype(int)
    return mask[idx[:, 1], idx[:, 0]]


@pytest.mark.parametrize("kind", SPLICE_KINDS)
def test_splice_mask_area_and_long_pasted_edges(splices, kind):
    img = splices[kind]
    assert img.kind == kind and img.mask.shape == SHAPE
    assert 0.10 <= img.mask.mean() <= 0.35
    long_inside = [p for p in img.paste.lines_px if _chord(p) >= SHAPE[0] / 3 and np.all(_mask_at(img.mask, p))]
    assert len(long_inside) >= 2
    assert not any(np.any(_mask_at(img.mask, p)) for p in img.lines_px)  # the host's edges stay outside


@pytest.mark.parametrize("kind", SPLICE_KINDS)
def test_splice_changes_only_the_masked_pixels(splices, kind):
    authentic = render_authentic(11, SIZE, 0.1, **LOSSLESS)
    changed = np.any(splices[kind].image != authentic.image, axis=2)
    assert not np.any(changed & ~splices[kind].mask)
    assert changed[splices[kind].mask].mean() > 0.5


def test_splice_kinds_carry_the_paper_inconsistencies(splices):
    cm, cam, zoom = splices["copy_move"], splices["other_camera"], splices["other_zoom"]
    assert cm.pasted_k1 is None and cm.paste.scale == 1.0
    centre_x = (SIZE[0] - 1) / 2.0
    src_x, tgt_x = cm.paste.source_centre_px[0], cm.paste.target_centre_px[0]
    assert abs(src_x - tgt_x) >= 0.25 * SIZE[0] and (src_x - centre_x) * (tgt_x - centre_x) <= 0
    assert abs(cam.pasted_k1 - cam.k1) >= 0.08 and cam.paste.scale == 1.0
    assert zoom.pasted_k1 != zoom.k1 and abs(np.log(zoom.paste.scale)) > np.log(1.2)


@pytest.mark.parametrize("kind", ["other_camera", "other_zoom"])
def test_pasted_edges_are_straight_for_the_source_lens(splices, kind):
    img = splices[kind]
    for p in img.paste.source_lines_px:
        rms_px = _line_rms(undistort(to_normalised(p, SHAPE), img.paste.source_k1)) * norm_scale(SHAPE)
        assert rms_px < 0.01


def test_jpeg_decodes_and_resize_scales_truth():
    img = make_splice("copy_move", 2, SIZE, jpeg_quality=85, resize=0.5)
    decoded = Image.open(io.BytesIO(img.jpeg_bytes))
    assert decoded.format == "JPEG" and decoded.size == (200, 150)
    assert np.array_equal(np.asarray(decoded.convert("RGB")), img.image)
    assert img.mask.shape == (150, 200)
    for p in img.lines_px + img.paste.lines_px:
        assert np.all((p >= -0.5) & (p <= [199.5, 149.5]))


def test_params_regenerate_the_image():
    img = make_splice("other_camera", 9, SIZE, 0.05, jpeg_quality=80)
    again = generate(json.loads(json.dumps(img.params)))
    assert again.jpeg_bytes == img.jpeg_bytes


def test_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="unknown splice kind"):
        make_splice("rotate", 0, SIZE)


def test_write_outputs_photo_mask_and_truth(tmp_path, splices):
    paths = write(splices["other_zoom"], tmp_path, "z")
    assert [p.name for p in paths] == ["z.png", "z_mask.png", "z.json"]
    mask = np.asarray(Image.open(paths[1])) > 0
    assert np.array_equal(mask, splices["other_zoom"].mask)
    truth = json.loads(paths[2].read_text())
    assert truth["kind"] == "other_zoom" and truth["paste"]["source_k1"] == splices["other_zoom"].pasted_k1


def test_command_writes_files_and_is_byte_reproducible(tmp_path):
    args = ["--kind", "all", "--count", "1", "--seed", "7", "--size", "240x180", "--k1", "0.12"]
    runner = CliRunner()
    first, second = tmp_path / "a", tmp_path / "b"
    for out in (first, second):
        result = runner.invoke(synth_command, [str(out), *args])
        assert result.exit_code == 0, result.output
    listing = json.loads((first / "truth.json").read_text())
    assert [e["kind"] for e in listing["images"]] == ["authentic", *SPLICE_KINDS]
    for entry in listing["images"]:
        assert entry["seed"] == 7 and entry["k1"] == 0.12
        assert (first / entry["file"]).exists() and (first / entry["truth"]).exists()
        assert (entry["mask"] is None) == (entry["kind"] == "authentic")
        Image.open(first / entry["file"]).verify()
    names = sorted(p.name for p in first.iterdir())
    assert names == sorted(p.name for p in second.iterdir())
    assert all((first / n).read_bytes() == (second / n).read_bytes() for n in names)


def test_command_rejects_bad_size(tmp_path):
    result = CliRunner().invoke(synth_command, [str(tmp_path), "--size", "big"])
    assert result.exit_code != 0 and "WIDTHxHEIGHT" in result.output

"""The synthetic photos: deterministic, tagged, with the grids they claim."""

import io

import numpy as np
import pytest
from PIL import Image

from forensics_plugins.jpeg_grid import synth
from forensics_plugins.jpeg_grid.zeros import zero_counts

SIZE = (192, 256)


def _grid_of(y: np.ndarray) -> tuple[int, int]:
    """Origin (dx, dy) whose blocks hold the most zeros on average."""
    z = zero_counts(y.astype(np.float32))
    h, w = (z.shape[0] // 8) * 8, (z.shape[1] // 8) * 8
    means = z[:h, :w].reshape(h // 8, 8, w // 8, 8).mean(axis=(0, 2))
    dy, dx = np.unravel_index(np.argmax(means), means.shape)
    return int(dx), int(dy)


@pytest.mark.parametrize("origin", [(0, 0), (3, 5), (7, 1)])
def test_jpeg_bytes_puts_the_grid_where_asked(origin):
    scene = synth.render_scene(np.random.default_rng(0), SIZE, "astronaut")
    decoded = synth.decode_cropped(synth.jpeg_bytes(scene, 80, origin), origin)
    assert decoded.shape == scene.shape
    y = decoded.astype(np.float64) @ np.array([0.299, 0.587, 0.114])
    assert _grid_of(np.round(y)) == origin


def test_scene_is_a_camera_like_photo():
    scene = synth.render_scene(np.random.default_rng(1), SIZE, "chelsea")
    assert scene.shape == (*SIZE, 3) and scene.dtype == np.uint8
    # Fine detail: the texture and the noise leave energy at the highest frequencies.
    assert np.abs(np.diff(scene[..., 1].astype(float), axis=1)).mean() > 2.0


def test_cases_are_deterministic_and_tagged():
    first = list(synth.synthetic_cases(3, 8, size=SIZE))
    second = list(synth.synthetic_cases(3, 8, size=SIZE))
    assert [c.data for c in first] == [c.data for c in second]
    assert len(first) == 16 and len({c.name for c in first}) == 16
    kinds = [c.conditions["kind"] for c in first]
    assert kinds.count("never_compressed") == 1 and kinds.count("recompressed") == 2 and kinds.count("none") == 5
    assert kinds.count("splice") == 4 and kinds.count("copy_move") == kinds.count("uncompressed_paste") == 2
    for case in first:
        img = Image.open(io.BytesIO(case.data))
        assert img.format == ("PNG" if case.suffix == ".png" else "JPEG")
        assert img.size == (SIZE[1], SIZE[0]) and case.conditions["size"] == f"{SIZE[1]}x{SIZE[0]}"
        if case.spliced:
            assert case.mask.shape == SIZE and case.mask.dtype == bool
            assert 0.12 <= case.mask.mean() <= 0.33
            assert 75 <= int(case.conditions["jpeg_quality"]) <= 95
            if case.conditions["kind"] == "uncompressed_paste":
                assert case.suffix == ".png" and case.conditions["shift"] == "none"
            else:
                assert synth.FINAL_QUALITY_RANGE[0] <= int(case.conditions["final_quality"]) <= 100
                assert case.conditions["shift"] != "0,0"
        else:
            assert case.mask is None


@pytest.mark.parametrize("kind", synth.SPLICE_KINDS)
def test_spliced_region_carries_the_shifted_grid(kind):
    case = synth.make_spliced(9, kind, size=(256, 320), final_quality=100, shift=(6, 3))
    assert case.shift == (6, 3) and case.params["shift"] == [6, 3]
    with Image.open(io.BytesIO(case.data)) as img:
        img.draft("YCbCr", img.size)
        y = np.asarray(img)[..., 0]
    ys, xs = np.nonzero(case.mask)
    # Inside the paste, on whole blocks of the pasted grid; outside, the host grid.
    y0, x0 = ys.min() + 8, xs.min() + 8
    inner = y[y0:ys.max() - 8, x0:xs.max() - 8]
    off = ((6 - x0) % 8, (3 - y0) % 8)
    assert _grid_of(inner) == off
    assert _grid_of(y[:, : max(16, xs.min() - 1)] if xs.min() > 40 else y[: max(16, ys.min() - 1)]) == (0, 0)


def test_copy_move_displacement_keeps_the_residue_and_the_frame():
    rng = np.random.default_rng(0)
    for residue in range(8):
        o = synth._displacement(rng, 40, 120, 300, residue)
        assert o % 8 == residue and abs(o) >= 8
        assert 40 - o >= 0 and 120 - o < 300


def test_recorded_parameters_regenerate_the_case():
    case = synth.make_spliced(12, "splice", size=SIZE)
    p = case.params
    again = synth.make_spliced(12, "splice", size=SIZE, quality=p["quality"], paste_quality=p["paste_quality"],
                               final_quality=p["final_quality"], source=p["source"], shift=tuple(p["shift"]))
    assert again.data == case.data


def test_shift_zero_is_refused():
    with pytest.raises(ValueError):
        synth.make_spliced(1, "splice", size=SIZE, shift=(8, 0))

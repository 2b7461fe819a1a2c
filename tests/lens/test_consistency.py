"""The splice decision on point-level synthetic scenes (fixed seeds).

Scenes: a 1600x1200 frame; 8-20 random straight 3-D lines (random angle and
position, length 0.3-1.0 normalised) seen through one camera (k1 in
0.03..0.15, |k2| <= 0.03, centre of distortion up to 0.05 = 40 px off the
image centre), sampled one point per pixel, with edge noise of 0.1-0.2 px
smoothed along the line (Gaussian, sd 1-3 points) as JPEG and blur do.
Spliced scenes add a group of 2-4 lines (length 0.3-0.6) within 0.15 of a
region centre 0.45-0.8 from the image centre, either from another camera
(k1 differing by 0.05-0.1) or copied from a region at least 0.6 away in the
same photo. Pasted lines are kept at least 30 degrees from radial: a radial
line stays straight under any radial distortion, so a group of radial lines
is undetectable by this method whatever the estimator.

These scenes are drawn with perfectly straight world lines and Gaussian edge
noise, so the search for departing groups is validated here under that
physics (``SYNTHETIC_NULL``: no model error, normal tails). The default error
model is the one measured on real photos (heavy-tailed, edge non-straightness),
under which the same splices are not called: see
``test_default_real_photo_null_is_conservative_on_synthetic_splices``.
"""


import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from forensics_plugins.lens_distortion import geometry
from forensics_plugins.lens_distortion.consistency import assess, paper_rules
from forensics_plugins.lens_distortion.error_model import TAU_PHOTO

SHAPE = (1200, 1600)
SCALE = geometry.norm_scale(SHAPE)
HALF = np.array([1.0, 0.75])  # normalised half-extent of the frame
N_SCENES = 100
SYNTHETIC_NULL = {"tau_k1": 0.0, "bow_rel": 0.0, "dof": np.inf}


def _camera(rng):
    angle, radius = rng.uniform(0, 2 * np.pi), 0.05 * np.sqrt(rng.uniform())
    centre = (radius * np.cos(angle), radius * np.sin(angle))
    return {"k1": rng.uniform(0.03, 0.15), "k2": rng.uniform(-0.03, 0.03), "centre": centre}


def _inside(p):
    return np.all(np.isfinite(p)) and np.all(np.abs(p) <= HALF - 2.0 / SCALE)


def _line(rng, cam, midpoint, lengths, min_radial_angle=0.0):
    """Distorted points of a random straight line, one per pixel, normalised."""
    while True:
        mid = midpoint()
        phi = rng.uniform(0, np.pi)
        radial = abs(np.cos(phi - np.arctan2(mid[1], mid[0])))
        if radial > np.cos(np.radians(min_radial_angle)):
            continue
        length = rng.uniform(*lengths)
        t = np.arange(-length / 2, length / 2, 1.0 / SCALE)
        p = geometry.distort(mid + np.outer(t, [np.cos(phi), np.sin(phi)]), **cam)
        if _inside(p):
            return p


def _in_frame(rng):
    return lambda: rng.uniform(-0.9 * HALF, 0.9 * HALF)


def _region(rng):
    while True:
        angle, radius = rng.uniform(0, 2 * np.pi), rng.uniform(0.45, 0.8)
        c = radius * np.array([np.cos(angle), np.sin(angle)])
        if np.all(np.abs(c) < HALF - 0.15):
            return c


def _to_pixels(rng, lines):
    """Correlated edge noise along each line's normal, then pixels."""
    out = []
    for p in lines:
        tangent = np.gradient(p, axis=0)
        normal = np.column_stack((-tangent[:, 1], tangent[:, 0])) / np.hypot(*tangent.T)[:, None]
        w = gaussian_filter1d(rng.standard_normal(len(p)), rng.uniform(1.0, 3.0))
        w *= rng.uniform(0.1, 0.2) / w.std()
        out.append(geometry.to_pixels(p + normal * (w / SCALE)[:, None], SHAPE))
    return out


def authentic_scene(seed, n_lines=None, cam=None):
    rng = np.random.default_rng(seed)
    cam = cam or _camera(rng)
    n = n_lines or int(rng.integers(8, 21))
    lines = [_line(rng, cam, _in_frame(rng), (0.3, 1.0)) for _ in range(n)]
    return _to_pixels(rng, lines), cam


def spliced_scene(seed, kind):
    """Authentic lines plus a pasted group; returns pixels, camera and the pasted ids."""
    rng = np.random.default_rng(seed)
    cam = _camera(rng)
    n = int(rng.integers(8, 17))
    lines = [_line(rng, cam, _in_frame(rng), (0.3, 1.0)) for _ in range(n)]
    k = int(rng.integers(2, 5))
    target = _region(rng)
    while True:
        if kind == "camera":
            dk = rng.uniform(0.05, 0.1) * rng.choice([-1.0, 1.0])
            other = {"k1": cam["k1"] + dk, "k2": 0.0, "centre": (0.0, 0.0)}
            group = [_line(rng, other, lambda: target + rng.uniform(-0.15, 0.15, 2), (0.3, 0.6), 30) for _ in range(k)]
        else:
            source = _region(rng)
            if np.linalg.norm(source - target) < 0.6:
                continue
            near = lambda: source + rng.uniform(-0.15, 0.15, 2)  # noqa: E731
            # Radial angle judged where the line is pasted, where it must carry information.
            group = [
                p + (target - source)
                for p in (_line(rng, cam, near, (0.3, 0.6)) for _ in range(20))
                if abs(np.cos(np.arctan2(*np.diff(p[[0, -1]], axis=0)[0][::-1])
                              - np.arctan2(*(p.mean(0) + target - source)[::-1]))) < np.cos(np.radians(30))
            ][:k]
        if len(group) == k and all(_inside(p) for p in group):
            return _to_pixels(rng, lines + group), cam, set(range(n, n + k))


@pytest.fixture(scope="module")
def authentic_results():
    out = []
    for seed in range(N_SCENES):
        lines, cam = authentic_scene(seed)
        out.append((assess(lines, SHAPE, **SYNTHETIC_NULL), cam))
    return out


@pytest.fixture(scope="module")
def spliced_results():
    out = []
    for seed in range(N_SCENES):
        kind = ("camera", "copy")[seed % 2]
        lines, _, pasted = spliced_scene(1000 + seed, kind)
        out.append((assess(lines, SHAPE, **SYNTHETIC_NULL), assess(lines, SHAPE, single_lines=True, **SYNTHETIC_NULL),
                    pasted, kind))
    return out


def test_global_k1_recovered(authentic_results):
    errors = np.array([r.model.k1 - cam["k1"] for r, cam in authentic_results if r.model is not None])
    pulls = np.array([(r.model.k1 - cam["k1"]) / r.model.k1_stderr for r, cam in authentic_results if r.model])
    print(f"\nk1 error: rms {np.sqrt(np.mean(errors**2)):.4f}, within 0.005 in {np.mean(np.abs(errors) <= 0.005):.0%}")
    assert errors.size >= 0.9 * N_SCENES
    assert np.mean(np.abs(errors) <= 0.005) >= 0.9
    assert np.max(np.abs(pulls)) < 4.5  # every miss is explained by its stated stderr


def test_false_alarm_rate(authentic_results):
    conclusive = [r for r, _ in authentic_results if r.verdict != "inconclusive"]
    rate = np.mean([r.verdict == "inconsistent" for r in conclusive])
    print(f"\nfalse alarms: {rate:.1%} of {len(conclusive)} authentic scenes")
    assert len(conclusive) >= 0.9 * N_SCENES
    assert rate <= 0.05


def test_detection_rate(spliced_results):
    """Scenes whose pasted part is 2-4 lines. With ``single_lines=True`` the per-line test must reach 90 %.
    By default only a compact region whose lines in two directions follow one other lens (or this lens about a
    displaced centre) can reject (:mod:`.regions`: a lone or scattered departure is an outlier, a parallel
    bundle a curved object), so pasted pairs that are parallel, and copies moved along one family of their
    lines, are not called. Measured when the region test was introduced: 76 % of other-camera and 68 % of
    copy-move scenes (the group test before it: 48 % and 10 %); what is called must point at the pasted lines."""
    for mode, index, required in (("default", 0, 0.6), ("single_lines", 1, 0.90)):
        conclusive = [(r[index], pasted, kind) for *r, pasted, kind in spliced_results
                      if r[index].verdict != "inconclusive"]
        detected = np.array([r.verdict == "inconsistent" for r, _, _ in conclusive])
        localised = np.array([bool(set(r.flagged_ids) & pasted) for r, pasted, _ in conclusive])
        for kind in ("camera", "copy"):
            pick = np.array([k == kind for _, _, k in conclusive])
            print(f"\n{mode} {kind}: detected {detected[pick].mean():.0%} of {pick.sum()}")
        print(f"{mode}: pasted lines among the flagged of the detected: {localised[detected].mean():.0%}")
        assert len(conclusive) >= 0.9 * N_SCENES
        assert detected.mean() >= required
        assert localised[detected].mean() >= 0.85


def test_chessboard_like_offset_centre_and_k2_do_not_alarm():
    """640x480 grids seen by a lens like the calibration camera: k1 0.11, k2 0.03, centre 23 px right."""
    shape = (480, 640)
    scale = geometry.norm_scale(shape)
    cam = {"k1": 0.11, "k2": 0.03, "centre": (23.0 / scale, 0.0)}
    alarms = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        angle, offset = rng.uniform(-0.3, 0.3), rng.uniform(-0.1, 0.1, 2)
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        grid = np.linspace(-0.55, 0.55, 8)
        t = np.arange(-0.55, 0.55, 1.0 / scale)
        lines = [np.column_stack((np.full_like(t, g), t * 0.75)) for g in grid]
        lines += [np.column_stack((t, np.full_like(t, g * 0.75))) for g in grid[1:-1]]
        lines = [geometry.distort(p @ rot.T + offset, **cam) for p in lines]
        px = []
        for p in lines:
            w = gaussian_filter1d(rng.standard_normal(len(p)), 2.0)
            px.append(geometry.to_pixels(p + rng.normal(0, 1e-9, p.shape), shape) + np.outer(0.1 * w / w.std(), [1, 1]) / np.sqrt(2))
        result = assess(px, shape, **SYNTHETIC_NULL)
        assert result.verdict != "inconclusive"
        assert result.model.cx * scale == pytest.approx(23.0, abs=6.0)
        alarms += result.verdict == "inconsistent"
    assert alarms <= 1


def test_too_few_lines_is_inconclusive_not_authentic():
    lines, _ = authentic_scene(3, n_lines=4)
    result = assess(lines, SHAPE)
    assert result.verdict == "inconclusive" and not result.informative
    assert result.model is None and "informative line" in result.reason
    # Radial lines only: plenty of lines, no information.
    t = np.arange(-0.6, 0.6, 1.0 / SCALE)
    radial = [geometry.to_pixels(np.outer(t, [np.cos(a), np.sin(a)]), SHAPE) for a in np.linspace(0, 3, 10)]
    assert assess(radial, SHAPE).verdict == "inconclusive"


def test_paper_rules_with_stderrs():
    d = np.array([-0.45, -0.2, -0.12, 0.12, 0.2, 0.45])
    k1 = np.array([0.10, 0.10, -0.08, 0.10, 0.10, 0.02])
    se = np.array([0.005, 0.01, 0.01, 0.2, 0.01, 0.005])
    rules = paper_rules(d, k1, se, alpha=0.01)
    assert rules.sign == 1 and rules.sign_violators == (2,)
    assert (4, 5) in rules.order_violations and 3 not in rules.order_violators
    assert not rules.consistent
    # A line of the other sign within its error is no violator.
    assert paper_rules(d[:2], np.array([0.1, -0.01]), np.array([0.01, 0.02])).consistent


def test_result_is_deterministic():
    rng = np.random.default_rng(5)
    cam = _camera(rng)
    lines = [_line(rng, cam, lambda: rng.uniform(-0.5 * HALF, 0.5 * HALF), (1.2, 1.3)) for _ in range(40)]
    px = _to_pixels(rng, lines)
    assert np.mean([len(p) for p in px]) > 950
    first = assess(px, SHAPE)
    second = assess([p.copy() for p in px], SHAPE)
    assert first.p_value == second.p_value and first.model.k1 == second.model.k1
    assert first.flagged_ids == second.flagged_ids


def test_default_real_photo_null_is_conservative_on_synthetic_splices(spliced_results):
    """The default error model (measured on real photos) on the same spliced scenes: it calls no more of
    them than the synthetic-physics test does, and the figure is printed."""
    seeds = range(0, N_SCENES, 5)
    called = 0
    for seed in seeds:
        kind = ("camera", "copy")[seed % 2]
        lines, _, _ = spliced_scene(1000 + seed, kind)
        called += assess(lines, SHAPE).verdict == "inconsistent"
    strict = sum(spliced_results[seed][0].verdict == "inconsistent" for seed in seeds)
    print(f"\ndefault error model: {called} of {len(seeds)} synthetic splices called ({strict} under SYNTHETIC_NULL)")
    assert called <= strict


def test_global_k1_stderr_widens_when_lines_scatter_beyond_their_error_model():
    """World edges bowing on their own, more than the measured model allows: the stated k1 error widens.

    Each line gets its own random bow (sd 0.5 px at its middle, three times
    the measured ``BOW_REL`` on a 1000 px edge). The cluster-robust standard
    error (lines as clusters) measures that scatter, so the true k1 falls
    within the stated error more often than with the model-based covariance
    alone; it is never smaller than the model-based one.
    """
    robust, model = [], []
    for seed in range(30):
        rng = np.random.default_rng(500 + seed)
        cam = _camera(rng)
        lines = []
        for _ in range(int(rng.integers(10, 16))):
            u = geometry.undistort(_line(rng, cam, _in_frame(rng), (0.3, 1.0)), **cam)
            t = np.linspace(-1.0, 1.0, len(u))
            d = np.diff(u[[0, -1]], axis=0)[0]
            normal = np.array([-d[1], d[0]]) / np.hypot(*d)
            lines.append(geometry.distort(u + np.outer((1.0 - t**2) * rng.normal(0.0, 0.5 / SCALE), normal), **cam))
        m = assess(_to_pixels(rng, lines), SHAPE).model
        assert m.k1_stderr >= np.sqrt(m.covariance[0, 0])
        robust.append(abs(m.k1 - cam["k1"]) / m.k1_stderr)
        model.append(abs(m.k1 - cam["k1"]) / np.sqrt(m.covariance[0, 0]))
    covered, covered_model = np.mean(np.array(robust) < 1.96), np.mean(np.array(model) < 1.96)
    print(f"\nwithin 1.96 stated errors: {covered:.0%} (model-based only: {covered_model:.0%})")
    assert covered > covered_model
    assert np.median(robust) < np.median(model)


def test_photo_k1_is_the_one_term_model_with_its_error_covering_a_one_term_lens():
    """The photo's k1 (one-term, centre free) recovers a one-term lens within its stated error.

    Its error carries the photo-level term, so it is never below
    ``TAU_PHOTO``; the displacement at the stated radius is ``k1 r^3`` in
    pixels with the same relative error.
    """
    pulls = []
    for seed in range(20):
        rng = np.random.default_rng(700 + seed)
        cam = {**_camera(rng), "k2": 0.0}
        lines = [_line(rng, cam, _in_frame(rng), (0.3, 1.0)) for _ in range(int(rng.integers(10, 16)))]
        one = assess(_to_pixels(rng, lines), SHAPE).model.one_term
        assert one.k1_stderr >= TAU_PHOTO
        assert one.displacement_px == pytest.approx(one.k1 * one.radius**3 * SCALE)
        assert one.displacement_stderr_px / abs(one.displacement_px) == pytest.approx(one.k1_stderr / abs(one.k1))
        pulls.append((one.k1 - cam["k1"]) / one.k1_stderr)
    assert np.mean(np.abs(pulls) < 1.96) >= 0.9


def test_photo_k1_error_widens_when_one_direction_bows_on_its_own():
    """Lines of one direction sharing a bow (one kind of curved object) widen the photo's k1 error.

    The vertical lines of each scene bow alike by 1 px at their middle,
    towards the centre, as identical window frames leaning the same way
    would; the horizontal ones are straight. The shared bow moves k1, and
    the stated error grows with it (the two directions' disagreement and
    the structure jackknife), so the one-term lens stays covered.
    """
    ratios, pulls = [], []
    for seed in range(12):
        cam = {**_camera(np.random.default_rng(900 + seed)), "k2": 0.0}
        fit = {}
        for bow in (0.0, 1.0):
            r = np.random.default_rng(900 + seed)
            _camera(r)
            lines = []
            for i in range(14):
                u = geometry.undistort(_line(r, cam, _in_frame(r), (0.3, 1.0)), **cam)
                d = np.diff(u[[0, -1]], axis=0)[0]
                t = np.linspace(-1.0, 1.0, len(u))
                normal = np.array([-d[1], d[0]]) / np.hypot(*d)
                normal *= -np.sign(normal @ u.mean(axis=0)) or 1.0
                shared = bow if abs(d[1]) > abs(d[0]) else 0.0
                lines.append(geometry.distort(u + np.outer((1.0 - t**2) * shared / SCALE, normal), **cam))
            fit[bow] = assess(_to_pixels(r, lines), SHAPE).model.one_term
        ratios.append(fit[1.0].k1_stderr / fit[0.0].k1_stderr)
        pulls.append((fit[1.0].k1 - cam["k1"]) / fit[1.0].k1_stderr)
    print(f"\nstated k1 error with a shared bow / without: median {np.median(ratios):.2f}; "
          f"within 1.96: {np.mean(np.abs(pulls) < 1.96):.0%}")
    assert np.median(ratios) > 1.05
    assert np.mean(np.abs(pulls) < 1.96) >= 0.8

"""The radial warp that explains regions on shifted grids: lens correction after a first compression."""

import numpy as np

from forensics_plugins.jpeg_grid.regions import Region
from forensics_plugins.jpeg_grid.resampling import radial_steps, radial_warp
from forensics_plugins.jpeg_grid.votes import grid_code

SHAPE = (2000, 3000)


def _region(label: int, angle_deg: float, rho: float, shift_px: float, origin=(0, 0)) -> Region:
    """A region at ``rho`` half diagonals from the centre whose grid is ``origin`` moved ``shift_px`` along its radius."""
    centre = np.array([(SHAPE[1] - 1) / 2, (SHAPE[0] - 1) / 2])
    u = np.array([np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))])
    x, y = centre + rho * np.hypot(*centre) * u
    dx, dy = np.round(origin + shift_px * u).astype(int)
    return Region(label, grid_code(int(dx), int(dy)), 500, (int(x) - 20, int(y) - 20, int(x) + 20, int(y) + 20),
                  -10.0 - label)


def test_regions_in_one_band_establish_the_warp():
    # The old grid survives best where the shift is near whole pixels: every region at 0.57 half diagonals,
    # 18 px out. Two regions this close in distance cannot fix a two-term profile; one term through one does.
    regions = [_region(i, angle, 0.57, 18.0) for i, angle in enumerate(range(0, 360, 45))]
    # In one band a grid shows the shift modulo 8 only: 18 px out also reads as about 14 px in.
    warp = radial_warp(regions, [(0, 0)], SHAPE)
    assert warp is not None and len(warp.explained) == len(regions)


def test_the_first_grid_may_be_the_files_own_when_the_main_grid_is_another():
    regions = [_region(i, angle, 0.4 + 0.05 * i, 6.0 + 10 * (0.4 + 0.05 * i) ** 3) for i, angle in
               enumerate(range(10, 360, 60))]
    warp = radial_warp(regions, [(4, 4), (0, 0)], SHAPE)
    assert warp is not None and len(warp.explained) == len(regions)


def test_two_regions_or_regions_in_one_direction_are_not_a_warp():
    assert radial_warp([_region(0, 0, 0.5, 9.0), _region(1, 120, 0.6, 11.0)], [(0, 0)], SHAPE) is None
    one_side = [_region(i, 10 + 5 * i, 0.5 + 0.03 * i, 9.0) for i in range(5)]
    assert radial_warp(one_side, [(0, 0)], SHAPE) is None


def _nearest_neighbour_field(a: float, b: float, shape=(600, 800)) -> tuple[np.ndarray, list[Region]]:
    """Labels and regions of the grids a nearest-neighbour warp ``D = a rho^3 + b rho`` leaves, one per patch.

    The shift is floored, as a remap on fixed-point coordinates does: a patch's centre then lies off the radius.
    """
    from scipy import ndimage

    h, w = shape
    ys, xs = np.mgrid[0:h, 0:w].astype(float)
    vx, vy = xs - (w - 1) / 2, ys - (h - 1) / 2
    r = np.maximum(np.hypot(vx, vy), 1e-9)
    rho = r / np.hypot((w - 1) / 2, (h - 1) / 2)
    d = (a * rho**3 + b * rho) / r
    codes = 8 * (np.floor(d * vy).astype(int) % 8) + np.floor(d * vx).astype(int) % 8
    labels = np.zeros(shape, np.int32)
    regions = []
    for code in np.unique(codes):
        if code == 0:
            continue
        parts, n = ndimage.label(codes == code)
        for k, box in enumerate(ndimage.find_objects(parts), start=1):
            mask = parts[box] == k
            if mask.sum() < 400:
                continue
            label = len(regions) + 1
            labels[box][mask] = label
            regions.append(Region(label, int(code), int(mask.sum()),
                                  (box[1].start, box[0].start, box[1].stop - 1, box[0].stop - 1), -float(mask.sum())))
    regions.sort(key=lambda reg: reg.log10_nfa)
    return labels, regions


def test_an_established_warp_is_refitted_and_judged_pixel_by_pixel_and_a_paste_stays_foreign():
    from forensics_plugins.jpeg_grid.resampling import field_explained

    labels, regions = _nearest_neighbour_field(40.0, -15.0)  # with the zoom to fill the frame: up to 25 px
    paste = Region(len(regions) + 1, grid_code(3, 5), 3600, (100, 80, 159, 139), -50.0)
    labels[80:140, 100:160] = paste.label
    regions = [paste] + regions
    warp = radial_warp(regions, [(0, 0)], labels.shape)
    assert warp is not None and len(warp.explained) < len(regions) - 10  # by the regions' centres
    refitted, explained = field_explained(warp, regions, labels)
    assert np.allclose(refitted.terms, (40.0, -15.0), atol=1.0)
    assert 0 not in explained and len(explained) == len(regions) - 1


def test_a_lone_region_one_pixel_along_its_radius_is_a_radial_step_and_other_shifts_are_not():
    # Below the centre one pixel inwards is (0, -1), i.e. the grid (0, 7); to the right outwards, (1, 0); on the
    # diagonal, (1, 1). The same shifts across the radius, or of several pixels, are what a paste may have.
    steps = [_region(0, 90, 0.5, -1.0), _region(1, 0, 0.4, 1.0), _region(2, 45, 0.6, 1.2)]
    others = [_region(3, 90, 0.5, 0.0, origin=(1, 0)), _region(4, 0, 0.4, 0.0, origin=(3, 5)),
              _region(5, 0, 0.4, 3.0)]
    assert radial_steps(steps + others, [(0, 0)], SHAPE) == [0, 1, 2]
    # Measured from another first grid the same regions are no step.
    assert radial_steps(steps, [(4, 4)], SHAPE) == []


def _box(label: int, bbox: tuple[int, int, int, int], grid: tuple[int, int]) -> Region:
    return Region(label, grid_code(*grid), 500, bbox, -10.0 - label)


def test_a_tall_band_left_of_the_centre_one_pixel_out_is_a_step_and_a_shift_it_does_not_round_to_is_not():
    # As a frame-preserving lens correction at quality 98 leaves it (a Canon photo, k1 -0.08): a band 144 px wide
    # and 344 px tall, 370 px left of the centre, spanning 60 degrees of directions, whose grid is the first grid
    # moved one pixel outwards, (-1, 0) = (7, 0). The other coordinate of the move stays below half a pixel across
    # it, so one move rounds to that shift over the whole band.
    shape = (2272, 1704)
    band = (408, 952, 552, 1296)
    assert radial_steps([_box(0, band, (7, 0))], [(0, 0)], shape) == [0]
    # Across the radius, diagonal, or two pixels: a pasted piece's grid, not a step.
    assert radial_steps([_box(i, band, g) for i, g in enumerate([(0, 1), (7, 1), (6, 0)])], [(0, 0)], shape) == []
    # A shift one move gives at a corner of a wide box only is no step either.
    wide = (100, 100, 1600, 1000)
    assert radial_steps([_box(0, wide, (7, 7))], [(0, 0)], shape) == []

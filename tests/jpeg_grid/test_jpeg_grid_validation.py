"""Validation on synthetic photos with fixed seeds: the issue's figures, measured and printed.

Run with ``pytest -s tests/jpeg_grid/test_validation.py`` to see them.

Spliced: a host compressed at quality q (75-95) with a region of 15-30 % of
the frame, pasted from another scene compressed at quality qp (75-95) on a
grid shifted by (dx, dy) != (0, 0), or copied within the host by an offset that
is not a multiple of 8 (qp = q); the whole is saved again at quality q2.
Found: a meaningful region (NFA < 1, the detector's default threshold, fixed
before these seeds were drawn) with IoU >= 0.5 against the paste mask.

The target (>= 90 % found) is asserted for final qualities q2 of 98-100.
Below 98 the last compression rewrites the pasted piece's zeros on the main
grid, so that its pixels vote for the main grid and ZERO, as published, does
not see it (measured: 1 of 20 found at q2 90-97); the rate there is printed.
Also measured: pieces never compressed pasted into a JPEG saved as PNG (a
region missing the main grid, by the test that is off by default), and false
regions on authentic photos compressed once or twice on the same grid.
"""

from collections import Counter, defaultdict

import numpy as np
import pytest

from forensics_core import Status, load_evidence
from forensics_plugins.jpeg_grid import synth
from forensics_plugins.jpeg_grid.detector import JpegGrid
from forensics_plugins.jpeg_grid.spec import DEFAULT_PARAMS
from forensics_plugins.jpeg_grid.figures import tiles_mask

pytestmark = pytest.mark.slow

SIZE = (480, 640)
N_SPLICED = 40
N_AUTHENTIC = 60
N_RECOMPRESSED = 16
N_NEVER = 8
N_LOW_FINAL = 20
N_MEGAPIXEL = 16
N_MISSING = 10


def _analyse(tmp_path, name, data, suffix=".jpg", **params):
    path = tmp_path / f"{name}{suffix}"
    path.write_bytes(data)
    return JpegGrid().analyze(load_evidence(path), {**DEFAULT_PARAMS, **params})


def _best_iou(result, truth):
    details = result.details
    best = 0.0
    for region in details["regions"]:
        if not region["meaningful"]:
            continue
        cell = details["map"]["cell_px"]
        tiles = tiles_mask(region["tiles_rle"], tuple(details["map"]["tiles_shape"]))
        mask = np.zeros(truth.shape, bool)
        grown = np.kron(tiles, np.ones((cell, cell), bool))
        mask[: grown.shape[0], : grown.shape[1]] = grown[: truth.shape[0], : truth.shape[1]]
        best = max(best, float((mask & truth).sum() / (mask | truth).sum()))
    return best


def _spliced_runs(tmp_path, n, final_range, seed, size=SIZE):
    runs = []
    for i in range(n):
        q2 = int(np.random.default_rng([seed, i]).integers(final_range[0], final_range[1] + 1))
        kind = synth.SPLICE_KINDS[i % 2]
        case = synth.make_spliced(seed + i, kind, size=size, final_quality=q2)
        result = _analyse(tmp_path, f"s{seed}-{i}", case.data)
        iou = _best_iou(result, case.mask)
        runs.append({**case.params, "iou": iou, "found": iou >= 0.5, "status": result.status})
    return runs


def _rate(runs):
    return sum(r["found"] for r in runs) / len(runs)


def _breakdown(runs, key, bins=None):
    groups = defaultdict(list)
    for r in runs:
        value = r[key]
        label = value if bins is None else next(f"{lo}-{hi}" for lo, hi in bins if lo <= value <= hi)
        groups[label].append(r["found"])
    return {k: f"{sum(v)}/{len(v)}" for k, v in sorted(groups.items())}


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("jpeg_grid_validation")


def test_shifted_grid_regions_found_at_final_quality_98_to_100(work):
    runs = _spliced_runs(work, N_SPLICED, (98, 100), seed=10_000)
    rate = _rate(runs)
    print(f"\nspliced, q2 98-100, {SIZE[1]}x{SIZE[0]}: found (IoU >= 0.5) {sum(r['found'] for r in runs)}/{len(runs)}"
          f" = {rate:.1%}; median IoU of found {np.median([r['iou'] for r in runs if r['found']]):.2f}")
    print("  by host quality q:", _breakdown(runs, "quality", [(75, 84), (85, 95)]))
    print("  by paste quality qp:", _breakdown(runs, "paste_quality", [(75, 84), (85, 92), (93, 95)]))
    print("  by final quality q2:", _breakdown(runs, "final_quality"))
    print("  by kind:", _breakdown(runs, "kind"))
    print("  missed:", [(r["kind"], r["quality"], r["paste_quality"], r["final_quality"], tuple(r["shift"]),
                         round(r["iou"], 2)) for r in runs if not r["found"]])
    assert all(r["status"] is Status.OK for r in runs)
    assert rate >= 0.9


def test_shifted_grid_regions_below_final_quality_98_are_measured(work):
    runs = _spliced_runs(work, N_LOW_FINAL, (90, 97), seed=20_000)
    rate = _rate(runs)
    print(f"\nspliced, q2 90-97 (below the target's range): found {sum(r['found'] for r in runs)}/{len(runs)} "
          f"= {rate:.1%}; by q2 {_breakdown(runs, 'final_quality')}")
    # Not a target: the main grid is found on every one, and a photo without a found region stays a non-detection.
    assert all(r["status"] is Status.OK for r in runs)


def test_at_one_megapixel(work):
    runs = _spliced_runs(work, N_MEGAPIXEL, (98, 100), seed=70_000, size=synth.DEFAULT_SIZE)
    flagged = 0
    for i in range(N_MEGAPIXEL):
        data, _ = synth.make_authentic(71_000 + i, size=synth.DEFAULT_SIZE)
        result = _analyse(work, f"m{i}", data)
        flagged += any(r["meaningful"] for r in result.details["regions"])
    rate = _rate(runs)
    print(f"\n{synth.DEFAULT_SIZE[1]}x{synth.DEFAULT_SIZE[0]}, q2 98-100: found {sum(r['found'] for r in runs)}/"
          f"{len(runs)} = {rate:.1%}; authentic single-compressed with a false region {flagged}/{N_MEGAPIXEL}")
    assert rate >= 0.9 and flagged <= 1


def test_regions_missing_the_main_grid_are_found(work):
    found = []
    for i in range(N_MISSING):
        case = synth.make_uncompressed_paste(60_000 + i, size=SIZE)
        result = _analyse(work, f"u{i}", case.data, suffix=case.suffix, missing_grid=True, missing_method="zero_q99")
        found.append(_best_iou(result, case.mask) >= 0.5)
    print(f"\nnever-compressed piece pasted, saved as PNG: region missing the main grid found (ZERO's test) {sum(found)}/"
          f"{N_MISSING}")
    assert sum(found) >= 0.9 * N_MISSING


def test_false_regions_on_single_compressed_photos(work):
    flagged, statuses, qualities = [], Counter(), []
    for i in range(N_AUTHENTIC):
        data, params = synth.make_authentic(30_000 + i, size=SIZE)
        result = _analyse(work, f"a{i}", data)
        statuses[result.status.value] += 1
        qualities.append(params["quality"])
        hits = [r for r in result.details["regions"] if r["meaningful"]]
        if hits:
            flagged.append((params["quality"], params["source"], hits[0]["grid"], hits[0]["log10_nfa"]))
        assert result.details["main_grid"]["origin"] == [0, 0]
    rate = len(flagged) / N_AUTHENTIC
    print(f"\nauthentic single-compressed (q {min(qualities)}-{max(qualities)}): false region in "
          f"{len(flagged)}/{N_AUTHENTIC} = {rate:.1%}; statuses {dict(statuses)}; flagged {flagged}")
    assert statuses["ok"] == N_AUTHENTIC
    assert rate <= 0.05


def test_false_regions_on_photos_saved_twice_on_the_same_grid(work):
    flagged = []
    for i in range(N_RECOMPRESSED):
        data, params = synth.make_recompressed(40_000 + i, size=SIZE)
        result = _analyse(work, f"r{i}", data)
        if any(r["meaningful"] for r in result.details["regions"]):
            flagged.append((params["quality"], params["final_quality"]))
    print(f"\nauthentic saved twice (q 75-95, then q2 90-100): false region in {len(flagged)}/{N_RECOMPRESSED} "
          f"{flagged}")
    assert len(flagged) <= 1


def test_never_compressed_photos_are_inconclusive(work):
    statuses = Counter()
    for i in range(N_NEVER):
        data, _ = synth.make_never_compressed(50_000 + i, size=SIZE)
        result = _analyse(work, f"n{i}", data, suffix=".png")
        statuses[result.status.value] += 1
        assert result.score is None and result.nfa is None
    print(f"\nnever compressed (PNG): {dict(statuses)}")
    assert statuses["inconclusive"] == N_NEVER

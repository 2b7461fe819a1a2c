"""Timing of the lens-distortion edge and line stages on a 4000 x 3000 photo.

Usage::

    python benchmarks/lens_stages_edges.py [PHOTO ...]

Each photo is converted to luma, resized to 4000 x 3000 (bilinear) and run
through :func:`subpixel_edges` and :func:`extract_lines` (minimum length 1/4 of
the image height) ``REPEATS`` times in this process; the first run (which pays
for touching fresh memory) and the median are printed per stage.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from PIL import Image

from forensics_plugins.lens_distortion.edges import subpixel_edges
from forensics_plugins.lens_distortion.lines import extract_lines

REPEATS = 5
SIZE = (4000, 3000)
DEFAULT_PHOTOS = (
    "/work/shared/data/exif/30-type_error.jpg",  # road, bridge, sky: few strong lines
    "/work/shared/data/exif/iphone_hdr_NO.jpg",  # flowers, foliage: dense texture
)


def load(path: str) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("L").resize(SIZE, Image.BILINEAR), dtype=np.float64) / 255.0


def bench(gray: np.ndarray) -> dict[str, list[float]]:
    times: dict[str, list[float]] = {"edges": [], "lines": [], "total": []}
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        edges = subpixel_edges(gray)
        t1 = time.perf_counter()
        lines = extract_lines(edges, gray.shape, gray.shape[0] / 4)
        t2 = time.perf_counter()
        times["edges"].append(t1 - t0)
        times["lines"].append(t2 - t1)
        times["total"].append(t2 - t0)
    print(f"  {len(edges)} edge points, {len(lines)} lines")
    return times


def main(paths: list[str]) -> None:
    for path in paths or DEFAULT_PHOTOS:
        print(path)
        for stage, t in bench(load(path)).items():
            print(f"  {stage:6s} first {t[0]:.3f} s   median of {REPEATS} {np.median(t):.3f} s")


if __name__ == "__main__":
    main(sys.argv[1:])

"""The lens distortion detector beside OpenCV's decode + Canny + LSD on the same photo (issue 12's speed target).

Usage: ``python benchmarks/lens_vs_lsd.py [--runs 5] [--photo PATH ...]``

Without ``--photo``, the synthetic 4000 x 3000 JPEG of ``benchmarks/lens.py``
is used (rendered into ``benchmarks/out/`` if absent). Each side is timed in
this process after one warm-up run (numba's compilation and OpenCV's first
call are not counted), ``--runs`` times, alternating the two so that a busy
machine slows both alike; the medians, their ratio (target <= 2) and the
number of segments each finds are printed. OpenCV (``opencv-python-headless``,
the ``bench`` extra) is needed; without it the script says so and exits 0.

* OpenCV: ``cv2.imdecode`` of the file's bytes as greyscale, ``cv2.Canny``
  (thresholds 50, 150) and ``cv2.createLineSegmentDetector().detect``; the
  segments counted are those at least as long as the detector's minimum.
* Ours: ``load_evidence`` (hashing and decoding), the luma, and
  ``analyse`` with default parameters; the lines counted are its lines.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from lens import photo  # noqa: E402


def _opencv(cv2, data: bytes, min_length: float) -> int:
    grey = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
    cv2.Canny(grey, 50, 150)
    segments = cv2.createLineSegmentDetector().detect(grey)[0]
    if segments is None:
        return 0
    s = segments.reshape(-1, 4)
    return int(np.sum(np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]) >= min_length))


def _ours(path: Path) -> tuple[int, tuple[int, int]]:
    from forensics_core.evidence import load_evidence
    from forensics_plugins.lens_distortion.detector import analyse
    from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS

    luma = load_evidence(path).luma
    return len(analyse(luma, DEFAULT_PARAMS).details["lines"]), luma.shape


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--photo", type=Path, nargs="*")
    args = parser.parse_args()
    try:
        import cv2
    except ImportError:
        print("OpenCV is not installed (pip install opencv-python-headless, or the 'bench' extra): nothing measured")
        return
    from forensics_plugins.lens_distortion.spec import DEFAULT_PARAMS

    for path in args.photo or [photo((4000, 3000))]:
        data = path.read_bytes()
        n_ours, shape = _ours(path)
        min_length = DEFAULT_PARAMS["min_length_fraction"] * min(shape)
        n_cv = _opencv(cv2, data, min_length)
        t_cv, t_ours = [], []
        for _ in range(args.runs):
            t = time.perf_counter()
            _opencv(cv2, data, min_length)
            t_cv.append(time.perf_counter() - t)
            t = time.perf_counter()
            _ours(path)
            t_ours.append(time.perf_counter() - t)
        cv_s, ours_s = statistics.median(t_cv), statistics.median(t_ours)
        print(f"{path.name} ({shape[1]}x{shape[0]}), median of {args.runs}: OpenCV decode+Canny+LSD {cv_s:.2f} s "
              f"({n_cv} segments >= {min_length:.0f} px); lens_distortion with intake {ours_s:.2f} s ({n_ours} "
              f"lines); ratio {ours_s / cv_s:.2f} (target <= 2)")


if __name__ == "__main__":
    main()

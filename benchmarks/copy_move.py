"""Time and peak memory of the copy_move detector on a 4000 x 3000 photo.

Usage: ``python benchmarks/copy_move.py [--runs 5] [--size 4000x3000]``

A synthetic scene of :mod:`forensics_plugins.copy_move.synth` (objects, a row
of windows of one design, sensor noise) is rendered once into
``benchmarks/out/`` as JPEG 90, with a rotated copy of one of its squares.
Each run analyses it in a fresh process. Printed: median and range of each
stage (decode = intake with hashing; the detector's stages as it records
them, on its work image of at most 2 MP; the report's overlay) and of the
peak resident memory (``VmHWM``; ``baseline`` = interpreter and libraries).
"""

from __future__ import annotations

from pathlib import Path

from harness import OUT, photo_benchmark


_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.copy_move.detector import analyse
from forensics_plugins.copy_move.spec import DEFAULT_PARAMS
from forensics_plugins.copy_move.figures import overlay_png
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
luma = ev.luma
t1 = time.perf_counter()
result = analyse(luma, DEFAULT_PARAMS)
t2 = time.perf_counter()
overlay_png(luma, result.details)
t3 = time.perf_counter()
stages = {"decode+hash+luma": t1 - t0, **result.details["elapsed_s"], "detector total": t2 - t1,
          "report overlay": t3 - t2}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "score": result.score}))
"""


def photo(size: tuple[int, int]) -> Path:
    """The benchmark photo (size is width, height), rendered once."""
    path = OUT / f"copy_move_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        import numpy as np

        from forensics_plugins.copy_move.synth import clone, encode, scene

        rng = np.random.default_rng(4)
        cloned, _ = clone(scene(rng, (size[1], size[0])), rng, "rotation")
        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(encode(cloned, 90))
    return path


if __name__ == "__main__":
    photo_benchmark(__doc__, "copy_move", _CHILD, photo)

"""Time and peak memory of the noise detector on a 4000 x 3000 photo with a piece of noisier grain pasted in.

Usage: ``python benchmarks/noise.py [--runs 5] [--size 4000x3000]``

A synthetic scene of :mod:`forensics_plugins.noise.synth` with grain of
standard deviation 3 is given a piece of another scene with 2.5 to 3.5 times
that grain and saved at JPEG 90, once, into ``benchmarks/out/``. Each run
analyses it in a fresh process. Printed: median and range of each stage
(decode = intake with hashing and the luma; the detector; the report's z-score
map, drawn from the z-scores the finding carries) and of the peak resident
memory (``VmHWM``; ``baseline`` = interpreter and libraries).
"""

from __future__ import annotations

from pathlib import Path

from harness import OUT, photo_benchmark


_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.noise.detector import NoiseLevel, decode_z
from forensics_plugins.noise.spec import DEFAULT_PARAMS
from forensics_plugins.noise.figures import z_map_png
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
luma = ev.luma
t1 = time.perf_counter()
result = NoiseLevel().analyze(ev, DEFAULT_PARAMS)
t2 = time.perf_counter()
z_map_png(luma, *decode_z(result.details["z_map"]), result.details)
t3 = time.perf_counter()
stages = {"decode+hash+luma": t1 - t0, "detector": t2 - t1, "report z map": t3 - t2}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "score": result.score}))
"""


def photo(size: tuple[int, int]) -> Path:
    """The benchmark photo (size is width, height), rendered once."""
    path = OUT / f"noise_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        import numpy as np

        from forensics_plugins.noise.synth import encode, paste, scene

        rng = np.random.default_rng(4)
        spliced, _ = paste(scene(rng, size, 3.0), rng, "noisier", 3.0)
        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(encode(spliced, 90))
    return path


if __name__ == "__main__":
    photo_benchmark(__doc__, "noise", _CHILD, photo)

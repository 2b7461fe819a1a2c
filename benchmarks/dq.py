"""Time and peak memory of the dq detector on a 4000 x 3000 photo saved twice with a pasted piece.

Usage: ``python benchmarks/dq.py [--runs 5] [--size 4000x3000]``

A synthetic scene of :mod:`forensics_plugins.dq.synth` is saved at JPEG 75,
decoded, given a piece of another scene and saved at JPEG 92, once, into
``benchmarks/out/``. Each run analyses it in a fresh process. Printed: median
and range of each stage (decode = intake with hashing; the detector, which
reads the coefficients itself; the report's vote map, drawn from the votes
the finding carries) and of the peak resident memory (``VmHWM``; ``baseline`` =
interpreter and libraries).
"""

from __future__ import annotations

from pathlib import Path

from harness import OUT, photo_benchmark


_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.dq.detector import DoubleQuantisation
from forensics_plugins.dq.spec import DEFAULT_PARAMS
from forensics_plugins.dq.figures import votes_png
from forensics_plugins.dq.votes import decode_votes
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
luma = ev.luma
t1 = time.perf_counter()
result = DoubleQuantisation().analyze(ev, DEFAULT_PARAMS)
t2 = time.perf_counter()
votes_png(luma, *decode_votes(result.details["block_votes"]), result.details)
t3 = time.perf_counter()
stages = {"decode+hash+luma": t1 - t0, "detector": t2 - t1, "report vote map": t3 - t2}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "score": result.score}))
"""


def photo(size: tuple[int, int]) -> Path:
    """The benchmark photo (size is width, height), rendered once."""
    path = OUT / f"dq_{size[0]}x{size[1]}.jpg"
    if not path.exists():
        import numpy as np

        from forensics_plugins.dq.synth import decode, encode, paste, scene

        rng = np.random.default_rng(4)
        spliced, _ = paste(decode(encode(scene(rng, size), 75)), rng, "raw")
        OUT.mkdir(parents=True, exist_ok=True)
        path.write_bytes(encode(spliced, 92))
    return path


if __name__ == "__main__":
    photo_benchmark(__doc__, "dq", _CHILD, photo)

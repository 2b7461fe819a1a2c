"""A tiny detector and its synthetic photos, loaded through real entry points by the validation tests.

Spliced photos carry a bright square; the detector's p-value falls with the
brightest 8x8 block, and it localises that block's surroundings.
"""

import io

import numpy as np
from PIL import Image

from forensics_core import Detector, DetectorResult, DetectorSpec, Status, SyntheticCase, hookimpl

SIZE = 64


def _png(pixels):
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()


class _Registers:
    """A fixture plugin that is also the one detector it registers."""

    @hookimpl
    def forensics_register_detectors(self, register):
        register(self)


class Squares(_Registers, Detector):
    spec = DetectorSpec("square", "2.0", "Finds a bright square.")

    def analyze(self, evidence, params):
        luma = evidence.luma
        if luma.std() == 0:
            return DetectorResult(Status.INCONCLUSIVE, "Flat photo.")
        blocks = luma.reshape(SIZE // 8, 8, SIZE // 8, 8).mean(axis=(1, 3))
        p = float(np.exp(-20 * max(0.0, blocks.max() - 0.5)))
        ys, xs = np.nonzero(luma > 0.5)
        box = [int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())] if len(xs) else None
        return DetectorResult(Status.OK, "Brightest block.", score=1 - p, p_value=p, details={"box": box})

    def localize(self, finding, shape):
        mask = np.zeros(shape, dtype=bool)
        if finding.p_value is not None and finding.p_value < 0.01 and finding.details["box"]:
            x0, y0, x1, y1 = finding.details["box"]
            mask[y0 : y1 + 1, x0 : x1 + 1] = True
        return mask

    def synthetic_cases(self, seed, count):
        for i in range(count):
            rng = np.random.default_rng([seed, i])
            base = rng.uniform(0, 110, (SIZE, SIZE)).astype(np.uint8)
            yield SyntheticCase(f"au-{i}", _png(base), ".png", False, None, {"kind": "none", "size": "small"})
            spliced = base.copy()
            mask = np.zeros((SIZE, SIZE), dtype=bool)
            y, x = rng.integers(0, SIZE - 16, 2)
            mask[y : y + 16, x : x + 16] = True
            level = 140 if i % 4 == 0 else 250
            spliced[mask] = level
            yield SyntheticCase(f"sp-{i}", _png(spliced), ".png", True, mask,
                                {"kind": "faint" if level == 140 else "bright", "size": "small"})


class Observer(_Registers, Detector):
    spec = DetectorSpec("observer", "1.0", "Ventures no test.")

    def analyze(self, evidence, params):
        return DetectorResult(Status.INCONCLUSIVE, "Never decides.")


class BrokenGenerator(_Registers, Detector):
    spec = DetectorSpec("broken_generator", "1.0", "Generates no valid case.")

    def analyze(self, evidence, params):
        return DetectorResult(Status.INCONCLUSIVE, "Never decides.")

    def synthetic_cases(self, seed, count):
        yield "not a case"


squares, observer, broken_generator = Squares(), Observer(), BrokenGenerator()

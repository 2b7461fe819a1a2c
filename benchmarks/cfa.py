"""Time and peak memory of the CFA detector on a 4000 x 3000 photo.

Usage: ``python benchmarks/cfa.py [--runs 5] [--size 4000x3000]``

A synthetic raw-like photo (Hamilton-Adams demosaicing, stored as JPEG of
quality 95, as a camera would) is rendered once into ``benchmarks/out/`` in
horizontal bands of the same sensor phase, so the rendering never holds a
12 MP float canvas; a spliced version replaces a quarter of it (the central
2000 x 1500 pixels) by another scene shot with the mosaic shifted by one
column, which exercises the region scan. Each run then analyses a photo in a
fresh process, so import costs and memory of one run do not leak into the
next. Printed: the median
and range over the runs of each stage (decode = intake with hashing; the
detector's own stages as it records them; the report's map figure) and of the
peak resident memory of the analysing process (``VmHWM``, which includes the
interpreter and the imported libraries, measured separately as ``baseline``).
Target (issue 5): detector <= 3 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from harness import OUT, fresh_runs, parse_size, print_stages

BAND_ROWS = 750

_CHILD = r"""
import forensics_core
from forensics_core.evidence import load_evidence
from forensics_plugins.cfa.detector import analyse
from forensics_plugins.cfa.spec import DEFAULT_PARAMS
from forensics_plugins.cfa.figures import map_png
base = hwm_mb()
t0 = time.perf_counter()
ev = load_evidence(sys.argv[1])
pixels = ev.pixels
t1 = time.perf_counter()
result = analyse(pixels, DEFAULT_PARAMS)
t2 = time.perf_counter()
map_png(pixels, result.details)
t3 = time.perf_counter()
stages = {"decode+hash": t1 - t0, **result.details["elapsed_s"], "detector total": t2 - t1, "report map": t3 - t2}
print(json.dumps({"stages": stages, "peak_mb": hwm_mb(), "baseline_mb": base, "status": result.status.value,
                  "regions": len(result.details.get("regions", []))}))
"""


def photos(size: tuple[int, int]) -> dict[str, Path]:
    """The authentic and the spliced benchmark photos (size is width, height), rendered once."""
    paths = {kind: OUT / f"cfa_{kind}_{size[0]}x{size[1]}.jpg" for kind in ("authentic", "spliced")}
    if not all(p.exists() for p in paths.values()):
        import numpy as np
        from PIL import Image

        from forensics_plugins.cfa.bayer import shifted
        from forensics_plugins.cfa.synth import capture, random_camera, render_scene

        width, height = size
        camera = random_camera(np.random.default_rng(5), pattern="RGGB", algorithm="hamilton_adams")
        bands = []
        for i, top in enumerate(range(0, height, BAND_ROWS)):
            rows = min(BAND_ROWS, height - top)
            scene = render_scene(100 + i, (rows, width))
            bands.append(np.round(capture(scene, camera, np.random.default_rng(i)) * 255.0).astype(np.uint8))
        host = np.vstack(bands)
        OUT.mkdir(parents=True, exist_ok=True)
        Image.fromarray(host).save(paths["authentic"], format="JPEG", quality=95)
        h, w = height // 2, width // 2
        y0, x0 = (height - h) // 2 // 2 * 2, (width - w) // 2 // 2 * 2
        donor_camera = random_camera(np.random.default_rng(6), pattern=shifted(camera.pattern, 0, 1),
                                     algorithm=camera.algorithm)
        donor = capture(render_scene(77, (h, w)), donor_camera, np.random.default_rng(99))
        host[y0:y0 + h, x0:x0 + w] = np.round(donor * 255.0).astype(np.uint8)
        Image.fromarray(host).save(paths["spliced"], format="JPEG", quality=95)
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", default="4000x3000")
    args = parser.parse_args()
    size = parse_size(args.size)
    for kind, target in photos(size).items():
        runs = fresh_runs(_CHILD, target, args.runs)
        print(f"cfa on the {kind} {target.name} ({size[0]}x{size[1]}), {args.runs} runs, status "
              f"{runs[0]['status']}, {runs[0]['regions']} regions")
        print_stages(runs)
        print()


if __name__ == "__main__":
    main()

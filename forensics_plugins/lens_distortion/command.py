"""``forensics synth``: the lens plugin's command, writing synthetic photos with known lens distortion.

The command's options are declared here, apart from the generator
(:mod:`.splice` and :mod:`.truth`), which is imported only when the command
runs: every ``forensics`` invocation registers the command, and ``--help``
should not pay for the renderer.
"""

from __future__ import annotations

import json
from pathlib import Path

import click

from .spec import KINDS


def _parse_size(ctx: click.Context, param: click.Parameter, value: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in value.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"{value!r} is not of the form WIDTHxHEIGHT") from None
    if w < 64 or h < 64:
        raise click.BadParameter("both sides must be at least 64 pixels")
    return w, h


@click.command("synth")
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--kind", type=click.Choice([*KINDS, "all"]), default="all", show_default=True,
              help="What to generate.")
@click.option("--count", type=click.IntRange(min=1), default=1, show_default=True, help="Images per kind.")
@click.option("--seed", type=int, default=0, show_default=True, help="Image i of every kind uses seed SEED + i.")
@click.option("--size", default="1600x1200", show_default=True, callback=_parse_size,
              help="WIDTHxHEIGHT of the camera frame.")
@click.option("--k1", type=float, default=0.08, show_default=True, help="Host lens k1 (normalised, >0 barrel).")
@click.option("--jpeg-quality", type=click.IntRange(0, 100), default=90, show_default=True,
              help="0 writes lossless PNG.")
@click.option("--resize", type=click.FloatRange(min=0.05, max=4.0), default=1.0, show_default=True,
              help="Final rescale factor.")
@click.option("--noise", type=click.FloatRange(min=0.0), default=0.01, show_default=True,
              help="Noise sigma, fraction of full scale.")
@click.option("--blur", type=click.FloatRange(min=0.0), default=0.7, show_default=True,
              help="Optics blur sigma, pixels.")
def synth_command(
    *, out_dir: Path, kind: str, count: int, seed: int, size: tuple[int, int], k1: float,
    jpeg_quality: int, resize: float, noise: float, blur: float,
) -> None:
    """Write synthetic authentic and spliced photos with known lens distortion to OUT_DIR.

    Each image comes with STEM.json (its truth) and, if spliced, STEM_mask.png;
    OUT_DIR/truth.json lists every file. Image i of every kind shares the host
    scene of seed SEED + i, so splices pair with their authentic original.
    Identical arguments give identical files.
    """
    from .splice import make_splice
    from .truth import write

    kinds = KINDS if kind == "all" else (kind,)
    post = {
        "noise": noise,
        "blur": blur,
        "jpeg_quality": jpeg_quality or None,
        "resize": None if resize == 1.0 else resize,
    }
    entries = []
    for name in kinds:
        for i in range(count):
            img = make_splice(name, seed + i, size, k1, **post)
            paths = write(img, out_dir, f"{name}_{i:03d}")
            entries.append(
                {
                    "file": paths[0].name,
                    "kind": name,
                    "seed": seed + i,
                    "k1": img.k1,
                    "pasted_k1": img.pasted_k1,
                    "mask": paths[1].name if img.mask is not None else None,
                    "truth": paths[-1].name,
                }
            )
            click.echo(f"wrote {paths[0]}")
    arguments = {"kind": kind, "count": count, "seed": seed, "size": list(size), "k1": k1, **post}
    listing = {"generator": f"{__name__}.synth_command", "arguments": arguments, "images": entries}
    (out_dir / "truth.json").write_text(json.dumps(listing, indent=1, sort_keys=True) + "\n")

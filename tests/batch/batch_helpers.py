"""Helpers of the batch tests: the fixture plugins' site folder, photos, running the command."""

import hashlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

SITE = Path(__file__).resolve().parent / "site"
DATA = Path(__file__).resolve().parents[1] / "data"
FIXTURE_PLUGINS = "steady,killer,core.fusion"
FORENSICS = [sys.executable, "-m", "forensics_core"]


def fixture_env(**extra: str) -> dict[str, str]:
    """The environment of a run that loads only the fixture plugins (and the core's fusion)."""
    path = os.pathsep.join(p for p in (str(SITE), os.environ.get("PYTHONPATH")) if p)
    return {**os.environ, "PYTHONPATH": path, "FORENSICS_PLUGINS": FIXTURE_PLUGINS, **extra}


def run(*args, env=None, timeout=300):
    return subprocess.run([*FORENSICS, *map(str, args)], capture_output=True, text=True, env=env or fixture_env(),
                          timeout=timeout)


def popen(*args, env=None):
    return subprocess.Popen([*FORENSICS, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env or fixture_env())


def tiny_jpeg(seed: int, size=(96, 64)) -> bytes:
    """A small textured JPEG, different for each seed."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:size[1], 0:size[0]]
    base = 128 + 60 * np.sin(xx / (3 + seed % 5)) * np.cos(yy / 4)
    rgb = np.clip(base[..., None] + rng.normal(0, 8, (size[1], size[0], 3)), 0, 255).astype(np.uint8)
    buffer = io.BytesIO()
    Image.fromarray(rgb).save(buffer, "JPEG", quality=90)
    return buffer.getvalue()


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def summary(out: Path) -> dict:
    doc = json.loads((out / "summary.json").read_text())
    doc["by_photo"] = {Path(r["photo"]).name: r for r in doc["photos"]}
    return doc


def temp_files(out: Path) -> list[Path]:
    return [p for p in out.rglob("*.tmp")]

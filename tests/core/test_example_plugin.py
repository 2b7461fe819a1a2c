"""The example third-party plugin, installed by pip as its own distribution."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "forensics-plugin-example"


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """A folder the example is pip-installed into, put on the path of the runs below."""
    target = tmp_path_factory.mktemp("site")
    source = tmp_path_factory.mktemp("src") / EXAMPLE.name
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--target", str(target), str(source)],
        check=True, capture_output=True, timeout=300,
    )
    return target


def forensics(site: Path, *args):
    env = {**os.environ, "PYTHONPATH": str(site)}
    return subprocess.run([sys.executable, "-m", "forensics_core", *map(str, args)],
                          capture_output=True, text=True, env=env, timeout=300)


def test_example_plugin_is_discovered_runs_and_reaches_findings_and_the_report(site, photo, tmp_path, validate):
    listed = json.loads(forensics(site, "plugins", "--json").stdout)
    plugins = {p["name"]: p for p in listed["plugins"]}
    assert plugins["noise_level"]["status"] == "loaded", plugins["noise_level"]["error"]
    assert plugins["noise_level"]["distribution"] == "forensics-plugin-example"
    assert plugins["noise_level"]["hooks"] == ["forensics_register_detectors"]
    assert plugins["noise_level"]["detectors"] == ["noise_level"]

    out = forensics(site, "analyze", photo, "--out", tmp_path, "--detectors", "noise_level",
                    "--param", "noise_level.block=64", "--format", "json,html")
    assert out.returncode == 0, out.stderr
    doc = validate(json.loads((tmp_path / "left01" / "findings.json").read_text()))
    finding = doc["detectors"][0]
    assert finding["name"] == "noise_level" and finding["status"] == "ok"
    assert finding["plugin"] == "noise_level" and finding["parameters"] == {"block": 64}
    assert 0.0 < finding["details"]["sigma"] < 20.0
    html = (tmp_path / "left01" / "report.html").read_text()
    assert "Noise level" in html and "measured in 64-pixel blocks" in html
    assert finding["headline"] in html

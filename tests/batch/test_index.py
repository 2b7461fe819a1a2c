"""DIR/index.html: one self-contained page for the batch, a row per photo, by likelihood ratio."""

import base64
import hashlib
import io
import json
import re
import shutil
from dataclasses import replace
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pytest
from PIL import Image

from batch_helpers import fixture_env, run, sha256, tiny_jpeg
from forensics_core.batch.index import BatchPhoto, found_by, thumbnail, write_index
from forensics_core.batch.inputs import sha256_of
from forensics_core.batch.plan import make_plan
from forensics_core.batch.resume import Expected
from forensics_core.batch.summary import Row
from forensics_core.findings import Findings, Role, VerdictLabel
from forensics_core.report import wording

EVIL = "<script>alert(1)#?"
# Mean luma 0.78, 0.5 and 0.23: with CALIBRATION, the steady detector's LR is about 10^3, 1 and 10^-3.
LEVELS = {"bright.jpg": 200, f"{EVIL}.jpg": 128, "dark.jpg": 60}
CALIBRATION = {
    "format": "forensics-calibration/1", "data": {"n_hp": 10, "n_hd": 10}, "tool": {"forensics": "test"},
    "calibrators": {"steady": {"detector": "steady", "intercept": -5.5, "slope": 11.0, "lower": -5.0, "upper": 5.0,
                               "n_hp": 10, "n_hd": 10, "feature": "score"}},
    "fusion": {"intercept": 0.0, "weights": {"steady": 1.0}, "lower": -5.0, "upper": 5.0},
}
DATA_URL = re.compile(r"data:image/jpeg;base64,[A-Za-z0-9+/=]*")


class Page(HTMLParser):
    """What a test reads of the index: the CSP, the inline script and style, and each row's data, text and links."""

    def __init__(self, html: str):
        super().__init__(convert_charrefs=True)
        self.csp = ""
        self.raw: dict[str, list[str]] = {"script": [], "style": []}
        self.rows: list[dict] = []
        self._row: dict | None = None
        self._raw: tuple[str, list[str]] | None = None
        self.feed(html)
        self.close()

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "meta" and a.get("http-equiv") == "Content-Security-Policy":
            self.csp = a["content"]
        elif tag in self.raw:
            self._raw = (tag, [])
        elif tag == "tr" and "data-order" in a:
            self._row = {"attrs": a, "text": [], "links": [], "images": []}
            self.rows.append(self._row)
        elif self._row is not None and tag == "a":
            self._row["links"].append(a["href"])
        elif self._row is not None and tag == "img":
            self._row["images"].append(a["src"])

    def handle_endtag(self, tag):
        if self._raw is not None and tag == self._raw[0]:
            self.raw[tag].append("".join(self._raw[1]))
            self._raw = None
        elif tag == "tr":
            self._row = None

    def handle_data(self, data):
        if self._raw is not None:
            self._raw[1].append(data)
        elif self._row is not None:
            self._row["text"].append(data)

    def by_name(self) -> dict[str, dict]:
        return {row["attrs"]["data-name"]: row for row in self.rows}


def text(row: dict) -> str:
    return " ".join("".join(row["text"]).split())


def flat_jpeg(path: Path, level: int) -> Path:
    rng = np.random.default_rng(level)
    Image.fromarray(np.clip(level + rng.normal(0, 8, (64, 96, 3)), 0, 255).astype(np.uint8)).save(path, quality=90)
    return path


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """Three photos and a file that is no image, analysed with HTML reports and a calibration for `steady`."""
    root = tmp_path_factory.mktemp("index")
    photos = root / "in"
    photos.mkdir()
    for name, level in LEVELS.items():
        flat_jpeg(photos / name, level)
    (photos / "notes.txt").write_text("not a photo")
    (root / "calibration.json").write_text(json.dumps(CALIBRATION))
    before = {p.name: (sha256(p), p.stat().st_mtime_ns) for p in photos.iterdir()}
    env = fixture_env(FORENSICS_HOME=str(root / "home"))
    out = root / "out"
    args = ("batch", photos, "--out", out, "--format", "json,html", "--calibration", root / "calibration.json")
    res = run(*args, env=env)
    assert res.returncode == 1, res.stderr  # notes.txt failed
    assert f"index: {out / 'index.html'}" in res.stdout
    return {"root": root, "photos": photos, "out": out, "args": args, "env": env, "before": before,
            "html": (out / "index.html").read_text(encoding="utf-8")}


def test_every_photo_has_a_row_with_its_statement_lr_and_a_link_to_its_report(batch):
    out = batch["out"]
    page = Page(batch["html"])
    rows = page.by_name()
    assert set(rows) == {name.lower() for name in LEVELS} | {"notes.txt"}
    for name in LEVELS:
        row = rows[name.lower()]
        folder = out / Path(name).stem
        verdict = Findings.from_dict(json.loads((folder / "findings.json").read_text())).verdict
        said = wording.statement(verdict)
        shown = text(row)
        assert said.verbal in shown and said.sentence in shown and said.lr in shown
        assert wording.screening(verdict) in shown
        assert float(row["attrs"]["data-lr"]) == pytest.approx(verdict.likelihood_ratio.log10_lr, abs=1e-3)
        [href] = row["links"]
        assert "#" not in href and "?" not in href and "<" not in href  # the folder's name, percent-encoded
        assert href.endswith("/report.html") and (out / unquote(href)).resolve() == (folder / "report.html").resolve()
    assert "not an image" in text(rows["notes.txt"]) and not rows["notes.txt"]["links"]
    assert [r["attrs"]["data-name"] for r in page.rows] == ["bright.jpg", f"{EVIL}.jpg", "dark.jpg", "notes.txt"]
    assert "strong support for Hp" in text(rows["bright.jpg"]) and "support for Hd" in text(rows["dark.jpg"])


def test_the_detectors_that_found_something_are_named_with_their_finding(batch):
    rows = Page(batch["html"]).by_name()
    assert rows["bright.jpg"]["attrs"]["data-found"] == "1"
    assert re.search(r"steady: Mean luma 0\.7\d+\.", text(rows["bright.jpg"]))
    for quiet in (f"{EVIL}.jpg", "dark.jpg"):
        assert rows[quiet.lower()]["attrs"]["data-found"] == "0" and "steady:" not in text(rows[quiet.lower()])


def test_the_page_is_self_contained_and_its_policy_names_the_inline_script_and_style(batch):
    html = batch["html"]
    page = Page(html)
    [script], [style] = page.raw["script"], page.raw["style"]
    digest = {name: base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()
              for name, body in (("script", script), ("style", style))}
    assert f"script-src 'sha256-{digest['script']}'" in page.csp
    assert f"style-src 'sha256-{digest['style']}'" in page.csp
    assert "default-src 'none'" in page.csp and "img-src data:" in page.csp and "base-uri 'none'" in page.csp
    assert "addEventListener" in script and html.count("<script") == 1 and html.count("<style") == 1
    without_images = DATA_URL.sub("", html)
    for external in ("http:", "https:", "//", "url("):
        assert external not in without_images
    assert ' src="' not in without_images.replace('<img src=""', "")  # every image is inline
    assert re.search(r'name="viewport" content="width=device-width', html) and "@media (max-width" in style


def test_a_file_name_from_the_evidence_is_escaped(batch):
    html = batch["html"]
    assert EVIL not in html
    assert "&lt;script&gt;alert(1)#?.jpg" in html
    assert text(Page(html).by_name()[f"{EVIL}.jpg"]).startswith(f"{EVIL}.jpg")


def test_thumbnails_are_small_jpegs_of_the_photos_which_are_left_as_they_were(batch):
    rows = Page(batch["html"]).by_name()
    for name in LEVELS:
        [src] = rows[name.lower()]["images"]
        assert src.startswith("data:image/jpeg;base64,")
        with Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1]))) as img:
            assert img.format == "JPEG" and max(img.size) <= 160
    assert not rows["notes.txt"]["images"]
    after = {p.name: (sha256(p), p.stat().st_mtime_ns) for p in batch["photos"].iterdir()}
    assert after == batch["before"]


def test_a_photo_whose_bytes_changed_gets_no_thumbnail(tmp_path):
    photo = flat_jpeg(tmp_path / "p.jpg", 90)
    taken = sha256(photo)
    src, size = thumbnail(photo, taken)
    assert src.startswith("data:image/jpeg;base64,") and size == (96, 64)
    photo.write_bytes(tiny_jpeg(1))
    assert thumbnail(photo, taken) is None
    assert thumbnail(tmp_path / "gone.jpg", taken) is None


def test_a_rerun_rewrites_the_index_with_the_photos_of_earlier_runs_still_in_dir(batch, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(batch["out"], out, symlinks=True)
    (out / "index.html").write_text("stale")
    new = tmp_path / "new"
    new.mkdir()
    (new / "later.jpg").write_bytes(tiny_jpeg(5))
    res = run("batch", new, "--out", out, "--format", "json", env=batch["env"])
    assert res.returncode == 0, res.stderr
    page = Page((out / "index.html").read_text(encoding="utf-8"))
    rows = page.by_name()
    assert set(rows) == {"later.jpg", "bright.jpg", f"{EVIL}.jpg", "dark.jpg"}  # notes.txt left no findings
    later = rows["later.jpg"]
    assert "no support for either proposition" in text(later) and float(later["attrs"]["data-lr"]) == 0.0
    assert later["links"] == ["later/findings.json"] and (out / "later" / "findings.json").is_file()
    assert [r["attrs"]["data-name"] for r in page.rows] == ["bright.jpg", f"{EVIL}.jpg", "later.jpg", "dark.jpg"]
    for name in ("bright.jpg", "dark.jpg"):
        assert "from an earlier run" in text(rows[name])
        assert all((out / unquote(href)).is_file() for href in rows[name]["links"])

    again = run(*batch["args"], env=batch["env"])
    assert again.returncode == 1
    rows = Page((batch["out"] / "index.html").read_text(encoding="utf-8")).by_name()
    assert set(rows) == {name.lower() for name in LEVELS} | {"notes.txt"}
    assert "from an earlier run" not in text(rows["bright.jpg"])


def test_an_interrupted_batch_lists_finished_pending_and_failed_photos(batch, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    shutil.copytree(batch["out"] / "bright", out / "bright")
    bright, dark = batch["photos"] / "bright.jpg", batch["photos"] / "dark.jpg"
    shutil.copytree(batch["out"] / "dark", out / "dark")
    doc = json.loads((out / "dark" / "findings.json").read_text())
    doc["verdict"]["likelihood_ratio"] = None  # as when no calibrator covers the detectors
    (out / "dark" / "findings.json").write_text(json.dumps(doc))
    pending = tmp_path / "p.jpg"
    bidi = tmp_path / "photo\u202egpj.exe"
    photos = [
        BatchPhoto(dark, Row(str(dark), sha256(dark), "analysed", output=str(out / "dark")), out / "dark"),
        BatchPhoto(bright, Row(str(bright), sha256(bright), "resumed", output=str(out / "bright")), out / "bright"),
        BatchPhoto(pending, Row(str(pending), "cd" * 32, "pending"), out / "p"),
        BatchPhoto(bidi, Row(str(bidi), None, "failed", error="corrupt\x1b[31m"), None),
    ]
    html = write_index(out, photos).read_text(encoding="utf-8")
    page = Page(html)
    assert [r["attrs"]["data-name"] for r in page.rows] == ["bright.jpg", "dark.jpg", "p.jpg", "photo\\u202egpj.exe"]
    rows = page.by_name()
    assert "not evaluated" in text(rows["dark.jpg"]) and rows["dark.jpg"]["attrs"]["data-lr"] == ""
    assert rows["bright.jpg"]["links"] == ["bright/report.html"] and rows["bright.jpg"]["images"]
    assert "stopped before this photo was done" in text(rows["p.jpg"])
    assert "corrupt\\x1b[31m" in text(rows["photo\\u202egpj.exe"])
    assert "\u202e" not in html and "\x1b" not in html
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")]


def test_found_by_names_rejecting_tests_and_detectors_whose_lr_supports_hp(batch):
    findings = Findings.from_dict(json.loads((batch["out"] / "dark" / "findings.json").read_text()))
    steady = findings.detectors[0]
    verdict = findings.verdict
    assert [c.role for c in verdict.contributions] == [Role.DROVE] and verdict.label is VerdictLabel.CONSISTENT
    assert found_by(findings) == []  # it decided that nothing was rejected
    rejected = replace(findings, verdict=replace(verdict, label=VerdictLabel.INCONSISTENT))
    assert [f.detector for f in found_by(rejected)] == ["steady"]
    for log10_lr, listed in ((0.31, True), (0.29, False), (-2.0, False)):
        one = replace(findings, detectors=[replace(steady, log10_lr=log10_lr)])
        assert bool(found_by(one)) is listed


def test_a_headline_is_one_short_sentence():
    from forensics_core.findings import DetectorFinding, Status
    from forensics_core.report.wording import row_sentence

    finding = DetectorFinding(name="d", version="1", plugin="p", status=Status.OK,
                              summary="Regions at x 10-20 differ (p = 0.001). More text\nhere.", score=None,
                              p_value=None, nfa=None, details={}, parameters={}, elapsed_s=0.1)
    assert row_sentence(finding) == "Regions at x 10-20 differ (p = 0.001)."
    assert row_sentence(replace(finding, headline="  A grid\nat x 10. ")) == "A grid at x 10."
    long = replace(finding, headline="word " * 40, summary="e.g. " + "many " * 40 + "words.")
    assert row_sentence(long).endswith(" …") and len(row_sentence(long).split()) == 25


def test_no_photo_takes_the_index_page_for_its_folder(tmp_path):
    path = tmp_path / "in" / "index.html.jpg"
    path.parent.mkdir()
    path.write_bytes(b"one")
    plan = make_plan([sha256_of(path)], tmp_path / "out", Expected((), {"detectors": ["steady"]}, None))
    assert plan.entry_of[path].name != "index.html"

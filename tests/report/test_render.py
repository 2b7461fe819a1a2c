"""The report as a reader and an attacker meet it: real HTML, real PDFs read back with poppler."""

import base64
import csv
import hashlib
import io
import json
import re
import subprocess
import zipfile
from html.parser import HTMLParser
from pathlib import Path

import pytest
from PIL import Image, ImageFile

from forensics_core.evidence import load_evidence
from forensics_core.findings import Findings
from forensics_core.report import fetcher as fetcher_module
from forensics_core.report.render import ReportOptions, SignatureInfo, render_html, render_pdf
from forensics_core.validation import shipped_record
from report_helpers import HOSTILE_EXIF, hostile_jpeg, make_bundle, pdf_pages_text, report_host

SIGNATURE = SignatureInfo("A. Examiner", "Lab", "CN=A. Examiner", "AA:BB", True, "2024-01-01T00:00:00Z",
                          "2026-01-01T00:00:00Z")


class Tags(HTMLParser):
    """Every start tag with its attributes."""

    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def tags(html: str) -> list[tuple[str, dict]]:
    parser = Tags()
    parser.feed(html)
    return parser.tags


def render(evidence_path: Path, *plugins: str, **options):
    from forensics_core.analysis import Options, analyze_evidence

    host = report_host(*plugins)
    evidence = load_evidence(evidence_path)
    findings = analyze_evidence(evidence, host, Options(case_id="C-1", isolation="inline"))
    return render_html(findings, evidence, SIGNATURE, ReportOptions(exhibit_id="E-1", **options), host=host)


def test_page_one_is_the_statement_the_screen_where_and_a_row_per_detector(bundle):
    pages = pdf_pages_text(bundle / "report.pdf")
    assert len(pages) >= 5
    first = " ".join(pages[0].split())
    assert "EVALUATIVE STATEMENT" in first.upper() and "The findings are" in first
    assert "Likelihood ratio" in first and "Hp:" in first and "Hd:" in first
    assert "Screening:" in first and "Where." in first
    assert "A.1 no_section" in first and "A.2 sectioned" in first  # the detector table, numbered as Appendix A
    whole = " ".join(" ".join(pages).split())
    assert "onsistent with an original" not in whole  # a screen that rejects nothing is not support for an original
    assert "Verbal scale" in " ".join(" ".join(p.split()) for p in pages[:3])  # in section 1
    for number, page in enumerate(pages, 1):
        text = " ".join(page.split())
        assert "Case 2024/117" in text and "Exhibit EX-7" in text
        assert f"page {number} of {len(pages)}" in text
    for heading in ("1. The statement explained", "2. Evidence", "3. Method and reproducibility", "4. Known error rates",
                    "5. Examiner and signature", "Appendix A. The detectors' analyses", "A.1 no_section",
                    "A.2 Sectioned fixture detector", "Appendix B. The command line that reproduces the findings",
                    "Appendix C. Metadata (ExifTool)"):
        assert heading in whole, heading
    # The fixture detectors are in no validation record, so no figure may be stated for them.
    if shipped_record() is None:
        assert "No validation record is available" in whole
    else:
        assert "no_section: not covered by this validation record" in whole
    assert "self-signed" in whole
    assert "forensics analyze" in whole and "--detectors no_section,sectioned" in whole


def test_every_metadata_tag_is_beside_the_report_and_in_the_manifest(bundle):
    rows = list(csv.reader(io.StringIO((bundle / "metadata.csv").read_text(encoding="utf-8"))))
    assert rows[0] == ["group", "tag", "value"] and len(rows) > 20
    assert ["IFD0", "Model", "Canon EOS 40D"] in rows
    manifest = json.loads((bundle / "manifest.json").read_text())
    assert "metadata.csv" in {f["name"] for f in manifest["files"]}
    assert "metadata.csv" in (bundle / "report.html").read_text()


def test_a_row_sentence_keeps_to_25_words():
    from forensics_core.findings import DetectorFinding, Status
    from forensics_core.report.wording import row_sentence

    long = "word " * 40
    finding = DetectorFinding(name="d", version="1", plugin="p", status=Status.OK,
                              summary=long + ". Second sentence.", score=0.5, p_value=None, nfa=None, details={},
                              parameters={}, elapsed_s=0.1)
    assert len(row_sentence(finding).split()) == 25 and row_sentence(finding).endswith("…")
    finding.summary = "Short first sentence. Second sentence."
    assert row_sentence(finding) == "Short first sentence."
    finding.headline = "The plugin's own headline."
    assert row_sentence(finding) == "The plugin's own headline."
    finding.headline = long
    assert row_sentence(finding) == "Short first sentence."


def test_evidence_section_has_hashes_camera_table_and_thumbnail(bundle, data_dir):
    html = (bundle / "report.html").read_text()
    info = load_evidence(data_dir / "exif" / "Canon_40D.jpg").info
    for text in (info.sha256, info.sha512, "Canon EOS 40D", "GIMP 2.4.5", "135 mm", "Hashes taken"):
        assert text in html
    images = [a["src"] for t, a in tags(html) if t == "img"]
    assert len([s for s in images if s.startswith("data:image/jpeg")]) >= 2  # the photo and its EXIF thumbnail
    assert "Thumbnail embedded in the EXIF data" in html


def test_no_thumbnail_is_said_plainly(tmp_path):
    report = render(hostile_jpeg(tmp_path / "plain.jpg"))
    assert "The file carries no embedded thumbnail." in report.html


def test_hostile_exif_is_text_in_html_and_pdf_and_nothing_is_fetched(tmp_path, monkeypatch):
    fetched: list[str] = []
    original = fetcher_module.SafeFetcher.fetch

    def spy(self, url, headers=None):
        fetched.append(url)
        return original(self, url, headers)

    monkeypatch.setattr(fetcher_module.SafeFetcher, "fetch", spy)
    photo = hostile_jpeg(tmp_path / "<img src=x onerror=alert(1)>.jpg")
    report = render(photo, "sectioned")
    html = report.html

    found = tags(html)
    assert not [t for t, _ in found if t in ("script", "link", "iframe", "object", "embed", "base")]
    assert all(a["src"].startswith("data:") for t, a in found if t == "img")
    assert "<img src=x" not in html and "&lt;img src=x onerror=alert(1)&gt;.jpg" in html
    for value in HOSTILE_EXIF.values():
        assert value not in html
    assert "&lt;script&gt;alert(&#39;make&#39;)&lt;/script&gt;" in html
    description = [r for r in csv.reader(io.StringIO(report.files["metadata.csv"].decode())) if r[1] == "ImageDescription"]
    assert description[0][2] == HOSTILE_EXIF[0x010E]  # shown as text, not evaluated
    assert html.count("<style>") == 1 and html.count("</style>") == 1
    csp = [a for t, a in found if t == "meta" and a.get("http-equiv") == "Content-Security-Policy"][0]["content"]
    assert "default-src 'none'" in csp and "script-src 'none'" in csp and "img-src data:" in csp
    assert "unsafe-inline" not in csp
    style = html.split("<style>", 1)[1].split("</style>", 1)[0]
    digest = base64.b64encode(hashlib.sha256(style.encode()).digest()).decode()
    assert f"style-src 'sha256-{digest}'" in csp  # the only stylesheet a browser will apply

    pdf_path = tmp_path / "report.pdf"
    pdf_path.write_bytes(render_pdf(report))
    assert report.refused_urls == []
    assert all(url.startswith("data:") for url in fetched)
    text = "".join(pdf_pages_text(pdf_path))
    assert "<script>alert('make')</script>" in text
    assert '<img src="file:///etc/passwd">' in text
    assert "<img src=x onerror=alert(1)>.jpg" in text
    detach = subprocess.run(["pdfdetach", "-list", str(pdf_path)], capture_output=True, text=True, check=True)
    assert detach.stdout.startswith("0 embedded files")
    raw = pdf_path.read_bytes()
    assert b"/EmbeddedFile" not in raw and b"root:" not in raw


def test_fetcher_refuses_local_files_and_web_named_by_plugin_markup(tmp_path):
    report = render(hostile_jpeg(tmp_path / "p.jpg"), "section_fetches")
    pdf_path = tmp_path / "report.pdf"
    pdf_path.write_bytes(render_pdf(report))
    assert "file:///etc/passwd" in report.refused_urls
    assert "file:///etc/hostname" in report.refused_urls
    assert "http://127.0.0.1:9/x.png" in report.refused_urls
    detach = subprocess.run(["pdfdetach", "-list", str(pdf_path)], capture_output=True, text=True, check=True)
    assert detach.stdout.startswith("0 embedded files")
    assert "fetching fixture rendered" in "".join(pdf_pages_text(pdf_path))


def test_fetcher_allows_only_data_and_template_assets(tmp_path):
    from forensics_core.report.fetcher import RefusedURL, SafeFetcher
    from forensics_core.report.render import TEMPLATES_PACKAGE
    from importlib.resources import files

    assets = Path(str(files(TEMPLATES_PACKAGE)))
    fetch = SafeFetcher(assets)
    assert fetch("data:text/plain;base64,aGk=").read() == b"hi"
    assert b"@page" in fetch((assets / "report.css").as_uri()).read()
    for url in ("file:///etc/passwd", (assets / ".." / ".." / "pyproject.toml").as_uri(), "https://example.org/",
                "ftp://example.org/x"):
        with pytest.raises(RefusedURL):
            fetch(url)
    # An ordinary exception: WeasyPrint leaves the resource out and goes on, never aborting the report.
    assert issubclass(RefusedURL, Exception)


def test_plugin_section_renders_generically_with_escaped_context_and_inline_figures(bundle):
    html = (bundle / "report.html").read_text()
    assert "Sectioned fixture detector" in html
    assert "Lines found: 7" in html and "-0.049 ± 0.008" in html
    assert '&lt;script&gt;alert(&#34;x&#34;)&lt;/script&gt;' in html
    assert "Lines drawn on the photo &lt;b&gt;numbered&lt;/b&gt;" in html
    assert html.count("data:image/png;base64,") >= 1 and "data:image/svg+xml;base64," in html  # unplaced SVG too
    assert (bundle / "sectioned-overlay.png").is_file() and (bundle / "sectioned-plot.svg").is_file()
    with Image.open(bundle / "sectioned-overlay.png") as img:
        assert img.size == (64, 48)
    assert "provides no report section of its own" in html  # no_section gets the generic section


@pytest.mark.parametrize("plugin, reason", [
    ("section_raising", "its report_section raised RuntimeError: the section hook broke"),
    ("section_wrong_type", "returned a dict, not a ReportSection"),
    ("section_escapes", "SecurityError"),
])
def test_a_failing_section_is_reported_and_the_report_still_renders(tmp_path, plugin, reason):
    report = render(hostile_jpeg(tmp_path / "p.jpg"), plugin, "sectioned")
    assert f"{plugin}: report section failed" in report.html
    assert reason in report.html
    assert "Sectioned fixture detector" in report.html
    pdf = render_pdf(report)
    assert pdf.startswith(b"%PDF")


@pytest.mark.parametrize("jobs", [1, 2])
@pytest.mark.parametrize("plugin, reason", [("section_hanging", "timed out after 3 s"),
                                            ("section_template_hanging", "timed out after 3 s"),
                                            ("section_exiting", "process died (exit code 0)")])
def test_a_section_hook_that_hangs_or_ends_its_process_costs_only_its_section(tmp_path, monkeypatch, plugin, reason,
                                                                              jobs):
    # The plugin's template is filled in the hook's child too, so one that never finishes is stopped like a hook.
    monkeypatch.setattr("forensics_core.report.plugin_sections.SECTION_TIMEOUT_S", 3.0)
    report = render(hostile_jpeg(tmp_path / "p.jpg"), plugin, "sectioned", jobs=jobs)
    assert f"{plugin}: report section failed" in report.html and reason in report.html
    assert "Sectioned fixture detector" in report.html


def test_a_hanging_section_is_held_to_the_run_s_timeout(tmp_path):
    # It was held for a fixed 300 s whatever --timeout said.
    from forensics_core.analysis import Options, analyze_evidence

    host = report_host("section_hanging")
    evidence = load_evidence(hostile_jpeg(tmp_path / "p.jpg"))
    findings = analyze_evidence(evidence, host, Options(case_id="C-1", isolation="inline", timeout_s=2.0))
    report = render_html(findings, evidence, SIGNATURE, ReportOptions(exhibit_id="E-1"), host=host)
    assert "section_hanging: report section failed" in report.html and "timed out after 2 s" in report.html


def test_sections_made_at_once_are_those_made_one_at_a_time(tmp_path):
    photo = hostile_jpeg(tmp_path / "p.jpg")
    one, two = (render(photo, "sectioned", "no_section", "section_raising", report_date="2026-01-01T00:00:00Z",
                       jobs=jobs) for jobs in (1, 2))
    assert [s.title for s in two.sections] == [s.title for s in one.sections]
    assert [s.failure for s in two.sections] == [s.failure for s in one.sections]
    assert [str(s.body) for s in two.sections] == [str(s.body) for s in one.sections]


@pytest.mark.parametrize("paper, size", [("a4", "595.276 x 841.89"), ("letter", "612 x 792")])
def test_paper_size(tmp_path, paper, size):
    report = render(hostile_jpeg(tmp_path / "p.jpg"), paper=paper)
    pdf = tmp_path / "r.pdf"
    pdf.write_bytes(render_pdf(report))
    info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True, check=True).stdout
    assert re.search(rf"Page size:\s+{re.escape(size)} pts", info), info


def test_pdf_turns_into_png_pages(bundle, tmp_path):
    info = subprocess.run(["pdfinfo", str(bundle / "report.pdf")], capture_output=True, text=True, check=True).stdout
    pages = int(re.search(r"Pages:\s+(\d+)", info).group(1))
    subprocess.run(["pdftoppm", "-png", "-r", "40", str(bundle / "report.pdf"), str(tmp_path / "p")], check=True)
    pngs = sorted(tmp_path.glob("p-*.png"))
    assert len(pngs) == pages
    with Image.open(pngs[0]) as first:
        assert first.size[0] > 200 and first.getextrema() != ((255, 255),) * 3


def test_findings_round_trip_renders_the_same_summary(bundle):
    findings = Findings.from_dict(json.loads((bundle / "findings.json").read_text()))
    html = (bundle / "report.html").read_text()
    assert findings.verdict.explanation.replace("'", "&#39;") in html


def test_importing_weasyprint_leaves_pillow_strict():
    import forensics_core.report.weasy  # noqa: F401

    assert ImageFile.LOAD_TRUNCATED_IMAGES is False


def test_templates_ship_in_a_regular_wheel(tmp_path):
    import shutil
    import sys

    root = Path(__file__).resolve().parents[2]
    source = tmp_path / "src"  # a copy, so that the build leaves nothing in the working tree
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(root / name, source / name)
    for name in ("forensics_core", "forensics_plugins"):
        shutil.copytree(root / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--quiet",
                    "-w", str(tmp_path / "dist"), str(source)], check=True, capture_output=True, timeout=300)
    wheel = next((tmp_path / "dist").glob("forensics-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    for name in ("report.html.j2", "report.css", "_summary.html.j2", "__init__.py"):
        assert f"forensics_core/templates/{name}" in names


def test_large_photo_keeps_the_pdf_small(tmp_path, key):
    import numpy as np

    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 255, size=(3000, 4000, 3), dtype=np.uint8)  # 12 MP of noise: the worst case for size
    photo = tmp_path / "big.jpg"
    Image.fromarray(pixels).save(photo, "JPEG", quality=90)
    folder = make_bundle(photo, tmp_path / "big", key)
    assert (folder / "report.pdf").stat().st_size < 10 * 1024 * 1024


def test_page_one_names_apart_the_detectors_whose_likelihood_ratio_is_within_the_no_support_band():
    from forensics_core.findings import DetectorFinding, LikelihoodRatio, Status
    from forensics_core.fusion import likelihood_ratio
    from forensics_core.report.render import _lr_summary

    findings = []
    for name, log10_lr in (("strong", 0.6), ("against", -0.4), ("faint", -0.02), ("none", 0.0)):
        finding = DetectorFinding(name=name, version="1", plugin="p", status=Status.OK, summary="s", score=0.5,
                                  p_value=None, nfa=None, details={}, parameters={}, elapsed_s=0.1)
        finding.log10_lr = log10_lr
        findings.append(finding)
    verdict = likelihood_ratio(findings)
    verdict.likelihood_ratio = LikelihoodRatio(hp="h", hd="d", log10_lr=0.18, verbal="weak",
                                               contributed=["against", "faint", "strong"])
    summary = _lr_summary(verdict, findings)
    assert summary["contributed"] == "against, strong" and summary["slight"] == "faint"
    assert summary["band"] == "between 1/2 and 2"


@pytest.mark.parametrize("label, log10_lr, said", [
    ("consistent", 1.48, "carry the likelihood ratio (copy_move)"),
    ("inconsistent", -0.5, "more probable in originals"),
    ("consistent", 0.2, None),
    ("consistent", -1.0, None),
    ("inconsistent", 1.0, None),
])
def test_the_report_says_when_the_screen_and_the_likelihood_ratio_point_different_ways(label, log10_lr, said):
    from forensics_core.calibration.model import verbal
    from forensics_core.findings import LikelihoodRatio, Verdict, VerdictLabel
    from forensics_core.report.render import _tension

    verdict = Verdict(VerdictLabel(label), 0.5, "e", "bonferroni")
    verdict.likelihood_ratio = LikelihoodRatio(hp="h", hd="d", log10_lr=log10_lr, verbal=verbal(log10_lr),
                                               contributed=["copy_move"])
    rows = [{"name": "copy_move", "role": "advisory"}, {"name": "jpeg_grid", "role": "drove"}]
    text = _tension(verdict, {"contributed": "copy_move"}, rows)
    if said is None:
        assert text is None
    else:
        assert said in text and verbal(log10_lr) in text
        if label == "consistent":
            assert "(copy_move state none and are left out of it)" in text
    verdict.policy = "likelihood_ratio"
    assert _tension(verdict, {"contributed": "copy_move"}, rows) is None


def test_a_skipped_detector_s_section_hook_is_not_called(tmp_path):
    # Nothing was measured, so there is nothing for the plugin to show, and its module is not imported for it.
    from dataclasses import replace

    from forensics_core import Status
    from forensics_core.analysis import Options, analyze_evidence
    from forensics_core.report.plugin_sections import sections_for

    evidence = load_evidence(hostile_jpeg(tmp_path / "p.jpg"))
    host = report_host("section_raising")
    findings = analyze_evidence(evidence, host, Options(isolation="inline"))
    skipped = replace(findings.detectors[0], status=Status.SKIPPED, summary="Not applied: no references.")
    section = sections_for(host, [skipped], evidence)[0]
    assert section.failure is None and section.body is None
    assert sections_for(host, [findings.detectors[0]], evidence)[0].failure


def test_one_processing_seen_by_two_detectors_is_one_line_on_page_one(tmp_path):
    # jpeg_grid and cfa both name a lens correction (in the JPEG grid and in the mosaic): one fact, one line.
    report = render(hostile_jpeg(tmp_path / "p.jpg"), "processed_grid", "processed_mosaic", "processed_crop")
    lines = re.findall(r"Processing, not manipulation \(([^)]*)\):</strong>\s*the photo was ([^.]*)\.", report.html)
    assert lines == [("processed_crop", "cropped off the block grid after a first JPEG compression and saved again"),
                     ("processed_grid, processed_mosaic",
                      "resampled by a radial warp about its centre, as lens correction does")]


def test_the_where_caption_states_how_well_the_map_found_forged_pixels_on_the_shipped_realistic_record():
    from forensics_core.report.render import _where_validated
    from forensics_core.validation.record import SHIPPED_REALISTIC, shipped_record

    where = shipped_record(SHIPPED_REALISTIC).method("verdict").localisation
    text = _where_validated(["jpeg_grid", "no_such_detector"])
    assert f"On {where.n} forgeries with known masks" in text and f"mean pixel F1 was {where.f1_mean:.2f}" in text
    assert "jpeg_grid's own map" in text and "no_such_detector" not in text

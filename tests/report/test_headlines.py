"""Every bundled detector's headline on photos made here: there, at most 25 words, never calling a photo authentic."""

import io
import re

import numpy as np
import pytest
from PIL import Image, ImageDraw

from forensics_core import Status, grey_jpeg, load_evidence
from forensics_core.analysis import Options, analyze_evidence
from forensics_core.findings import HEADLINE_WORDS
from forensics_core.plugins import PluginHost

BUNDLED = ("cfa", "copy_move", "dq", "jpeg_grid", "lens_distortion", "metadata", "noise", "provenance")
_VERDICT_WORDS = re.compile(r"\b(authentic|original|genuine)\b", re.IGNORECASE)


def _png(pixels: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, "PNG")
    return buf.getvalue()


def _chessboard() -> bytes:
    """A chessboard drawn with straight edges, saved as a colour JPEG with a camera's and an editor's EXIF."""
    img = Image.new("RGB", (800, 600), (235, 235, 235))
    draw = ImageDraw.Draw(img)
    for row in range(7):
        for col in range(9):
            if (row + col) % 2:
                draw.rectangle((70 + 74 * col, 40 + 74 * row, 143 + 74 * col, 113 + 74 * row), fill=(25, 25, 25))
    exif = Image.Exif()
    exif[0x010F], exif[0x0110], exif[0x0131] = "Canon", "Canon EOS 40D", "Adobe Photoshop CS3 Windows"
    buf = io.BytesIO()
    img.save(buf, "JPEG", quality=92, exif=exif.tobytes())
    return buf.getvalue()


def _cloned() -> bytes:
    from forensics_plugins.copy_move.synth import clone, scene

    rng = np.random.default_rng(12)
    return grey_jpeg(clone(scene(rng, (480, 640)), rng, "translation")[0], 90)


def _double() -> bytes:
    from forensics_plugins.dq.synth import decode, paste, scene

    rng = np.random.default_rng(6)
    return grey_jpeg(paste(decode(grey_jpeg(scene(rng, (640, 480)), 70)), rng, "shifted_jpeg")[0], 92)


def _shifted_grid() -> bytes:
    from forensics_plugins.jpeg_grid import synth

    return synth.make_spliced(3, "splice", size=(384, 512), final_quality=99, shift=(5, 2)).data


def _mosaic() -> bytes:
    from forensics_plugins.cfa import synth

    _, spliced = synth.make_pair(4, (384, 512), algorithm="hamilton_adams", shift=(1, 0), fraction=0.2)
    return synth.encode(spliced.rgb)[0]


def _noisier() -> bytes:
    from forensics_plugins.noise.synth import paste, scene

    rng = np.random.default_rng(3)
    return grey_jpeg(paste(scene(rng, (480, 640), 2.0), rng, "noisier", 2.0)[0], 95)


PHOTOS = {
    "chessboard.jpg": _chessboard,
    "cloned.jpg": _cloned,
    "double.jpg": _double,
    "shifted-grid.jpg": _shifted_grid,
    "mosaic.png": _mosaic,
    "noisier.jpg": _noisier,
    "grey.png": lambda: _png(np.random.default_rng(0).integers(0, 256, (128, 160), dtype=np.uint8)),
    "tiny.png": lambda: _png(np.full((24, 32, 3), 128, np.uint8)),
}


@pytest.fixture(scope="module")
def host():
    return PluginHost.from_entry_points(allow=list(BUNDLED))


@pytest.mark.parametrize("name", sorted(PHOTOS))
def test_every_finding_of_a_bundled_detector_has_a_short_headline(host, tmp_path, name):
    path = tmp_path / name
    path.write_bytes(PHOTOS[name]())
    findings = analyze_evidence(load_evidence(path), host, Options(detectors=list(BUNDLED), isolation="inline"))
    for f in findings.detectors:
        print(f"{name} {f.name} {f.status.value}: {f.headline}")
        assert f.status is not Status.ERROR, f.error
        if f.status is Status.SKIPPED:  # the core's, before the plugin runs: its summary stands in
            continue
        assert f.headline, f"{f.name} gave no headline ({f.status.value})"
        assert len(f.headline.split()) <= HEADLINE_WORDS, f.headline
        assert not _VERDICT_WORDS.search(f.headline), f.headline


def _short(text: str) -> None:
    assert text and len(text.split()) <= HEADLINE_WORDS, text
    assert not _VERDICT_WORDS.search(text), text


def _lens_headlines():
    from types import SimpleNamespace as NS

    from forensics_plugins.lens_distortion.detector import _headline

    model = NS(one_term=NS(k1=-0.0149, k1_stderr=0.0110))
    records = [{"informative": True}] * 150
    box = [{"x0": 1000.4, "y0": 1200.0, "x1": 1487.9, "y1": 2239.0}]
    many = tuple(range(40))
    departs = dict(verdict="inconsistent", model=model, p_value=1.2e-05, flagged_ids=many)
    return [
        _headline(NS(verdict="inconclusive"), records, []),
        _headline(NS(**departs, evidence="region", region=NS(alternative="another lens", donor_k1=0.0712)), records,
                  box),
        _headline(NS(**departs, evidence="region", region=NS(alternative="a moved copy", donor_k1=None)), records,
                  box),
        _headline(NS(**departs, evidence="single line", region=None), records, box),
        _headline(NS(**{**departs, "flagged_ids": (4,)}, evidence="single line", region=None), records, box),
        _headline(NS(verdict="consistent", model=model, p_value=0.43, outlier_ids=many), records, []),
        _headline(NS(verdict="consistent", model=model, p_value=1.0, outlier_ids=()), records, []),
    ]


def _jpeg_grid_headlines():
    from forensics_core import PROCESSING_KEY
    from forensics_plugins.jpeg_grid.detector import _headline

    def details(significant, regions, cropped=False, processing=None):
        return {"main_grid": {"origin": [3, 5], "significant": significant, "log10_nfa": -1000.0},
                "regions": regions, "cropped": cropped, PROCESSING_KEY: processing}

    hit = {"meaningful": True, "bbox_px": [1380, 1024, 1625, 2239], "log10_nfa": -1000.0, "grid": [5, 2]}
    hits = [{**hit, "stage": "foreign"}] * 12
    return [_headline(details(True, [], cropped=True)), _headline(details(False, [], processing={"kind": "crop"})),
            _headline(details(False, [])), _headline(details(False, hits)),
            _headline(details(True, [{**hit, "stage": "missing"}] * 12)), _headline(details(True, hits))]


def _cfa_headlines():
    from forensics_plugins.cfa.detector import _headline

    region = {"bbox_px": [1024, 1536, 2048, 3072], "area_fraction": 0.1234, "log10_nfa": -412.3}
    return [_headline({"diagonal": {"rate": 0.62}}, [], 0.53), _headline({}, [region] * 12, 1e-412)]


def _provenance_headlines():
    from types import SimpleNamespace as NS

    from forensics_plugins.provenance.detector import _headline

    long_name = {"common_name": "Department of Official Photography and Digital Imaging Services of the Republic"}
    out = []
    for signer in (long_name, {"common_name": "Tests Camera"}, {}):
        for broken, state, sources, edited in ((True, "Invalid", [], []), (False, "Invalid", [], []),
                                               (False, "Valid", [], ["c2pa.edited"]), (False, "Trusted", [], [])):
            cred = NS(signer=signer, binding_broken=broken, integrity_broken=False, state=state, source_types=sources)
            out.append(_headline(cred, edited))
    return out


def _metadata_headlines():
    from forensics_plugins.metadata.checks import Check
    from forensics_plugins.metadata.detector import _headline

    titles = ["Documents placed into the file (XMP)", "Lens (lensfun) vs measured distortion",
              "Serial number: EXIF vs MakerNotes", "DateTime vs DateTimeOriginal", "EXIF vs XMP capture dates"]
    return [_headline([Check(str(i), t, "suspicious", "x") for i, t in enumerate(titles)]),
            _headline([Check("a", titles[0], "consistent", "x"), Check("b", titles[1], "note", "x")]),
            _headline([Check("a", titles[0], "not available", "x")])]


@pytest.mark.parametrize("made", [_lens_headlines, _jpeg_grid_headlines, _cfa_headlines, _provenance_headlines,
                                  _metadata_headlines], ids=lambda f: f.__name__.strip("_"))
def test_headlines_stay_short_with_the_longest_values_a_finding_holds(made):
    for text in made():
        print(text)
        _short(text)

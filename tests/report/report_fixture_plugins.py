"""Plugins whose report sections behave well or badly on purpose, loaded through real entry points."""

import io

from PIL import Image

from forensics_core import PROCESSING_KEY, Detector, DetectorResult, DetectorSpec, Processing, Status, hookimpl
from forensics_core.report import Figure, ReportSection

HOSTILE = '<script>alert("x")</script>'

SVG = (b'<svg xmlns="http://www.w3.org/2000/svg" width="120" height="40">'
       b'<rect width="120" height="40" fill="#ccd"/><text x="6" y="25">k1 plot</text></svg>')


def png(size=(64, 48), colour=(200, 40, 40)) -> bytes:
    buf = io.BytesIO()
    Image.new("RGB", size, colour).save(buf, "PNG")
    return buf.getvalue()


class _Detector(Detector):
    """A fixture plugin that is also the one detector it registers."""

    name = "base"

    @property
    def spec(self):
        return DetectorSpec(self.name, "2.0", f"Report fixture {self.name}.")

    @hookimpl
    def forensics_register_detectors(self, register):
        register(self)

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, f"{self.name} looked at the photo.", score=0.2, p_value=0.4,
                              details={"lines": [[1, 2], [3, 4]], "note": HOSTILE})


class Sectioned(_Detector):
    """The generic path: title, escaped context, a placed PNG, an unplaced SVG."""

    name = "sectioned"

    def report_section(self, finding, evidence):
        template = ("<p class='fixture-intro'>Lines found: {{ n_lines }}; label {{ label }}.</p>"
                    "<table><tr><th>k1</th><td>{{ '%.3f' | format(k1) }} ± {{ '%.3f' | format(k1_stderr) }}</td></tr></table>"
                    "{{ figures.overlay }}")
        return ReportSection(
            title="Sectioned fixture detector",
            template=template,
            context={"n_lines": 7, "label": HOSTILE, "k1": -0.0491, "k1_stderr": 0.0083},
            figures={"overlay": Figure(png(), "image/png", "Lines drawn on the photo <b>numbered</b>"),
                     "plot": Figure(SVG, "image/svg+xml", "k1 against distance")},
        )


class SectionRaising(_Detector):
    name = "section_raising"

    def report_section(self, finding, evidence):
        raise RuntimeError("the section hook broke")


class SectionHanging(_Detector):
    name = "section_hanging"

    def report_section(self, finding, evidence):
        import time

        time.sleep(3600)


class SectionExiting(_Detector):
    name = "section_exiting"

    def report_section(self, finding, evidence):
        import os

        os._exit(0)


class SectionTemplateHanging(_Detector):
    """A hook that returns at once with a template whose rendering never ends (10^10 empty loops)."""

    name = "section_template_hanging"

    def report_section(self, finding, evidence):
        return ReportSection("Endless", "{% for i in range(100000) %}{% for j in range(100000) %}{% endfor %}"
                                        "{% endfor %}")


class SectionWrongType(_Detector):
    name = "section_wrong_type"

    def report_section(self, finding, evidence):
        return {"title": "not a ReportSection"}


class SectionEscapes(_Detector):
    """A template that tries to leave the sandbox."""

    name = "section_escapes"

    def report_section(self, finding, evidence):
        return ReportSection("Escaping", "{{ ''.__class__.__mro__[1].__subclasses__() }}")


class SectionFetches(_Detector):
    """Plugin markup (not evidence) that names local files: the PDF renderer must load none of them."""

    name = "section_fetches"

    def report_section(self, finding, evidence):
        template = ('<img src="file:///etc/passwd" alt="passwd">'
                    '<link rel="attachment" href="file:///etc/hostname">'
                    '<a rel="attachment" href="file:///etc/hostname">hostname</a>'
                    '<img src="http://127.0.0.1:9/x.png" alt="web">'
                    "<p>fetching fixture rendered</p>")
        return ReportSection("Fetching", template)


class NoSection(_Detector):
    name = "no_section"


class _Processed(_Detector):
    """Names global processing, as jpeg_grid and cfa do for a lens correction."""

    kind = "radial resampling"
    description = "resampled by a radial warp about its centre, as lens correction does"

    def analyze(self, evidence, params):
        return DetectorResult(Status.OK, f"{self.name} saw processing.", score=0.0, p_value=1.0,
                              details={PROCESSING_KEY: Processing(self.kind, self.description).to_details()})


class ProcessedGrid(_Processed):
    name = "processed_grid"


class ProcessedMosaic(_Processed):
    name = "processed_mosaic"
    description = "resampled by a radial warp about its centre, which moved its colour mosaic"


class ProcessedCrop(_Processed):
    name = "processed_crop"
    kind = "crop after compression"
    description = "cropped off the block grid after a first JPEG compression and saved again"


sectioned, section_raising, section_wrong_type = Sectioned(), SectionRaising(), SectionWrongType()
section_escapes, section_fetches, no_section = SectionEscapes(), SectionFetches(), NoSection()
section_hanging, section_exiting = SectionHanging(), SectionExiting()
section_template_hanging = SectionTemplateHanging()
processed_grid, processed_mosaic, processed_crop = ProcessedGrid(), ProcessedMosaic(), ProcessedCrop()

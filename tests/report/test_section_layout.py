"""How a plugin's template places its figures: capped in height, or beside the text at their own aspect."""

import io

from PIL import Image

from forensics_core.report.plugin_sections import RenderedFigure, RenderedTable, _aspect
from report_fixture_plugins import SVG, png


def figure(aspect):
    return RenderedFigure("map", "data:image/png;base64,AA==", "Blocks <b>tinted</b>", "x-map.png", aspect=aspect)


def test_a_figure_beside_the_text_takes_the_width_its_height_and_aspect_give():
    fig = figure(2 / 3)
    html = str(fig.beside(90))
    assert fig.used and 'class="plugin-figure fig-x-map_png"' in html and "style=" not in html
    rules = " ".join(fig.rules)
    assert "figure.fig-x-map_png { float: right; clear: right" in rules and "width: 60.0mm; max-width: 50%" in rules
    assert "<figcaption>Blocks &lt;b&gt;tinted&lt;/b&gt;</figcaption>" in html
    unsized = figure(None)
    unsized.beside(90)
    assert "width: 45%" in " ".join(unsized.rules)


def test_a_fitted_figure_is_capped_in_height_and_keeps_its_aspect():
    fig = figure(1.5)
    html = str(fig.fit(70))
    assert "style=" not in html and fig.rules == ["figure.fig-x-map_png img { max-height: 70mm; width: auto }"]


def test_a_placed_figure_s_rules_join_the_hashed_stylesheet(tmp_path):
    from forensics_core.report.plugin_sections import DetectorSection

    fig = figure(1.0)
    fig.beside(50)
    section = DetectorSection(None, "t", figures=[fig, figure(1.0)])
    assert section.css == "\n".join(fig.rules) and "float: right" in section.css


def test_aspect_is_read_from_the_image_header():
    assert _aspect(png((60, 40)), "image/png") == 1.5
    assert _aspect(SVG, "image/svg+xml") == 3.0
    assert _aspect(b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 4 3"/>', "image/svg+xml") is None
    buf = io.BytesIO()
    Image.new("RGB", (30, 60)).save(buf, "JPEG")
    assert _aspect(buf.getvalue(), "image/jpeg") == 0.5


def test_a_table_renders_as_the_line_that_names_its_file():
    assert str(RenderedTable("lines", "x-lines.csv", "every <line>", 3).__html__()) == (
        '<p class="note">every &lt;line&gt; (3 rows): in x-lines.csv, beside this report.</p>')

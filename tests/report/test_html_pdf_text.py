"""report.html and report.pdf say the same thing, word for word, and report.html can run nothing.

The HTML's text is read as the PDF renderer lays it out: the body only,
without the elements the report's own stylesheet hides in print (the
``<style>`` of report.html, so whatever the templates become) and with the
text its ``::before``/``::after`` rules add. The PDF's text is read back with
poppler's ``pdftotext -raw`` (the order it was drawn in, which is the
document's), without the running headers and footers of the stylesheet's
``@page`` margin boxes. What only the layout makes differ is then set aside:
case (``text-transform``), compatibility forms (ligatures), soft hyphens,
words broken or hyphenated at a line's end, table headers repeated on every
page, list markers and the text inside SVG figures (drawn after the page's
text). Nothing else is forgiven.
"""

import base64
import hashlib
import re
import subprocess
import unicodedata
import urllib.parse
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from xml.etree import ElementTree

import cssselect2
import pytest
import tinycss2

from report_helpers import hostile_jpeg, make_bundle

VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}
# The start tags that close an open element of these names first (HTML's implied end tags).
IMPLIED_END = {"li": {"li"}, "dt": {"dt", "dd"}, "dd": {"dt", "dd"}, "tr": {"tr", "td", "th"},
               "td": {"td", "th"}, "th": {"td", "th"}, "thead": {"thead", "tbody", "tfoot", "tr", "td", "th"},
               "tbody": {"thead", "tbody", "tfoot", "tr", "td", "th"}, "tfoot": {"thead", "tbody", "tr", "td", "th"},
               "option": {"option"}}
BLOCKS = {"address", "article", "aside", "blockquote", "br", "caption", "dd", "details", "div", "dl", "dt",
          "fieldset", "figcaption", "figure", "footer", "form", "h1", "h2", "h3", "h4", "h5", "h6", "header", "hr",
          "li", "main", "nav", "ol", "p", "pre", "section", "summary", "table", "tbody", "td", "tfoot", "th",
          "thead", "tr", "ul"}
"""Elements whose text is never run together with their neighbours' (block boxes, table cells, line breaks)."""
NOT_RENDERED = {"head", "style", "script", "template", "title", "noscript"}
REPEATED = {"thead", "tfoot"}
"""Table parts a paged renderer repeats on every page the table spans."""
BULLET = re.compile(r"^[•◦▪‣⁃]+$")
ORDINAL = re.compile(r"^\d+\.$")
INVISIBLE = dict.fromkeys(map(ord, "\u00ad\u200b\u200c\u200d\u2060\ufeff"))
"""Soft hyphens and zero-width characters: break opportunities, never text."""
WINDOW = 20


def words(text: str) -> list[str]:
    """The words of ``text`` as compared: compatibility forms folded, case folded, invisible characters dropped."""
    return unicodedata.normalize("NFKC", text.translate(INVISIBLE)).casefold().split()


@pytest.fixture(scope="module")
def small_bundle(tmp_path_factory, key) -> Path:
    """A signed bundle of a 320x240 photo made here, whose EXIF strings are markup."""
    folder = tmp_path_factory.mktemp("html-pdf")
    return make_bundle(hostile_jpeg(folder / "photo.jpg"), folder / "photo", key)


# --- report.html as a tree, and the stylesheet's print rules applied to it ---------------------------------------

class _TreeBuilder(HTMLParser):
    """An ElementTree of an HTML document, closing the elements HTML closes implicitly."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.root = ElementTree.Element("document")
        self.stack = [self.root]

    def handle_starttag(self, tag, attrs):
        closes = set(IMPLIED_END.get(tag, ()))
        if tag in BLOCKS:
            closes.add("p")
        while len(self.stack) > 1 and self.stack[-1].tag in closes:
            self.stack.pop()
        element = ElementTree.SubElement(self.stack[-1], tag, {k: v or "" for k, v in attrs})
        if tag not in VOID:
            self.stack.append(element)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if any(e.tag == tag for e in self.stack[1:]):
            while self.stack.pop().tag != tag:
                pass

    def handle_data(self, data):
        parent = self.stack[-1]
        if len(parent):
            parent[-1].tail = (parent[-1].tail or "") + data
        else:
            parent.text = (parent.text or "") + data


def parse_html(html: str) -> ElementTree.Element:
    """The ``<html>`` element of ``html``."""
    builder = _TreeBuilder()
    builder.feed(html)
    builder.close()
    return builder.root.find("html")


def _for_print(prelude) -> bool:
    """Whether an ``@media`` prelude applies to paged media."""
    for query in tinycss2.serialize(prelude).lower().split(","):
        kind = query.split()[1:2] if query.split()[:1] == ["only"] else query.split()[:1]
        if not kind or kind[0] in ("print", "all") or kind[0].startswith("("):
            return True
    return False


def print_rules(css: str):
    """Every rule of ``css`` that applies in print, ``@media`` blocks opened: (selectors, declarations, at-rules);
    an ``@page`` rule comes with no selectors and its margin boxes as at-rules."""
    def walk(rules):
        for rule in rules:
            if rule.type == "qualified-rule":
                content = tinycss2.parse_blocks_contents(rule.content, skip_whitespace=True, skip_comments=True)
                yield rule.prelude, [d for d in content if d.type == "declaration"], []
            elif rule.type == "at-rule" and rule.content is not None:
                if rule.lower_at_keyword == "media" and _for_print(rule.prelude) or rule.lower_at_keyword == "supports":
                    yield from walk(tinycss2.parse_rule_list(rule.content, skip_whitespace=True, skip_comments=True))
                elif rule.lower_at_keyword == "page":
                    content = tinycss2.parse_blocks_contents(rule.content, skip_whitespace=True, skip_comments=True)
                    yield None, [d for d in content if d.type == "declaration"], [
                        r for r in content if r.type == "at-rule"]
    yield from walk(tinycss2.parse_stylesheet(css, skip_whitespace=True, skip_comments=True))


@dataclass
class Styled:
    """What the stylesheet makes of an element in print: hidden or not, generated text, named strings it sets."""

    hidden: bool = False
    before: str = ""
    after: str = ""
    strings: dict[str, str] = field(default_factory=dict)


def _generated(tokens, element: ElementTree.Element) -> str:
    """The text of a ``content`` or ``string-set`` value: strings, ``attr()`` and ``content()``."""
    out = []
    for token in tokens:
        if token.type == "string":
            out.append(token.value)
        elif token.type == "function" and token.lower_name == "attr":
            out.append(element.get(tinycss2.serialize(token.arguments).strip(), ""))
        elif token.type == "function" and token.lower_name == "content":
            out.append("".join(element.itertext()))
    return "".join(out)


def style(root: ElementTree.Element, css: str) -> dict[int, Styled]:
    """The print rules of ``css`` cascaded onto ``root``'s elements (by ``id()``): the winning declaration of
    ``display``, ``content`` on ``::before``/``::after`` and ``string-set``, by importance, specificity and order."""
    matcher = cssselect2.Matcher()
    for prelude, declarations, _ in print_rules(css):
        if prelude is None:
            continue
        wanted = [d for d in declarations if d.lower_name in ("display", "content", "string-set")]
        try:
            selectors = cssselect2.compile_selector_list(prelude)
        except cssselect2.SelectorError:
            continue
        for selector in selectors:
            for declaration in wanted:
                matcher.add_selector(selector, declaration)
    styled: dict[int, Styled] = {}
    for wrapper in cssselect2.ElementWrapper.from_html_root(root).iter_subtree():
        element = wrapper.etree_element
        winners = {}
        for specificity, order, pseudo, declaration in matcher.match(wrapper):
            key = (pseudo, declaration.lower_name)
            rank = (declaration.important, specificity, order)
            if key not in winners or rank >= winners[key][0]:
                winners[key] = (rank, declaration)
        found = Styled(hidden="hidden" in element.attrib)
        for (pseudo, name), (_, declaration) in winners.items():
            value = [t for t in declaration.value if t.type not in ("whitespace", "comment")]
            if pseudo is None and name == "display":
                found.hidden = tinycss2.serialize(value).strip().lower() == "none"
            elif pseudo in ("before", "after") and name == "content":
                setattr(found, pseudo, _generated(value, element))
            elif pseudo is None and name == "string-set":
                commas = [k for k, t in enumerate(value) if t.type == "literal" and t.value == ","]
                for lo, hi in zip([-1, *commas], [*commas, len(value)]):
                    head, *rest = value[lo + 1:hi] or [None]
                    if head is not None and head.type == "ident":
                        found.strings[head.value] = _generated(rest, element)
        styled[id(element)] = found
    return styled


# --- the HTML's words ---------------------------------------------------------------------------------------------

@dataclass
class HtmlText:
    """The words of report.html as printed, and where the PDF may show words the HTML flow does not hold."""

    css: str
    """Its stylesheet, which the PDF renderer used too."""
    words: list[str] = field(default_factory=list)
    repeated: list[list[str]] = field(default_factory=list)
    """Words of each table header and footer group."""
    figures: list[tuple[int, list[str]]] = field(default_factory=list)
    """(index in ``words`` where it stands, its words) of each SVG figure's own text."""
    strings: dict[str, set[str]] = field(default_factory=dict)
    """The values each named string (``string-set``) takes."""
    ordered_lists: bool = False
    """Whether it has ``<ol>``, whose markers (1., 2., ...) the PDF draws as text."""

    def marker(self, word: str) -> bool:
        """Whether ``word`` is a list marker, which the HTML's text does not hold and the PDF draws apart."""
        return bool(BULLET.match(word) or self.ordered_lists and ORDINAL.match(word))


def _svg_words(svg: ElementTree.Element) -> list[str]:
    """The words an SVG draws: its ``<text>`` elements, in document order."""
    return words(" ".join("".join(e.itertext()) for e in svg.iter() if e.tag.rsplit("}", 1)[-1] == "text"))


def _data_svg(src: str) -> ElementTree.Element | None:
    """The SVG of a ``data:image/svg+xml`` address, or None."""
    if not src.startswith("data:image/svg+xml"):
        return None
    header, _, payload = src.partition(",")
    raw = base64.b64decode(payload) if header.endswith(";base64") else urllib.parse.unquote_to_bytes(payload)
    return ElementTree.fromstring(raw)


def html_text(html: str) -> HtmlText:
    """What report.html shows when printed, in document order."""
    root = parse_html(html)
    css = "".join("".join(s.itertext()) for s in root.iter("style"))
    styled = style(root, css)
    out = HtmlText(css, ordered_lists=root.find(".//ol") is not None)
    pieces: list[str] = []

    def flow() -> list[str]:
        return [w for w in words("".join(pieces)) if not out.marker(w)]

    def figure(drawn: list[str]) -> None:
        out.figures.append((len(flow()), drawn))

    def walk(element: ElementTree.Element) -> None:
        look = styled.get(id(element), Styled())
        if element.tag in NOT_RENDERED or look.hidden:
            return
        for name, value in look.strings.items():
            out.strings.setdefault(name, set()).add(" ".join(words(value)))
        block = element.tag in BLOCKS
        if element.tag == "svg":
            figure(_svg_words(element))
            return
        if element.tag == "img":
            svg = _data_svg(element.get("src", ""))
            if svg is not None:
                figure(_svg_words(svg))
            return
        start = len(pieces)
        pieces.append(" " if block else "")
        pieces.append(look.before + (element.text or ""))
        for child in element:
            walk(child)
            pieces.append(child.tail or "")
        pieces.append(look.after + (" " if block else ""))
        if element.tag in REPEATED:
            out.repeated.append(words("".join(pieces[start:])))

    walk(root)
    out.words = flow()
    return out


# --- the PDF's words ----------------------------------------------------------------------------------------------

@dataclass
class PdfWord:
    """A word of the PDF: whether a line or a page of ``pdftotext -raw``'s ends after it or starts with it."""

    text: str
    line_end: bool
    page_start: bool


def _margin_pattern(css: str, strings: dict[str, set[str]]) -> re.Pattern:
    """A line made only of the texts the ``@page`` margin boxes (``@top-left`` ...) of ``css`` write."""
    boxes = []
    for prelude, _, margin_rules in print_rules(css):
        for box in margin_rules:
            for declaration in tinycss2.parse_blocks_contents(box.content, skip_whitespace=True, skip_comments=True):
                if declaration.type != "declaration" or declaration.lower_name != "content":
                    continue
                parts = []
                for token in declaration.value:
                    if token.type == "string":
                        parts.append(r"\s*".join(map(re.escape, words(token.value))))
                    elif token.type == "function" and token.lower_name == "string":
                        name = tinycss2.serialize(token.arguments).split(",")[0].strip()
                        values = sorted(strings.get(name, ()), key=len, reverse=True)
                        parts.append(f"(?:{'|'.join(map(re.escape, values))})?" if values else r"\S*")
                    elif token.type == "function" and token.lower_name in ("counter", "counters"):
                        parts.append(r"\w+")
                    elif token.type == "function":
                        parts.append(r"\S*")
                boxes.append(r"\s*".join(p for p in parts if p))
    one = "|".join(f"(?:{b})" for b in boxes if b) or "(?!)"
    return re.compile(rf"(?:{one})(?:\s*(?:{one}))*")


def pdf_words(pdf: Path, html: HtmlText) -> list[PdfWord]:
    """The PDF's words in drawing order, without running headers and footers or list markers."""
    raw = subprocess.run(["pdftotext", "-raw", "-enc", "UTF-8", str(pdf), "-"], capture_output=True, text=True,
                         check=True).stdout
    margin = _margin_pattern(html.css, html.strings)
    out = []
    for page in raw.split("\f")[:-1]:
        lines = [words(line) for line in page.splitlines()]
        lines = [line for line in lines if line]
        while lines and margin.fullmatch(" ".join(lines[-1])):
            lines.pop()
        while lines and margin.fullmatch(" ".join(lines[0])):
            lines.pop(0)
        first = True
        for line in lines:
            line = [w for w in line if not html.marker(w)]
            for i, word in enumerate(line):
                out.append(PdfWord(word, i == len(line) - 1, first))
                first = False
    return out


def _take(pdf: list[PdfWord], i: int, expected: str) -> int | None:
    """Where the PDF goes on after reading ``expected`` from word ``i``, joining what a line's end split (with or
    without the hyphen put there); None when it does not read so."""
    joined, k = pdf[i].text, i
    while joined != expected and pdf[k].line_end and k + 1 < len(pdf) and expected.startswith(joined):
        follow = pdf[k + 1].text
        options = [joined + follow] + ([joined[:-1] + follow] if joined.endswith("-") else [])
        fitting = [o for o in options if expected.startswith(o)]
        if not fitting:
            return None
        joined, k = fitting[0], k + 1
    return k + 1 if joined == expected else None


def _take_run(pdf: list[PdfWord], i: int, run: list[str]) -> int | None:
    """:func:`_take` for a run of words."""
    for expected in run:
        if i is None or i >= len(pdf):
            return None
        i = _take(pdf, i, expected)
    return i


def align(pdf: list[PdfWord], html: HtmlText) -> list[str]:
    """The PDF's words read as the HTML's: words split at a line's end joined again, table headers repeated at the
    top of a page and the text of SVG figures already met left out. The HTML's words only guide where a PDF word
    is joined or skipped: any other difference stays, for the comparison to find."""
    pending = [f for f in html.figures if f[1]]
    out: list[str] = []
    i = 0
    while i < len(pdf):
        end = _take(pdf, i, html.words[len(out)]) if len(out) < len(html.words) else None
        if end is not None:
            out.append(html.words[len(out)])
            i = end
            continue
        figure = next(((f, e) for f in pending if f[0] <= len(out)
                       for e in [_take_run(pdf, i, f[1])] if e is not None), None)
        if figure is not None:
            pending.remove(figure[0])
            i = figure[1]
            continue
        header = next((e for g in html.repeated if g for e in [_take_run(pdf, i, g)] if e is not None), None)
        if pdf[i].page_start and header is not None:
            i = header
            continue
        out.append(pdf[i].text)
        i += 1
    return out


def first_difference(a: list[str], b: list[str]) -> str:
    """The first place ``a`` and ``b`` part, with ``WINDOW`` words either side of it in each."""
    n = next((k for k, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
    lo = max(0, n - WINDOW)
    return (f"first difference at word {n} of {len(a)} (HTML) / {len(b)} (PDF)\n"
            f"HTML: ... {' '.join(a[lo:n])} >>> {' '.join(a[n:n + WINDOW])}\n"
            f"PDF:  ... {' '.join(b[lo:n])} >>> {' '.join(b[n:n + WINDOW])}")


def test_html_and_pdf_say_the_same(small_bundle):
    text = html_text((small_bundle / "report.html").read_text(encoding="utf-8"))
    assert len(text.words) > 200, "report.html shows almost no text: the extraction is broken"
    got = align(pdf_words(small_bundle / "report.pdf", text), text)
    assert got == text.words, first_difference(text.words, got)


# --- report.html runs nothing -------------------------------------------------------------------------------------

class _Scan(HTMLParser):
    """Every element with its attributes, the Content-Security-Policy and the text of each ``<style>``."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.elements: list[tuple[str, list[tuple[str, str | None]]]] = []
        self.policies: list[str] = []
        self.styles: list[str] = []
        self._in_style = False

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, attrs))
        found = dict(attrs)
        if tag == "meta" and (found.get("http-equiv") or "").lower() == "content-security-policy":
            self.policies.append(found.get("content") or "")
        if tag == "style":
            self._in_style = True
            self.styles.append("")

    def handle_endtag(self, tag):
        if tag == "style":
            self._in_style = False

    def handle_data(self, data):
        if self._in_style:
            self.styles[-1] += data


def test_report_html_runs_nothing(small_bundle):
    scan = _Scan()
    scan.feed((small_bundle / "report.html").read_text(encoding="utf-8"))
    scan.close()
    assert [tag for tag, _ in scan.elements if tag == "script"] == []
    handlers = [(tag, name) for tag, attrs in scan.elements for name, _ in attrs if name.startswith("on")]
    assert handlers == [], "event-handler attributes"
    scripted = [(tag, name, value) for tag, attrs in scan.elements for name, value in attrs
                if re.sub(r"[\s\x00-\x1f]", "", value or "").lower().startswith("javascript:")]
    assert scripted == [], "javascript: addresses"
    # The policy admits one hashed stylesheet: a style attribute would be refused by a browser and laid out by the PDF.
    styled = [tag for tag, attrs in scan.elements for name, _ in attrs if name == "style"]
    assert styled == [], "style attributes"
    assert len(scan.policies) == 1, "one Content-Security-Policy meta tag"
    policy = {d.split()[0].lower(): d.split()[1:] for d in scan.policies[0].split(";") if d.strip()}
    assert policy.get("script-src") == ["'none'"]
    assert scan.styles, "report.html has its stylesheet inline"
    for css in scan.styles:
        digest = base64.b64encode(hashlib.sha256(css.encode("utf-8")).digest()).decode("ascii")
        assert f"'sha256-{digest}'" in policy.get("style-src", []), "the stylesheet's hash is not the allowed one"

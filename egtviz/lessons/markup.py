r"""A step's text: Markdown whose ``$...$`` and ``$$...$$`` formulas are rendered offline to MathML.

viser's Markdown panel has no math; it does show inline HTML, so each formula is converted once, when the
lesson is loaded, by ``latex2mathml`` and put in the Markdown as a ``<math>`` element. Lesson files are
shared between people, so nothing else in a step's text may become HTML, a link or an outside image:

* ``<``, ``>``, ``&``, ``[``, ``]`` and a lone backtick in the text are written as character references, so no
  HTML, no link and no image can be written, and a bare address (``https://...``, ``www.``, an e-mail
  address) is split by an empty ``<span>`` so that the viewer's Markdown does not make it a link;
* code is turned into ``<code>`` with every punctuation character a character reference (the viewer's
  Markdown and viser's image loader, which reads any ``![...](path)`` of the text on the server, see no
  syntax in it);
* an image ``![text](name.png)`` is a file of the lesson's folder or of the package's assets
  (:class:`~egtviz.lessons.images.LessonImages`), read by the server and embedded as an ``<img>`` with a
  ``data:`` URL; any other image is refused;
* the MathML is parsed and rebuilt from an allow-list of MathML elements and attributes (``latex2mathml``
  copies ``\text{...}`` verbatim), and a formula with unbalanced braces, a command missing an argument or a
  fraction, script or root missing a part is refused with the reason.

``\$`` is a literal dollar sign; a backslash before any other punctuation character makes it literal, as in
Markdown.
"""

from __future__ import annotations

import re
import string
import xml.etree.ElementTree as ET
from collections.abc import Callable

from latex2mathml.converter import convert

from ..files import printable

__all__ = ["FORMULA_FONT_PX", "PANEL_WIDTH_PX", "ImageSource", "MarkupError", "displayed_formulas",
           "formula_to_mathml", "formula_width_px", "render_markdown"]

ImageSource = Callable[[str], str]
"""An image's file name to the ``data:`` URL the text shows (:meth:`~egtviz.lessons.images.LessonImages.data_url`);
raises ``ValueError`` with the reason for an image it cannot show."""

_MATHML = "http://www.w3.org/1998/Math/MathML"
_ELEMENTS = frozenset(
    "math mrow mi mn mo ms mtext mspace msub msup msubsup mfrac msqrt mroot mover munder munderover "
    "mtable mtr mtd mstyle mpadded mphantom menclose merror semantics annotation mfenced".split()
)
_ATTRIBUTES = frozenset(
    "display xmlns mathvariant stretchy fence form accent accentunder separator lspace rspace width height "
    "depth columnalign rowspacing columnspacing columnlines rowlines frame displaystyle scriptlevel linethickness "
    "notation open close separators minsize maxsize movablelimits largeop symmetric class".split()
)
# Fenced blocks, code spans, images, a backslash before punctuation, then the formulas.
_TOKENS = re.compile(
    r"(```.*?```|`[^`\n]*`|!\[[^\[\]\n]*\]\([^()\n]*\)|\\[!-/:-@\[-`{-~]|\$\$.+?\$\$|\$[^$\n]+?\$)", re.S
)
_IMAGE = re.compile(r"!\[([^\[\]\n]*)\]\(\s*([^()\n]*?)\s*\)")
# Where the viewer's Markdown (GFM) would start a link from bare text: after "http", "https", "www", before "@".
_AUTOLINK = re.compile(r"(?i)(?:https?|www)(?=[:.])|(?=@)")
_UNLINK = "<span></span>"
_ALL_PUNCTUATION = str.maketrans({c: f"&#{ord(c)};" for c in string.punctuation + "\n"})
_TEXT_ACTIVE = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", "[": "&#91;", "]": "&#93;", "`": "&#96;"})
# latex2mathml's own errors carry no message: what each means.
_LATEX_ERRORS = {
    "NumeratorNotFoundError": "\\frac has no numerator",
    "DenominatorNotFoundError": "\\frac has no denominator",
    "ExtraLeftOrMissingRightError": "a \\left without its \\right, or a \\right without its \\left",
    "MissingSuperScriptOrSubscriptError": "a ^ or _ with nothing after it",
    "DoubleSubscriptsError": "two subscripts on one symbol (write x_{ab}, not x_a_b)",
    "DoubleSuperscriptsError": "two superscripts on one symbol (write x^{ab}, not x^a^b)",
    "NoAvailableTokensError": "a command is missing its argument (e.g. \\sqrt or \\frac at the end)",
    "InvalidStyleForGenfracError": "\\genfrac's style must be 0, 1, 2 or 3",
    "MissingEndError": "a \\begin{...} without its matching \\end{...}",
    "InvalidAlignmentError": "an array's column alignment must be l, c or r",
    "InvalidWidthError": "a width that is not a length",
    "LimitsMustFollowMathOperatorError": "\\limits must follow an operator such as \\sum",
}
# How many children the MathML of a fraction, script or root must have (latex2mathml leaves one out silently).
_ARITY = {"mfrac": 2, "msub": 2, "msup": 2, "msubsup": 3, "mroot": 2, "munder": 2, "mover": 2, "munderover": 3}
_PARTS = {"mfrac": "a fraction needs a numerator and a denominator (\\frac{a}{b})",
          "mroot": "a root needs its index and radicand"}


class MarkupError(ValueError):
    """Text that cannot be shown (a formula, an image, an unclosed ``$``); ``offset`` is its position in the text
    (characters)."""

    def __init__(self, offset: int, reason: str) -> None:
        self.offset = offset
        super().__init__(reason)


def _unlinked(raw: str, encode: Callable[[str], str]) -> str:
    """``raw`` encoded, with an empty ``<span>`` where the viewer's Markdown would start a bare link."""
    cuts = [m.end() for m in _AUTOLINK.finditer(raw)]
    if not cuts:
        return encode(raw)
    pieces = [raw[a:b] for a, b in zip([0, *cuts], [*cuts, len(raw)], strict=True)]
    return _UNLINK.join(encode(p) for p in pieces)


def _text(raw: str) -> str:
    return _unlinked(raw, lambda p: p.translate(_TEXT_ACTIVE))


def _code(raw: str, *, block: bool) -> str:
    if block:  # an info string (```python) names a language the viewer does not highlight
        first, newline, rest = raw.partition("\n")
        raw = rest if newline and re.fullmatch(r"[\w+.-]*", first.strip()) else raw
        raw = raw.removesuffix("\n")
    code = "<code>" + _unlinked(raw, lambda p: p.translate(_ALL_PUNCTUATION)) + "</code>"
    return f"<pre>{code}</pre>" if block else code


def _unbalanced(latex: str) -> str | None:
    r"""Why the braces of ``latex`` do not pair up (``\{`` and ``\}`` are characters), or None."""
    opened: list[int] = []
    i = 0
    while i < len(latex):
        c = latex[i]
        if c == "\\":
            i += 2
            continue
        if c == "{":
            opened.append(i)
        elif c == "}":
            if not opened:
                return f"the '}}' at character {i + 1} closes no '{{'"
            opened.pop()
        i += 1
    if opened:
        return f"the '{{' at character {opened[0] + 1} is never closed"
    return None


def _rebuild(node: ET.Element, offset: int, shown: str) -> ET.Element:
    tag = node.tag.split("}", 1)[-1]
    if tag not in _ELEMENTS:
        raise MarkupError(offset, f"the formula {shown} produced an element <{tag}> that is not MathML")
    if len(node) < _ARITY.get(tag, 0):
        reason = _PARTS.get(tag, "a ^ or _ (or an accent) without its base or its script")
        raise MarkupError(offset, f"cannot render the formula {shown}: {reason}")
    out = ET.Element(tag, {k: v for k, v in node.attrib.items() if k in _ATTRIBUTES})
    out.text = node.text
    if node.text and "\\" in node.text:
        raise MarkupError(offset, f"unknown LaTeX command {node.text.strip()[:30]!r}")
    for child in node:
        rebuilt = _rebuild(child, offset, shown)
        rebuilt.tail = child.tail
        out.append(rebuilt)
    return out


def formula_to_mathml(latex: str, *, display: bool, offset: int = 0) -> str:
    """One LaTeX formula as a sanitised ``<math>`` element.

    Raises:
        MarkupError: the formula's braces do not pair up, ``latex2mathml`` refuses it, leaves a command it does
            not know or a fraction, script or root without one of its parts, or produces markup outside the
            MathML allow-list. The message always says why.
    """
    shown = f"'{printable(latex[:40])}'"  # as written: repr() would double every backslash
    unbalanced = _unbalanced(latex)
    if unbalanced:
        raise MarkupError(offset, f"cannot render the formula {shown}: {unbalanced}")
    try:
        mathml = convert(latex, display="block" if display else "inline")
    except Exception as exc:  # latex2mathml raises many unrelated types for bad input, most without a message
        name = type(exc).__name__
        reason = _LATEX_ERRORS.get(name) or str(exc) or re.sub(r"(?<!^)(?=[A-Z])", " ", name).lower()
        raise MarkupError(offset, f"cannot render the formula {shown}: {reason}") from None
    # latex2mathml copies \text{...} verbatim, so its output may not even be XML: such text is refused.
    try:
        root = ET.fromstring(mathml)
    except ET.ParseError:
        raise MarkupError(offset, f"the formula {shown} holds characters (<, &) that \\text cannot show") from None
    rebuilt = _rebuild(root, offset, shown)
    rebuilt.set("xmlns", _MATHML)
    return _MARKDOWN_TEXT.sub(_quote_markdown, ET.tostring(rebuilt, encoding="unicode"))


# The viewer's Markdown parses the text between the MathML tags too: two tildes (two \tilde) would become a
# strike-through, two '*' or '_' an emphasis, and the formula would break; '[', ']' and '`' could start a link
# or code. They go in as character references, and a bare address is split as in the text.
_MARKDOWN_TEXT = re.compile(r">([^<]+)<")
_MARKDOWN_ACTIVE = str.maketrans({"~": "&#126;", "*": "&#42;", "_": "&#95;", "[": "&#91;", "]": "&#93;",
                                  "`": "&#96;"})


def _quote_markdown(m: re.Match) -> str:
    return ">" + _unlinked(m.group(1), lambda p: p.translate(_MARKDOWN_ACTIVE)) + "<"


def _image(token: str, offset: int, images: ImageSource | None) -> str:
    m = _IMAGE.fullmatch(token)
    assert m is not None  # the token pattern is the image pattern's
    alt, target = m.group(1), m.group(2)
    if images is None:
        raise MarkupError(offset, f"image {target[:80]!r}: only a step's text shows images")
    try:
        url = images(target)
    except ValueError as exc:
        raise MarkupError(offset, str(exc)) from None
    # An element, not Markdown: viser's handle would try to read a Markdown image's address as a file.
    return f'<img src="{url}" alt="{alt.translate(_ALL_PUNCTUATION)}">'


def render_markdown(text: str, images: ImageSource | None = None) -> str:
    """``text`` with its formulas as MathML, its images embedded, and anything else that could become HTML, a
    link or an outside image written as plain text.

    ``$...$`` is an inline formula, ``$$...$$`` a displayed one (put on its own line); code spans and fenced
    code blocks are shown as code (``<code>``, ``<pre>``).

    Args:
        text: the Markdown as written.
        images: reads the images the text names (``![text](name.png)``); None: the text may show none.

    Raises:
        MarkupError: a formula cannot be rendered, a ``$`` is left unclosed, or an image cannot be shown.
    """
    out = []
    pos = 0
    for m in _TOKENS.finditer(text):
        out.append(_plain(text[pos : m.start()], pos))
        token = m.group(0)
        if token.startswith("```"):
            out.append(_code(token[3:-3], block=True))
        elif token.startswith("`"):
            out.append(_code(token[1:-1], block=False))
        elif token.startswith("!"):
            out.append(_image(token, m.start(), images))
        elif token == "\\$":
            out.append("\\$")
        elif token.startswith("\\"):
            out.append(token[1].translate(_ALL_PUNCTUATION))
        elif token.startswith("$$"):
            out.append("\n\n" + formula_to_mathml(token[2:-2].strip(), display=True, offset=m.start()) + "\n\n")
        else:
            out.append(formula_to_mathml(token[1:-1].strip(), display=False, offset=m.start()))
        pos = m.end()
    out.append(_plain(text[pos:], pos))
    return "".join(out)


def _plain(segment: str, offset: int) -> str:
    if "$" in segment:
        raise MarkupError(
            offset + segment.index("$"), "a '$' opens a formula that is never closed (write \\$ for a dollar)"
        )
    if "![" in segment:
        raise MarkupError(
            offset + segment.index("!["),
            "an image egtviz cannot show: write ![text](name.png), naming an image file of the lesson's folder "
            "(write \\! for an exclamation mark before '[')",
        )
    return _text(segment)


#: The control panel's width for a displayed formula, CSS pixels, and the formula's type size there: Chromium at
#: 1366 x 768 in presentation mode, the narrowest the panel is for its type (252 px at 14.89 px, 16.9 em; without
#: presentation mode 262 px at 11.91 px, 22.0 em). tests/browser/test_formula_width_browser.py measures both.
PANEL_WIDTH_PX = 252.0
FORMULA_FONT_PX = 14.8925
# The estimate is scaled up and padded so that it is never below the width Chromium renders: calibrated on every
# displayed formula of the course (the estimate is 2.7 % to 24 % above the real width there).
_WIDTH_SCALE = 1.08
_WIDTH_PAD_EM = 0.6
_SCRIPT = 0.71  # a sub- or superscript's size relative to its base
_RELATIONS = frozenset("=\u2243\u2248\u2208\u2260\u2264\u2265<>\u2192\u21d2\u223c\u2261\u221d")
_BINARY = frozenset("+\u2212-\u00b1\u00d7\u2297\u00b7\u2218\u2217/")
_LENGTH = re.compile(r"\s*(-?\d*\.?\d+)\s*(em|ex|px|mu)?\s*")
_UNIT_EM = {"em": 1.0, "ex": 0.45, "px": 1 / FORMULA_FONT_PX, "mu": 1 / 18}


def _glyph_em(c: str) -> float:
    """A generous advance width of one character, em (italic capitals and the wide letters are wider)."""
    if c.isspace():
        return 0.3
    if c in "MWmw":
        return 1.05 if c.isupper() else 0.9
    if c.isupper():
        return 0.82
    if c.islower():
        return 0.6
    if c.isdigit():
        return 0.55
    if c in "()[]{}|":
        return 0.42
    if c in ",.;:!'":
        return 0.3
    return 0.8  # operators, Greek capitals, symbols


def _node_em(node: ET.Element, scale: float) -> float:
    """The width of a MathML element, em of the formula's type; scripts are smaller by :data:`_SCRIPT`."""
    tag = node.tag.split("}", 1)[-1]
    kids = list(node)
    if tag in ("mi", "mn", "mtext", "ms"):
        return scale * sum(_glyph_em(c) for c in (node.text or "").strip())
    if tag == "mo":
        op = (node.text or "").strip()
        # MathML's operator spacing: a thick space either side of a relation, a medium one of a binary operator.
        space = 0.5556 if op in _RELATIONS else 0.4444 if op in _BINARY else 0.1667
        return scale * (sum(_glyph_em(c) for c in op) + space)
    if tag == "mspace":
        m = _LENGTH.fullmatch(node.get("width") or "")
        return scale * float(m.group(1)) * _UNIT_EM[m.group(2) or "em"] if m else 0.0
    if tag in ("msub", "msup", "msubsup") and len(kids) >= 2:
        return _node_em(kids[0], scale) + max(_node_em(k, scale * _SCRIPT) for k in kids[1:]) + 0.05 * scale
    if tag in ("munder", "mover", "munderover") and kids:
        return max(_node_em(kids[0], scale), *(_node_em(k, scale * _SCRIPT) for k in kids[1:]))
    if tag == "mfrac" and kids:
        return max(_node_em(k, scale) for k in kids) + 0.25 * scale
    if tag in ("msqrt", "mroot") and kids:
        index = _node_em(kids[1], scale * 0.5) if tag == "mroot" and len(kids) > 1 else 0.0
        return (_node_em(kids[0], scale) if tag == "mroot" else sum(_node_em(k, scale) for k in kids)) + index + scale
    if tag == "mtable":
        rows = [[_node_em(cell, scale) for cell in row] for row in kids]
        n = max((len(r) for r in rows), default=0)
        columns = [max(r[i] for r in rows if i < len(r)) for i in range(n)]
        return sum(columns) + 0.8 * scale * n  # each cell's 0.4 em padding either side
    return sum(_node_em(k, scale) for k in kids)


def formula_width_px(mathml: str, font_px: float = FORMULA_FONT_PX) -> float:
    """An estimate, never below the width Chromium renders, of a ``<math>`` element (:func:`formula_to_mathml`)
    at ``font_px``: a table of generous advance widths per kind of character, MathML's operator spacing, scripts
    at 71 %, a table's columns side by side; scaled and padded so that it stays above every formula measured."""
    em = _node_em(ET.fromstring(mathml), 1.0)
    return (_WIDTH_SCALE * em + _WIDTH_PAD_EM) * font_px


def displayed_formulas(text: str) -> list[tuple[int, str]]:
    """The ``$$...$$`` formulas of a step's text (not those in code): ``(offset, LaTeX)`` each."""
    return [(m.start(), m.group(0)[2:-2].strip()) for m in _TOKENS.finditer(text) if m.group(0).startswith("$$")]

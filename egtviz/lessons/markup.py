r"""A step's text: Markdown whose ``$...$`` and ``$$...$$`` formulas are rendered offline to MathML.

viser's Markdown panel has no math; it does show inline HTML, so each formula is converted once, when the
lesson is loaded, by ``latex2mathml`` and put in the Markdown as a ``<math>`` element. Lesson files are
shared between people, so nothing else in a step's text may become HTML: ``<``, ``>`` and ``&`` outside
code are written as entities, and the MathML is parsed and rebuilt from an allow-list of MathML elements
and attributes (``latex2mathml`` copies ``\text{...}`` verbatim). ``\$`` is a literal dollar sign.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

from latex2mathml.converter import convert

__all__ = ["MarkupError", "render_markdown"]

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
# Code spans and fenced blocks are left alone; so is an escaped dollar.
_TOKENS = re.compile(r"(```.*?```|`[^`\n]*`|\\\$|\$\$.+?\$\$|\$[^$\n]+?\$)", re.S)


class MarkupError(ValueError):
    """A formula that cannot be rendered; ``offset`` is its position in the text (characters)."""

    def __init__(self, offset: int, reason: str) -> None:
        self.offset = offset
        super().__init__(reason)


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _rebuild(node: ET.Element, offset: int) -> ET.Element:
    tag = node.tag.split("}", 1)[-1]
    if tag not in _ELEMENTS:
        raise MarkupError(offset, f"the formula produced an element <{tag}> that is not MathML")
    out = ET.Element(tag, {k: v for k, v in node.attrib.items() if k in _ATTRIBUTES})
    out.text = node.text
    if node.text and "\\" in node.text:
        raise MarkupError(offset, f"unknown LaTeX command {node.text.strip()[:30]!r}")
    for child in node:
        rebuilt = _rebuild(child, offset)
        rebuilt.tail = child.tail
        out.append(rebuilt)
    return out


def formula_to_mathml(latex: str, *, display: bool, offset: int = 0) -> str:
    """One LaTeX formula as a sanitised ``<math>`` element.

    Raises:
        MarkupError: ``latex2mathml`` refuses it, leaves a command it does not know, or produces markup
            outside the MathML allow-list.
    """
    try:
        mathml = convert(latex, display="block" if display else "inline")
    except Exception as exc:  # latex2mathml raises many unrelated types for bad input
        raise MarkupError(offset, f"cannot render the formula {latex[:40]!r}: {exc}") from None
    # latex2mathml copies \text{...} verbatim, so its output may not even be XML: such text is refused.
    try:
        root = ET.fromstring(mathml)
    except ET.ParseError:
        raise MarkupError(
            offset, f"the formula {latex[:40]!r} holds characters (<, &) that \\text cannot show"
        ) from None
    rebuilt = _rebuild(root, offset)
    rebuilt.set("xmlns", _MATHML)
    return _MARKDOWN_TEXT.sub(_quote_markdown, ET.tostring(rebuilt, encoding="unicode"))


# The viewer's Markdown parses the text between the MathML tags too: two tildes (two \tilde) would become a
# strike-through, two '*' or '_' an emphasis, and the formula would break. They go in as character references.
_MARKDOWN_TEXT = re.compile(r">([^<]+)<")
_MARKDOWN_ACTIVE = {"~": "&#126;", "*": "&#42;", "_": "&#95;"}


def _quote_markdown(m: re.Match) -> str:
    return ">" + "".join(_MARKDOWN_ACTIVE.get(c, c) for c in m.group(1)) + "<"


def render_markdown(text: str) -> str:
    """``text`` with its formulas as MathML and any other HTML written as plain text.

    ``$...$`` is an inline formula, ``$$...$$`` a displayed one (put on its own line); code spans and fenced
    code blocks are kept as they are.

    Raises:
        MarkupError: a formula cannot be rendered, or a ``$`` is left unclosed.
    """
    out = []
    pos = 0
    for m in _TOKENS.finditer(text):
        out.append(_plain(text[pos : m.start()], pos))
        token = m.group(0)
        if token.startswith("`"):
            out.append(token)
        elif token == "\\$":
            out.append("\\$")
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
    return _escape(segment)

"""The exported page: a lesson step's text (or a scene's description) beside the 3D scene's frame.

Pure string work, no viser. A step's text arrives as the lesson view shows it (:attr:`egtviz.lessons.Step.html`:
Markdown in which ``<``, ``>``, ``&``, brackets and backticks of the text are already character references and the
only elements are the allow-listed MathML of the formulas, code and ``data:`` images); :func:`markdown_to_html`
turns its blocks (paragraphs, ``#`` headings, ``*``/``-`` and ``1.`` lists) and its ``**strong**`` and
``*emphasis*`` into HTML, leaving the formulas as they are. Everything else written into the page (titles,
camera names, file names) goes through :func:`html.escape`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from html import escape

__all__ = ["SCENE_FRAME", "markdown_to_html", "page_html"]

#: The file the page frames: viser's client with the recorded scene in it.
SCENE_FRAME = "scene.html"

_MATH = re.compile(r"<math\b.*?</math>", re.S)
_HOLD = "\x00{}\x00"
_HELD = re.compile("\x00(\\d+)\x00")
_STRONG = re.compile(r"\*\*(?=\S)(.+?)(?<=\S)\*\*", re.S)
_EMPHASIS = re.compile(r"(?<![*\w])\*(?=\S)([^*]+?)(?<=\S)\*(?![*\w])")
_BULLET = re.compile(r"^\s{0,3}[*-]\s+")
_NUMBERED = re.compile(r"^\s{0,3}\d{1,3}[.)]\s+")
_HEADING = re.compile(r"^(#{1,6})\s+(.*)$")

_STYLE = """
*{box-sizing:border-box}
html,body{margin:0;height:100%;font-family:"DejaVu Sans",system-ui,sans-serif;color:#222;background:#fff}
main{display:flex;height:100%}
article{flex:0 0 clamp(18rem,32vw,34rem);overflow-y:auto;padding:1rem 1.2rem;border-right:1px solid #ddd;
  line-height:1.45;font-size:0.95rem}
article h1{font-size:1.15rem;margin:0.2rem 0 0.8rem}
article h2{font-size:1rem;margin:1.2rem 0 0.4rem}
article .lesson{color:#555;margin:0;font-size:0.9rem}
article .how{color:#555;font-size:0.85rem;margin-top:1.5rem}
article code{background:#f3f3f3;padding:0 0.2em;border-radius:3px}
article img{max-width:100%}
math[display="block"]{max-width:100%;overflow-x:auto;overflow-y:hidden;font-size:0.92em;padding:0.35em 0 0.2em}
iframe{flex:1 1 auto;border:0;height:100%;min-width:0}
@media (max-width:700px){main{flex-direction:column}article{flex:0 0 auto;max-height:45%;border-right:0;
  border-bottom:1px solid #ddd}iframe{height:auto;flex:1 1 55%}}
"""


def _inline(text: str) -> str:
    return _EMPHASIS.sub(r"<em>\1</em>", _STRONG.sub(r"<strong>\1</strong>", text))


def _list_items(lines: Sequence[str], marker: re.Pattern[str]) -> list[str]:
    """The items of a list block: a line starting with ``marker`` opens one, other lines continue it."""
    items: list[str] = []
    for line in lines:
        if marker.match(line) or not items:
            items.append(marker.sub("", line, count=1))
        else:
            items[-1] += "\n" + line.strip()
    return items


def _block(block: str) -> str:
    lines = block.split("\n")
    heading = _HEADING.match(lines[0]) if len(lines) == 1 else None
    if heading is not None:
        level = min(len(heading.group(1)) + 1, 6)  # the page's own title is the h1
        return f"<h{level}>{_inline(heading.group(2))}</h{level}>"
    for marker, tag in ((_BULLET, "ul"), (_NUMBERED, "ol")):
        if marker.match(lines[0]):
            items = "".join(f"<li>{_inline(item)}</li>" for item in _list_items(lines, marker))
            return f"<{tag}>{items}</{tag}>"
    return f"<p>{_inline(block)}</p>"


def markdown_to_html(markdown: str) -> str:
    """HTML of a step's text as the lesson view shows it (see the module docstring); formulas kept verbatim.

    Args:
        markdown: :attr:`egtviz.lessons.Step.html` (or a task's ``prompt_html``), never raw user text: its
            characters that HTML would read as markup must already be references.
    """
    held: list[str] = []

    def hold(m: re.Match[str]) -> str:
        held.append(m.group(0))
        return _HOLD.format(len(held) - 1)

    text = _MATH.sub(hold, markdown.replace("\r\n", "\n"))
    blocks = [b.strip("\n") for b in re.split(r"\n\s*\n", text) if b.strip()]
    html = "\n".join(_block(b) for b in blocks)
    return _HELD.sub(lambda m: held[int(m.group(1))], html)


def page_html(*, title: str, heading: str, subtitle: str, body_html: str, tasks_html: Sequence[str] = (),
              how: str = "") -> str:
    """The exported ``index.html``: the text column and the scene's frame.

    Args:
        title: the document's title (plain text).
        heading: the column's heading (plain text), e.g. "Step 2 of 3: Steer the epipole".
        subtitle: the line above it (plain text), e.g. the lesson's title.
        body_html: the column's content, already HTML (from :func:`markdown_to_html`, or escaped by the caller).
        tasks_html: the step's task prompts, each already HTML; listed under "In the live lesson".
        how: plain text at the foot of the column (how to open the live version).
    """
    tasks = ""
    if tasks_html:
        items = "".join(f"<li>{t}</li>" for t in tasks_html)
        tasks = f'<section data-egtviz="export-tasks"><h2>In the live lesson this step asks</h2><ol>{items}</ol></section>'
    foot = f'<p class="how">{escape(how)}</p>' if how else ""
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n<body>\n<main>\n"
        f'<article data-egtviz="export-step">\n<p class="lesson">{escape(subtitle)}</p>\n'
        f"<h1>{escape(heading)}</h1>\n"
        f'<div data-egtviz="export-text">\n{body_html}\n</div>\n{tasks}\n{foot}\n</article>\n'
        f'<iframe src="{SCENE_FRAME}" title="3D scene" data-egtviz="export-scene"></iframe>\n'
        "</main>\n</body>\n</html>\n"
    )

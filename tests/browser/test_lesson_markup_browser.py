"""A lesson's text in a real browser (headless Chromium, playwright, viser's own Markdown renderer): the page
fetches no outside address and shows no link, whatever the text writes; the lesson's own image is shown from
the data the server embedded, code is code and formulas are MathML."""

from __future__ import annotations

import struct
import zlib

import pytest

from egtviz.lessons.images import LessonImages
from egtviz.lessons.markup import render_markdown

pytestmark = pytest.mark.browser

HOSTILE = r"""MARKER-START [a link](http://links.example/page) and [data](data:text/html,<b>x</b>),
bare http://bare.example/x and www.www.example and mail@mail.example, <http://angle.example>,
<img src="http://raw.example/x.png">, a formula $\text{see www.formula.example}$ and $x^2$,
code `![c](http://code.example/c.png)` and our picture ![the rig](rig.png).

[ref]: http://ref.example/r.png

```
![f](http://fence.example/f.png)
```
MARKER-END"""


def _png() -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 1, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\x00" + b"\xff\x00\x00" * 2)) + chunk(b"IEND", b""))


def test_a_hostile_step_text_fetches_nothing_outside_and_shows_no_link(browser, tmp_path):
    import viser

    (tmp_path / "rig.png").write_bytes(_png())
    html = render_markdown(HOSTILE, LessonImages(tmp_path).data_url)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        server.gui.add_markdown(html)
        url = f"http://127.0.0.1:{server.get_port()}"
        page = browser.new_page()
        try:
            requests: list[str] = []
            page.on("request", lambda r: requests.append(r.url))
            page.goto(url)
            page.get_by_text("MARKER-END").wait_for()
            page.wait_for_load_state("networkidle")  # whatever the text makes the page fetch, it has asked for it
            shown = page.evaluate("""() => {
                let box = [...document.querySelectorAll('code')].find(c => c.textContent.includes('code.example'));
                while (!box.innerText.includes('MARKER-END')) box = box.parentElement;  // the whole Markdown element
                return {
                    text: box.innerText,
                    links: [...box.querySelectorAll('a')].map(a => a.getAttribute('href')),
                    images: [...box.querySelectorAll('img')].map(i => [i.getAttribute('src').slice(0, 22),
                                                                      i.naturalWidth]),
                    code: [...box.querySelectorAll('code, pre')].map(c => c.textContent),  // a block is a <pre>
                    maths: box.querySelectorAll('math').length,
                };
            }""")
        finally:
            page.close()
    finally:
        server.stop()
    outside = [r for r in requests if not r.startswith((url, f"blob:{url}", "data:"))]
    assert outside == []
    assert shown["links"] == []
    assert shown["images"] == [["data:image/png;base64,", 2]]  # the lesson's own picture, decoded
    assert shown["code"] == ["![c](http://code.example/c.png)", "![f](http://fence.example/f.png)"]
    assert shown["maths"] == 2
    for written in ("[a link](http://links.example/page)", "[data](data:text/html,<b>x</b>)",
                    "http://bare.example/x", "www.www.example", "mail@mail.example", "<http://angle.example>",
                    '<img src="http://raw.example/x.png">', "[ref]: http://ref.example/r.png"):
        assert written in shown["text"]

"""A lesson's Markdown cannot make a learner's browser fetch an outside address, nor the server read a path.

Images come only from the lesson's folder or the package's assets, read by the server and embedded as ``data:``
URLs; ``egtviz check`` refuses any other image with file:line. Links (written, bare, ``data:``) are plain text.
Code is shown as code that neither the viewer's Markdown nor viser's image loader reads as syntax.
"""

from __future__ import annotations

import base64
import struct
import zlib
from pathlib import Path

import pytest

from egtviz.lessons import LessonError, load_lesson
from egtviz.lessons.cli import check_file
from egtviz.lessons.markup import MarkupError, render_markdown
from egtviz.resources import shipped_folder

LESSON = """\
title = "Pictures"
summary = "For the tests."
scene = "default"

[[steps]]
title = "First"
text = '''
Look at this:

IMAGE
'''
"""
IMAGE_LINE = 10


def png(width: int = 1) -> bytes:
    """A real PNG of ``width`` x 1 red pixels."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = b"\x00" + b"\xff\x00\x00" * width
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, 1, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def lesson_file(folder: Path, image: str) -> Path:
    path = folder / "01-pictures.toml"
    path.write_text(LESSON.replace("IMAGE", image))
    return path


def test_an_image_of_the_lessons_folder_is_embedded_as_data(tmp_path):
    (tmp_path / "rig.png").write_bytes(png())
    lesson = load_lesson(lesson_file(tmp_path, "![The rig, *two* cameras](rig.png)"))
    url = "data:image/png;base64," + base64.b64encode(png()).decode()
    assert f'<img src="{url}" alt="The rig&#44; &#42;two&#42; cameras">' in lesson.steps[0].html
    assert "![" not in lesson.steps[0].html


def test_an_image_of_the_packages_assets_is_embedded_as_data(tmp_path):
    name = "screenshot-lesson-start.png"
    data = (shipped_folder("assets") / name).read_bytes()
    lesson = load_lesson(lesson_file(tmp_path, f"![The start page]({name})"))
    assert f'<img src="data:image/png;base64,{base64.b64encode(data).decode()}" alt="The start page">' in \
        lesson.steps[0].html


@pytest.mark.parametrize(("target", "reason"), [
    ("http://example.com/logo.png", "images come only from the lesson's folder or egtviz's assets"),
    ("https://example.com/a.png", "an address or a path is not shown"),
    ("//example.com/a.png", "an address or a path is not shown"),
    ("data:image/png;base64,iVBORw0KGgo=", "an address or a path is not shown"),
    ("/etc/passwd", "an address or a path is not shown"),
    ("../secret.png", "an address or a path is not shown"),
    ("sub/rig.png", "an address or a path is not shown"),
    ("rig.svg", "expected a .png, .jpg, .jpeg, .gif, .webp file"),
    ("missing.png", "no such file in the lesson's folder or egtviz's assets"),
])
def test_egtviz_check_refuses_any_other_image_at_its_line(tmp_path, target, reason):
    (tmp_path / "rig.svg").write_text("<svg/>")
    path = lesson_file(tmp_path, f"An image: ![logo]({target})")
    message = check_file(str(path))
    assert message is not None and message.startswith(f"{path}:{IMAGE_LINE}: steps[0].text: image ")
    assert reason in message


def test_a_link_leading_out_of_the_folder_a_fake_and_a_huge_image_are_refused(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.png").write_bytes(png())
    folder = tmp_path / "course"
    folder.mkdir()
    (folder / "link.png").symlink_to(outside / "secret.png")
    (folder / "fake.png").write_text("not an image")
    (folder / "huge.png").write_bytes(png() + b"\0" * (1_000_001 - len(png())))
    for name, reason in (("link.png", "a symbolic link leading out of its folder"), ("fake.png", "not a PNG file"),
                         ("huge.png", "1,000,001 bytes, more than the 1,000,000-byte limit")):
        with pytest.raises(LessonError) as info:
            load_lesson(lesson_file(folder, f"![x]({name})"))
        assert (info.value.line, info.value.reason) == (IMAGE_LINE, f"steps[0].text: image '{name}': {reason}")


def test_the_images_of_a_lesson_are_bounded_in_all(tmp_path):
    (tmp_path / "big.png").write_bytes(png() + b"\0" * 900_000)
    text = "\n\n".join(["![x](big.png)"] * 5)
    with pytest.raises(LessonError, match=r"image 'big.png': the lesson's images come to more than 4,000,000 bytes"):
        load_lesson(lesson_file(tmp_path, text))
    text = "\n\n".join(["![x](big.png)"] * 4)
    assert load_lesson(lesson_file(tmp_path, text)).steps[0].html.count("data:image/png") == 4


def test_images_in_prompts_and_unreadable_image_syntax_are_refused():
    with pytest.raises(MarkupError, match="only a step's text shows images"):
        render_markdown("See ![x](rig.png).")  # a task's prompt or hint: no image source
    with pytest.raises(MarkupError, match="an image egtviz cannot show"):
        render_markdown("See ![x](http://e.com/a(1).png) or ![y][ref].")
    assert render_markdown(r"Wow\![x]") == "Wow&#33;&#91;x&#93;"  # an escaped "!" is an exclamation mark


def test_links_of_every_kind_are_plain_text():
    out = render_markdown("[click](data:text/html,<b>hi</b>) [site](http://e.com) <http://e.com> "
                          "http://e.com https://e.com www.e.com mail a@b.co\n\n[ref]: http://e.com\n[ref]")
    assert "[" not in out and "]" not in out  # no link, no reference definition, no image can be written
    assert "<b>" not in out and "&lt;http" in out
    assert "http<span></span>://e.com" in out and "https<span></span>://e.com" in out
    assert "www<span></span>.e.com" in out and "a<span></span>@b.co" in out


def test_code_shows_image_and_link_syntax_as_characters():
    out = render_markdown("Code `![x](/etc/passwd)` and\n\n```text\n![y](/dev/zero) [z](http://e.com)\n```\n")
    assert "![" not in out and "](" not in out
    assert "<code>&#33;&#91;x&#93;&#40;&#47;etc&#47;passwd&#41;</code>" in out
    assert out.endswith("<pre><code>&#33;&#91;y&#93;&#40;&#47;dev&#47;zero&#41; &#91;z&#93;&#40;http<span></span>"
                        "&#58;&#47;&#47;e&#46;com&#41;</code></pre>\n")


def test_a_formulas_text_cannot_hold_a_link_or_an_image():
    out = render_markdown(r"$\text{see www.e.com ![x](/etc/passwd)}$")
    assert "![" not in out and "www<span></span>.e.com" in out


def test_viser_reads_no_file_and_fetches_nothing_for_a_step(tmp_path, monkeypatch):
    """viser's Markdown handle reads every ``![...](path)`` of a text from the server's disk (relative to its
    own package without an ``image_root``): none may reach it but the ``data:`` images egtviz embedded."""
    import imageio.v3 as iio
    import viser

    reads = []
    monkeypatch.setattr(iio, "imread", lambda path, *a, **k: reads.append(str(path)))
    (tmp_path / "rig.png").write_bytes(png())
    text = ("![rig](rig.png) `![x](/etc/passwd)` $\\text{![y](/etc/hosts)}$ [z](/etc/group)\n\n"
            "```\n![w](/dev/zero)\n```")
    lesson = load_lesson(lesson_file(tmp_path, text))
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        handle = server.gui.add_markdown(lesson.steps[0].html)
        handle.content = lesson.steps[0].html
    finally:
        server.stop()
    assert reads == []

"""The classroom's viewer side without a browser: its links and QR code, the HTML it shows (names as text), the
token kept out of logs, and ``egtviz serve --classroom``'s two URLs (a real subprocess)."""

from __future__ import annotations

import logging
import os
import re
import signal
import subprocess
import sys
import urllib.request
import xml.etree.ElementTree as ET

import pytest

from egtviz.classroom import Histogram, RosterRow
from egtviz.controllers.class_state import answers_view, roster_lines
from egtviz.viewer.classroom.links import (
    INSTRUCTOR_PREFIX, instructor_url, qr_svg, qr_terminal, shown_url, token_from_path,
)
from egtviz.viewer.classroom.room_html import histogram_html, pause_html, roster_html, student_status_html

from _subprocesses import Printed
from _waiting import PATIENCE, wait_for

TOKEN = "abcdefghijklmnop-0123456789_XYZ"


@pytest.mark.parametrize(("path", "want"), [
    ("/", None),
    ("/?egtviz-instructor=" + TOKEN, None),  # a query never reaches the server's websocket: not a way in
    (f"{INSTRUCTOR_PREFIX}/{TOKEN}", TOKEN),
    (f"{INSTRUCTOR_PREFIX}/{TOKEN}/", TOKEN),
    (f"{INSTRUCTOR_PREFIX}/{TOKEN}?websocket=x", TOKEN),
    (INSTRUCTOR_PREFIX, ""),
    (f"{INSTRUCTOR_PREFIX}x/{TOKEN}", None),
    (f"/lessons{INSTRUCTOR_PREFIX}/{TOKEN}", None),
])
def test_the_token_is_read_from_the_path_only(path, want):
    assert token_from_path(path) == want


def test_links_and_qr_code():
    url = instructor_url("http://127.0.0.1:8080/", TOKEN)
    assert url == f"http://127.0.0.1:8080{INSTRUCTOR_PREFIX}/{TOKEN}"
    assert token_from_path(url.removeprefix("http://127.0.0.1:8080")) == TOKEN
    assert TOKEN not in shown_url(url, TOKEN) and shown_url(url, TOKEN).endswith("abcd\u2026")
    text = qr_terminal("http://192.168.1.20:8080")
    rows = text.splitlines()
    import segno

    size = segno.make("http://192.168.1.20:8080", error="m").symbol_size()[0]  # modules with the quiet zone
    assert len(rows) == (size + 1) // 2 and all(len(r) == size for r in rows)
    svg = ET.fromstring(qr_svg("http://192.168.1.20:8080", max_px=300))
    assert svg.tag.endswith("svg") and svg.get("viewBox") == f"0 0 {size} {size}" and svg.get("width") == "100%"
    assert "max-width:300px" in svg.get("style")


def _cells(html: str) -> list[ET.Element]:
    return list(ET.fromstring(html).iter("td"))


def test_names_are_text_in_the_roster_and_the_bar():
    rows = [RosterRow("<b>Bob</b>", True, True, "01-frames", 2, 1, 4),
            RosterRow('x" onmouseover="alert(1)', False, False, None, None, 0, 0)]
    html = roster_html(roster_lines(rows))
    root = ET.fromstring(html)
    assert root.get("data-rows") == "2"
    assert [c.text for c in _cells(html)] == ["<b>Bob</b>", "1/4", "following · 01-frames · step 3",
                                              'x" onmouseover="alert(1)', "0", "away"]
    assert [c.text for c in _cells(roster_html(roster_lines(rows, {"01-frames": 1})))][2] == "following · lesson 1 · step 3"
    assert not list(root.iter("b")) and all(tr.get("onmouseover") is None for tr in root.iter("tr"))
    bar = ET.fromstring(student_status_html("<i>Eve</i>", True, "Is <F> rank 2?"))
    assert "".join(bar.itertext()).startswith("<i>Eve</i> ·") and "Is <F> rank 2?" in "".join(bar.itertext())
    assert not list(bar.iter("i"))
    assert "".join(ET.fromstring(pause_html("<script>x</script>")).itertext()) == "<script>x</script>"


def test_the_histogram_counts_and_hides_names_unless_asked():
    hist = Histogram("where is e1?", (100.0, 110.0, 120.0), (2, 1), (("left", 3),), 6, 4)
    root = ET.fromstring(histogram_html(answers_view(hist)))
    bars = [int(b.get("data-count")) for b in root.iter("{http://www.w3.org/2000/svg}rect")]
    assert bars == [2, 1, 3] and root.get("data-n") == "6"
    assert "Bob" not in "".join(root.itertext())
    named = ET.fromstring(histogram_html(answers_view(hist, {"<b>Bob</b>": 110.0, "Ann": "left"})))
    items = ["".join(li.itertext()) for li in named.iter("li")]
    assert items == ["<b>Bob</b>: 110", "Ann: left"]  # by name, case folded


def test_the_token_is_shortened_in_every_log_record(caplog):
    import viser

    from egtviz.classroom import Classroom
    from egtviz.viewer.classroom import ClassroomHost
    from egtviz.viewer.server.guard import install_guards
    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        install_guards(server)
        host = ClassroomHost(EgtvizApp(server, None, field_delay=0.0), Classroom(token=TOKEN))
        with caplog.at_level(logging.INFO):
            logging.getLogger("websockets.server").info("GET %s", instructor_url("http://h:1", TOKEN))
        host.close()
        with caplog.at_level(logging.INFO):
            logging.getLogger("websockets.server").info("after %s", TOKEN)  # the host is gone: no filter left
    finally:
        server.stop()
    assert TOKEN not in caplog.records[0].getMessage() and "abcd\u2026" in caplog.records[0].getMessage()
    assert TOKEN in caplog.records[1].getMessage()


def test_serve_classroom_prints_the_student_url_its_qr_code_and_the_instructor_url_once():
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "COLUMNS": "120"}
    proc = subprocess.Popen([sys.executable, "-m", "egtviz.cli", "serve", "--classroom", "--port", "0",
                             "--scene", "default"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    printed = Printed(proc)
    try:
        printed.wait_line("instructor (keep this secret)", "egtviz serve --classroom to print the instructor's URL")
        text = "".join(printed.out)
        instructor = re.search(r"instructor \(keep this secret\) (\S+)", text).group(1)
        student = re.search(r"students open (\S+)", text).group(1)
        token = instructor.rsplit("/", 1)[1]
        assert instructor == f"{student}{INSTRUCTOR_PREFIX}/{token}" and len(token) >= 16
        assert "\u2588" in text  # the QR code's blocks
        # The instructor's page is served (the same page as the student's); the token is checked on connect.
        page = urllib.request.urlopen(instructor, timeout=PATIENCE).read()
        assert page == urllib.request.urlopen(student, timeout=PATIENCE).read()
        proc.send_signal(signal.SIGINT)
        out, err = printed.finish("egtviz serve --classroom to stop on Ctrl-C")
    finally:
        printed.kill()
    everything = out + err
    assert everything.count(token) == 1, everything


@pytest.mark.parametrize(("typed", "value"), [("12", 12.0), (" 1,5 ", 1.5), ("-3e2", -300.0),
                                              ("parallel", "parallel"), (" e1 is left ", "e1 is left"),
                                              ("14_85", "14_85"), ("nan", "nan"), ("1e400", "1e400"),
                                              ("0x0E", "0x0E"), ("14.85.3", "14.85.3"), (".5", 0.5)])
def test_an_answer_is_a_number_when_it_reads_as_one(typed, value):
    from egtviz.controllers.class_text import typed_answer

    assert typed_answer(typed) == value


@pytest.mark.parametrize("typed", ["", "   ", None, 3])
def test_an_empty_answer_is_refused(typed):
    from egtviz.controllers.class_text import ClassRefusal, typed_answer

    with pytest.raises(ClassRefusal, match="type it first"):
        typed_answer(typed)


def test_the_page_under_the_instructor_prefix_and_the_handshake_path():
    import urllib.error

    import viser

    from egtviz.viewer.server.guard import handshake_of, install_guards, serve_page_under
    from egtviz.viewer.server.headless import FakeTab

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        install_guards(server)
        with pytest.raises(ValueError, match="prefix"):
            serve_page_under(server, "egtviz-instructor/")
        serve_page_under(server, INSTRUCTOR_PREFIX)
        base = f"http://127.0.0.1:{server.get_port()}"
        page = urllib.request.urlopen(base + "/", timeout=PATIENCE).read()
        for path in (f"{INSTRUCTOR_PREFIX}/{TOKEN}", f"{INSTRUCTOR_PREFIX}/{TOKEN}/", f"{INSTRUCTOR_PREFIX}/"):
            assert urllib.request.urlopen(base + path, timeout=PATIENCE).read() == page
        for path in (f"{INSTRUCTOR_PREFIX}/a/../../pyproject.toml", f"{INSTRUCTOR_PREFIX}x/{TOKEN}"):
            with pytest.raises(urllib.error.HTTPError, match="404"):
                urllib.request.urlopen(base + path, timeout=PATIENCE)
        student = FakeTab(server.get_port())
        wait_for(lambda: server.get_clients(), "the headless tab to connect")
        (cid,) = server.get_clients()
        shake = handshake_of(server, cid)
        assert shake is not None and shake.path == "/" and shake.peer == "127.0.0.1"
        student.close()
        assert handshake_of(server, 10_000) is None
    finally:
        server.stop()

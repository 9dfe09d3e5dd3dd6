"""A panel's or the read-out's text goes to the tab as viser's own assignment sends it, and the same text not again.

``viser_adapter.assign_text`` skips viser's type-hint casts on the drag path; it must queue the very message the
public ``handle.content = text`` queues, keep what the handle reads back, and fall back to the public path where
that path does more (a Python property, a removed handle).
"""

from __future__ import annotations

import pytest
import viser

from egtviz.viewer.server import viser_adapter
from egtviz.viewer.server.viser_adapter import assign_text


@pytest.fixture
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def _recorded(handle, monkeypatch):
    sent = []
    interface = handle._impl.gui_api._websock_interface
    monkeypatch.setattr(interface, "queue_message", lambda message: sent.append(message))
    return sent


def test_text_is_queued_as_the_public_assignment_queues_it(server, monkeypatch):
    fast, public = server.gui.add_html("a"), server.gui.add_html("a")
    sent = _recorded(fast, monkeypatch)  # the server's one GUI interface: both handles queue through it
    for text in ("<svg>1</svg>", "<svg>1</svg>", "<svg>2</svg>", "", "<b>é</b>"):
        changed = fast.content != text
        assert assign_text(fast, "content", text) == changed
        public.content = text
        assert fast.content == public.content == text
    sent_fast = [m for m in sent if m.uuid == fast._impl.uuid]
    sent_public = [m for m in sent if m.uuid == public._impl.uuid]
    assert len(sent_fast) + len(sent_public) == len(sent)
    assert [(type(m), m.updates) for m in sent_fast] == [(type(m), m.updates) for m in sent_public]
    assert [m.updates["content"] for m in sent_fast] == ["<svg>1</svg>", "<svg>2</svg>", "", "<b>é</b>"]


def test_the_public_path_is_taken_where_it_does_more(server, monkeypatch):
    md = server.gui.add_markdown("a")  # content is a Python property: it also parses the markdown
    assign_text(md, "content", "**b**")
    assert md.content == "**b**"
    html = server.gui.add_html("a")
    html.remove()
    with pytest.raises(RuntimeError):  # as viser refuses a write to a removed element
        assign_text(html, "content", "c")
    monkeypatch.setattr(viser_adapter, "FAST_PATH", False)
    other = server.gui.add_html("a")
    sent = _recorded(other, monkeypatch)
    assert assign_text(other, "content", "d") and other.content == "d" and len(sent) == 1

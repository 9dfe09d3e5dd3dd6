"""The real-browser tests' shared Chromium: one launch per test file (closed with the file, by the suite's
``conftest.py``: playwright's event loop must not outlive it in a process that runs other files next), whose pages and contexts wait :data:`_waiting.PATIENCE` by default for what they wait for, and never
show viser's software-WebGL notification (no GPU here: it would come seconds after each page loads, over the
window's corner, and a test would wait for it to close it).

A test opens its own pages or contexts (each context has its own storage) and closes them; the browser itself is
shared, since launching it costs each test a second or more (several on a loaded machine). It is
:func:`~egtviz.viewer.server.browser.shared_chromium`'s, which a browser test outside this folder gets too
(playwright's sync API runs one instance per thread at a time).
"""

from __future__ import annotations

import pytest

from _waiting import PATIENCE_MS
from egtviz.viewer.server.browser import close_shared_chromium, shared_chromium


@pytest.fixture(scope="module")
def browser():
    """A launched headless Chromium (:class:`~egtviz.viewer.server.browser.PatientBrowser`)."""
    yield shared_chromium(timeout_ms=PATIENCE_MS, quiet=True)
    close_shared_chromium()

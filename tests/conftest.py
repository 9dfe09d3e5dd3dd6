"""Test-suite settings: hypothesis without wall-clock deadlines (CI machines are shared), derandomised in CI;
EGT figures kept in memory (an example script run by a test must not start a server and wait for Ctrl-C; a test
that wants the server sets ``EGTVIZ_FIGURE=on``); the real-browser tests (marked ``browser``) skipped on a
developer machine without Chromium, and a failure in CI, where ``bash .ci/run`` installs it."""

import os
import sys

import pytest
from hypothesis import settings

settings.register_profile("egtviz", deadline=None, print_blob=True)
settings.register_profile("egtviz-ci", deadline=None, print_blob=True, derandomize=True)
settings.load_profile("egtviz-ci" if os.environ.get("CI") else "egtviz")
os.environ.setdefault("EGTVIZ_FIGURE", "off")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    browser_tests = [item for item in items if item.get_closest_marker("browser")]
    if not browser_tests:
        return
    from egtviz.viewer.server.browser import CHROMIUM, chromium_available

    if chromium_available():
        return
    why = f"headless Chromium ({CHROMIUM}) or the playwright package is missing (bash .ci/run installs both)"
    if os.environ.get("CI"):
        raise pytest.UsageError(f"CI: {why}; the browser tests must run")
    for item in browser_tests:
        item.add_marker(pytest.mark.skip(reason=why))


@pytest.fixture(autouse=True, scope="module")
def _no_browser_left_running():
    """A test file's shared Chromium ends with the file: playwright's sync API keeps an event loop in the thread
    that started it, and the next file run by the same process (``pytest-xdist`` gives each process many) may
    start an ``asyncio.run`` of its own there."""
    yield
    browser = sys.modules.get("egtviz.viewer.server.browser")
    if browser is not None:
        browser.close_shared_chromium()

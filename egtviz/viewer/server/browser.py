"""Headless Chromium helpers (playwright) shared by the browser tests, the screenshot and the benchmark.

Chromium is Debian's ``/usr/bin/chromium``; playwright's own browser download
is not needed.
"""

from __future__ import annotations

import os
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

CHROMIUM = os.environ.get("EGTVIZ_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
PANEL_SELECTOR = 'svg[data-egtviz="image-plane"]'

#: Counts of ``data-kind`` elements per panel, read in the page.
COUNT_JS = """() => Object.fromEntries([...document.querySelectorAll('svg[data-egtviz="image-plane"]')].map(
  s => [s.dataset.camera, {
    rev: s.dataset.rev,
    point: s.querySelectorAll('[data-kind="point"]').length,
    epipole: s.querySelectorAll('[data-kind="epipole"]').length,
    line: s.querySelectorAll('[data-kind="epipolar-line"]').length,
    conic: new Set([...s.querySelectorAll('[data-kind="epipolar-conic"]')].map(e => e.dataset.index)).size,
    border: s.querySelectorAll('[data-kind="border"]').length,
    rim: s.querySelectorAll('[data-kind="rim"]').length,
    message: [...s.querySelectorAll('[data-kind="message"]')].map(e => e.textContent),
    rect: s.getBoundingClientRect().toJSON(),
  }]))"""

#: The epipolar lines of one panel as [[x1, y1, x2, y2], ...].
LINES_JS = """(camera) => [...document.querySelectorAll(
  `svg[data-egtviz="image-plane"][data-camera="${camera}"] [data-kind="epipolar-line"]`)].map(
  e => ['x1', 'y1', 'x2', 'y2'].map(k => parseFloat(e.getAttribute(k))))"""


def chromium_available() -> bool:
    """Debian's Chromium and the playwright driver (a test extra: ``pip install -e '.[test]'``) are both here."""
    import importlib.util

    has_browser = Path(CHROMIUM).exists() or shutil.which(CHROMIUM) is not None
    return has_browser and importlib.util.find_spec("playwright") is not None


@contextmanager
def chromium() -> Iterator[Any]:
    """A launched headless Chromium (playwright ``Browser``)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


def open_viewer(browser: Any, url: str, *, width: int = 1600, height: int = 900, n_panels: int = 2,
                timeout_ms: float = 60_000) -> Any:
    """A new page on ``url``, returned once ``n_panels`` image-plane panels are in the DOM."""
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url)
    page.wait_for_function(
        f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= {n_panels}", timeout=timeout_ms
    )
    return page


def close_notifications(page: Any) -> None:
    """Dismiss Chromium's "software WebGL" toast before a screenshot."""
    try:
        button = page.locator("#webgl-software-rendering button.mantine-Notification-closeButton")
        button.wait_for(timeout=8000)
        # A DOM click: software WebGL keeps the page too busy for playwright's actionability checks.
        page.evaluate("document.querySelector('#webgl-software-rendering button').click()")
    except Exception:  # noqa: BLE001 - no toast (hardware WebGL) or already gone
        pass


def folder_field(page: Any, folder: str, label: str) -> Any:
    """The text box of field ``label`` inside the GUI folder titled ``folder``, opening the folder if it is closed
    (the first two cameras' folders start open, the others closed)."""
    field = page.locator(f'xpath=//*[normalize-space(text())="{folder}"]/following::label['
                         f'normalize-space(.)="{label}"][1]/following::input[1]').first
    if not field.is_visible():
        page.get_by_text(folder).first.click()
    field.wait_for(state="visible", timeout=10_000)
    return field


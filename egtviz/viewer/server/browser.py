"""Headless Chromium helpers (playwright) shared by the browser tests, the screenshot and the benchmark.

Chromium is Debian's ``/usr/bin/chromium``; playwright's own browser download
is not needed.
"""

from __future__ import annotations

import os
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Literal, Sequence, TypeVar

if TYPE_CHECKING:  # playwright is a test extra: imported where a browser is launched
    from playwright.sync_api import Browser, BrowserContext, Frame, JSHandle, Locator, Page, Playwright

    _Target = TypeVar("_Target", "Page", "BrowserContext")

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


#: An init script that hides viser's "Software WebGL rendering detected" notification (a machine without a GPU
#: shows it some seconds after the page loads, over whatever is in the window's corner) and marks the page so
#: that :func:`close_notifications` need not wait for it.
HIDE_SOFTWARE_WEBGL_NOTICE_JS = """(() => {
  window.__egtvizToastClosed = true;
  const hide = () => { const s = document.createElement('style');
    s.textContent = '#webgl-software-rendering { display: none !important; }';
    document.head.appendChild(s); };
  if (document.head) hide(); else document.addEventListener('DOMContentLoaded', hide);
})();"""


class PatientBrowser:
    """A launched playwright ``Browser`` whose new pages and contexts wait ``timeout_ms`` by default (playwright's
    own default is 30 s: too short on a loaded machine, where every step is many times slower).

    With ``quiet`` their pages never show the software-WebGL notification (:data:`HIDE_SOFTWARE_WEBGL_NOTICE_JS`).
    Everything else is the browser's own (attribute access is passed through).
    """

    def __init__(self, browser: Browser, timeout_ms: float, *, quiet: bool = False) -> None:
        self._browser = browser
        #: The default timeout of every page and context made here (ms); :func:`open_viewer` reads it too.
        self.timeout_ms = timeout_ms
        self.quiet = quiet

    def _patient(self, target: _Target) -> _Target:
        target.set_default_timeout(self.timeout_ms)
        target.set_default_navigation_timeout(self.timeout_ms)
        return target

    def _context(self, context: BrowserContext) -> BrowserContext:
        if self.quiet:
            context.add_init_script(HIDE_SOFTWARE_WEBGL_NOTICE_JS)
        return self._patient(context)

    # The keywords are playwright's own (``viewport``, ``locale``, ...), passed on unread.
    def new_context(self, **kwargs: Any) -> BrowserContext:
        return self._context(self._browser.new_context(**kwargs))

    def new_page(self, **kwargs: Any) -> Page:
        page = self._browser.new_page(**kwargs)
        self._context(page.context)
        return self._patient(page)

    def __getattr__(self, name: str) -> object:
        return getattr(self._browser, name)


@contextmanager
def chromium(*, timeout_ms: float | None = None, args: Sequence[str] = ()) -> Iterator[Browser | PatientBrowser]:
    """A launched headless Chromium (playwright ``Browser``).

    Args:
        timeout_ms: every new page's and context's default timeout (a :class:`PatientBrowser`); None keeps
            playwright's (30 s), as the screenshot scripts and the benchmark want.
        args: command-line switches added to :data:`CHROMIUM_ARGS`.
    """
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=[*CHROMIUM_ARGS, *args])
        try:
            yield browser if timeout_ms is None else PatientBrowser(browser, timeout_ms)
        finally:
            browser.close()


class _Shared:
    """The process's shared playwright instance (None: not started) and its browsers by their extra switches
    (:func:`shared_chromium`)."""

    playwright: Playwright | None = None
    browsers: dict[tuple[str, ...], Browser] = {}


_SHARED = _Shared()


def shared_chromium(*, timeout_ms: float, args: Sequence[str] = (), quiet: bool = False) -> PatientBrowser:
    """This process's launched headless Chromium with ``args``, started on first use and kept until
    :func:`close_shared_chromium` (or the process's exit): the test suite's, whose modules would otherwise each
    launch one (seconds each on a loaded machine), and whose helpers cannot each start playwright (its sync API
    runs one instance per thread at a time).

    Every call gets its own :class:`PatientBrowser` (``timeout_ms``, ``quiet``) on the shared browser. Call it from
    one thread (the one that first did).
    """
    from playwright.sync_api import sync_playwright

    playwright = _SHARED.playwright
    if playwright is None:
        playwright = _SHARED.playwright = sync_playwright().start()
        _SHARED.browsers = {}
        import atexit

        atexit.register(close_shared_chromium)
    browsers = _SHARED.browsers
    key = tuple(args)
    if key not in browsers or not browsers[key].is_connected():
        browsers[key] = playwright.chromium.launch(executable_path=CHROMIUM, args=[*CHROMIUM_ARGS, *key])
    return PatientBrowser(browsers[key], timeout_ms, quiet=quiet)


def close_shared_chromium() -> None:
    """Close the browsers of :func:`shared_chromium` and stop its playwright (nothing if none was started)."""
    playwright, browsers = _SHARED.playwright, _SHARED.browsers
    _SHARED.playwright, _SHARED.browsers = None, {}
    for browser in browsers.values():
        try:
            browser.close()
        except Exception:  # noqa: BLE001 - already gone (it crashed, or the driver stopped)
            pass
    if playwright is not None:
        playwright.stop()


def wait_for_js(page: Page | Frame, expression: str, what: str, *, arg: object = None,
                timeout_ms: float | None = None, polling: float | Literal["raf"] = "raf") -> JSHandle:
    """Wait until ``expression`` (a JS function of ``arg``) returns a truthy value in ``page`` (or a frame); that
    value's handle.

    Raises:
        TimeoutError: naming ``what`` was awaited, after ``timeout_ms`` (None: the page's default timeout).
    """
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    try:  # playwright takes a timeout of None as none given: the page's default
        return page.wait_for_function(expression, arg=arg, polling=polling, timeout=timeout_ms)
    except PlaywrightTimeout as exc:
        first = str(exc).splitlines()[0] if str(exc) else "timed out"
        raise TimeoutError(f"waited for {what}: {first}") from exc


def open_viewer(browser: Browser | PatientBrowser, url: str, *, width: int = 1600, height: int = 900,
                n_panels: int = 2, timeout_ms: float | None = None) -> Page:
    """A new page on ``url``, returned once ``n_panels`` image-plane panels are in the DOM.

    ``timeout_ms``: how long that may take (None: the browser's default if it is a :class:`PatientBrowser`,
    else 60 s).
    """
    if timeout_ms is None:
        timeout_ms = getattr(browser, "timeout_ms", None) or 60_000.0
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url, timeout=timeout_ms)
    wait_for_js(page, f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= {n_panels}",
                f"{n_panels} image-plane panels on {url}", timeout_ms=timeout_ms)
    return page


#: Whether the page's WebGL is drawn in software: viser's own test (``BrowserWarning.tsx``), after which it shows
#: its "Software WebGL rendering detected" notification.
SOFTWARE_WEBGL_JS = """() => {
  const gl = document.createElement('canvas').getContext('webgl2')
    || document.createElement('canvas').getContext('webgl');
  if (!gl) return false;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const renderer = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL) || '') : '';
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(renderer);
}"""


def close_notifications(page: Page, *, timeout_ms: float | None = None) -> None:
    """Dismiss Chromium's "software WebGL" toast (before a screenshot, or so that it covers nothing).

    The toast comes when the page's WebGL is drawn in software (:data:`SOFTWARE_WEBGL_JS`): then this waits for it
    (``timeout_ms``; None: the page's default timeout) and closes it; with hardware WebGL, or on a page of a quiet
    :class:`PatientBrowser` (where it is hidden), it returns at once.
    """
    try:
        if page.evaluate("() => window.__egtvizToastClosed === true") or not page.evaluate(SOFTWARE_WEBGL_JS):
            return
        button = page.locator("#webgl-software-rendering button.mantine-Notification-closeButton")
        if timeout_ms is None:
            button.wait_for(state="attached")
        else:
            button.wait_for(state="attached", timeout=timeout_ms)
        # A DOM click: software WebGL keeps the page too busy for playwright's actionability checks.
        page.evaluate("() => { document.querySelector('#webgl-software-rendering button').click();"
                      " window.__egtvizToastClosed = true; }")
    except Exception:  # noqa: BLE001 - the toast is cosmetic: a page without it carries on
        pass


#: True once the page's 3D view (its largest canvas) has drawn: at least ``minColours`` colours in a small copy
#: of it, the same copy as at the previous poll, and no CSS transition or animation running (the view fades in).
DRAWN_3D_JS = """(minColours) => {
  const canvases = [...document.querySelectorAll('canvas')];
  if (!canvases.length) return false;
  const c = canvases.reduce((a, b) => (a.width * a.height >= b.width * b.height ? a : b));
  const small = document.createElement('canvas');
  small.width = 64; small.height = 36;
  const g = small.getContext('2d');
  g.drawImage(c, 0, 0, small.width, small.height);
  const data = g.getImageData(0, 0, small.width, small.height).data;
  const colours = new Set();
  for (let i = 0; i < data.length; i += 4)
    colours.add((data[i] >> 4) << 8 | (data[i + 1] >> 4) << 4 | data[i + 2] >> 4);
  const sig = Array.from(data).join(',');
  const same = window.__egtvizLastDraw === sig;
  window.__egtvizLastDraw = sig;
  const moving = document.getAnimations().some(a => a.playState === 'running'
    && a.effect && a.effect.getComputedTiming().iterations !== Infinity);
  return same && !moving && colours.size >= minColours;
}"""


def wait_for_3d_view(page: Page | Frame, *, min_colours: int = 8, timeout_ms: float | None = None) -> None:
    """Wait until the page's 3D view has drawn and stopped changing (:data:`DRAWN_3D_JS`), polled every 0.25 s;
    the event a screenshot of it waits for, instead of a fixed sleep that a slow machine outlasts."""
    wait_for_js(page, DRAWN_3D_JS, "the 3D view drawn and still", arg=min_colours, timeout_ms=timeout_ms,
                polling=250)


def folder_field(page: Page, folder: str, label: str) -> Locator:
    """The text box of field ``label`` inside the GUI folder titled ``folder``, opening the folder if it is closed
    (the first two cameras' folders start open, the others closed)."""
    title = page.get_by_text(folder).first
    title.wait_for()  # drawn (open or closed) before its field is looked at: a click then never closes it
    field = page.locator(f'xpath=//*[normalize-space(text())="{folder}"]/following::label['
                         f'normalize-space(.)="{label}"][1]/following::input[1]').first
    if not field.is_visible():
        title.click()
    field.wait_for(state="visible")
    return field

"""``python -m egtviz.viewer.servo.servo_screenshot [pinhole|panoramic] [OUT.png] [--frac F] [--size WxH]``: a demo mid-run.

Starts an in-process server with the demo, opens it in headless Chromium (a window of ``W x H`` CSS pixels,
default 1366x768), waits for the run, shows the frame at ``F`` of the run (default 0.3) and saves the picture.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

SVG_SELECTOR = 'svg[data-egtviz="servo-image"]'


def take(kind: str, out: str | Path, *, frac: float = 0.3, width: int = 1366, height: int = 768) -> Path:
    import viser

    from ..tabs import EgtvizApp
    from ..server.browser import chromium, close_notifications

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, demo=kind)
        with chromium() as browser:
            page = browser.new_page(viewport={"width": width, "height": height})
            page.goto(f"http://127.0.0.1:{server.get_port()}")
            page.wait_for_selector(SVG_SELECTOR, timeout=60_000)
            demo = app.wait_for_demo()[0]
            demo.wait(60.0)
            demo.pause()
            demo.seek(int(frac * (demo.n_frames - 1)))
            rev = demo.revision
            page.wait_for_function(
                f"() => document.querySelector('{SVG_SELECTOR}')?.dataset.rev === '{rev}'", timeout=30_000)
            close_notifications(page)
            time.sleep(2.5)  # let the WebGL canvas and the plots settle
            out = Path(out)
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
            page.close()
    finally:
        server.stop()
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m egtviz.viewer.servo.servo_screenshot")
    p.add_argument("kind", choices=["pinhole", "panoramic"])
    p.add_argument("out", nargs="?", default=None)
    p.add_argument("--frac", type=float, default=0.3, help="where in the run (0..1)")
    p.add_argument("--size", default="1366x768", help="window size WxH in CSS pixels (default 1366x768)")
    a = p.parse_args(argv)
    try:
        width, height = (int(v) for v in a.size.lower().split("x"))
    except ValueError:
        p.error(f"--size: expected WxH, e.g. 1366x768, got {a.size!r}")
    if not (0.0 <= a.frac <= 1.0 and 200 <= width <= 4000 and 200 <= height <= 4000):
        p.error("--frac must be in [0, 1] and --size between 200x200 and 4000x4000")
    out = a.out or f"assets/screenshot-servo-{a.kind}.png"
    print(take(a.kind, out, frac=a.frac, width=width, height=height))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

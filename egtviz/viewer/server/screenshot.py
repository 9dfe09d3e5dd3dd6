"""Save a screenshot of the viewer: ``python -m egtviz.viewer.server.screenshot [--panoramic] [OUT.png]``.

Starts an in-process server on a free port, opens it in headless Chromium at
1600 x 900, selects point 3 (so its epipolar plane shows) and writes the PNG
(default ``assets/screenshot-default.png``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "assets" / "screenshot-default.png"


def take_screenshot(out: str | Path = DEFAULT_OUT, *, width: int = 1600, height: int = 900, browser=None,
                    scene=None) -> Path:
    """Write the PNG to ``out``.

    Args:
        browser: an already launched playwright browser (else one is started).
        scene: the scene to show (default: :func:`default_scene` with point 3 selected).
    """
    import viser

    from ...scene import default_scene
    from ..tabs import EgtvizApp
    from .browser import chromium, close_notifications, open_viewer

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, scene if scene is not None else default_scene().replace(selected_point=2))
        def shoot(b) -> None:
            page = open_viewer(b, f"http://127.0.0.1:{server.get_port()}", width=width, height=height)
            close_notifications(page)
            time.sleep(6.0)  # let the 3D view settle and fade in (software WebGL is slow)
            page.screenshot(path=str(out))
            page.close()

        if browser is not None:
            shoot(browser)
        else:
            with chromium() as b:
                shoot(b)
        del app
    finally:
        server.stop()
    return out


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    scene = None
    if "--panoramic" in argv:
        from ...scene import panoramic_scene

        argv.remove("--panoramic")
        scene = panoramic_scene().replace(selected_point=2)
    out = take_screenshot(argv[0] if argv else DEFAULT_OUT, scene=scene)
    print(f"screenshot written to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

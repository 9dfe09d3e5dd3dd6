"""Viewer latency: server time per gizmo event, and browser time from the update to the changed SVG.

Method (also in ``docs/viewer.md``):

* **Server.** A real :class:`viser.ViserServer` on a free local port, the app,
  and one connected tab (a websocket client that drains messages, so viser
  really serialises and sends every update). Each event moves camera 1's gizmo
  by 1 cm exactly as viser does before it runs our callback (the handle's
  pose and timestamp are set, then ``on_update`` fires); the time is measured
  from the callback's entry to the exit of the ``client.atomic()`` block that
  carries the 3D scene, the panels, the read-out and the fields. 200 events,
  5 ms apart, each to a new place (no cached result is reused); p50 and p99.
  Scenes (:data:`SCENES`): the default pin-hole pair, the panoramic pair (the
  targets), four cameras (a third pin-hole and a unified camera beside the
  drawn pair) and a pin-hole / unified pair; 8 and 200 points.
* **Server CPU per drag update.** :mod:`egtviz.bench.classroom` with :data:`CPU_TABS` raw websocket tabs
  dragging camera 1 of the default pin-hole and panoramic scenes at 20 Hz: the server process's CPU time
  over the drag divided by the updates it applied, with its parts; and the floor under it
  (:mod:`egtviz.bench.viser_floor`: a bare viser server receiving the same number of updates a second).
* **Browser.** The same with headless Chromium as the tab. Each update gives
  the SVGs a new ``data-rev``; a ``MutationObserver`` in the page records
  ``performance.timeOrigin + performance.now()`` when an SVG with a new
  revision enters the DOM. The server records ``time.time()`` at the end of
  the atomic update for that revision. Both clocks are the same machine's
  wall clock, so the difference is the time from the end of the server update
  to the changed SVG in the page (websocket, decoding, React). 60 events,
  150 ms apart; median. Measured with the 3D view drawn, with its canvas
  hidden, and with the 3D view drawn but 30 updates 0.6 s apart. Without a GPU
  Chromium draws WebGL in software (SwiftShader) and every frame blocks the
  page's main thread for 30-100 ms; viser keeps drawing for 250 ms after each
  change, so during a drag the panels' update waits behind a frame. The hidden
  figure is the panel path alone; the spaced one is an update that finds the
  page idle (a field edit).
"""

from __future__ import annotations

import time
import types
from typing import Any

import numpy as np

EVENTS = 200
#: Tabs dragging at once, and seconds they drag, for the server CPU per drag update.
CPU_TABS = 5
CPU_SECONDS = 5.0
BROWSER_EVENTS = 60
#: (hide the 3D view, seconds between updates, label): a drag with the 3D view drawn and hidden, and
#: updates far enough apart that the page has stopped drawing (a field edit).
BROWSER_MODES = (
    (False, 0.15, "3D view drawn"),
    (True, 0.15, "3D view hidden"),
    (False, 0.6, "3D view drawn, one update at a time"),
)

_OBSERVER_JS = """() => {
  window.__egtRev = {};
  const seen = new Set();
  const scan = () => {
    const now = performance.timeOrigin + performance.now();
    for (const s of document.querySelectorAll('svg[data-egtviz="image-plane"]')) {
      const key = s.dataset.camera + '@' + s.dataset.rev;
      if (!seen.has(key)) { seen.add(key); window.__egtRev[key] = now; }
    }
  };
  scan();
  new MutationObserver(scan).observe(document.body, {subtree: true, childList: true, attributes: true});
}"""


def _four_cameras() -> Any:
    """The default pair, a third pin-hole and a unified camera; cam1 & cam2 drawn."""
    from ..scene import SceneModel, default_scene

    model = SceneModel(default_scene())
    model.add_camera("pinhole")
    model.add_camera("unified")
    return model.scene


def _unified_pair() -> Any:
    """cam1 of the default scene and a unified camera, drawn as the pair."""
    from ..scene import SceneModel, default_scene

    model = SceneModel(default_scene())
    uni = model.add_camera("unified")
    model.set_pair("cam1", uni)
    model.remove_camera("cam2")
    return model.scene


#: The viewer bench's scenes: label -> factory. The first two are the servers' targets.
SCENES = (("pin-hole", "default_scene"), ("panoramic", "panoramic_scene"), ("4 cameras", _four_cameras),
          ("unified", _unified_pair))


def _scenes(n_points: int) -> dict[str, Any]:
    from .. import scene as scenes
    from ..scene import SceneModel

    out = {}
    for label, factory in SCENES:
        model = SceneModel(getattr(scenes, factory)() if isinstance(factory, str) else factory())
        X = model.scene.points_array()
        model.randomize_points(n_points, seed=0, center=tuple(X.mean(axis=0)), extent=2.0)
        out[label] = model.scene
    return out


def _drag_event(gizmo: Any, position: np.ndarray) -> Any:
    """What viser does on a TransformControlsUpdateMessage before calling our callback."""
    from ..viewer.server.viser_adapter import gizmo_moved_by_client

    gizmo_moved_by_client(gizmo, position)
    return types.SimpleNamespace(target=gizmo, phase="update", client=None, client_id=None)


def _drive(view: Any, name: str, n: int, spacing: float) -> list[tuple[int, float, dict]]:
    """Drag camera ``name`` 2 mm further ``n`` times (always to a new place), ``spacing`` seconds apart.

    Returns ``(revision, wall time at the end of the update, its wall seconds by part)`` per applied update, from
    the view's timing hook (:attr:`~egtviz.viewer.workbench.app.ClientView.on_update_timed`).
    """
    gizmo = view.scene3d.gizmo(name)
    start = np.array(gizmo.position, float)
    out: list[tuple[int, float, dict]] = []
    view.on_update_timed = lambda t: out.append((t.revision, time.time(), dict(t.wall)))
    try:
        for k in range(n):
            view.drag.camera_event(name, _drag_event(gizmo, start + np.array([0.002 * k, 0.0, 0.0])))
            time.sleep(spacing)
    finally:
        view.on_update_timed = None
    return out


def server_latency(scene: Any, n: int = EVENTS, *, spacing: float = 0.005) -> dict[str, float]:
    """p50 / p99 (ms) from a gizmo event to the end of the atomic update, and the median breakdown.

    Each event moves the camera to a new place (no cached result is reused); ``spacing`` seconds apart.
    """
    from ..viewer.server.headless import start_headless

    server, _app, fakes, views = start_headless(scene)
    try:
        view = views[0]
        breakdown = [b for _, _, b in _drive(view, scene.cameras[0].name, n, spacing)]
        t = np.array([sum(b.values()) for b in breakdown]) * 1e3  # the parts run from the event to the flush
        parts = {k: float(np.median([b[k] for b in breakdown]) * 1e3) for k in breakdown[0]}
        return {"p50": float(np.percentile(t, 50)), "p99": float(np.percentile(t, 99)), **parts}
    finally:
        for f in fakes:
            f.close()
        server.stop()


def browser_latency(scene: Any, n: int = BROWSER_EVENTS, *, width: int = 1600, height: int = 900,
                    spacing: float = 0.15, hide_3d: bool = False) -> float | None:
    """Median ms from the end of the server update to the changed SVG in headless Chromium (None: no browser).

    ``hide_3d``: hide the 3D view's canvas (CSS ``visibility``), so that the
    figure is the panel path alone (websocket, decoding, React, the SVG parse)
    without the software-WebGL frames that share the page's main thread on a
    machine with no GPU.
    """
    import viser

    from ..viewer.tabs import EgtvizApp
    from ..viewer.server.browser import chromium, chromium_available, open_viewer

    if not chromium_available():
        return None
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, scene)
        with chromium() as browser:
            page = open_viewer(browser, f"http://127.0.0.1:{server.get_port()}", n_panels=len(scene.cameras),
                               width=width, height=height)
            view = app.wait_for_view()[0]
            if hide_3d:
                page.add_style_tag(content="canvas { visibility: hidden !important; }")
            page.evaluate(_OBSERVER_JS)
            time.sleep(1.0)
            name = scene.cameras[0].name
            revs = _drive(view, name, n, spacing=spacing)
            time.sleep(1.0)
            seen = page.evaluate("() => window.__egtRev")
            page.close()
        lat = []
        for rev, t_server, _ in revs:
            key = f"{name}@{rev}"
            if key in seen:
                lat.append(seen[key] - t_server * 1e3)
        return float(np.median(lat)) if lat else float("nan")
    finally:
        server.stop()


def server_cpu_rows(*, tabs: int = CPU_TABS, seconds: float = CPU_SECONDS) -> list[dict]:
    """Server CPU per drag update of the default pin-hole and panoramic pairs (:mod:`egtviz.bench.classroom`)."""
    from .classroom import RATE_HZ, run_classroom

    rows = []
    for label, scene in (("pin-hole", "default"), ("panoramic", "panoramic")):
        case = f"viewer server CPU per drag update, {label} pair ({scene} scene), {tabs} tabs at {RATE_HZ:g} Hz"
        try:
            run, _ = run_classroom(tabs, seconds=seconds, scene=scene)
        except Exception as exc:  # noqa: BLE001 - report, do not hide the other rows
            rows.append({"case": case, "ours_ms": float("nan"), "opencv_ms": None, "ratio": None,
                         "note": f"failed: {type(exc).__name__}: {exc}"})
            continue
        parts = ", ".join(f"{k} {v:.2f}" for k, v in run.parts_ms.items())
        rows.append({"case": case, "ours_ms": run.cpu_ms_per_update, "opencv_ms": None, "ratio": None,
                     "note": f"{run.applied} updates applied of {run.sent} sent; CPU ms per update: {parts}"})
    from .viser_floor import viser_floor

    rate = tabs * RATE_HZ
    case = f"viewer server CPU per drag update, the floor: bare viser, no-op gizmo callback, {rate:g} updates/s"
    try:
        floor = viser_floor(rate, seconds)
        rows.append({"case": case, "ours_ms": floor.cpu_ms_per_update, "opencv_ms": None, "ratio": None,
                     "note": f"{floor.callbacks} of {floor.sent} received; no egtviz code in the server"})
    except Exception as exc:  # noqa: BLE001 - report, do not hide the other rows
        rows.append({"case": case, "ours_ms": float("nan"), "opencv_ms": None, "ratio": None,
                     "note": f"failed: {type(exc).__name__}: {exc}"})
    return rows


def _case(label: str) -> str:
    return label if label == "4 cameras" else f"{label} pair"


def run_viewer_bench(events: int = EVENTS, browser: bool = True, *, cpu_seconds: float = CPU_SECONDS) -> list[dict]:
    """Rows ``{case, ours_ms, opencv_ms: None, ratio: None, note}`` for the scenes of :data:`SCENES`.

    The server's latency rows, then (``cpu_seconds > 0``) its CPU per drag update with :data:`CPU_TABS` tabs
    dragging for ``cpu_seconds``, then (``browser``) the browser's rows.
    """
    rows: list[dict] = []
    if cpu_seconds > 0:
        rows += server_cpu_rows(seconds=cpu_seconds)
    for n_points in (8, 200):
        for label, scene in _scenes(n_points).items():
            try:
                s = server_latency(scene, events)
            except Exception as exc:  # noqa: BLE001 - report, do not hide the other rows
                rows.append({"case": f"viewer server, {_case(label)}, {n_points} points", "ours_ms": float("nan"),
                             "opencv_ms": None, "ratio": None, "note": f"failed: {type(exc).__name__}: {exc}"})
                continue
            note = (f"median parts (ms): model {s['model']:.2f}, derived {s['derived']:.2f}, SVG {s['svg']:.2f}, "
                    f"fields {s['fields']:.2f}, 3D {s['scene3d']:.2f}, flush {s['flush']:.2f}")
            for q in ("p50", "p99"):
                rows.append({"case": f"viewer server, {_case(label)}, {n_points} points, gizmo event ({q})",
                             "ours_ms": s[q], "opencv_ms": None, "ratio": None, "note": note})
            if browser:
                for hide_3d, spacing, what in BROWSER_MODES:
                    try:
                        b = browser_latency(scene, n=BROWSER_EVENTS if spacing < 0.5 else BROWSER_EVENTS // 2,
                                            spacing=spacing, hide_3d=hide_3d)
                        note = "update -> changed SVG in headless Chromium (MutationObserver)"
                    except Exception as exc:  # noqa: BLE001
                        b, note = float("nan"), f"failed: {type(exc).__name__}: {exc}"
                    if b is not None:
                        rows.append({"case": f"viewer browser, {_case(label)}, {n_points} points, {what} (median)",
                                     "ours_ms": b, "opencv_ms": None, "ratio": None, "note": note})
    return rows


def main() -> int:
    from .runner import format_table

    print(format_table(run_viewer_bench()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

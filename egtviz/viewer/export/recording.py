"""A scene drawn once into viser and recorded: the 3D half of an exported page, playable without a server.

The scene is drawn by the workbench's own :class:`~egtviz.viewer.workbench.scene3d.Scene3D` into a viser server's
shared scene (no tab connects), with every camera's and point's gizmo locked (a static page cannot move them),
each camera's image panel as a picture standing above it (the panel's SVG rendered by resvg, as ``egtviz
figure`` does),
and the browser's first view framed on the scene as a tab's is. viser's scene serializer then records the
scene's messages, and :meth:`viser.infra.StateSerializer.as_html` puts them, base64-encoded, into a copy of
viser's client page (one self-contained HTML file shipped in viser's package: scripts, styles and assets
inline). The client plays an embedded recording without a server and without fetching anything, which is why
this form and not a ``.viser`` file beside the page (``?playbackPath=`` fetches the file, and a browser refuses
to fetch from a ``file://`` page).
"""

from __future__ import annotations

import contextlib
import io
import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # only named: the export imports viser and the scene layer when it records
    import viser

    from ...scene import Derived, Scene
    from ...scene.extent import SceneExtent

__all__ = ["PANEL_SCALE", "scene_page"]

#: Device pixels per CSS pixel of the panels' pictures (the panel's own width is the style's, about 400 px).
PANEL_SCALE = 1.5
#: Width of a panel's picture in the scene, in glyph lengths (the scene's own size unit, :class:`SceneExtent`).
PANEL_WIDTH_GLYPHS = 3.0
#: Aspect of the canvas the first view is framed for (the page's frame beside the text column).
CANVAS_ASPECT = 1.4


def _locked(scene: Scene) -> Scene:
    """The scene with every camera and point locked: the gizmos show no handles."""
    marks = set(scene.camera_names) | {f"point:{i}" for i in range(len(scene.points))}
    return scene.replace(locked=frozenset(marks) | scene.locked)


def _panel_picture(scene: Scene, camera: str) -> np.ndarray:
    """(H, W, 3) uint8 picture of ``camera``'s image panel as the figure export draws it."""
    import imageio.v3 as iio

    from ..render.figure_export import panel_svg, svg_to_png

    png = svg_to_png(panel_svg(scene, camera, fit=True), scale=PANEL_SCALE)
    picture = np.asarray(iio.imread(png, extension=".png"))
    return np.ascontiguousarray(picture[..., :3])


def _facing(toward: np.ndarray) -> tuple[float, float, float, float]:
    """Orientation (wxyz) of an upright picture whose face looks along the horizontal part of ``toward``."""
    from viser.transforms import SO3

    normal = np.array([toward[0], toward[1], 0.0])
    normal = normal / np.linalg.norm(normal) if np.linalg.norm(normal) > 1e-9 else np.array([0.0, -1.0, 0.0])
    up = np.array([0.0, 0.0, 1.0])
    # viser lays a picture in its node's x-y plane with the first row towards -y (image axes, as a camera's):
    # x to the viewer's right, y down, and so z away from the viewer.
    w, x, y, z = (float(q) for q in SO3.from_matrix(np.column_stack([np.cross(up, normal), -up, -normal])).wxyz)
    return w, x, y, z


def _panel_places(scene: Scene, derived: Derived,
                  extent: SceneExtent) -> list[tuple[str, np.ndarray, float, float, np.ndarray]]:
    """``(camera, picture, width, height, centre)`` of each camera's panel picture, standing over the camera's
    centre above everything in the scene (a mirror or a point would hide it)."""
    glyph = extent.glyph
    width = PANEL_WIDTH_GLYPHS * glyph
    floor = float(extent.hi[2]) + 0.3 * glyph
    places = []
    for camera in scene.camera_names:
        picture = _panel_picture(scene, camera)
        height = width * picture.shape[0] / picture.shape[1]
        x, y, z = (float(v) for v in derived.poses[camera][1])
        centre = np.array([x, y, max(z + 0.6 * glyph, floor) + height / 2.0])
        places.append((camera, picture, width, height, centre))
    return places


def _panel_reach(places: list[tuple[str, np.ndarray, float, float, np.ndarray]]) -> np.ndarray:
    """(8 N, 3) points a first view must see for every panel to be in it, whichever way the panel turns."""
    corners = [c + np.array([dx * w / 2.0, dy * w / 2.0, dz * h / 2.0])
               for _, _, w, h, c in places for dx in (-1, 1) for dy in (-1, 1) for dz in (-1, 1)]
    return np.array(corners).reshape(-1, 3)


def _add_panels(api: viser.SceneApi, places: list[tuple[str, np.ndarray, float, float, np.ndarray]],
                viewer: np.ndarray) -> None:
    """The panel pictures, upright, each facing the first view (see :func:`_panel_places`).

    They are not tied to a camera's image plane (a panoramic camera has no plane in the scene): they stand in
    the world so that the page's first view reads every one of them.
    """
    for k, (_camera, picture, width, height, centre) in enumerate(places):
        api.add_image(f"/egt/panel_{k}", picture, width, height, format="png", cast_shadow=False,
                      receive_shadow=False, wxyz=_facing(viewer - centre), position=tuple(centre))


def scene_page(scene: Scene) -> str:
    """viser's client page with ``scene`` recorded in it (see the module docstring).

    Args:
        scene: an :class:`egtviz.scene.Scene`.

    Returns:
        A standalone HTML document.
    """
    import viser

    from ...scene import compute_derived
    from ...scene.extent import scene_extent
    from ..render.panels import framed_camera
    from ..workbench.scene3d import Scene3D

    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner: no address here is meant to be opened
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        derived = compute_derived(scene)
        extent = scene_extent(scene, derived)
        drawn = Scene3D(server.scene, lambda *_: None, lambda *_: None)
        drawn.set_glyph(extent.glyph)
        drawn.draw(_locked(scene), derived, force=True)
        places = _panel_places(scene, derived, extent)
        seen = np.vstack([extent.points, _panel_reach(places)]) if places else extent.points
        framed = framed_camera(seen, CANVAS_ASPECT, pad=extent.glyph, min_radius=3.0 * extent.glyph)
        _add_panels(server.scene, places, np.asarray(framed.position, float))
        server.initial_camera.up = (0.0, 0.0, 1.0)
        server.initial_camera.position = framed.position
        server.initial_camera.look_at = framed.look_at
        server.initial_camera.fov = framed.fov if math.isfinite(framed.fov) else math.radians(60.0)
        return server.get_scene_serializer().as_html()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()

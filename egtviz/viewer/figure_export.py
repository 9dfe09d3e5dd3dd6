"""Image-plane panels as figure files: SVG, and PNG rendered without a browser; the ``egtviz figure`` command.

The numbers come from the scene layer (:func:`egtviz.scene.compute_derived`),
the drawing from :func:`egtviz.viewer.svg.image_plane_svg`; this module only
fixes the figure's size and renders it. PNGs are rendered by resvg
(``resvg-py``, a binary wheel: no system library, no browser) with the
DejaVu Sans fonts that matplotlib ships, so a figure looks the same on every
machine, fonts installed or not.

How the GUI uses it: ``panel_svg_of(plane, ...)`` for its "download SVG"
button (the panel it shows, with its view) and ``svg_to_png(svg)`` for
"download PNG". ``egtviz figure`` calls :func:`add_arguments` and :func:`run`::

    egtviz figure example3 --camera cam1 --out fig.png --present
    egtviz figure --scene my.json --camera left --out fig.svg --no-fit
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from .panel_view import ViewBox, fit_view
from .svg import NORMAL, PRESENT, image_plane_svg

__all__ = ["FIGURE_FORMATS", "add_arguments", "panel_svg", "panel_svg_of", "run", "svg_to_png"]

#: Output formats by file extension.
FIGURE_FORMATS = (".svg", ".png")

#: Background of exported figures (a slide or a paper is white).
FIGURE_BACKGROUND = "#ffffff"


def panel_svg_of(plane: Any, *, present: bool = False, view: ViewBox | None = None,
                 selected_point: int | None = None, show_labels: bool = True) -> str:
    """The SVG figure of one ``ImagePlane``: the panel's drawing with a fixed size in pixels.

    Args:
        plane: an :class:`egtviz.scene.ImagePlane`.
        present: presentation style (larger text, thicker lines) instead of the normal one.
        view: the part of the image plane shown (``None``: the image rectangle).
        selected_point: 0-based index of a point to draw selected.
        show_labels: write the point numbers.

    Returns:
        A standalone SVG document (``width``/``height`` in CSS pixels: the style's panel width).
    """
    style = PRESENT if present else NORMAL
    svg = image_plane_svg(plane, view=view, style=style, fixed_size=True, selected_point=selected_point,
                          show_labels=show_labels)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + svg + "\n"


def panel_svg(scene: Any, camera_name: str, *, present: bool = False, fit: bool = True) -> str:
    """The SVG figure of one camera's image plane in ``scene``.

    Args:
        scene: an :class:`egtviz.scene.Scene`.
        camera_name: the camera whose panel is drawn.
        present: presentation style.
        fit: show all the content (points outside the image, epipoles) as
            :func:`~egtviz.viewer.panel_view.fit_view` does; else the image rectangle.

    Raises:
        KeyError: no camera ``camera_name`` in the scene (the message lists the names).
    """
    from ..scene import compute_derived

    names = [c.name for c in scene.cameras]
    if camera_name not in names:
        raise KeyError(f"no camera {camera_name!r} in the scene (cameras: {', '.join(names) or 'none'})")
    plane = compute_derived(scene).image_planes[camera_name]
    return panel_svg_of(plane, present=present, view=fit_view(plane) if fit else None,
                        selected_point=scene.selected_point, show_labels=scene.options.show_labels)


def _font_dir() -> str:
    """matplotlib's bundled TrueType fonts (DejaVu Sans among them)."""
    import matplotlib

    return os.path.join(matplotlib.get_data_path(), "fonts", "ttf")


def svg_to_png(svg: str, *, scale: float = 2.0) -> bytes:
    """Render an SVG document to PNG bytes, ``scale`` device pixels per CSS pixel (2: sharp on slides).

    Raises:
        ValueError: ``scale`` is not in (0, 16], or the SVG cannot be parsed.
    """
    if not (0 < scale <= 16):
        raise ValueError(f"scale must be in (0, 16], got {scale}")
    import resvg_py

    png = resvg_py.svg_to_bytes(
        svg_string=svg, zoom=float(scale), background=FIGURE_BACKGROUND, skip_system_fonts=True,
        font_dirs=[_font_dir()], font_family="DejaVu Sans", sans_serif_family="DejaVu Sans",
    )
    return bytes(png)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``egtviz figure``: ``(--scene FILE | name) --camera NAME --out FILE [--present] [--no-fit]``."""
    src = parser.add_mutually_exclusive_group(required=True)
    src.add_argument("name", nargs="?", default=None, help="a built-in scene (see `egtviz scene list`)")
    src.add_argument("--scene", metavar="FILE", default=None, help="a scene file saved by egtviz")
    parser.add_argument("--camera", metavar="NAME", required=True, help="the camera whose image plane is drawn")
    parser.add_argument("--out", metavar="FILE", required=True, help="the figure: FILE.svg or FILE.png")
    parser.add_argument("--present", action="store_true", help="presentation style: large text, thick lines")
    parser.add_argument("--no-fit", dest="fit", action="store_false",
                        help="show the image rectangle only (default: fit all content, epipoles included)")
    parser.add_argument("--scale", type=float, default=2.0, help="PNG pixels per CSS pixel (default 2)")


def _fail(message: str) -> int:
    print(f"egtviz figure: {message}", file=sys.stderr)
    return 2


def run(args: argparse.Namespace) -> int:
    """Write the figure; 0 on success, 2 (with one line on stderr) for a bad scene, camera, extension or output."""
    from ..files import FileSafetyError, printable, write_atomic
    from ..scene import SCENES, SceneError, load_scene_file

    out = Path(args.out)
    ext = out.suffix.lower()
    if ext not in FIGURE_FORMATS:
        return _fail(f"{printable(args.out)}: unknown extension {printable(out.suffix) or '(none)'!s}; "
                     f"use {' or '.join(FIGURE_FORMATS)}")
    if not (0 < args.scale <= 16):
        return _fail(f"--scale must be in (0, 16], got {args.scale}")
    if args.scene is not None:
        try:
            scene = load_scene_file(args.scene)
        except (SceneError, OSError) as exc:
            return _fail(printable(exc))
    elif args.name in SCENES:
        scene = SCENES[args.name]()
    else:
        return _fail(f"no built-in scene {printable(args.name)!r} (have {', '.join(SCENES)}; a file needs --scene)")
    try:
        svg = panel_svg(scene, args.camera, present=args.present, fit=args.fit)
    except KeyError as exc:
        return _fail(printable(exc.args[0]))
    except SceneError as exc:
        return _fail(printable(exc))
    data = svg.encode("utf-8") if ext == ".svg" else svg_to_png(svg, scale=args.scale)
    try:
        write_atomic(out, data)
    except FileSafetyError as exc:
        return _fail(printable(exc))
    except OSError as exc:
        return _fail(f"{printable(args.out)}: cannot write: {exc.strerror or exc}")
    print(f"wrote {printable(args.out)}")
    return 0

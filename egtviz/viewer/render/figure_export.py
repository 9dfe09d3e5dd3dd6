"""Image-plane panels as figure files: SVG, and PNG rendered without a browser; the ``egtviz figure`` command.

The numbers come from the scene layer (:func:`egtviz.scene.compute_derived`),
the drawing from :func:`egtviz.viewer.render.svg.image_plane_svg`; this module only
fixes the figure's size and renders it. PNGs are rendered by resvg
(``resvg-py``, a binary wheel: no system library, no browser) with the
DejaVu Sans fonts that matplotlib ships, so a figure looks the same on every
machine, fonts installed or not.

How the GUI uses it: ``panel_svg_of(plane, ...)`` for its "download SVG"
button (the panel it shows, with its view); for "download PNG" it asks
:func:`png_refusal` whether the figure is small enough and has
:func:`svg_to_png` run in a worker process (:mod:`egtviz.viewer.render.png_worker`:
resvg holds the GIL for the whole render). ``egtviz figure`` calls
:func:`add_arguments` and :func:`run`, which renders in its own process::

    egtviz figure example3 --camera cam1 --out fig.png --present
    egtviz figure --scene my.json --camera left --out fig.svg --no-fit
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from pathlib import Path

from ...files import FileSafetyError, printable, write_atomic
from ...scene import SCENES, ImagePlane, Scene, SceneError, compute_derived, limits, load_scene_file
from .panel_view import ViewBox, fit_view
from .svg import NORMAL, PRESENT, image_plane_svg

__all__ = ["FIGURE_FORMATS", "add_arguments", "panel_svg", "panel_svg_of", "png_pixels", "png_refusal", "run",
           "svg_to_png"]

#: Output formats by file extension.
FIGURE_FORMATS = (".svg", ".png")

#: Background of exported figures (a slide or a paper is white).
FIGURE_BACKGROUND = "#ffffff"


def panel_svg_of(plane: ImagePlane, *, present: bool = False, view: ViewBox | None = None,
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


def panel_svg(scene: Scene, camera_name: str, *, present: bool = False, fit: bool = True) -> str:
    """The SVG figure of one camera's image plane in ``scene``.

    Args:
        scene: an :class:`egtviz.scene.Scene`.
        camera_name: the camera whose panel is drawn.
        present: presentation style.
        fit: show all the content (points outside the image, epipoles) as
            :func:`~egtviz.viewer.render.panel_view.fit_view` does; else the image rectangle.

    Raises:
        KeyError: no camera ``camera_name`` in the scene (the message lists the names).
    """
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


_ROOT_TAG = re.compile(r"<svg\b[^>]*>")
_START_TAG = re.compile(r"<[A-Za-z]")


def _root_length(root_tag: str, name: str) -> float | None:
    """The root's ``width`` or ``height`` in CSS pixels (a plain number or ``px``); None if absent or unreadable."""
    m = re.search(rf'\s{name}="([^"]*)"', root_tag)
    if m is None:
        return None
    try:
        value = float(m.group(1).strip().removesuffix("px"))
    except ValueError:
        return None
    return value if math.isfinite(value) and value > 0 else None


def png_pixels(svg: str, *, scale: float = 2.0) -> tuple[int, int] | None:
    """The ``(width, height)`` in pixels of :func:`svg_to_png`'s PNG of ``svg``; None if the root has no size."""
    root = _ROOT_TAG.search(svg)
    if root is None:
        return None
    w, h = _root_length(root.group(0), "width"), _root_length(root.group(0), "height")
    if w is None or h is None:
        return None
    return math.ceil(w * scale), math.ceil(h * scale)


def png_refusal(svg: str, *, scale: float = 2.0) -> str | None:
    """Why a tab's PNG of ``svg`` is not made (one sentence for the user), or None if it is within the limits.

    The limits (:mod:`egtviz.scene.limits`) keep one render to seconds and its memory to tens of megabytes:
    ``MAX_PNG_SVG_BYTES``, ``MAX_PNG_SVG_ELEMENTS`` and ``MAX_PNG_PIXELS`` (output width x height). The check
    reads the text only (no XML parse): it costs milliseconds for a panel of 2,000 points.
    """
    pixels = png_pixels(svg, scale=scale)
    if pixels is None:
        return "the figure has no width and height in pixels, so no PNG is made. Download the SVG instead."
    if pixels[0] * pixels[1] > limits.MAX_PNG_PIXELS:
        return (f"the PNG would be {pixels[0]:,} x {pixels[1]:,} pixels, and at most {limits.MAX_PNG_PIXELS:,} "
                f"pixels are rendered (so that a render takes seconds). Download the SVG instead.")
    size = len(svg.encode("utf-8"))
    if size > limits.MAX_PNG_SVG_BYTES:
        why = (f"the figure is {size / 1e6:.1f} MB of SVG, and a PNG is made from at most "
               f"{limits.MAX_PNG_SVG_BYTES / 1e6:g} MB")
    elif (n := len(_START_TAG.findall(svg))) > limits.MAX_PNG_SVG_ELEMENTS:
        why = f"the figure has {n:,} SVG elements, and a PNG is made from at most {limits.MAX_PNG_SVG_ELEMENTS:,}"
    else:
        return None
    return f"{why} (so that a render takes seconds). Download the SVG instead, or draw fewer points."


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
        return _fail(f"no built-in scene '{printable(args.name)}' (have {', '.join(SCENES)}; a file needs --scene)")
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

"""The browser viewer (viser): 3D scene, image-plane panels, fields and gizmos.

The only package that imports viser. It draws what :mod:`egtviz.scene` derives
and never computes geometry itself. See ``docs/viewer.md``.
"""

from .render.svg import image_plane_svg as image_plane_svg

__all__ = ["image_plane_svg", "EgtvizApp", "ClientView", "serve"]


def __getattr__(name: str):  # lazy: importing the SVG builder must not start viser
    if name == "EgtvizApp":
        from .tabs import EgtvizApp

        return EgtvizApp
    if name == "ClientView":
        from .workbench.app import ClientView

        return ClientView
    if name == "serve":
        from .server.cli import serve

        return serve
    raise AttributeError(name)

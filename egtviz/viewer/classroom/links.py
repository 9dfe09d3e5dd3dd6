"""The classroom's two links: the student URL (the server's own) and the instructor URL carrying the token.

viser's page connects its websocket to the page's own URL with the query dropped, so a token in a query would
never reach the server: the instructor URL puts it in the path, ``/egtviz-instructor/<token>``, where the
server serves the same page (:func:`egtviz.viewer.server.guard.serve_page_under`) and reads it back from the
tab's websocket handshake (:func:`egtviz.viewer.server.guard.handshake_of`).

The QR code of the student URL is drawn by ``segno`` (for the terminal, and as an SVG for the instructor's
panel). Nothing here logs or prints; :func:`shown_url` is how a URL holding the token may be shown elsewhere.
"""

from __future__ import annotations

import io

__all__ = ["INSTRUCTOR_PREFIX", "instructor_url", "qr_svg", "qr_terminal", "shown_url", "token_from_path"]

#: The path under which the page is served to the instructor: ``<prefix>/<token>``.
INSTRUCTOR_PREFIX = "/egtviz-instructor"
#: Characters of a token shown where a URL holding it is printed again (never the whole token).
_SHOWN = 4


def instructor_url(base: str, token: str) -> str:
    """The instructor's URL on the server at ``base`` (``http://host:port``, no trailing ``/``)."""
    return f"{base.rstrip('/')}{INSTRUCTOR_PREFIX}/{token}"


def token_from_path(path: str) -> str | None:
    """The token a handshake path offers (``""`` for the prefix without one); None: not an instructor path (a
    student's tab)."""
    path = path.partition("?")[0]
    if path != INSTRUCTOR_PREFIX and not path.startswith(INSTRUCTOR_PREFIX + "/"):
        return None
    return path[len(INSTRUCTOR_PREFIX) + 1:].strip("/")


def shown_url(url: str, token: str) -> str:
    """``url`` with ``token`` cut to its first characters (for a log or a page that is not the one start line)."""
    return url.replace(token, token[:_SHOWN] + "\u2026") if token else url


def qr_terminal(url: str) -> str:
    """The QR code of ``url`` as text for a terminal (block characters, two rows of modules per line)."""
    import segno

    out = io.StringIO()
    segno.make(url, error="m").terminal(out=out, compact=True)
    return out.getvalue()


def qr_svg(url: str, *, max_px: int = 360) -> str:
    """The QR code of ``url`` as an inline SVG as wide as its container up to ``max_px`` CSS pixels (dark modules
    on white, with its quiet zone): large enough on a projector to be read from the back of a room."""
    import segno

    svg = segno.make(url, error="m").svg_inline(omitsize=True, dark="#000", light="#fff")
    return svg.replace("<svg ", f'<svg data-egtviz="qr" width="100%" style="display:block;margin:auto;'
                                f'max-width:{int(max_px)}px" ', 1)

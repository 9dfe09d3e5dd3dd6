"""EGT's figures, live in the browser: the figure front-end of the EGT facade.

Every EGT drawing (a plot flag of ``f_perspproj``, ``f_epipline``'s line
style, ``f_3Dcamera``, ``f_3Dframe``, ...) becomes one call
:func:`draw` ``(kind, **data)`` that adds to the *current figure*. A figure is
a :class:`~egtviz.scene.Scene` of the scene model, drawn by the ordinary
viewer: cameras become scene cameras (with their image panels), points scene
points, frames, rays, lines, normals, surfaces and plane mirrors become
annotations (:mod:`egtviz.scene.annotations`), and image-plane plots become 2D
plot panels titled ``Figure <n>`` after EGT's figure numbers.

As MATLAB with ``hold on``: every call adds to the current figure;
:func:`figure` ``(n)`` selects (or creates) figure ``n``, :func:`clf` clears
the current one. The browser shows the current figure: each tab switches to
it when it changes (one scene per figure).

A drawing call returns at once, whatever the number of open tabs: it records
the figure's state, and one background thread shows the latest state in the
tabs (a loop of drawings becomes a few updates, :mod:`._publisher`). The tabs
are brought up to date (:func:`flush`) by :func:`show`, :func:`stop_server`,
at the end of each notebook cell and when the interpreter exits; in between
they follow within a fraction of a second.

The first drawing starts a local egtviz server (``127.0.0.1``, port 8080 or
the next free one; :func:`use_port` or ``EGTVIZ_FIGURE_PORT`` choose another,
0 any free one; viser serves from a daemon thread) and prints its URL once;
later drawings reuse it. In a Jupyter kernel the page is shown inline instead
(an ``IPython.display.IFrame``, once the tabs show the figure) when a figure
is first drawn, and nothing is printed: the cell's output is the figure. With the
environment variable ``EGTVIZ_FIGURE=off`` no server starts: figures are kept
in memory only (headless scripts, tests), readable with :func:`current_figure`.

A drawing that cannot be drawn (an unknown kind, bad data, a scene over its
limits) never raises into the student's script: the figure stays as it was,
the reason is added to the figure's messages (shown by the viewer) and issued
as a ``RuntimeWarning``.

Kinds handled: those of ``egtviz.egt._convert.draw`` (``image_points``,
``projection_rays``, ``epipolar_lines``, ``panoramic_points``,
``sphere_model``, ``circle``, ``normal``, ``line3d``, ``scene_points``,
``camera``, ``surface``) and the front-end's own, used by EGT's drawing
functions in ``egtviz.egt``: ``frame`` (``H``, ``style``, ``length``,
``label``), ``panoramic_camera`` (``H``, ``style``, ``quadric``, ``a``,
``b``), ``world_points`` (``points``, ``style``), ``numbered_points``
(``points``, ``numbers``, ``style``) and ``plane`` (``normal``, ``distance``,
``xlimit``, ``ylimit``, ``zlimit``, ``reflects``, ``virtual``).
"""

from __future__ import annotations

import atexit
import sys
import threading
import time
from typing import Any

from ._builder import KINDS, Figure
from ._publisher import Publisher
from ._server import FigureServer, figure_port, figures_enabled, in_jupyter, on_cell_end, show_inline

__all__ = [
    "KINDS",
    "Figure",
    "clf",
    "current_figure",
    "draw",
    "figure",
    "figure_server",
    "figures",
    "flush",
    "hold_on",
    "reset",
    "server_url",
    "show",
    "stop_server",
    "use_port",
]

_lock = threading.RLock()
_figures: dict[int, Figure] = {}
_current: int | None = None
_running: FigureServer | None = None
_publisher: Publisher | None = None
_port: int | None = None
#: Seconds the interpreter's exit waits for the tabs to show the last drawing.
EXIT_FLUSH_SECONDS = 10.0


def _current_figure() -> Figure:
    global _current
    if _current is None:
        _current = 1
    fig = _figures.get(_current)
    if fig is None:
        fig = _figures[_current] = Figure(_current)
    return fig


def _publish(fig: Figure) -> None:
    """Record ``fig`` for the browser's tabs (starting the server on first use), unless figures are off."""
    global _running, _publisher
    if not figures_enabled():
        return
    if _running is None:
        _running = FigureServer(_port)
        _publisher = Publisher(_running.show, settle=_running.catch_up)
        if in_jupyter():
            on_cell_end(lambda *_: flush())
        else:  # a notebook shows the figure inline; its loopback address is one a hub's student cannot open
            print(f"egtviz figure: {_running.url}", flush=True)
    assert _publisher is not None
    _publisher.submit(fig.scene())
    if not fig.displayed and in_jupyter():
        _publisher.flush()  # the inline frame opens on the figure, as the tabs show it
        show_inline(_running.url)
    fig.displayed = True


def flush(timeout: float | None = 30.0) -> bool:
    """Wait until every open tab shows the last drawing; True if it did within ``timeout`` seconds (or no
    server runs)."""
    publisher, running = _publisher, _running
    if publisher is None or running is None:
        return True
    done = publisher.flush(timeout)
    running.catch_up()
    return done


@atexit.register
def _flush_at_exit() -> None:
    flush(EXIT_FLUSH_SECONDS)


def draw(kind: str, **data: Any) -> bool:
    """Add one drawing to the current figure and show it; True if it was drawn (see the module docstring)."""
    with _lock:
        fig = _current_figure()
        drawn = fig.draw(kind, data)
        _publish(fig)
        return drawn


def figure(number: int | None = None) -> int:
    """Select figure ``number`` (created empty if new; None: a new figure numbered after the highest) and show it.

    Returns:
        The figure's number.
    """
    global _current
    if number is not None and (isinstance(number, bool) or not isinstance(number, int) or number < 1):
        raise ValueError(f"number: expected a whole number >= 1 (a figure number), got {number!r}")
    with _lock:
        _current = number if number is not None else max(_figures, default=0) + 1
        fig = _current_figure()
        _publish(fig)
        return fig.number


def clf() -> None:
    """Clear the current figure (EGT's ``clf``)."""
    with _lock:
        fig = _current_figure()
        fig.clear()
        _publish(fig)


def hold_on() -> None:
    """MATLAB's ``hold on``. egtviz always holds: drawings add to the current figure until :func:`clf`."""


def current_figure() -> Figure:
    """The current figure (created empty if there is none): its :meth:`Figure.scene` is what the browser shows."""
    with _lock:
        return _current_figure()


def figures() -> dict[int, Figure]:
    """Every figure by number (a copy of the registry)."""
    with _lock:
        return dict(_figures)


def figure_server() -> FigureServer | None:
    """The running figure server (its viser ``server`` and egtviz ``app``), or None."""
    return _running


def use_port(port: int | None) -> None:
    """Start the figure server on ``port`` (0: any free one; None: ``EGTVIZ_FIGURE_PORT`` or 8080), from the
    next drawing on; a server already running is stopped first, so the next drawing starts it there.

    Raises:
        ValueError: ``port`` is not a whole number 0..65535.
    """
    global _port
    if port is not None:
        figure_port(port)  # checked now, where the caller can see the mistake
    with _lock:
        _port = port
        if _running is not None:
            stop_server()


def server_url() -> str | None:
    """The URL of the figure server, or None when none is running."""
    return None if _running is None else _running.url


def stop_server() -> None:
    """Stop the figure server, if one runs, once its tabs show the last drawing (the next drawing starts a
    new one)."""
    global _running, _publisher
    with _lock:
        if _publisher is not None:
            _publisher.close()
            _publisher = None
        if _running is not None:
            _running.stop()
            _running = None


def reset() -> None:
    """Forget every figure (the server, if running, keeps serving; the next drawing starts figure 1)."""
    global _current
    with _lock:
        _figures.clear()
        _current = None


def show(wait: bool | None = None) -> None:
    """Keep a script's figures in the browser until Ctrl-C (the end of an example script).

    Args:
        wait: block until Ctrl-C; None: block unless ``--no-wait`` is on the command line. Never blocks when
            no server runs (``EGTVIZ_FIGURE=off``) or inside a notebook.
    """
    if wait is None:
        wait = "--no-wait" not in sys.argv[1:]
    flush()
    if not wait or _running is None or in_jupyter():
        return
    print("egtviz figure: serving until Ctrl-C", flush=True)
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        print("egtviz figure: stopped", flush=True)

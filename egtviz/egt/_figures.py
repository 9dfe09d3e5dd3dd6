"""EGT's drawing functions and figure commands: they draw into an egtviz figure in the browser.

Each function hands one drawing to the figure front-end (``egtviz.egt_figure``,
through :func:`~egtviz.egt._convert.draw`); MATLAB colour/line styles
(``'r'``, ``'b:'``, ``'g*'``) set the colour of what is not a scene camera or
point. Cameras become scene cameras: a pin-hole camera is drawn like every
camera of the workbench (frustum, gizmo, image panel) whatever ``color``,
``scale`` or ``version`` say. Nothing is returned except where EGT returned
something.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..geometry._validate import GeometryError, as_matrix, as_scalar, as_vector
from ._convert import draw as _draw
from ._convert import world_columns

__all__ = [
    "clf",
    "f_3Dcamera",
    "f_3Dframe",
    "f_3Dpanoramic",
    "f_3Dplane",
    "f_3Dreflenum",
    "f_3Dwf",
    "f_3Dwfenum",
    "f_scenepnt",
    "figure",
    "hold_on",
    "show",
]


def _pose(H: npt.ArrayLike) -> np.ndarray:
    return as_matrix(H, "H", (4, 4))


def f_3Dcamera(H: npt.ArrayLike, color: str = "r", scale: float = 1.0, version: int = 1, *title: Any) -> None:
    """Draw a pin-hole camera at the pose ``H`` (:func:`f_Rt2H`; a reflected ``H`` from :func:`f_reflcamera` too).

    The camera becomes a camera of the figure's scene, with its image panel. A reflected (left-handed)
    pose is drawn as its proper camera (x axis reversed: the frustum looks the same) plus a second frame
    with the reflected axes, labelled ``mirrored``. ``color``, ``scale`` and ``version`` are accepted;
    an optional fifth argument names the camera.
    """
    _draw("camera", H=_pose(H), style=color, scale=None, frame_length=None,
          title=title[0] if title and isinstance(title[0], str) else None)


def f_3Dframe(H: npt.ArrayLike, color: str = "r", scale: float = 1.0, axislabel: str = "_{c}") -> None:
    """Draw the frame of the pose ``H``: three axes of length ``scale`` labelled ``X<axislabel>``, ...

    A reflected pose's frame is drawn as it is (left-handed).
    """
    _draw("frame", H=_pose(H), style=color, length=as_scalar(scale, "scale"), label=str(axislabel))


def f_3Dwf(color: str = "k", scale: float = 1.0, axislabel: str = "_{wf}") -> None:
    """Draw the world frame (axes of length ``scale``)."""
    _draw("frame", H=np.eye(4), style=color, length=as_scalar(scale, "scale"), label=str(axislabel))


def f_3Dwfenum(P: npt.ArrayLike, color: str = "k", offset: float = 0.0) -> None:
    """Draw the points ``P`` (3, N) as numbered scene points (the viewer numbers scene points 1, 2, ...).

    ``color`` and ``offset`` (the label's distance) are accepted; points the figure already has are not
    added again.
    """
    _draw("world_points", points=world_columns(P, "P").T, style=color)


def f_scenepnt(P: npt.ArrayLike, color: str = "r*", plotta: int = 1) -> None:
    """Draw the points ``P`` (3, N) (homogeneous (4, N) accepted) as scene points, if ``plotta`` is 1.

    Non-finite columns (points with no image, from :func:`f_reflpersproj`) are skipped.
    """
    if plotta:
        arr = np.asarray(P, dtype=float)
        if arr.ndim == 2 and arr.shape[0] == 4:
            arr = arr[:3] / arr[3]
        arr = arr.reshape(3, -1) if arr.ndim == 1 else arr
        if arr.ndim != 2 or arr.shape[0] != 3:
            world_columns(P, "P")  # raises the facade's error naming P
        _draw("world_points", points=arr, style=color)


def f_3Dpanoramic(H: npt.ArrayLike, color: str = "k", quadric: int = 1, a: float = 3.0, b: float = 1.0,
                  r_rim: float = 2.0) -> None:
    """Draw a panoramic camera (mirror focus and axis from ``H = [R t; 0 1]``): a scene camera with the mirror
    ``quadric`` (1 hyperbolic ``a``, ``b``; 2 parabolic ``h = a``) and the tutorial's CCD.

    ``r_rim`` is accepted; the viewer draws the rim at ``2 b`` (hyperbolic) or ``2 h`` (parabolic).
    """
    _draw("panoramic_camera", H=_pose(H), style=color, quadric=quadric, a=as_scalar(a, "a"), b=as_scalar(b, "b"))


def f_3Dreflenum(points: Any, color: str = "r*", distance: float = 0.0) -> None:
    """Draw numbered points: EGT's list of ``{'point': (3,), 'number': k}`` records, or a (3, N) array
    (numbered 1..N). ``distance`` (the label's offset) is accepted."""
    if isinstance(points, (list, tuple)) and points and isinstance(points[0], dict):
        X = np.array([as_vector(p.get("point"), "points.point", 3) for p in points]).T
        numbers = [int(p.get("number", i + 1)) for i, p in enumerate(points)]
    else:
        X = world_columns(points, "points").T
        numbers = None
    _draw("numbered_points", points=X, numbers=numbers, style=color)


def f_3Dplane(Normal: npt.ArrayLike, Distance: float, xlimit: Any = (-10, 10), ylimit: Any = (-10, 10),
              zlimit: Any = (-10, 10)) -> np.ndarray:
    r"""Draw the plane (a plane mirror) :math:`n \cdot X = d` inside the box ``xlimit x ylimit x zlimit``.

    Returns:
        The plane's coefficients ``(n, -d)`` (4,), ``n`` the unit normal: :math:`(n, -d) \cdot (X, 1) = 0`.
        (EGT returned the symbolic equation.)
    """
    n = as_vector(Normal, "Normal", 3)
    norm = float(np.linalg.norm(n))
    if not norm > 0.0:
        raise GeometryError("Normal: expected a non-zero 3-vector (the plane's normal)")
    d = as_scalar(Distance, "Distance")
    _draw("plane", normal=n / norm, distance=d, xlimit=xlimit, ylimit=ylimit, zlimit=zlimit)
    return np.append(n / norm, -d)


def figure(n: int | None = None) -> int:
    """Select figure ``n`` (a new one if None) as MATLAB's ``figure(n)``; returns its number."""
    from ..egt_figure import figure as select

    return select(n)


def clf() -> None:
    """Clear the current figure."""
    from ..egt_figure import clf as clear

    clear()


def hold_on() -> None:
    """MATLAB's ``hold on``: egtviz figures always hold (drawings add up until :func:`clf`)."""


def show(wait: bool | None = None) -> None:
    """Keep serving the figures until Ctrl-C (unless ``--no-wait`` is given or figures are off)."""
    from ..egt_figure import show as serve

    serve(wait)

"""The EGT facade: the MATLAB Epipolar Geometry Toolbox's function names, in Python.

A student can type EGT code almost verbatim::

    from egtviz.egt import *
    H = f_Rt2H(rotoy(pi / 4), [-10, -5, 0])
    u, v = f_perspproj(Xw, H, eye(3))

Points are EGT's **columns** here: world points ``(3, N)``, pixels ``(2, N)``
(or homogeneous ``(3, N)``); a single point may be a flat vector. Everything
else in egtviz uses rows; these modules only convert and delegate to
:mod:`egtviz.geometry` (conventions: ``docs/conventions.md``; the table of
functions and the differences from EGT 2.0: ``docs/egt.md``).

EGT's trailing plotting arguments (``f_perspproj(P, H, K, 1)``,
``f_epipline(Ua, Ud, F, 1, 2, 3, 'b:')``, colours) are accepted everywhere;
they are handed to the figure front-end ``egtviz.egt_figure``, which draws
them live in the browser (``figure``, ``clf``, ``hold_on``, ``show`` and EGT's
drawing functions ``f_3Dcamera``, ``f_3Dframe``, ... are here too; ``docs/egt.md``). Every function raises
:class:`~egtviz.geometry.GeometryError` naming the argument for bad input.
"""

from __future__ import annotations

from math import pi

from numpy import eye

from ..geometry._validate import GeometryError
from ..geometry.poses import rotx, roty, rotz
from ._algebra import f_atan, f_E2Motion, f_forcerank2, f_normalize, f_Procrustes, f_skew, f_stack, f_unstacked
from ._convert import DEFAULT_PANORAMIC_K
from ._estimation import FESTIM_ALGORITHMS, FESTIM_NAMES, f_Festim, f_panEestim
from ._figures import (
    clf,
    f_3Dcamera,
    f_3Dframe,
    f_3Dpanoramic,
    f_3Dplane,
    f_3Dreflenum,
    f_3Dwf,
    f_3Dwfenum,
    f_scenepnt,
    figure,
    hold_on,
    show,
)
from ._mirror import f_reflcamera, f_reflFestim, f_reflmatrix, f_reflpersproj, f_reflpoint
from ._panoramic import (
    f_backcatmod,
    f_catmod,
    f_daqaXhmir,
    f_epipconics,
    f_findepipoles,
    f_lambda,
    f_panE,
    f_panepipoles,
    f_panparconic,
    f_panproj,
    f_projectmir,
)
from ._pinhole import f_epipline, f_epipole, f_perspline, f_perspproj, f_Rt2H
from ._scene import f_3Dpointplanedistance, f_3Drandpoint, f_3Dsurface, f_normplane

#: EGT's elementary rotations about x, y, z (radians).
rotox = rotx
rotoy = roty
rotoz = rotz

__all__ = [
    "DEFAULT_PANORAMIC_K",
    "FESTIM_ALGORITHMS",
    "FESTIM_NAMES",
    "GeometryError",
    "clf",
    "eye",
    "f_3Dcamera",
    "f_3Dframe",
    "f_3Dpanoramic",
    "f_3Dplane",
    "f_3Dreflenum",
    "f_3Dwf",
    "f_3Dwfenum",
    "f_3Dpointplanedistance",
    "f_3Drandpoint",
    "f_3Dsurface",
    "f_E2Motion",
    "f_Festim",
    "f_Procrustes",
    "f_Rt2H",
    "f_atan",
    "f_backcatmod",
    "f_catmod",
    "f_daqaXhmir",
    "f_epipconics",
    "f_epipline",
    "f_epipole",
    "f_findepipoles",
    "f_forcerank2",
    "f_lambda",
    "f_normalize",
    "f_normplane",
    "f_panE",
    "f_panEestim",
    "f_panepipoles",
    "f_panparconic",
    "f_panproj",
    "f_perspline",
    "f_perspproj",
    "f_projectmir",
    "f_reflFestim",
    "f_reflcamera",
    "f_reflmatrix",
    "f_reflpersproj",
    "f_reflpoint",
    "f_scenepnt",
    "f_skew",
    "f_stack",
    "f_unstacked",
    "figure",
    "hold_on",
    "pi",
    "rotox",
    "rotoy",
    "rotoz",
    "show",
]

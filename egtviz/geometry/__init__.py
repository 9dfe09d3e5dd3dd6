"""The numeric core of egtviz: pure numpy/scipy, points as rows, no viewer imports.

Conventions: ``docs/conventions.md``. Every public function refuses bad input with a
:class:`GeometryError` naming the argument (types, shapes, NaN and inf, magnitudes beyond
``MAX_MAGNITUDE``); quantities defined up to scale are accepted at any finite magnitude.
"""

from ._validate import MAX_MAGNITUDE as MAX_MAGNITUDE
from ._validate import MIN_MAGNITUDE as MIN_MAGNITUDE
from ._validate import DegenerateConfigurationError as DegenerateConfigurationError
from ._validate import GeometryError as GeometryError
from .camera_model import CAMERA_MODELS as CAMERA_MODELS
from .camera_model import CameraModel as CameraModel
from .camera_model import ParameterSpec as ParameterSpec
from .catadioptric import CatadioptricCamera as CatadioptricCamera
from .epipolar import EpipolarPair as EpipolarPair
from .epipolar import epipolar_lines as epipolar_lines
from .epipolar import epipolar_lines_in_first as epipolar_lines_in_first
from .epipolar import epipolar_pair as epipolar_pair
from .epipolar_curves import epipolar_curves as epipolar_curves
from .homogeneous import clip_lines_to_rect as clip_lines_to_rect
from .homogeneous import normalize_homogeneous as normalize_homogeneous
from .pinhole import Intrinsics as Intrinsics
from .pinhole import PinholeCamera as PinholeCamera
from .poses import Pose as Pose
from .poses import rotx as rotx
from .poses import roty as roty
from .poses import rotz as rotz
from .unified import UnifiedCamera as UnifiedCamera

__all__ = [
    "CAMERA_MODELS",
    "MAX_MAGNITUDE",
    "MIN_MAGNITUDE",
    "CameraModel",
    "CatadioptricCamera",
    "DegenerateConfigurationError",
    "EpipolarPair",
    "GeometryError",
    "Intrinsics",
    "ParameterSpec",
    "PinholeCamera",
    "Pose",
    "UnifiedCamera",
    "clip_lines_to_rect",
    "epipolar_curves",
    "epipolar_lines",
    "epipolar_lines_in_first",
    "epipolar_pair",
    "normalize_homogeneous",
    "rotx",
    "roty",
    "rotz",
]

"""The scene model: cameras, points, surfaces and display options, separate from any viewer.

Layer 3 of egtviz: uses the numeric core, knows nothing of viser.
"""

from .derived import Derived as Derived
from .derived import Epipole as Epipole
from .derived import ImagePlane as ImagePlane
from .derived import PairReadout as PairReadout
from .derived import compute_derived as compute_derived
from .examples import SCENES as SCENES
from .examples import default_scene as default_scene
from .examples import panoramic_scene as panoramic_scene
from .io import load_scene_file as load_scene_file
from .io import save_scene_file as save_scene_file
from .io import scene_from_argument as scene_from_argument
from .io import scene_from_bytes as scene_from_bytes
from .io import scene_to_bytes as scene_to_bytes
from .model import Change as Change
from .model import SceneModel as SceneModel
from .scene import Scene as Scene
from .scene import SceneFileError as SceneFileError
from .cameras import SPEC_CLASSES as _SPEC_CLASSES
from .cameras.catadioptric import PanoramicSpec as PanoramicSpec
from .cameras.pinhole import PinholeSpec as PinholeSpec
from .cameras.unified import UnifiedSpec as UnifiedSpec
from .specs import CameraSpec as CameraSpec
from .specs import DisplayOptions as DisplayOptions
from .specs import OutOfRangeError as OutOfRangeError
from .specs import SceneError as SceneError
from .specs import SurfaceSpec as SurfaceSpec
from .surfaces import mesh_names as mesh_names


def __getattr__(name: str) -> type:
    """Every registered camera spec class by its name (``egtviz.scene.cameras``), e.g. a model added since."""
    for cls in _SPEC_CLASSES:
        if cls.__name__ == name:
            return cls
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

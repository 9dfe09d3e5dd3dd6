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
from .specs import CameraSpec as CameraSpec
from .specs import FisheyeSpec as FisheyeSpec
from .specs import DisplayOptions as DisplayOptions
from .specs import OutOfRangeError as OutOfRangeError
from .specs import PanoramicSpec as PanoramicSpec
from .specs import PinholeSpec as PinholeSpec
from .specs import SceneError as SceneError
from .specs import SurfaceSpec as SurfaceSpec
from .specs import UnifiedSpec as UnifiedSpec
from .surfaces import mesh_names as mesh_names

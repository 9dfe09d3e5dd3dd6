"""Every plausible range of a scene, in one place: scene files, specs, the model, the GUI and lesson files.

A value outside these ranges is refused where it enters (a spec, a scene, a file, a field) with a message
that names the entry and the range. The names are stable: the GUI reads them for its fields' min/max,
converting units for display. ``docs/limits.md`` lists them with what each bad input gets.

Ranges are inclusive. Lengths are in metres (scene units), image quantities in pixels.

A camera parameter's range is the camera model's own (``ParameterSpec`` in ``egtviz.geometry``, read through the
registry ``CAMERA_MODELS``): the names below restate those ranges for the GUI and the docs, they do not set them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from ..geometry.camera_model import CAMERA_MODELS
from ..geometry.catadioptric import B_OVER_A_RANGE, HYPERBOLIC
from ..geometry.pinhole import FOCAL_PIXELS_RANGE, SKEW_OVER_FOCAL_RANGE, PinholeCamera
from ..geometry.unified import UnifiedCamera

__all__ = [
    "ANGLE_DEG",
    "COORDINATE",
    "FOCAL_LENGTH",
    "FOCAL_PIXELS",
    "IMAGE_SIZE",
    "MAX_CAMERAS",
    "MAX_JSON_DEPTH",
    "MAX_JSON_INT_DIGITS",
    "MAX_MESH_FILE_BYTES",
    "MAX_NAME_LENGTH",
    "MAX_PNG_PIXELS",
    "MAX_PNG_SVG_BYTES",
    "MAX_PNG_SVG_ELEMENTS",
    "MAX_POINTS",
    "MAX_SCENE_FILE_BYTES",
    "MAX_SURFACES",
    "MAX_TITLE_LENGTH",
    "MAX_TOTAL_SURFACE_SAMPLES",
    "MIRROR_B_OVER_A",
    "MIRROR_PARAMETER",
    "PANORAMIC_FOCAL_PIXELS",
    "PIXELS_PER_METRE",
    "PIXEL_SIZE",
    "PRINCIPAL_POINT",
    "SERVO_DEMO_STEPS",
    "SERVO_HEADLESS_STEPS",
    "SERVO_SERVER_FRAMES",
    "SKEW",
    "SKEW_OVER_FOCAL",
    "SURFACE_SAMPLES",
    "SURFACE_SIZE",
    "UNIFIED_FOCAL_PIXELS",
    "XI",
    "Range",
    "parameter_range",
]


@dataclass(frozen=True)
class Range:
    """An inclusive interval ``low <= x <= high`` of a quantity in ``unit``."""

    low: float
    high: float
    unit: str = ""
    """Unit of ``low`` and ``high`` as stored in a scene (``"m"``, ``"px"``, ``"deg"``, ``""``)."""
    integer: bool = False
    """Only whole numbers are accepted."""

    def __contains__(self, x: float) -> bool:
        return self.low <= x <= self.high  # False for NaN

    def describe(self, scale: float = 1.0, unit: str | None = None) -> str:
        """``"low..high unit"``, the bounds multiplied by ``scale`` (e.g. ``1e3`` and ``"mm"`` for metres)."""
        u = self.unit if unit is None else unit
        return f"{self.low * scale:g}..{self.high * scale:g}" + (f" {u}" if u else "")


@cache
def parameter_range(kind: str, name: str) -> Range:
    """The range of parameter ``name`` of the registered camera model ``kind``, as a :class:`Range`."""
    p = CAMERA_MODELS[kind].parameter(name)
    return Range(p.min, p.max, p.unit, p.integer)


# -- files ---------------------------------------------------------------------------------------------

MAX_SCENE_FILE_BYTES = 2_000_000
"""Largest scene file read (2 MB), checked before reading: CLI, ``serve --scene`` and uploads."""
MAX_JSON_DEPTH = 8
"""Deepest nesting of JSON arrays and objects in a scene file (a scene needs 4)."""
MAX_JSON_INT_DIGITS = 15
"""Most digits of a JSON integer (larger values are not exact as floats anyway)."""
MAX_MESH_FILE_BYTES = 5_000_000
"""Largest mesh asset read (5 MB)."""

# -- counts --------------------------------------------------------------------------------------------

MAX_CAMERAS = 8
"""Cameras in a scene (each has an image panel)."""
MAX_POINTS = 2000
"""Points in a scene; also the GUI's "how many points" maximum."""
MAX_SURFACES = 8
"""Surfaces in a scene."""
SURFACE_SAMPLES = Range(1, 10_000, "", integer=True)
"""Samples of one surface."""
MAX_TOTAL_SURFACE_SAMPLES = 20_000
"""Samples of all surfaces of a scene together."""
MAX_NAME_LENGTH = 40
"""Characters of a camera name (1 or more, no control characters)."""
MAX_TITLE_LENGTH = 200
"""Characters of a scene title (no control characters)."""

# -- placement -----------------------------------------------------------------------------------------

COORDINATE = Range(-1e4, 1e4, "m")
"""Each coordinate of a camera position, a point and a surface centre."""
ANGLE_DEG = Range(-3600.0, 3600.0, "deg")
"""Each of yaw, pitch, roll."""

# -- pin-hole camera (the ``pinhole`` model's ranges) ------------------------------------------------

FOCAL_LENGTH = parameter_range(PinholeCamera.kind, "focal_length")
"""Focal length f (0.1 mm to 10 m; the tutorial's ``K = I`` scenes use 1 m)."""
PIXELS_PER_METRE = parameter_range(PinholeCamera.kind, "ku")
"""ku, kv as a spec stores them: 1 / :data:`PIXEL_SIZE`."""
PIXEL_SIZE = Range(1.0 / PIXELS_PER_METRE.high, 1.0 / PIXELS_PER_METRE.low, "m")
"""Side of a pixel (0.1 um to 1 m), the inverse of :data:`PIXELS_PER_METRE`."""
FOCAL_PIXELS = Range(*FOCAL_PIXELS_RANGE, "px")
"""ku f and kv f, the focal length in pixels (what K holds): with :data:`PRINCIPAL_POINT` and
:data:`SKEW_OVER_FOCAL` this keeps K well conditioned (condition number below about 1e10)."""
PRINCIPAL_POINT = parameter_range(PinholeCamera.kind, "u0")
"""Each of u0, v0 (every model)."""
SKEW = parameter_range(PinholeCamera.kind, "skew")
"""gamma, the skew entry of K; also ``|gamma| <= ku f`` (:data:`SKEW_OVER_FOCAL`)."""
SKEW_OVER_FOCAL = Range(*SKEW_OVER_FOCAL_RANGE, "")
"""gamma / (ku f) = cot(theta), theta the angle between the pixel axes: 45 to 135 degrees."""
IMAGE_SIZE = parameter_range(PinholeCamera.kind, "width")
"""Image width and height, whole pixels (every model)."""

# -- panoramic camera (the ``hyperbolic`` and ``parabolic`` models' ranges) ------------------------------

PANORAMIC_FOCAL_PIXELS = parameter_range(HYPERBOLIC.kind, "focal_pixels")
"""The CCD's focal length in pixels."""
MIRROR_PARAMETER = parameter_range(HYPERBOLIC.kind, "a")
"""Hyperbola a and b; parabola h (stored as ``a``)."""
MIRROR_B_OVER_A = Range(*B_OVER_A_RANGE, "")
"""b / a of a hyperbolic mirror: flatter or sharper mirrors are not drawn reliably."""

# -- unified sphere camera (the ``unified`` model's ranges) -----------------------------------------------

XI = parameter_range(UnifiedCamera.kind, "xi")
"""xi: 0 a pin-hole, 1 a parabolic mirror, between them a hyperbolic one."""
UNIFIED_FOCAL_PIXELS = parameter_range(UnifiedCamera.kind, "focal_pixels")
"""The unified camera's focal length in pixels."""

# -- surfaces ------------------------------------------------------------------------------------------

SURFACE_SIZE = Range(1e-3, 1e3, "m")
"""Plane side, sphere radius, mesh scale factor."""

# -- figures: annotations and plots (egtviz.scene.annotations) ---------------------------------------

MAX_ANNOTATION_ITEMS = 2000
"""Items of each kind (frames, polylines, labels, point sets, meshes, mirrors) in one scene."""
MAX_POLYLINE_VERTICES = 2000
"""Vertices of one polyline or points of one point set."""
MAX_MESH_VERTICES = 20_000
"""Vertices of all meshes of a scene together (a 20 x 20 surface has 400)."""
MAX_PLOTS = 8
"""2D plot panels in one scene (each is a panel beside the cameras' panels)."""
MAX_PLOT_ITEMS = 2000
"""Points, lines, epipoles or circles of one plot."""
MAX_TEXT_LENGTH = 200
"""Characters of a label, a plot title or a message."""
PLOT_COORDINATE = Range(-1e9, 1e9, "px")
"""Pixel coordinates of plots (the same bound as a principal point, with room for far epipoles)."""
MESH_OPACITY = Range(0.0, 1.0, "")
"""A mesh's opacity."""
FRAME_AXIS_LENGTH = Range(1e-6, 1e4, "m")
"""A frame's axis length."""

# -- PNG downloads of a panel (egtviz.viewer.render.png_worker) --------------------------------------------------

MAX_PNG_SVG_BYTES = 2_000_000
"""Largest panel SVG rendered to PNG for a tab (2 MB; a panel of 2,000 numbered points with their epipolar lines
is about 0.8 MB). Above any of the three PNG limits the tab is told which one and why; the SVG download still
works."""
MAX_PNG_SVG_ELEMENTS = 10_000
"""Most SVG elements (tags) of a panel rendered to PNG for a tab (2,000 numbered points with their epipolar lines:
about 8,000)."""
MAX_PNG_PIXELS = 2_500_000
"""Most pixels (width x height) of a PNG rendered for a tab. A panel's PNG is 960 (presentation mode: 1,240) pixels
wide and about as tall (1.6 million pixels in presentation mode); this leaves room for portrait images and refuses a
1 x 8192 image's panel, millions of pixels tall. A render's time grows with the elements times the pixels
(an anti-aliased line costs its bounding box): at these limits it takes seconds, in a worker process."""

# -- the estimation lab (egtviz.scene.lab) ------------------------------------------------------------

LAB_NOISE_PX = Range(0.0, 20.0, "px")
"""Standard deviation of the pixel noise."""
LAB_OUTLIER_PERCENT = Range(0.0, 60.0, "%")
"""Share of the correspondences replaced by gross mismatches."""
LAB_THRESHOLD_PX = Range(0.05, 100.0, "px")
"""RANSAC's inlier threshold on the Sampson distance."""
LAB_SEED = Range(0, 2**31 - 1, "", integer=True)
"""Seed of the noise and the outliers."""

# -- visual-servoing runs (egtviz.servo, the demos in the browser) ---------------------------------------

SERVO_HEADLESS_STEPS = Range(1, 100_000, "", integer=True)
"""Steps of a headless servo run (``egtviz servo --steps``). The run keeps only its samples (poses, features,
velocities: under a kilobyte a step) in the command's own process; the demos' default runs converge in a
few hundred steps."""
SERVO_DEMO_STEPS = Range(1, 10_000, "", integer=True)
"""Steps of a servo run in the browser (a demo's *max steps* field, a lesson's ``open_demo`` ``steps``): ten
times fewer than :data:`SERVO_HEADLESS_STEPS` because the server derives every frame's geometry and keeps it
for playback, per tab, in the one process every tab shares (about 17 kB a frame for the panoramic demo's sampled
bi-conics: 170 MB at this bound)."""
SERVO_SERVER_FRAMES = 2 * (int(SERVO_DEMO_STEPS.high) + 1)
"""Frames of servo runs all tabs of one server keep together for playback: two runs at :data:`SERVO_DEMO_STEPS`'
bound (10,001 frames each; two non-converging panoramic runs raised a server's memory by 390 MB, three by 570 MB),
or dozens of the demos' default runs, which converge in a few hundred steps. A run reserves ``steps + 1`` frames
when it starts and keeps the frames it has once drawn; a run that does not fit waits for up to half a minute, then
is refused in its tab with a notification naming how many other runs hold the budget
(``egtviz.controllers.servo_budget``)."""

# -- lesson files (egtviz.lessons) --------------------------------------------------------------------

MAX_LESSON_FILE_BYTES = 1_000_000
"""Largest lesson file read (1 MB; a long lesson is about 20 kB)."""
MAX_STEPS = 60
"""Steps of one lesson."""
MAX_CHANGES = 100
"""Changes of one step (and of one task's solution)."""
MAX_TASKS = 20
"""Tasks of one step."""
MAX_PREREQUISITES = 20
"""Prerequisites of one lesson."""
MAX_LESSON_KEY_PARTS = 8
"""Parts of one dotted key (``a.b.c = 1``) or table header (``[a.b.c]``) of a lesson file (the course uses 2).
Checked by scanning the text before it is parsed: a TOML parser's work grows with the square of a key's parts."""
MAX_LESSON_NESTING = 8
"""Arrays and inline tables nested in one value of a lesson file (the course uses 3)."""
MAX_LESSON_KEYS = 20_000
"""Keys and table headers of a lesson file, inline tables' keys included (the longest lesson has about 170)."""
MAX_LESSON_CHANGES = 1_000
"""Changes of a whole lesson: every step's changes and every task's solution (the course uses at most 12)."""
MAX_LESSON_POINTS = 20_000
"""Points the changes of a lesson place in all (``random_points`` ``n``, ``set_points``), solutions included:
ten full scenes (the course places at most 100)."""
MAX_LESSON_SERVO_STEPS = 10_000
"""Steps of all the servo runs a lesson's ``servo_number`` tasks measure, simulated when the lesson is loaded:
one run of the longest a demo allows (the course simulates at most 2,000)."""
MAX_LESSON_IMAGE_BYTES = 1_000_000
"""Largest image a lesson's text shows (embedded in the text the server sends)."""
MAX_LESSON_IMAGES_BYTES = 4_000_000
"""All the images of a lesson's texts, each use counted."""

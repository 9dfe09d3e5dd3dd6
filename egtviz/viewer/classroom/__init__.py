"""The classroom in the viewer: the instructor's panel, students' tabs that follow the instructor or work on
their own scene, and the links (with a QR code) that ``egtviz serve --classroom`` prints.

The class's state is :class:`egtviz.classroom.Classroom` (headless); :class:`ClassroomHost` puts it on an
:class:`~egtviz.viewer.tabs.EgtvizApp`.
"""

from .host import ClassroomHost as ClassroomHost
from .links import INSTRUCTOR_PREFIX as INSTRUCTOR_PREFIX
from .links import instructor_url as instructor_url
from .links import qr_terminal as qr_terminal

__all__ = ["ClassroomHost", "INSTRUCTOR_PREFIX", "instructor_url", "qr_terminal"]

"""A lesson step or a scene as a static page: opens from disk (``file://``) or any static host, no server.

``egtviz export --lesson NAME [--step K] --out DIR`` and ``egtviz export --scene FILE --out DIR`` write into DIR:

* ``index.html``: the step's text (its formulas as MathML, as the lesson view shows them) and the step's task
  prompts in a column, beside a frame holding ``scene.html``; for a scene, its title and cameras;
* ``scene.html``: viser's client page with the 3D scene recorded in it (:mod:`.recording`): the cameras, points,
  rays, epipolar plane and each camera's image panel drawn in the scene;
* ``egtviz-export.json``: what was exported (it marks DIR as an export, which a later export may replace).

Nothing is downloaded when the page opens: every script, style and picture is in these files.
"""

from __future__ import annotations

from .writer import MARKER, ExportError, ExportFailed, export_lesson, export_scene

__all__ = ["MARKER", "ExportError", "ExportFailed", "export_lesson", "export_scene"]

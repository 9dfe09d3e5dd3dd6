"""The workbench: one tab's view (:class:`~egtviz.viewer.workbench.app.ClientView`) and its parts.

Controls, camera settings, dragging, the panel dock, the read-out, the 3D scene and its
annotations, the per-model camera drawings, and the GUI field rules they share.
"""

"""The catadioptric (panoramic) camera in 3D: its mirror, a reflective surface of revolution, above its CCD.

The mirror's mesh comes from the core (``Mirror.surface``, in the mirror frame) and is drawn as a child of the
camera's gizmo: a drag moves the node, and the mesh is sent again only when the mirror's shape changes.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from ...server.viser_adapter import assign
from . import CameraDrawing, DrawContext

if TYPE_CHECKING:
    import viser

    from ....geometry.catadioptric import CatadioptricCamera
    from ....geometry.mirrors import Mirror
    from ....scene.derived import ImagePlane

#: Samples of the mirror mesh (radial, angular).
MIRROR_MESH = (16, 48)
#: The mirror's look: a light, polished metal (glTF metallic-roughness material), seen from both sides.
MIRROR_RGBA = (200, 215, 230, 255)
MIRROR_METALLIC = 0.85
MIRROR_ROUGHNESS = 0.2


@lru_cache(maxsize=32)
def mirror_glb(mirror: Mirror) -> trimesh.Trimesh:
    """The mirror's surface as a trimesh with a reflective (metallic, smooth) material, in the mirror frame."""
    vertices, faces = mirror.surface(*MIRROR_MESH)
    material = trimesh.visual.material.PBRMaterial(
        baseColorFactor=MIRROR_RGBA, metallicFactor=MIRROR_METALLIC, roughnessFactor=MIRROR_ROUGHNESS,
        doubleSided=True,
    )
    mesh = trimesh.Trimesh(vertices=np.asarray(vertices), faces=np.asarray(faces), process=False)
    mesh.visual = trimesh.visual.TextureVisuals(material=material)
    return mesh


class CatadioptricDrawing(CameraDrawing["CatadioptricCamera"]):
    """The mirror (a reflective mesh about the focus, the frame's origin) and the CCD's frustum below it."""

    def __init__(self, api: viser.SceneApi, root: str, k: int, colour: tuple[int, int, int]) -> None:
        super().__init__(api, root, k, colour)
        self.ccd = api.add_camera_frustum(f"{root}/ccd", fov=0.5, aspect=4 / 3, scale=0.35, color=colour,
                                          thickness=0.015)
        self.mirror: viser.GlbHandle | None = None
        self._mirror_src: Mirror | None = None

    def named_nodes(self) -> dict[str, viser.SceneNodeHandle]:
        return {"ccd": self.ccd}

    @property
    def body(self) -> viser.CameraFrustumHandle:
        return self.ccd

    def update(self, camera: CatadioptricCamera, plane: ImagePlane, ctx: DrawContext) -> None:
        mirror = camera.mirror
        if self._mirror_src != mirror:
            if self.mirror is not None:
                self.mirror.remove()
            self.mirror = self.api.add_mesh_trimesh(f"{self.root}/mirror", mirror_glb(mirror), cast_shadow=False,
                                                    receive_shadow=False)
            self._mirror_src = mirror
            # The CCD in the mirror frame: on the axis, ccd_offset below the focus.
            assign(self.ccd, "position", (0.0, 0.0, -float(mirror.ccd_offset)))

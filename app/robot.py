"""The solid arm: link meshes placed at ``frames(q)[i]``, plus the base and flange axes."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.orientation import quaternion

from .meshes import LinkMesh
from .state import Snapshot
from .style import ALUMINIUM, JOINT_CAP_BLUE


def poses(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 4, 4) homogeneous frames → (wxyz (..., 4), position (..., 3)) for viser."""
    return quaternion(frames[..., :3, :3]), frames[..., :3, 3]


class RobotView:
    """Seven link nodes, each carrying its aluminium body and blue cap, moved as frames."""

    def __init__(self, scene: viser.SceneApi, links: tuple[LinkMesh, ...], root: str = "/arm") -> None:
        scene.add_frame("/base_frame", axes_length=0.3, axes_radius=0.008, origin_radius=0.015)
        self._links: list[viser.FrameHandle] = []
        for link in links:
            node = scene.add_frame(f"{root}/link{link.index}", show_axes=False)
            scene.add_mesh_simple(f"{root}/link{link.index}/body", link.body_vertices, link.body_faces, color=ALUMINIUM)
            if len(link.cap_faces):
                scene.add_mesh_simple(f"{root}/link{link.index}/cap", link.cap_vertices, link.cap_faces, color=JOINT_CAP_BLUE)
            self._links.append(node)
        scene.add_frame(f"{root}/link6/flange_frame", axes_length=0.15, axes_radius=0.005, origin_radius=0.01)

    def render(self, snapshot: Snapshot) -> None:
        wxyz, position = poses(snapshot.frames)
        for node, w, p in zip(self._links, wxyz, position):
            node.wxyz = w
            node.position = p

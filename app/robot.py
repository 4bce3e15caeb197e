"""The solid arm: link meshes in a kinematic tree of DH frames, plus the base and flange axes.

Link i's node is a child of link i−1's, posed by the link transform T(i−1, i). Its
translation is a constant of the DH table, so moving the arm only turns six nodes: six
small messages per redraw instead of fourteen.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core.orientation import quaternion

from .fast_updates import set_orientations
from .meshes import LinkMesh
from .state import Snapshot
from .view import View
from .style import ALUMINIUM, JOINT_CAP_GREY


def poses(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 4, 4) frames the core computed → (wxyz (..., 4), position (..., 3)) for viser."""
    return quaternion(frames[..., :3, :3], check=False), frames[..., :3, 3]


def node_name(index: int, root: str = "/arm") -> str:
    """Scene-tree name of link ``index``'s node: ``/arm/link0/link1/…/link<index>``."""
    return root + "".join(f"/link{i}" for i in range(index + 1))


class RobotScene(View):
    def __init__(self, scene: viser.SceneApi, links: tuple[LinkMesh, ...], first: Snapshot) -> None:
        scene.add_frame("/base_frame", axes_length=0.3, axes_radius=0.008, origin_radius=0.015)
        wxyz, position = poses(first.arm.link_transforms(first.q))
        self.links: list[viser.FrameHandle] = []
        for link in links:
            i = link.index
            pose = {} if i == 0 else {"wxyz": wxyz[i - 1], "position": position[i - 1]}
            node = scene.add_frame(node_name(i), show_axes=False, **pose)
            scene.add_mesh_simple(f"{node_name(i)}/body", link.body_vertices, link.body_faces, color=ALUMINIUM)
            if len(link.cap_faces):
                scene.add_mesh_simple(f"{node_name(i)}/cap", link.cap_vertices, link.cap_faces, color=JOINT_CAP_GREY)
            self.links.append(node)
        scene.add_frame(f"{node_name(6)}/flange_frame", axes_length=0.15, axes_radius=0.005, origin_radius=0.01)

    def render(self, snapshot: Snapshot) -> None:
        set_orientations(self.links[1:], snapshot.link_wxyz)  # the translations never change

"""The solid arm: link meshes in a kinematic tree of DH frames, plus the base and flange axes.

Link i's node is a child of link i−1's, posed by the link transform T(i−1, i). Its
translation is a constant of the DH table, so moving the arm only turns six nodes: six
small messages per redraw instead of fourteen. Each node holds the meshes of every model
(the real UR10, the schematic): switching model only changes which are visible.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import viser

from ur10core.orientation import quaternion

from ..feedback import chosen
from ..meshes import ArmModels
from ..state import Snapshot
from ..style import ALUMINIUM, JOINT_CAP_GREY
from ..view import Session, View
from ..viser_internals.fast_updates import set_orientations

if TYPE_CHECKING:
    from .drawings import MeshArm


def poses(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 4, 4) frames the core computed → (wxyz (..., 4), position (..., 3)) for viser."""
    return quaternion(frames[..., :3, :3], check=False), frames[..., :3, 3]


def node_name(index: int, root: str = "/arm") -> str:
    """Scene-tree name of link ``index``'s node: ``/arm/link0/link1/…/link<index>``."""
    return root + "".join(f"/link{i}" for i in range(index + 1))


def model_slug(name: str) -> str:
    """Scene-tree name of a model's meshes under each link node: "Real UR10" → "real_ur10"."""
    return "".join(c if c.isalnum() else "_" for c in name.lower())


class RobotScene(View):
    """The solid arm. A model's meshes are sent when it is first shown: a browser that never
    switches model never receives the other's (a tenth of the cost of a newcomer's scene)."""

    def __init__(self, scene: viser.SceneApi, models: ArmModels, first: Snapshot) -> None:
        scene.add_frame("/base_frame", axes_length=0.3, axes_radius=0.008, origin_radius=0.015)
        wxyz, position = poses(first.arm.link_transforms(first.q))
        self._scene, self._models = scene, models
        self._shading = {"material": models.material, "cast_shadow": models.shadows, "receive_shadow": models.shadows}
        self.names: tuple[str, ...] = tuple(models.names)  #: the models it can be drawn as
        self.model = models.names[0]
        self.links: list[viser.FrameHandle] = []
        #: the mesh handles (bodies and caps) of each model sent so far
        self.meshes: dict[str, list[viser.MeshHandle]] = {}
        for i in range(7):
            pose = {} if i == 0 else {"wxyz": wxyz[i - 1], "position": position[i - 1]}
            self.links.append(scene.add_frame(node_name(i), show_axes=False, **pose))
        self._send(self.model)
        scene.add_frame(f"{node_name(6)}/flange_frame", axes_length=0.15, axes_radius=0.005, origin_radius=0.01)

    def _send(self, name: str) -> None:
        models, handles, shading = self._models, [], self._shading
        for link in models.by_name[name]:
            parent = f"{node_name(link.index)}/{model_slug(name)}"
            handles.append(self._scene.add_mesh_simple(
                f"{parent}/body", link.body_vertices, link.body_faces, color=ALUMINIUM, **shading))
            if len(link.cap_faces):
                handles.append(self._scene.add_mesh_simple(
                    f"{parent}/cap", link.cap_vertices, link.cap_faces, color=JOINT_CAP_GREY, **shading))
        self.meshes[name] = handles

    def set_material(self, material: str) -> None:
        """Shade the arm with viser's ``material`` ("standard", "toon3"), the models sent so far and those to come."""
        self._shading["material"] = material
        for handle in (handle for handles in self.meshes.values() for handle in handles):
            handle.material = material

    def show(self, model: str) -> None:
        """Draw the arm as ``model`` (one of :attr:`names`)."""
        if model not in self.names:
            raise ValueError(f"no arm model {model!r}; the models are {', '.join(self.names)}")
        if model not in self.meshes:
            self._send(model)
        for name, handles in self.meshes.items():
            for handle in handles:
                handle.visible = name == model
        self.model = model  # named once drawn: whoever reads it finds its meshes

    def render(self, snapshot: Snapshot) -> None:
        set_orientations(self.links[1:], snapshot.link_wxyz)  # the translations never change


class ArmModelControls(View):
    """"Arm drawn as": the real UR10 or the schematic arm, for the solid arm and its ghosts.

    The dropdown sits in the Joints folder (``folder``); the scene is the session's, or
    the classroom's shared scene that its presenter drives.
    """

    def __init__(self, gui: viser.GuiApi, folder: viser.GuiFolderHandle, views: "MeshArm",
                 session: Session) -> None:
        self._views, self._session = views, session
        self._seen = views.robot.model  #: the model the dropdown last matched: another hand may draw another
        with folder:
            self.dropdown = gui.add_dropdown(
                "Arm drawn as", views.robot.names, initial_value=views.robot.model,
                hint="UR's own meshes, or the schematic arm that shows the DH geometry more plainly")
        self.dropdown.on_update(session.guard(self._chosen))

    def _chosen(self, _: viser.GuiEvent) -> None:
        model = chosen(self.dropdown, "arm model")
        if model == self._seen:  # render_panel matching the dropdown to what it read was drawn: no choice, and by
            return  # now maybe stale (a light view turned off meanwhile drew the real arm, and this drew it back)
        with self._session.state.lock:
            self._views.show(model)
            self._seen = model
        self._session.redraw()

    def render_panel(self, snapshot: Snapshot) -> None:
        # only a change of hands (the classroom's presenter) draws another model under this dropdown; while
        # this browser's own choice is being drawn, the arm is still the old model and the choice must stand
        model = self._views.robot.model
        if model != self._seen:
            self._seen = model
            self.dropdown.value = model

"""How an arm is drawn in 3D, chosen per arm: UR's meshes, its DH skeleton, or the desktop arm's own drawing.

Why it is built so: docs/architecture.md §2.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core import Arm

from ..meshes import ArmModels
from ..state import Snapshot
from ..style import UR10_SIZE
from .branch_labels import chain
from .camera import BODY_RADIUS
from .course_arms.desktop_arm import DesktopArmScene
from .course_arms.scene import CourseArmScene
from .dh_frames import FRAMES_NONE, DHFrames
from .floor import FloorScene
from .ik_target import GHOST_STYLES, BranchesScene
from .robot import RobotScene, node_name
from .singularity import SingularityOverlay


def reach(arm: Arm) -> float:
    """How far the arm's tool gets from the base (m), from a workspace sample: sizes follow it."""
    points, _ = arm.sample_workspace(4000, seed=0)
    return float(max(np.linalg.norm(points, axis=-1).max(), 0.3))


def _of_branches(name: str) -> property:
    return property(lambda self: getattr(self.branches, name), lambda self, value: setattr(self.branches, name, value))


class MeshArm:
    """A UR-family arm drawn with its meshes: the solid arm, eight mesh ghosts, the overlay, floor warnings.

    A session builds its own on its browser's scene; the classroom builds one on the
    shared scene, which the presenter's session then drives. Its nodes keep the names
    they have always had ("/arm", "/ghosts", …): a classroom explorer's own UR10 reuses
    them in its browser's scope, which hides the class's.
    """

    root = ""
    world = np.eye(4)
    size = handle_size = UR10_SIZE
    body_radius = BODY_RADIUS

    def __init__(self, scene: viser.SceneApi, models: ArmModels, first: Snapshot, target_marker: bool = False) -> None:
        self.robot = RobotScene(scene, models, first)
        self.branches = BranchesScene(scene, models, first, target_marker)
        self.overlay = SingularityOverlay(scene, first.arm, first, UR10_SIZE, "", link_node=node_name)
        self.floor = FloorScene(scene, self.branches)
        #: the table's frames on the arm, hidden until the DH folders draw them
        self.dh_frames = DHFrames(scene, first.arm, first.frames, UR10_SIZE, "/dh_frames", at_rest=FRAMES_NONE)
        self.target = self.branches.target
        self.roots = ("/base_frame", "/arm", "/ghosts", "/floor_hits", "/singular", "/dh_frames",
                      *(("/target",) if target_marker else ()))
        self.names = self.robot.names
        # the floor after the branches: it marks the ghosts they drew
        self._views = (self.robot, self.branches, self.overlay, self.floor, self.dh_frames)
        #: the 3D labels placed apart for a camera, in order, each pool clear of those before it
        self.label_sets = chain((self.overlay.names, self.dh_frames.values, self.dh_frames.names, self.branches.numbers))

    # which ghosts are drawn, and who hears a click on one: the mesh ghosts' own
    show_ghosts = _of_branches("show_ghosts")
    focus = _of_branches("focus")
    on_select = _of_branches("on_select")

    ghost_styles = GHOST_STYLES
    clicked = "a ghost"  #: what a student clicks to put the arm on a ghost's branch

    @property
    def ghost_style(self) -> str:
        return self.branches.style

    def set_ghost_style(self, style: str) -> None:
        self.branches.set_style(style)

    def show(self, model: str) -> None:
        """Draw the solid arm and its ghosts as ``model`` ("Real UR10", "Schematic")."""
        self.robot.show(model)
        self.branches.show(model)

    def set_material(self, material: str) -> None:
        self.robot.set_material(material)
        self.branches.set_material(material)

    def framed(self, snapshot: Snapshot) -> Snapshot:
        return snapshot

    def render(self, snapshot: Snapshot) -> None:
        for view in self._views:
            view.render(snapshot)

    def render_panel(self, snapshot: Snapshot) -> None:
        # the labels of the overlay and the frames first: the branch numbers keep clear of them
        for view in (self.overlay, self.dh_frames, self.robot, self.branches, self.floor):
            view.render_panel(snapshot)


def arm_drawing(scene: viser.SceneApi, arm: Arm, first: Snapshot, models: ArmModels | None = None,
                root: str | None = None, target_marker: bool = False) -> MeshArm | CourseArmScene | DesktopArmScene:
    """The arm in 3D: with ``models`` (UR's meshes, for a UR-family arm), its DH skeleton, or, for an arm
    without a DH table, its own drawing. ``root``: a classroom explorer's own arm, apart from the class's."""
    if models is not None:
        return MeshArm(scene, models, first, target_marker)
    kind = DesktopArmScene if arm.dh is None else CourseArmScene
    return kind(scene, arm, first, reach(arm), *(() if root is None else (root,)), target_marker=target_marker)

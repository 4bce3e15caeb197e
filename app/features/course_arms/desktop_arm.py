"""The course's 3-DOF desktop arm in 3D (docs/kinematics.md §8.6): on a pedestal, with its parallelogram drive.

The arm has no DH table (its forearm angle is absolute), so it is drawn from its frames,
not its DH skeleton; everything else is a course arm's (``session.ArmSession``). Its
base frame has y up: a node under the top one (``root``, ``scene.world_placement``) stands it in the
world (z up), and every node under it, the IK target and the other features' drawings
included, is in the course's frame.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core import Arm
from ur10core.orientation import quaternion

from ...state import Snapshot
from ...style import JOINT_CAP_GREY, SHOULDER_COLOR
from ..branch_labels import BranchLabels
from ..ik_target import numbered
from ..singularity import SingularityOverlay
from .scene import LineDrawing

ROOT = "/desktop_arm"
#: A classroom explorer's own desktop arm, apart from the class's (which it hides in that one browser).
EXPLORER_ROOT = "/explored_desktop_arm"
#: Length of the parallelogram's crank at the shoulder (m): the drive is drawn to scale with it.
CRANK = 0.3
LINK_GREY = (90, 94, 102)
#: What the drawing names in 3D: the base frame's axes (at their tips), the joints' angles and the tool.
NAMES = ("x₀", "y₀ (up)", "z₀", "θ2", "θ3 (absolute)", "tool")
AXIS_TIPS = np.array([[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]])
DRIVE_COLOR = SHOULDER_COLOR


class DesktopArmScene(LineDrawing):
    """Pedestal, upper arm and forearm, the parallelogram drive, the course's base frame, one ghost per branch,
    The course arms' scene for an arm without a DH table (the tool's v and ω while a path plays are the
    velocities folder's arrows)."""

    dh_frames = None  #: no DH frames to show (the DH folders say why)

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: Snapshot, size: float, top: str = ROOT,
                 target_marker: bool = False) -> None:
        self._arm = arm
        self._place(scene, arm, top)  # the course's base frame (y up), placed in the world under ``top``
        root = self.root
        self.size = size  #: the arm's reach (m)
        points = self._points(first.frames)
        self.links = scene.add_line_segments(f"{root}/links", self._links(points), LINK_GREY, thickness=0.06)
        self.drive = scene.add_line_segments(f"{root}/drive", self._drive(points), DRIVE_COLOR, thickness=0.025)
        self.joints = [scene.add_icosphere(f"{root}/joint_{k}", radius=0.07, color=JOINT_CAP_GREY, position=p)
                       for k, p in enumerate(points[1:3])]
        scene.add_frame(f"{root}/base_frame", axes_length=0.45, axes_radius=0.012)
        self.tool = scene.add_frame(f"{root}/tool", axes_length=0.3, axes_radius=0.01)
        #: the base frame's axes and what the joints are, named apart on the screen like the branch numbers
        self.captions = BranchLabels(scene, f"{root}/names", len(NAMES), scale=1.3, merge_px=4.0)
        self._name_points = np.zeros((len(NAMES), 3))
        self._add_ghosts(scene, arm, first.frames, 0.03, 0.05 * size)
        #: det J_v's two factors in 3D: the tool's distance from the vertical axis, the upper arm and forearm
        self.overlay = SingularityOverlay(scene, arm, first, size, root)
        # the captions keep clear of the factors' names, and the numbers of both
        self.label_sets = self._label_sets((self.overlay.names, self.captions, self.numbers))
        if target_marker:
            self._add_target_marker(scene)
        self.render(first)

    @property
    def handle_size(self) -> float:
        """1.5 × its reach: its ghosts reach behind the shoulder as far as the arm reaches in front (θ1 + 180°), so
        its camera frames about twice the arm, and a gizmo sized by the reach alone was 43 px long on a 1280 × 720
        canvas (the other arms' 63–104), the force's handle too."""
        return 1.5 * self.size

    def _points(self, frames: np.ndarray) -> np.ndarray:
        """(4, 3) the pedestal's foot, the shoulder, the elbow and the tool, in the course's frame."""
        return np.vstack([self.foot, frames[..., :3, 3]])

    @staticmethod
    def _links(points: np.ndarray) -> np.ndarray:
        foot, shoulder, elbow, tool = points
        return np.array([[foot, shoulder], [shoulder, elbow], [elbow, tool]])

    @staticmethod
    def _drive(points: np.ndarray) -> np.ndarray:
        """The crank at the shoulder, the coupler and the lever at the elbow: a parallelogram, so the forearm keeps the crank's angle."""
        _, shoulder, elbow, tool = points
        back = CRANK * (elbow - tool) / np.linalg.norm(tool - elbow)
        return np.array([[shoulder, shoulder + back], [shoulder + back, elbow + back], [elbow + back, elbow]])

    def render(self, snapshot: Snapshot) -> None:
        points = self._points(snapshot.frames)
        self.links.points = self._links(points)
        drive = self._drive(points)
        self.drive.points = drive
        for joint, point in zip(self.joints, points[1:3]):
            joint.position = point
        self.tool.wxyz = quaternion(snapshot.flange[:3, :3], check=False)
        self.tool.position = points[3]
        self._name_points = np.vstack([AXIS_TIPS, points[1], drive[0, 1], points[3]])
        self.overlay.render(snapshot)
        self._render_ghosts(snapshot)

    def render_panel(self, snapshot: Snapshot) -> None:
        """The factors' names, the captions and the branch numbers, each placed clear of those before it."""
        self.overlay.render_panel(snapshot)
        self.captions.show(self._name_points, list(NAMES))
        self.numbers.show(self._ghost_labels(snapshot), numbered(snapshot, self.show_ghosts, self.focus))

    def _ghost_lines(self, frames: np.ndarray) -> np.ndarray:
        return self._links(self._points(frames))[1:]

    def _ghost_labels(self, snapshot: Snapshot) -> np.ndarray:
        return np.array([self._points(frames)[2] for frames in snapshot.ghost_frames])  # the elbows

    def _ghost_joints(self, frames: np.ndarray) -> np.ndarray:
        return self._points(frames)[2:]  # the elbow and the tool (the shoulder is the solid arm's)

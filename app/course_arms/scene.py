"""The course arm in 3D: its DH skeleton, joint axes, DH frames with their labels, and one ghost per branch.

The arm is drawn as the DH method builds it: from each frame origin to the next along d
and a (:func:`skeleton`), a short rod along each joint axis (a box for a prismatic joint),
and, optionally, the x and z axes of every frame with their names. Each IK slot is a thin ghost skeleton in
its slot colour with its number at the tool, as the UR10's ghosts are.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core.orientation import quaternion
from ur10core.dh import DHTable
from ur10core.serial import SerialArm

from ..style import JOINT_CAP_GREY, SLOT_COLORS
from .state import CourseSnapshot

ROOT = "/course_arm"
SKELETON_GREY = (60, 62, 68)
X_AXIS_RED, Z_AXIS_BLUE = (213, 94, 0), (0, 114, 178)  # Okabe-Ito vermilion and blue


def skeleton(table: DHTable, frames: np.ndarray) -> np.ndarray:
    """(m, 2, 3) segments of the DH construction, zero-length ones dropped (at least one kept).

    Each row goes from one frame origin to the next in two straight moves, as the row's
    transform does: standard DH along z_{i−1} by d_i, then along x_i by a_i; modified DH
    along x_{i−1} by a_{i−1}, then along z_i by d_i.
    """
    origins = frames[..., :3, 3]
    points = [origins[0]]
    for i, row in enumerate(table.rows, start=1):
        if table.convention == "standard":
            corner = origins[i] - row.a * frames[i, :3, 0]
        else:
            corner = origins[i - 1] + row.a * frames[i - 1, :3, 0]
        points += [corner, origins[i]]
    points = np.array(points)
    segments = np.stack([points[:-1], points[1:]], axis=-2)
    long = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=-1) > 1e-9
    return segments[long] if long.any() else segments[:1]


class CourseArmScene:
    """Everything one course arm draws in a browser's scene."""

    def __init__(self, scene: viser.SceneApi, arm: SerialArm, first: CourseSnapshot, size: float) -> None:
        self._scene = scene
        self._arm = arm
        self.size = size  #: the arm's reach (m): sizes of rods, axes and the gizmo follow it
        self.show_frames = True
        segments = skeleton(arm.dh, first.frames)
        self.body = scene.add_line_segments(f"{ROOT}/body", segments, SKELETON_GREY, thickness=0.012 * size)
        self.joints = []
        for k, kind in enumerate(arm.joint_types):
            if kind == "R":
                rod = scene.add_cylinder(f"{ROOT}/joint{k + 1}", radius=0.018 * size, height=0.06 * size,
                                         color=JOINT_CAP_GREY)
            else:
                rod = scene.add_box(f"{ROOT}/joint{k + 1}", color=JOINT_CAP_GREY,
                                    dimensions=(0.03 * size, 0.03 * size, 0.06 * size))
            self.joints.append(rod)
        count = len(first.frames)
        self.axes = scene.add_batched_axes(f"{ROOT}/frames", np.tile((1.0, 0, 0, 0), (count, 1)), np.zeros((count, 3)),
                                           axes_length=0.12 * size, axes_radius=0.006 * size)
        self.axis_labels = [
            (scene.add_label(f"{ROOT}/frame_labels/x{i}", f"x{i}", font_screen_scale=1.1, anchor="center-left"),
             scene.add_label(f"{ROOT}/frame_labels/z{i}", f"z{i}", font_screen_scale=1.1, anchor="center-left"))
            for i in range(count)
        ]
        slots = len(arm.slot_labels)
        self.ghosts = [scene.add_line_segments(f"{ROOT}/ghosts/slot{k + 1}", segments, SLOT_COLORS[k % len(SLOT_COLORS)],
                                               thickness=0.006 * size) for k in range(slots)]
        self.ghost_labels = [scene.add_label(f"{ROOT}/ghosts/slot{k + 1}/number", str(k + 1), font_screen_scale=1.4,
                                             anchor="bottom-center") for k in range(slots)]

    def render(self, snapshot: CourseSnapshot) -> None:
        frames = snapshot.frames
        self.body.points = skeleton(self._arm.dh, frames)
        z, o = self._arm.dh.joint_axes(frames)
        for rod, axis, point, kind in zip(self.joints, z, o, self._arm.joint_types):
            rotation = np.eye(3)
            rotation[:, 2] = axis
            helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
            rotation[:, 0] = np.cross(helper, axis) / np.linalg.norm(np.cross(helper, axis))
            rotation[:, 1] = np.cross(axis, rotation[:, 0])
            rod.wxyz = quaternion(rotation, check=False)
            rod.position = point
        self._render_frames(frames)
        sol = snapshot.solution
        for k, (ghost, label) in enumerate(zip(self.ghosts, self.ghost_labels)):
            shown = sol is not None and bool(sol.valid[k]) and k != snapshot.chosen
            ghost.visible = label.visible = shown
            if shown:
                ghost_frames = self._arm.frames(sol.q[k])
                ghost.points = skeleton(self._arm.dh, ghost_frames)
                label.position = ghost_frames[-1, :3, 3]

    def _render_frames(self, frames: np.ndarray) -> None:
        self.axes.visible = self.show_frames
        for i, (x_label, z_label) in enumerate(self.axis_labels):
            x_label.visible = z_label.visible = self.show_frames
            if self.show_frames:
                tip = 0.14 * self.size
                x_label.position = frames[i, :3, 3] + tip * frames[i, :3, 0]
                z_label.position = frames[i, :3, 3] + tip * frames[i, :3, 2]
        if self.show_frames:
            self.axes.batched_wxyzs = quaternion(frames[:, :3, :3], check=False)
            self.axes.batched_positions = frames[:, :3, 3]

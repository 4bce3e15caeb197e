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
from ur10core import Arm

from ...viser_internals.fast_updates import set_orientations, set_positions
from ...style import JOINT_CAP_GREY, SLOT_COLORS
from .overlay import CourseOverlay, has_overlay
from .state import CourseSnapshot

ROOT = "/course_arm"
#: An explorer's own arm in a classroom, apart from the class's (which it hides in that one browser).
EXPLORER_ROOT = "/explored_arm"
SKELETON_GREY = (60, 62, 68)
X_AXIS_RED, Z_AXIS_BLUE = (220, 30, 30), (30, 60, 230)
#: A highlighted row's parameters (Okabe-Ito): d blue, a vermilion, θ bluish green, α reddish purple.
PARAMETER_COLORS = {"d": (0, 114, 178), "a": (213, 94, 0), "theta": (0, 158, 115), "alpha": (204, 121, 167)}
#: Which axes the frames show: none, the z axes only (the walkthrough's first step), or x and z.
FRAMES_NONE, FRAMES_Z, FRAMES_XZ = "none", "z", "xz"


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


def rod_rotations(axes: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations whose z columns are the unit ``axes`` (n, 3): how each joint's rod is turned."""
    helper = np.where(np.abs(axes[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, axes)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    return np.stack([x, np.cross(axes, x), axes], axis=-1)


def show(node: viser.SceneNodeHandle, visible) -> None:
    """Set a node's visibility only when it changes (viser's setter costs tens of µs even then)."""
    if node.visible != bool(visible):
        node.visible = bool(visible)


class CourseArmScene:
    """Everything one course arm draws in a browser's scene."""

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: CourseSnapshot, size: float,
                 root: str = ROOT) -> None:
        self._scene = scene
        self.root = self.top = root  #: every node's parent: a classroom explorer's own arm has one apart from the class's
        self._arm = arm
        self.size = size  #: the arm's reach (m): sizes of rods, axes and the gizmo follow it
        segments = skeleton(arm.dh, first.frames)
        self.body = scene.add_line_segments(f"{root}/body", segments, SKELETON_GREY, thickness=0.012 * size)
        self.joints = []
        for k, kind in enumerate(arm.joint_types):
            if kind == "R":
                rod = scene.add_cylinder(f"{root}/joint{k + 1}", radius=0.018 * size, height=0.06 * size,
                                         color=JOINT_CAP_GREY)
            else:
                rod = scene.add_box(f"{root}/joint{k + 1}", color=JOINT_CAP_GREY,
                                    dimensions=(0.03 * size, 0.03 * size, 0.06 * size))
            self.joints.append(rod)
        count = len(first.frames)
        self.frames_shown = FRAMES_XZ
        self.highlight_row: int | None = None  #: a DH row (1-based) whose parameters are drawn on the arm
        nothing = np.zeros((count, 2, 3))
        self.z_axes = scene.add_line_segments(f"{root}/frames/z", nothing, Z_AXIS_BLUE, thickness=0.008 * size)
        self.x_axes = scene.add_line_segments(f"{root}/frames/x", nothing, X_AXIS_RED, thickness=0.008 * size)
        self.axis_labels = [
            (scene.add_label(f"{root}/frame_labels/x{i}", f"x{i}", font_screen_scale=1.1, anchor="center-left"),
             scene.add_label(f"{root}/frame_labels/z{i}", f"z{i}", font_screen_scale=1.1, anchor="center-left"))
            for i in range(count)
        ]
        self.parameters = {key: scene.add_line_segments(f"{root}/row/{key}", np.zeros((1, 2, 3)), colour,
                                                        thickness=0.016 * size, visible=False)
                           for key, colour in PARAMETER_COLORS.items()}
        self.parameter_labels = {key: scene.add_label(f"{root}/row/{key}/value", key, font_screen_scale=1.3,
                                                      anchor="bottom-center", visible=False)
                                 for key in PARAMETER_COLORS}
        slots = len(arm.slot_labels)
        _, points = arm.dh.joint_axes(first.frames)
        self._label_frame = arm.dh.joint_rows[min(2, arm.n_joints - 1)] + (0 if arm.convention == "standard" else 1)
        self.ghosts = [scene.add_line_segments(f"{root}/ghosts/slot{k + 1}", segments, SLOT_COLORS[k % len(SLOT_COLORS)],
                                               thickness=0.006 * size) for k in range(slots)]
        self.ghost_labels = [scene.add_label(f"{root}/ghosts/slot{k + 1}/number", str(k + 1), font_screen_scale=1.4,
                                             anchor="bottom-center") for k in range(slots)]
        #: det J's factors in 3D (a preset's; a typed table's det J is not derived)
        self.overlay = CourseOverlay(scene, arm, first, size, root) if has_overlay(arm) else None

    #: Where the arm's base frame is in the scene: at the world's origin.
    world = np.eye(4)

    def framed(self, snapshot: CourseSnapshot) -> CourseSnapshot:
        """What the camera frames: the arm's frames and target, in the world as they are."""
        return snapshot

    def render(self, snapshot: CourseSnapshot) -> None:
        frames = snapshot.frames
        self._q = snapshot.q
        self.body.points = skeleton(self._arm.dh, frames)
        z, o = self._arm.dh.joint_axes(frames)
        set_orientations(self.joints, quaternion(rod_rotations(z), check=False))
        set_positions(self.joints, o)
        self._render_frames(frames)
        if self.overlay is not None:
            self.overlay.render(snapshot)
        sol = snapshot.solution
        shown = np.zeros(len(self.ghosts), bool)
        if sol is not None:
            shown[:] = sol.valid
            if snapshot.chosen >= 0:
                shown[snapshot.chosen] = False  # the arm itself
        ghost_frames = dict(zip(np.flatnonzero(shown), self._arm.frames(sol.q[shown]))) if shown.any() else {}  # one call
        for k, (ghost, label) in enumerate(zip(self.ghosts, self.ghost_labels)):
            show(ghost, shown[k])
            show(label, shown[k])
            if shown[k]:
                ghost.points = skeleton(self._arm.dh, ghost_frames[k])
        labelled = np.flatnonzero(shown)  # at each ghost's middle joint: the branches share the tool, not their elbows
        set_positions([self.ghost_labels[k] for k in labelled],
                      np.array([ghost_frames[k][self._label_frame, :3, 3] for k in labelled]).reshape(-1, 3))

    def _render_frames(self, frames: np.ndarray) -> None:
        shown = self.frames_shown
        length = 0.12 * self.size
        origins = frames[:, :3, 3]
        show(self.z_axes, shown != FRAMES_NONE)
        show(self.x_axes, shown == FRAMES_XZ)
        if shown != FRAMES_NONE:
            self.z_axes.points = np.stack([origins, origins + length * frames[:, :3, 2]], axis=1)
        if shown == FRAMES_XZ:
            self.x_axes.points = np.stack([origins, origins + length * frames[:, :3, 0]], axis=1)
        for x_label, z_label in self.axis_labels:
            show(z_label, shown != FRAMES_NONE)
            show(x_label, shown == FRAMES_XZ)
        if shown != FRAMES_NONE:
            tip = 0.14 * self.size
            x_labels, z_labels = zip(*self.axis_labels)
            set_positions(list(x_labels) + list(z_labels),
                          np.concatenate([origins + tip * frames[:, :3, 0], origins + tip * frames[:, :3, 2]]))
        self._render_row()

    def _render_row(self) -> None:
        row = self.highlight_row
        for key in PARAMETER_COLORS:
            self.parameters[key].visible = self.parameter_labels[key].visible = row is not None
        if row is None:
            return
        geometry = self._arm.dh.row_geometry(self._q, row)
        values = geometry.values
        radius = 0.08 * self.size
        # the subscripts the table uses: modified DH writes a row's a and α as a_{i−1}, α_{i−1}
        previous = row if self._arm.convention == "standard" else row - 1
        index = {"d": row, "theta": row, "a": previous, "alpha": previous}
        names = {"d": "d", "a": "a", "theta": "θ", "alpha": "α"}
        for key in ("d", "a", "theta", "alpha"):  # a zero parameter has nothing to draw (the panel lists it)
            self.parameters[key].visible = self.parameter_labels[key].visible = abs(values[key]) > 1e-9
        for key in ("d", "a"):
            segment = geometry.d if key == "d" else geometry.a
            self.parameters[key].points = segment[None]
            self.parameter_labels[key].position = segment.mean(axis=0)
            self.parameter_labels[key].text = f"{names[key]}{index[key]} = {1000 * values[key]:.1f} mm"
        for key in ("theta", "alpha"):
            turn = geometry.theta if key == "theta" else geometry.alpha
            arc = turn.points(radius)
            self.parameters[key].points = np.stack([arc[:-1], arc[1:]], axis=1)
            self.parameter_labels[key].position = arc[len(arc) // 2]
            self.parameter_labels[key].text = f"{names[key]}{index[key]} = {np.degrees(values[key]):.1f}°"

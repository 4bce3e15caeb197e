"""The DH frames on any arm with a DH table: x (red) and z (blue) of every frame, named, and one row's parameters.

What the DH folders draw (docs/kinematics.md §2, §7.1): the frames as the table places them
(``arm.frames(q)``), or only their z axes (the walkthrough's first step), and a highlighted
row's d and a as segments, θ and α as arcs, each with its value. The course's arms show
their frames from the start; the UR10 shows them when its walkthrough or its checkbox asks.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core import Arm

from ..view import View
from .branch_labels import BranchLabels

X_AXIS_RED, Z_AXIS_BLUE = (220, 30, 30), (30, 60, 230)
AXIS_NAME_SCALE = 1.2
#: A highlighted row's parameters (Okabe-Ito): d blue, a vermilion, θ bluish green, α reddish purple.
PARAMETER_COLORS = {"d": (0, 114, 178), "a": (213, 94, 0), "theta": (0, 158, 115), "alpha": (204, 121, 167)}
#: Which axes the frames show: none, the z axes only (the walkthrough's first step), or x and z.
FRAMES_NONE, FRAMES_Z, FRAMES_XZ = "none", "z", "xz"


def show(node: viser.SceneNodeHandle, visible) -> None:
    """Set a node's visibility only when it changes (viser's setter costs tens of µs even then)."""
    if node.visible != bool(visible):
        node.visible = bool(visible)


class DHFrames(View):
    """The frames of ``arm``'s DH table under ``root``, sized for an arm that reaches ``size`` m.

    ``shown`` (:data:`FRAMES_XZ`, ...) and ``highlight_row`` (1-based, or None) say what is
    drawn; ``at_rest`` is what ``shown`` goes back to when a walkthrough stops.
    """

    def __init__(self, scene: viser.SceneApi, arm: Arm, frames: np.ndarray, size: float, root: str,
                 at_rest: str = FRAMES_XZ) -> None:
        self._arm = arm
        self.size = size
        self.shown = self.at_rest = at_rest
        self.highlight_row: int | None = None
        self._q = np.zeros(arm.n_joints)
        count = len(frames)
        nothing = np.zeros((count, 2, 3))
        self.z_axes = scene.add_line_segments(f"{root}/frames/z", nothing, Z_AXIS_BLUE, thickness=0.008 * size, visible=False)
        self.x_axes = scene.add_line_segments(f"{root}/frames/x", nothing, X_AXIS_RED, thickness=0.008 * size, visible=False)
        #: each axis named at its tip; names that would overlap on screen read as one ("x4 · x6")
        self.names = BranchLabels(scene, f"{root}/frame_labels", 2 * count, scale=AXIS_NAME_SCALE,
                                  colours=[X_AXIS_RED] * count + [Z_AXIS_BLUE] * count, merge_px=4.0)
        self._tips = np.zeros((2 * count, 3))
        self.parameters = {key: scene.add_line_segments(f"{root}/row/{key}", np.zeros((1, 2, 3)), colour,
                                                        thickness=0.016 * size, visible=False)
                           for key, colour in PARAMETER_COLORS.items()}
        #: the highlighted row's values, by its segments and arcs, placed apart on the screen
        self.values = BranchLabels(scene, f"{root}/row/values", len(PARAMETER_COLORS), scale=1.3,
                                   colours=list(PARAMETER_COLORS.values()), merge_px=4.0)
        self._value_points, self._value_texts = np.zeros((len(PARAMETER_COLORS), 3)), [""] * len(PARAMETER_COLORS)
        self._drawn = False  #: something is on screen (hidden frames cost a drag nothing)
        self._nodes = (self.z_axes, self.x_axes, *self.names.labels, *self.values.labels, *self.parameters.values())

    @property
    def parameter_labels(self) -> dict[str, viser.LabelHandle]:
        """The label showing each of the highlighted row's values ("d", "a", "theta", "alpha")."""
        return self.values.carriers(list(PARAMETER_COLORS))

    def render(self, snapshot) -> None:
        frames = snapshot.frames
        self._q = snapshot.q
        shown = self.shown
        if shown == FRAMES_NONE and self.highlight_row is None and not self._drawn:
            return
        self._drawn = shown != FRAMES_NONE or self.highlight_row is not None
        length = 0.12 * self.size
        origins = frames[:, :3, 3]
        show(self.z_axes, shown != FRAMES_NONE)
        show(self.x_axes, shown == FRAMES_XZ)
        if shown != FRAMES_NONE:
            self.z_axes.points = np.stack([origins, origins + length * frames[:, :3, 2]], axis=1)
        if shown == FRAMES_XZ:
            self.x_axes.points = np.stack([origins, origins + length * frames[:, :3, 0]], axis=1)
        tip = 0.14 * self.size
        self._tips = np.concatenate([origins + tip * frames[:, :3, 0], origins + tip * frames[:, :3, 2]])
        self._render_row()

    def render_panel(self, snapshot) -> None:
        """The row's values and the axes' names, placed apart on the screen at the panel's pace."""
        self.values.show(self._value_points, self._value_texts)
        count = len(self._tips) // 2
        texts = [*(f"x{i}" if self.shown == FRAMES_XZ else "" for i in range(count)),
                 *(f"z{i}" if self.shown != FRAMES_NONE else "" for i in range(count))]
        self.names.show(self._tips, texts)

    def _render_row(self) -> None:
        row = self.highlight_row
        for key in PARAMETER_COLORS:
            show(self.parameters[key], row is not None)
        self._value_texts = [""] * len(PARAMETER_COLORS)
        if row is None:
            return
        geometry = self._arm.dh.row_geometry(self._q, row)
        values = geometry.values
        radius = 0.08 * self.size
        # the subscripts the table uses: modified DH writes a row's a and α as a_{i−1}, α_{i−1}
        previous = row if self._arm.convention == "standard" else row - 1
        index = {"d": row, "theta": row, "a": previous, "alpha": previous}
        names = {"d": "d", "a": "a", "theta": "θ", "alpha": "α"}
        keys = list(PARAMETER_COLORS)
        for key in keys:  # a zero parameter has nothing to draw (the panel lists it)
            show(self.parameters[key], abs(values[key]) > 1e-9)
        for key in ("d", "a"):
            segment = geometry.d if key == "d" else geometry.a
            self.parameters[key].points = segment[None]
            self._value_points[keys.index(key)] = segment.mean(axis=0)
            self._value_texts[keys.index(key)] = f"{names[key]}{index[key]} = {1000 * values[key]:.1f} mm"
        for key in ("theta", "alpha"):
            turn = geometry.theta if key == "theta" else geometry.alpha
            arc = turn.points(radius)
            self.parameters[key].points = np.stack([arc[:-1], arc[1:]], axis=1)
            self._value_points[keys.index(key)] = arc[len(arc) // 2]
            self._value_texts[keys.index(key)] = f"{names[key]}{index[key]} = {np.degrees(values[key]):.1f}°"
        for key in keys:
            if abs(values[key]) <= 1e-9:
                self._value_texts[keys.index(key)] = ""

    def close(self) -> None:
        """The session has gone: so do the frames, even from a scene everyone shares."""
        for node in self._nodes:
            node.remove()  # the labels of the row's parameters hang under their segments

"""A course arm's "Forces" folder: a force at the tool and τ = Jᵀ F at each joint (docs/kinematics.md §8.3).

The UR10's folder (``ur10teach.statics``) adds its weight and its joints' ratings; the course's
other arms come without masses, so this one shows the force's torques alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import viser

from ..feedback import chosen
from ..statics import ARROW_METRES_PER_N, DIRECTIONS, DRAGGED, FORCE_COLOR, MAX_FORCE_N, force_vector
from ..style import number
from ..view import View
from .state import CourseSnapshot

if TYPE_CHECKING:
    from .session import CourseArmSession

#: The directions a course arm's force takes: the UR10's, but "flange" is the tool here and no handle.
TOOL_DIRECTIONS = {("along the tool's z" if unit is None else name): name for name, unit in DIRECTIONS.items() if unit != DRAGGED}


def torques_markdown(torques: np.ndarray, names: tuple[str, ...], kinds: str, newtons: float) -> str:
    """τ per joint: N·m for a revolute joint, N (a force along its axis) for a prismatic one."""
    rows = [f"| {name} | {number(value, '+.2f')} {'N·m' if kind == 'R' else 'N'} |"
            for name, value, kind in zip(names, torques, kinds)]
    return "\n".join([f"The joints hold {newtons:.0f} N at the tool with τ = Jᵀ F:", "", "| joint | τ |", "|---|---:|", *rows])


class CourseForces(View):
    """A force at a course arm's tool: its arrow, and the torques the joints hold against it."""

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: "CourseArmSession", root: str) -> None:
        self._session = session
        folder = gui.add_folder("Forces", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.enabled = gui.add_checkbox("Show the force at the tool", False)
            self.newtons = gui.add_slider("Force at the tool (N)", min=0.0, max=MAX_FORCE_N, step=5.0, initial_value=50.0)
            self.direction = gui.add_dropdown("Force direction", tuple(TOOL_DIRECTIONS), initial_value="down (−z)")
            self.torques = gui.add_markdown("", visible=False)
        size = session.scene.size
        self.arrow = scene.add_arrows(f"{root}/force", np.zeros((1, 2, 3)), FORCE_COLOR, shaft_radius=0.01 * size,
                                      head_radius=0.025 * size, head_length=0.05 * size, visible=False)
        self.label = scene.add_label(f"{root}/force_label", "F", font_screen_scale=1.4, anchor="center-left", visible=False)
        self._metres_per_n = ARROW_METRES_PER_N * size  # the UR10's 10 cm per 50 N, for an arm 1 m across
        for widget in (self.enabled, self.newtons, self.direction):
            widget.on_update(session.guard(lambda _: session.redraw()))

    def force(self, snapshot: CourseSnapshot) -> np.ndarray:
        """(3,) the force in the base frame, N."""
        newtons = float(self.newtons.value)
        if not 0.0 <= newtons <= MAX_FORCE_N:
            raise ValueError(f"force: from 0 to {MAX_FORCE_N:g} N, got {newtons:g}")
        return force_vector(TOOL_DIRECTIONS[chosen(self.direction, "force direction")], newtons, snapshot.frames[-1])

    def render(self, snapshot: CourseSnapshot) -> None:
        shown = bool(self.enabled.value) and float(self.newtons.value) > 0.0
        if shown:
            tip = snapshot.frames[-1, :3, 3]
            end = tip + self._metres_per_n * self.force(snapshot)
            self.arrow.points = np.array([[tip, end]])
            self.label.position = end
            text = f"F = {float(self.newtons.value):.0f} N"
            if self.label.text != text:
                self.label.text = text
        for node in (self.arrow, self.label):
            if node.visible != shown:
                node.visible = shown

    def render_panel(self, snapshot: CourseSnapshot) -> None:
        self.torques.visible = bool(self.enabled.value)
        if self.torques.visible:
            arm = self._session.arm
            torques = arm.static_torques(snapshot.q, self.force(snapshot))
            self.torques.content = torques_markdown(torques, arm.joint_names, "".join(arm.joint_types), float(self.newtons.value))

    def close(self) -> None:
        self.arrow.remove()
        self.label.remove()

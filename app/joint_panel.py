"""Six joint sliders in degrees (±360°, each with its exact number box), pose buttons,
a box to type all six angles, and the UR-controller view of the same angles."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import viser

from .readouts import joints_markdown
from .state import COURSE_POSES, ArmState, Snapshot
from .style import JOINT_LABELS
from .view import View

if TYPE_CHECKING:
    from .session import ClientSession

POSE_BUTTONS = ("Zero", "Stretched", "Arbitrary", "Random")


class JointPanel(View):
    def __init__(self, gui: viser.GuiApi, session: "ClientSession") -> None:
        self._session = session
        self._rng = np.random.default_rng()
        q = np.degrees(session.state.q)
        folder = gui.add_folder("Joints (°)")
        self.folders = (folder,)
        with folder:
            self.sliders = [
                gui.add_slider(
                    f"θ{i + 1} {name}", min=-360.0, max=360.0, step=0.1, initial_value=round(float(q[i]), 2),
                    hint=f"Joint {i + 1} ({name}) in degrees; the UR10 turns ±360°. Type an exact value in the box.",
                )
                for i, name in enumerate(JOINT_LABELS)
            ]
            self.poses = gui.add_button_group("Pose", POSE_BUTTONS)
            self.typed = gui.add_text(
                "All six (°)", ", ".join(f"{v:g}" for v in COURSE_POSES["arbitrary"]),
                hint="Six angles in degrees, separated by commas or spaces, e.g. 30, 45, 26, 50, 60, 80",
            )
            self.apply_typed = gui.add_button("Set these angles", icon=viser.Icon.CHECK)
            self.controller = gui.add_checkbox(
                "UR controller angles", False, hint="Show what a real UR teach pendant displays for this pose"
            )
            self.summary = gui.add_markdown("")

        for index, slider in enumerate(self.sliders):
            slider.on_update(session.guard(self._slider_moved(index)))
        self.poses.on_click(session.guard(self._pose_button))
        self.apply_typed.on_click(session.guard(self._typed_angles))
        self.controller.on_update(session.guard(lambda _: self.render_panel(session.state.last)))

    def _slider_moved(self, index: int):
        def moved(event: viser.GuiEvent) -> None:
            if event.client is None:  # our own render() setting the value: not a user's move
                return
            value = float(self.sliders[index].value)
            self._session.apply(lambda state: state.set_joint(index, np.radians(value)))

        return moved

    def _pose_button(self, event: viser.GuiEvent) -> None:
        choice = self.poses.value
        if choice == "Random":
            q = self._rng.uniform(-np.pi, np.pi, 6)
        else:
            q = np.radians(COURSE_POSES[choice.lower()])
        self._session.apply(lambda state: state.set_joints(q))

    def _typed_angles(self, _: viser.GuiEvent) -> None:
        q = ArmState.parse_degrees(self.typed.value)
        self._session.apply(lambda state: state.set_joints(np.radians(q)))

    def render_panel(self, snapshot: Snapshot) -> None:
        for slider, value in zip(self.sliders, np.degrees(snapshot.q)):
            value = round(float(value), 2)
            if not abs(slider.value - value) <= 1e-9:  # also true when a bad client left a NaN there
                slider.value = value
        self.summary.content = joints_markdown(snapshot.q, self.controller.value)

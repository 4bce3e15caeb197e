"""Six joint sliders in degrees (±360°, each with its exact number box), pose buttons,
a box to type all six angles, and the UR-controller view of the same angles.

viser's number box beside a slider sends every keystroke: typing 200 would move the arm
through 2° and 20°. A value that jumps further than :data:`DRAG_STEP` from the one before
is therefore taken as typed and applied once typing pauses (:data:`TYPING_PAUSE`); a
slider being dragged moves in small steps and is applied as it moves.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np
import viser

from ..feedback import chosen
from .readouts import joints_markdown
from ..state import ArmState, Snapshot
from ..style import number
from ..view import View

if TYPE_CHECKING:
    from ..session import ClientSession

POSE_BUTTONS = ("Zero", "Stretched", "Arbitrary", "Random")
#: Degrees between two values of a slider beyond which the second was typed, not dragged.
DRAG_STEP = 10.0
#: Seconds a typed value waits for the next keystroke before it is applied.
TYPING_PAUSE = 0.5


def _same(a: float, b: float) -> bool:
    """Equal, a NaN a bad client sent included."""
    return a == b or (a != a and b != b)


def degrees_text(q: np.ndarray) -> str:
    """Six angles (rad) as the "All six" box takes them: ``30, 45, 26, 50, 60, 80``."""
    return ", ".join(number(v, ".2f").rstrip("0").rstrip(".") for v in np.degrees(q))


class JointPanel(View):
    def __init__(self, gui: viser.GuiApi, session: "ClientSession") -> None:
        self._session = session
        self._rng = np.random.default_rng()
        self._typing: dict[int, threading.Timer] = {}  # slider index -> its typed value, waiting
        self._typing_lock = threading.Lock()
        q = np.degrees(session.state.q)
        self._received = [round(float(v), 2) for v in q]  # each slider's last value, as the browser sent or we set it
        self._shown_q = session.state.q
        folder = gui.add_folder("Joints (°)")
        self.folders = (folder,)
        with folder:
            self.sliders = [
                gui.add_slider(
                    f"θ{i + 1} {name}", min=-360.0, max=360.0, step=0.1, initial_value=round(float(q[i]), 2),
                    hint=f"Joint {i + 1} ({name}) in degrees; the UR10 turns ±360°. Type an exact value in the box.",
                )
                for i, name in enumerate(session.arm.joint_names)
            ]
            self.poses = gui.add_button_group("Pose", POSE_BUTTONS)
            self.typed = gui.add_text(
                "All six (°)", degrees_text(session.state.q),
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
        self.controller.on_update(session.guard(lambda _: session.refresher.request(session)))

    def _slider_moved(self, index: int):
        def moved(event: viser.GuiEvent) -> None:
            if event.client is None:  # our own render() setting the value: not a user's move
                return
            with self._typing_lock:  # read under the lock: callbacks run side by side, and the last must see the newest
                value = float(self.sliders[index].value)
                previous, self._received[index] = self._received[index], value
                waiting = self._typing.pop(index, None)
                if waiting is not None:
                    waiting.cancel()
                if abs(value - previous) > DRAG_STEP or waiting is not None:  # typed: wait for the next keystroke
                    timer = threading.Timer(TYPING_PAUSE, self._session.guard(lambda _: self._move(index, value)), (None,))
                    timer.daemon = True
                    self._typing[index] = timer
                    timer.start()
                    return
            self._move(index, value)

        return moved

    def _move(self, index: int, degrees: float) -> None:
        with self._typing_lock:
            self._typing.pop(index, None)
        self._session.apply(lambda state: state.set_joint(index, np.radians(degrees)))

    def _pose_button(self, event: viser.GuiEvent) -> None:
        choice = chosen(self.poses, "pose")
        if choice == "Random":
            q = self._rng.uniform(-np.pi, np.pi, 6)
        else:
            q = self._session.arm.specs.poses[choice.lower()]
        self._session.apply(lambda state: state.set_joints(q))

    def _typed_angles(self, _: viser.GuiEvent) -> None:
        q = ArmState.parse_degrees(self.typed.value)
        self._session.apply(lambda state: state.set_joints(np.radians(q)))

    def render_panel(self, snapshot: Snapshot) -> None:
        with self._typing_lock:
            typing = set(self._typing)
        for index, (slider, value) in enumerate(zip(self.sliders, np.degrees(snapshot.q))):
            value = round(float(value), 2)
            if index in typing or not _same(slider.value, self._received[index]):
                continue  # the student's newer value, whose callback has yet to run: it is the last word
            if not abs(slider.value - value) <= 1e-9:  # true for a NaN a bad client left too
                slider.value = value
                self._received[index] = value
        if not np.array_equal(snapshot.q, self._shown_q):  # leave the student's own typing alone otherwise
            self._shown_q = snapshot.q
            self.typed.value = degrees_text(snapshot.q)
        self.summary.content = joints_markdown(snapshot.q, self.controller.value)

    def close(self) -> None:
        with self._typing_lock:
            for timer in self._typing.values():
                timer.cancel()
            self._typing.clear()

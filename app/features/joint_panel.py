"""One slider per joint (degrees, or millimetres for a prismatic joint, each with its exact number box),
pose buttons, a box to type every joint at once, and, for the UR family, the teach pendant's angles.

viser's number box beside a slider sends every keystroke: typing 200 would move the arm
through 2° and 20°. A value that jumps further than :data:`DRAG_STEP` from the one before
is therefore taken as typed and applied once typing pauses (:data:`TYPING_PAUSE`); a
slider being dragged moves in small steps and is applied as it moves.
"""

from __future__ import annotations

import re
import threading
from typing import Callable

import numpy as np
import viser

from ur10core import to_controller

from ..feedback import Beside, Crossings, chosen
from ..state import ArmState, Snapshot, joint_value_text
from ..style import number
from ..view import Session, View

#: Display units between two values of a slider beyond which the second was typed, not dragged.
DRAG_STEP = 10.0
#: Seconds a typed value waits for the next keystroke before it is applied.
TYPING_PAUSE = 0.5


def _same(a: float, b: float) -> bool:
    """Equal, a NaN a bad client sent included."""
    return a == b or (a != a and b != b)


def to_display(kind: str, value):
    """A joint value as the panel shows it: degrees for R, millimetres for P."""
    return np.degrees(value) if kind == "R" else 1000.0 * np.asarray(value)


def from_display(kind: str, value):
    return np.radians(value) if kind == "R" else np.asarray(value) / 1000.0


def joint_label(arm, index: int) -> str:
    """``θ1 base``, ``d3``, ``A1``: the joint's variable and its name, once each."""
    name, kind = arm.joint_names[index], arm.joint_types[index]
    if not re.match(r"^(θ\d|d\d|A\d|joint )", name):  # a name that is not already a variable (a typed table's "joint 3")
        name = f"{'θ' if kind == 'R' else 'd'}{index + 1} {name}"
    return name


def slider_label(arm, index: int) -> str:
    """``θ1 base (°)``, ``d3 (mm)``: the joint's variable, its name, its unit."""
    return f"{joint_label(arm, index)} ({'°' if arm.joint_types[index] == 'R' else 'mm'})"


def rate_label(arm, index: int) -> str:
    """``θ̇1 base (°/s)``, ``ḋ3 (mm/s)``: the joint's rate, named as its slider is."""
    name = re.sub(r"^[θd](?=\d)", lambda variable: {"θ": "θ̇", "d": "ḋ"}[variable[0]], joint_label(arm, index))
    return f"{name} ({'°/s' if arm.joint_types[index] == 'R' else 'mm/s'})"


def typed_label(arm) -> str:
    units = set(arm.joint_types)
    unit = "°" if units == {"R"} else "mm" if units == {"P"} else "° and mm"
    return f"All {arm.n_joints} ({unit})"


def display_text(arm, q: np.ndarray) -> str:
    """The joints as the typing box takes them: ``30, 45, 26, 50, 60, 80``."""
    return ", ".join(number(float(to_display(kind, v)), ".2f").rstrip("0").rstrip(".")
                     for kind, v in zip(arm.joint_types, q))


def joints_markdown(arm, q: np.ndarray, with_controller: bool = False) -> str:
    """The joint values, and the UR teach pendant's beside them when asked."""
    if not with_controller:
        return " · ".join(f"{name} {joint_value_text(kind, v, '.2f')}" for name, kind, v in zip(arm.joint_names, arm.joint_types, q))
    controller = np.degrees(to_controller(q))
    rows = ["| joint | course | UR controller |", "|---|---:|---:|"]
    rows += [f"| {name} | {number(a, '.2f')}° | {number(b, '.2f')}° |" for name, a, b in zip(arm.joint_names, np.degrees(q), controller)]
    rows.append("\nThe controller uses standard DH with a2, a3 < 0: shoulder + 180°, flange turned 180° about z6.")
    return "\n".join(rows)


class JointPanel(View):
    """The "Joints" folder; ``before()`` runs before a slider or a button moves the arm (a playing path stops)."""

    def __init__(self, gui: viser.GuiApi, session: Session, before: Callable[[], None] = lambda: None) -> None:
        self._session = session
        self._before = before
        arm = self._arm = session.arm
        self._rng = np.random.default_rng()
        self._typing: dict[int, threading.Timer] = {}  # slider index -> its typed value, waiting
        self._typing_lock = threading.Lock()
        q = session.state.q
        shown = [round(float(to_display(kind, v)), 2) for kind, v in zip(arm.joint_types, q)]
        self._received = list(shown)  # each slider's last value, as the browser sent or we set it
        self._crossings = Crossings(later=lambda: session.refresher.request(session))  # by slider index
        self._shown_q = q
        self._typed_text = display_text(arm, q)  # the box as we last wrote it or the student last sent it
        self._typed_over = -1  # the order of the newest change the student's typing was made after
        self._student_text = False  # the box holds what the student typed: a playing path does not write over it
        self.pose_names = (*(name.capitalize() for name in arm.specs.poses), "Random")
        folder = gui.add_folder("Joints")
        self.folders = (folder,)
        with folder:
            self.sliders = []
            for k, kind in enumerate(arm.joint_types):
                low, high = (round(float(to_display(kind, v)), 1) for v in arm.limits[k])
                unit = "°" if kind == "R" else " mm"
                slider = gui.add_slider(
                    slider_label(arm, k), min=low, max=high, step=1.0, initial_value=shown[k],
                    hint=f"Joint {k + 1} ({arm.joint_names[k]}): {'revolute' if kind == 'R' else 'prismatic'}, "
                         f"{low:g}…{high:g}{unit}. Type an exact value in the box.")
                slider.precision = 1  # an arrow key moves it a whole degree (or mm); the box takes tenths
                self.sliders.append(slider)
            self.slider_refusal = Beside(gui)  # a value typed in a slider's box beyond its joint's limits
            self.poses = gui.add_button_group("Pose", self.pose_names)
            self.typed = gui.add_text(typed_label(arm), display_text(arm, q),
                                      hint="Every joint, separated by commas or spaces: degrees, or mm for a prismatic joint")
            self.apply_typed = gui.add_button("Set these values", icon=viser.Icon.CHECK)
            self.refusal = Beside(gui)
            self.controller = (gui.add_checkbox("UR controller angles", False,
                                                hint="Show what a real UR teach pendant displays for this pose")
                               if arm.name in arm.UR_PRESETS else None)
            self.summary = gui.add_markdown("")

        for index, slider in enumerate(self.sliders):
            slider.on_update(session.guard(self._slider_moved(index), beside=self.slider_refusal))
        self.poses.on_click(session.guard(self._pose_button))
        self.typed.on_update(self._text_typed)
        self.apply_typed.on_click(session.guard(self._typed_values, beside=self.refusal))
        if self.controller is not None:
            self.controller.on_update(session.guard(lambda _: session.refresher.request(session)))

    def _slider_moved(self, index: int):
        def moved(event: viser.GuiEvent) -> None:
            if event.client is None:  # our own render() setting the value: not a user's move
                return
            with self._typing_lock:  # read under the lock: callbacks run side by side, and the last must see the newest
                value = float(self.sliders[index].value)
                previous, self._received[index] = self._received[index], value
                self._crossings.received(index)
                waiting = self._typing.pop(index, None)
                if waiting is not None:
                    waiting.cancel()
                if abs(value - previous) > DRAG_STEP or waiting is not None:  # typed: wait for the next keystroke
                    timer = threading.Timer(TYPING_PAUSE, self._session.guard(lambda _: self._move(index, value),
                                                                              beside=self.slider_refusal), (event,))
                    timer.daemon = True
                    self._typing[index] = timer
                    timer.start()
                    return
            self._move(index, value)

        return moved

    def _move(self, index: int, shown: float) -> None:
        with self._typing_lock:
            self._typing.pop(index, None)
        self._moving()
        value = float(from_display(self._arm.joint_types[index], shown))
        self._session.apply(lambda state: state.set_joint(index, value))

    def _moving(self) -> None:
        """A student's change of the joints, about to be made: what was refused before it no longer stands below."""
        self.slider_refusal.clear()
        self.refusal.clear()
        self._before()

    def _pose_button(self, event: viser.GuiEvent) -> None:
        choice = chosen(self.poses, "pose")
        arm = self._arm
        q = arm.sample_joints(1, seed=int(self._rng.integers(2**31)))[0] if choice == "Random" else arm.specs.poses[choice.lower()]
        self._moving()
        self._session.apply(lambda state: state.set_joints(q))

    def _text_typed(self, event: viser.GuiEvent) -> None:
        if event.client is not None:
            self._keep_student_text()

    def _keep_student_text(self) -> None:
        """The student's text stands until the arm changes after it. (A box already redrawn since is not theirs: viser
        runs the text's callback and *Set these values*' in threads of their own, in either order.)"""
        with self._typing_lock:
            if self.typed.value != self._typed_text:
                self._typed_text, self._typed_over = self.typed.value, self._session.state.last.order
                self._shown_q = None
                self._student_text = True

    def _typed_values(self, _: viser.GuiEvent) -> None:
        self._keep_student_text()
        arm = self._arm
        values = ArmState.parse_numbers(self.typed.value, arm.n_joints, "joint values")
        q = [float(from_display(kind, v)) for kind, v in zip(arm.joint_types, values)]
        self._moving()
        self._session.apply(lambda state: state.set_joints(q))

    def render_panel(self, snapshot: Snapshot) -> None:
        with self._typing_lock:
            for index, (slider, kind, value) in enumerate(zip(self.sliders, self._arm.joint_types, snapshot.q)):
                value = round(float(to_display(kind, value)), 2)
                if index in self._typing or not _same(slider.value, self._received[index]):
                    continue  # the student's newer value, whose callback has yet to run: it is the last word
                if not abs(slider.value - value) <= 1e-9:  # true for a NaN a bad client left too
                    slider.value = value  # its callback returns at once: not a student's move
                    self._received[index] = value
                    self._crossings.sent(index)
                else:
                    self._crossings.settle(slider, index)
        with self._typing_lock:  # a panel drawn late, or before the typing's callback has run, leaves the typing alone
            typed_since = (self.typed.value != self._typed_text or snapshot.order <= self._typed_over
                           or (self._student_text and snapshot.cause == "motion"))
            if not typed_since and not np.array_equal(snapshot.q, self._shown_q):
                self._shown_q, self._student_text = snapshot.q, False
                self._typed_text = self.typed.value = display_text(self._arm, snapshot.q)
        with_controller = self.controller is not None and bool(self.controller.value)
        self.summary.content = joints_markdown(self._arm, snapshot.q, with_controller)

    def close(self) -> None:
        with self._typing_lock:
            for timer in self._typing.values():
                timer.cancel()
            self._typing.clear()

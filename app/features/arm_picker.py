"""The "Arm" folder: which arm this browser drives — the UR10, one of the course's other arms, or a typed table.

Picking one takes the current arm out of this browser (its panel and scene) and builds an
``ur10teach.session.ArmSession`` on the other; the server keeps each arm's state for the browser's return.
Each browser picks for itself; in shared mode the presenter picks the class's arm (``ur10teach.serving.classroom``).
The labels are short enough to be read whole in the dropdown in lecture mode."""

from __future__ import annotations

from typing import Callable

import viser

from ur10core import Arm
from ur10core.serial import PRESETS

from ..feedback import put_back
from ..viser_internals import name_tab

#: Seconds between two rebuilds of one browser's arm (the picker, the DH editor's "Build"), or of
#: the classroom's: building an arm costs tens of milliseconds, and a flicked picker must not load the server.
SWITCH_INTERVAL = 0.5

UR10 = "UR10 (the app's arm)"
CUSTOM = "Your own DH table"
DESKTOP = "3-DOF desktop arm"
#: What the dropdown shows → the ``Arm.preset`` name (None: the server's own UR10; "custom": the DH editor;
#: "three_dof": the course's desktop arm, ``ur10teach.features.course_arms.desktop_arm``).
ARM_CHOICES: dict[str, str | None] = {
    UR10: None,
    "KR210 (spherical wrist)": "kr210",
    "Stanford arm (RRP + wrist)": "stanford",
    "Elbow arm + spherical wrist": "elbow",
    "SCARA (RRP + roll)": "scara",
    "Planar elbow (2R)": "planar_elbow",
    "Cylindrical arm (RPP)": "cylindrical",
    "Cylindrical arm + wrist": "cylindrical_wrist",
    DESKTOP: "three_dof",
    CUSTOM: "custom",
}
assert set(ARM_CHOICES.values()) - {None, "custom", "three_dof"} == set(PRESETS)


def panel_title(choice: str, preset: str) -> str:
    """The panel's title: the arm it shows (``choice``, an :data:`ARM_CHOICES` label; ``preset``, the UR10's numbers),
    short enough to be read whole in lecture mode on a projector (no ": kinematics" after the arm's name)."""
    return f"UR10 kinematics ({preset})" if choice == UR10 else choice


def show_title(gui: viser.GuiApi, title: str, tab: viser.GuiMarkdownHandle | None = None) -> viser.GuiMarkdownHandle:
    """Name the arm shown in ``gui``'s panel title and its browser tab's (a tab named "Viser" among a student's
    others was one to hunt for). Returns the tab title's element: pass it back as ``tab`` to rename it."""
    gui.set_panel_label(title)
    return name_tab(gui, title, tab)


def choice_of(preset: str) -> str:
    """The picker's label for an ``Arm.preset`` name: the UR family's is the app's own UR10."""
    return UR10 if preset in Arm.UR_PRESETS else next(label for label, name in ARM_CHOICES.items() if name == preset)


#: What a server may open every browser on (``--arm``): the app's own UR10 (its numbers are ``--preset``'s) or the
#: ``Arm.preset`` name of one of the course's other arms; a typed table is built in a browser, from its DH editor.
FIRST_ARMS = ("ur10", *(name for name in ARM_CHOICES.values() if name not in (None, "custom")))

#: The browser tab's title while the panel's is not shown (folded away, or still to come).
PAGE_TITLE = "Robot-arm kinematics"

#: The panel's title while the class is shown a table the presenter typed (their picker still says CUSTOM).
CLASS_TYPED_TITLE = "The presenter's DH table"


class ArmPicker:
    """The dropdown; ``on_pick(label)`` is called with a checked choice (one of ``choices``) when it changes."""

    def __init__(self, gui: viser.GuiApi, current: str, on_pick: Callable[[str], None],
                 guard: Callable[[Callable], Callable], choices: tuple[str, ...] = tuple(ARM_CHOICES),
                 hint: str = "The course's other arms: their branches, singularities and DH frames") -> None:
        self.folder = gui.add_folder("Arm", order=0.1)
        with self.folder:
            self.dropdown = gui.add_dropdown("Which arm", choices, initial_value=current, hint=hint)
        self._choices = choices
        self._current = current
        self.dropdown.on_update(guard(lambda _: self._picked(on_pick)))

    def _picked(self, on_pick: Callable[[str], None]) -> None:
        label = self.dropdown.value
        if label not in self._choices:  # not from a browser: put back the arm this one drives, and refuse
            put_back(self.dropdown, self._current)
            raise ValueError(f"arm: {label!r:.40} is not one of the choices")
        if label != self._current:
            try:
                on_pick(label)
            except ValueError:  # refused (too soon after the last change): show the arm this browser still drives
                put_back(self.dropdown, self._current)
                raise
            self._current = label

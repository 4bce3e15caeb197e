"""The DH table of any arm in both conventions, a row's values on the arm, and the DH walkthrough."""

from __future__ import annotations

import math

import numpy as np
import viser

from ur10core import Arm
from ur10core.dh import DHTable

from ..feedback import chosen, put_back
from ..state import Snapshot
from ..style import number
from ..view import HELD_BACK, Session, View, say_held_back
from .dh_frames import FRAMES_NONE, FRAMES_XZ, FRAMES_Z, DHFrames

#: What the DH folders say of an arm without a DH table (the desktop arm).
NO_DH_TABLE = ("This arm has no DH table: its parallelogram makes θ3 the forearm's angle to the horizontal, not a "
               "turn about its own joint axis, and a DH row turns each joint about its own axis. Its map is written "
               "out instead (the arm's own folder).")


def _cell(value: float, kind: str, variable: bool, symbol: str, angle: bool) -> str:
    text = number(math.degrees(value), ".0f") + "°" if angle else number(1000 * value, ".1f")
    if variable:
        return symbol if abs(value) < 1e-12 else f"{symbol} {'+' if value > 0 else '−'} {text.lstrip('-')}"
    return text


def dh_table_markdown(table: DHTable) -> str:
    """The rows in the convention's own column order (lengths in mm, angles in degrees)."""
    modified = table.convention == "modified"
    header = ("| i | α<sub>i−1</sub> | a<sub>i−1</sub> (mm) | d<sub>i</sub> (mm) | θ<sub>i</sub> |" if modified
              else "| i | θ<sub>i</sub> | d<sub>i</sub> (mm) | a<sub>i</sub> (mm) | α<sub>i</sub> |")
    lines = [header, "|---|---|---|---|---|"]
    joint = 0
    for k, row in enumerate(table.rows):
        name = str(joint + 1) if row.joint else "fixed"
        if row.joint:
            joint += 1
        theta = _cell(row.theta, row.joint, row.joint == "R", f"q{joint}", True)
        d = _cell(row.d, row.joint, row.joint == "P", f"q{joint}", False)
        alpha, a = _cell(row.alpha, None, False, "", True), _cell(row.a, None, False, "", False)
        cells = (alpha, a, d, theta) if modified else (theta, d, a, alpha)
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


class DHTableView(View):
    """The DH table as the arm is defined and converted to the other convention; the frames and row highlight.

    ``frames`` draws them on the arm (None for an arm without a DH table).
    """

    answers = ("dh_table",)  # the table, and a row's values drawn on the arm

    def __init__(self, gui: viser.GuiApi, session: Session, frames: DHFrames | None) -> None:
        self._session = session
        self._frames = frames
        arm = session.arm
        folder = gui.add_folder("DH table", expand_by_default=False)
        self.folders = (folder,)
        if arm.dh is None:
            with folder:
                gui.add_markdown(f"**{arm.description}.** {NO_DH_TABLE}")
            return
        other = arm.dh.converted("modified" if arm.convention == "standard" else "standard")
        self.row_choices = ("none",) + tuple(f"row {i}" for i in range(1, len(arm.dh.rows) + 1))
        with folder:
            self.show_frames = gui.add_checkbox("Show DH frames (x red, z blue)", frames.shown != FRAMES_NONE)
            self.highlight = gui.add_dropdown("Show a row on the arm", self.row_choices, initial_value="none",
                                              hint="Its d and a as segments, its θ and α as arcs, with their values")
            self.row_values = gui.add_markdown("")
            self._table = (f"**{arm.description}.** As defined ({arm.convention} DH):\n\n" + dh_table_markdown(arm.dh)
                           + f"\n\nThe same chain in {other.convention} DH (the tool pose is the same; "
                           "the frames slide to the neighbouring joint axes):\n\n" + dh_table_markdown(other))
            self.table = gui.add_markdown("")  # (filled by render_panel unless a challenge asks the table)
            self.held_back = gui.add_markdown("", visible=False)
        self.show_frames.on_update(session.guard(lambda _: self._apply()))
        self.highlight.on_update(session.guard(lambda _: self._apply()))

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        if self._session.arm.dh is None:
            return
        for widget in (self.highlight, self.row_values, self.table):
            widget.visible = self.held is None
        say_held_back(self.held_back, self.held is not None)
        if self.held and self.highlight.value != "none":
            self.highlight.value = "none"  # its callback takes the row's values off the arm

    def _apply(self) -> None:
        choice = chosen(self.highlight, "row")
        if self.held and choice != "none":  # a choice a browser cannot send while it is off
            put_back(self.highlight, "none")
            raise ValueError(HELD_BACK)
        frames = self._frames
        frames.shown = FRAMES_XZ if self.show_frames.value else FRAMES_NONE
        frames.highlight_row = None if choice == "none" else int(choice.split()[1])
        self._session.redraw()

    def render_panel(self, snapshot: Snapshot) -> None:
        if self._session.arm.dh is None:
            return
        if self.held is None and self.table.content != self._table:
            self.table.content = self._table
        row = self._frames.highlight_row
        self.row_values.content = "" if row is None else row_values_markdown(self._session.arm, snapshot.q, row)


def row_values_markdown(arm: Arm, q: np.ndarray, row: int) -> str:
    """One row's four values at joints ``q``, with the table's subscripts (mm and degrees)."""
    values = arm.dh.row_geometry(q, row).values
    previous = row if arm.convention == "standard" else row - 1
    return (f"Row {row}: θ<sub>{row}</sub> = {number(math.degrees(values['theta']), '.1f')}°, "
            f"d<sub>{row}</sub> = {number(1000 * values['d'], '.1f')} mm, a<sub>{previous}</sub> = "
            f"{number(1000 * values['a'], '.1f')} mm, α<sub>{previous}</sub> = {number(math.degrees(values['alpha']), '.1f')}°")


def walkthrough_steps(arm: Arm) -> list[tuple[str, str, int | None]]:
    """The DH procedure on ``arm``: (text, which frame axes show, row highlighted) per step."""
    standard = arm.convention == "standard"
    steps = [
        ("**Step 1 — the z axes.** Put z along each joint's axis: "
         + ("z<sub>i</sub> on the axis of joint i + 1 (z<sub>0</sub> on joint 1's)." if standard
            else "z<sub>i</sub> on the axis of joint i.")
         + " A revolute joint turns about its z, a prismatic one slides along it.", FRAMES_Z, None),
        ("**Step 2 — the x axes.** Each x lies along the common normal of two neighbouring z axes "
         + ("(from z<sub>i−1</sub> to z<sub>i</sub>, x<sub>i</sub> through the origin of frame i where it meets z<sub>i</sub>)."
            if standard else "(from z<sub>i</sub> to z<sub>i+1</sub>, x<sub>i</sub> starting on z<sub>i</sub>).")
         + " Where two z axes meet, x is perpendicular to both; where they are parallel, any common normal will do.",
         FRAMES_XZ, None),
    ]
    for row in range(1, len(arm.dh.rows) + 1):
        if standard:
            text = (f"**Row {row}.** θ<sub>{row}</sub>: about z<sub>{row - 1}</sub>, from x<sub>{row - 1}</sub> to x<sub>{row}</sub>; "
                    f"d<sub>{row}</sub>: along z<sub>{row - 1}</sub>; a<sub>{row}</sub>: along x<sub>{row}</sub>; "
                    f"α<sub>{row}</sub>: about x<sub>{row}</sub>, from z<sub>{row - 1}</sub> to z<sub>{row}</sub>.")
        else:
            text = (f"**Row {row}.** a<sub>{row - 1}</sub>: along x<sub>{row - 1}</sub>; α<sub>{row - 1}</sub>: about "
                    f"x<sub>{row - 1}</sub>, from z<sub>{row - 1}</sub> to z<sub>{row}</sub>; d<sub>{row}</sub>: along "
                    f"z<sub>{row}</sub>; θ<sub>{row}</sub>: about z<sub>{row}</sub>, from x<sub>{row - 1}</sub> to x<sub>{row}</sub>.")
        steps.append((f"{text} {row_variable(arm, row)}", FRAMES_XZ, row))
    return steps


def row_variable(arm: Arm, row: int) -> str:
    """Which of row ``row``'s four values its joint moves (θ for a revolute joint, d for a prismatic one), as the
    table's q<sub>k</sub> says, or that the row has none.

    >>> from ur10core import Arm
    >>> kr210 = Arm.preset("kr210")
    >>> row_variable(Arm.preset("stanford"), 3), row_variable(kr210, 2), row_variable(kr210, 7)  # doctest: +NORMALIZE_WHITESPACE
    ('*Joint 3 slides: d<sub>3</sub> = q3 varies; the other three are fixed.*',
     '*Joint 2 turns: θ<sub>2</sub> = q2 − 90° varies; the other three are fixed.*',
     '*A fixed row: all four are constants.*')
    """
    values = arm.dh.rows[row - 1]
    if values.joint is None:
        return "*A fixed row: all four are constants.*"
    joint = arm.dh.joint_rows.index(row - 1) + 1
    revolute = values.joint == "R"
    name, verb = ("θ", "turns") if revolute else ("d", "slides")
    variable = _cell(values.theta if revolute else values.d, values.joint, True, f"q{joint}", revolute)
    return f"*Joint {joint} {verb}: {name}<sub>{row}</sub> = {variable} varies; the other three are fixed.*"


class DHWalkthrough(View):
    """Step through the DH procedure on the arm: z axes, x axes, then each row's four parameters.

    ``frames`` draws them (:class:`ur10teach.features.dh_frames.DHFrames`; None for an arm without a DH table).
    While a class challenge asks for the table, the steps are there without the rows' values.
    """

    answers = ("dh_table",)

    def __init__(self, gui: viser.GuiApi, session: Session, frames: DHFrames | None) -> None:
        self._session = session
        self._frames = frames
        self.step = -1  #: -1: not walking through (the arm as it is)
        folder = gui.add_folder("DH walkthrough", expand_by_default=False)
        self.folders = (folder,)
        if session.arm.dh is None:
            self.steps = []
            with folder:
                gui.add_markdown(NO_DH_TABLE)
            return
        self.steps = walkthrough_steps(session.arm)
        with folder:
            self.buttons = gui.add_button_group("Step", ("◀ Back", "Next ▶", "Stop"))
            self.text = gui.add_markdown("Press **Next** to build this arm's frames the DH way, one step at a time.")
        self.buttons.on_click(session.guard(self._clicked))

    def _clicked(self, _: viser.GuiEvent) -> None:
        choice = chosen(self.buttons, "step")
        if choice == "Stop":
            self.step = -1
        elif choice == "Next ▶":
            self.step = min(self.step + 1, len(self.steps) - 1)
        else:
            self.step = max(self.step - 1, -1)
        self._show()

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        if self.step >= 0:
            self._show()  # the step shown, with its row's values or without them

    def _show(self) -> None:
        frames = self._frames
        if self.step < 0:
            frames.shown, frames.highlight_row = frames.at_rest, None
            self.text.content = "Press **Next** to build this arm's frames the DH way, one step at a time."
        else:
            text, frames_shown, row = self.steps[self.step]
            if self.held:
                row = None
            frames.shown, frames.highlight_row = frames_shown, row
            values = "" if row is None else "\n\n" + row_values_markdown(self._session.arm, self._session.state.last.q, row)
            self.text.content = f"{text}{values}\n\n*Step {self.step + 1} of {len(self.steps)}*"
        self._session.redraw()

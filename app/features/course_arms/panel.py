"""The course arm's panel: joint sliders (degrees, or mm for a prismatic joint), its branches,
the factors of det J with what each means, and its DH table in both conventions."""

from __future__ import annotations

import functools
import math
import threading
from typing import TYPE_CHECKING, Callable

import numpy as np
import viser

from ur10core import symbolic_arms
from ur10core.dh import DHTable
from ur10core import Arm
from ur10core.serial import PRESETS

from ...feedback import chosen
from ..singularity import alarm
from ...style import DANGER_RED, SAFE_GREEN, SLOT_COLORS, blend, hex_color, number, swatch
from ...view import View
from ..dh_frames import FRAMES_NONE, FRAMES_XZ, FRAMES_Z, DHFrames
from .state import CourseSnapshot

if TYPE_CHECKING:
    from .session import CourseArmSession


def display_value(kind: str, value: float) -> float:
    """A joint value as the panel shows it: degrees for R, millimetres for P."""
    return math.degrees(value) if kind == "R" else 1000.0 * value


def joint_text(arm: Arm, q: np.ndarray) -> str:
    return ", ".join(number(display_value(kind, v), ".1f") + ("°" if kind == "R" else " mm")
                     for kind, v in zip(arm.joint_types, q))


class CourseJointSliders(View):
    """One slider per joint, within its limits; ``before()`` runs before a slider moves the arm (stop a motion, say)."""

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession", before: Callable[[], None] = lambda: None,
                 order: float | None = None) -> None:
        self._session = session
        self._before = before
        arm = session.arm
        q = session.state.last.q
        folder = gui.add_folder("Joints", order=order)
        self.folders = (folder,)
        with folder:
            self.sliders = []
            for k, (kind, name) in enumerate(zip(arm.joint_types, arm.joint_names)):
                low, high = (display_value(kind, v) for v in arm.limits[k])
                unit = "°" if kind == "R" else " mm"
                self.sliders.append(gui.add_slider(
                    f"{name} ({unit.strip()})", min=round(low, 1), max=round(high, 1), step=0.1 if kind == "R" else 1.0,
                    initial_value=round(display_value(kind, q[k]), 1),
                    hint=f"Joint {k + 1}: {'revolute, degrees' if kind == 'R' else 'prismatic, millimetres'}, "
                         f"{low:.0f}…{high:.0f}{unit}"))
        #: what each slider was last set to from the state: a slider is written only when the state
        #: moved away from it (never just because the student's newer value differs from an older state)
        self._shown = [slider.value for slider in self.sliders]
        self._moving = threading.Lock()
        for k, slider in enumerate(self.sliders):
            slider.on_update(session.guard(self._moved(k)))

    def _moved(self, index: int):
        def moved(event: viser.GuiEvent) -> None:
            if event.client is None:
                return
            kind = self._session.arm.joint_types[index]
            self._before()
            with self._moving:  # callbacks run side by side: the last to apply reads the newest value
                shown = float(self.sliders[index].value)
                value = math.radians(shown) if kind == "R" else shown / 1000.0
                self._shown[index] = shown  # what the browser shows now: if refused, the next panel redraw puts it back
                self._session.apply(lambda state: state.set_joint(index, value))
        return moved

    def render_panel(self, snapshot: CourseSnapshot) -> None:
        for k, (slider, kind, value) in enumerate(zip(self.sliders, self._session.arm.joint_types, snapshot.q)):
            shown = round(display_value(kind, value), 1)
            if not abs(self._shown[k] - shown) <= 1e-9:
                self._shown[k] = shown
                slider.value = shown


def branches_markdown(arm: Arm, snapshot: CourseSnapshot) -> str:
    sol = snapshot.solution
    if sol is None:  # a typed table: the numerical search runs when asked
        lines = ["The arm follows the target from its own joints (damped least squares). "
                 "**Find every branch** searches from many starts for the others."]
        if snapshot.reason:
            lines += ["", f"<span style='color:{hex_color(DANGER_RED)}'>**Not reached:** {snapshot.reason}</span>"]
        return "\n".join(lines)
    lines = [f"**{int(sol.valid.sum())} of {len(sol.labels)} branches reach the target** ({sol.method}; "
             f"the arm places its {sol.task})", "",
             "| # | branch | joints | |", "|---|---|---|---|"]
    for k, label in enumerate(sol.labels):
        colour = swatch(SLOT_COLORS[k % len(SLOT_COLORS)])
        if not sol.valid[k]:
            lines.append(f"| {colour} {k + 1} | {label} | — | out of reach |")
            continue
        flags = []
        if k == snapshot.chosen:
            flags.append("**the arm**")
        if not sol.within_limits[k]:
            flags.append(f"<span style='color:{hex_color(DANGER_RED)}'>beyond a joint limit</span>")
        if sol.singular[k]:
            flags.append("singular: a joint chosen, not fixed")
        lines.append(f"| {colour} {k + 1} | {label} | {joint_text(arm, sol.q[k])} | {', '.join(flags)} |")
    if snapshot.reason:
        lines += ["", f"<span style='color:{hex_color(DANGER_RED)}'>**Out of reach:** {snapshot.reason}</span>"]
    return "\n".join(lines)


class CourseBranches(View):
    """The table of branches: each slot, its joints, and whether it is beyond a limit."""

    def __init__(self, gui: viser.GuiApi, arm: Arm) -> None:
        self._arm = arm
        folder = gui.add_folder("IK branches")
        self.folders = (folder,)
        with folder:
            self.table = gui.add_markdown("")

    def render_panel(self, snapshot: CourseSnapshot) -> None:
        self.table.content = branches_markdown(self._arm, snapshot)


@functools.lru_cache(maxsize=len(PRESETS) + 1)
def factor_scales(name: str) -> np.ndarray:
    """Per factor, the 99th percentile of its size over the arm's workspace: a gauge is full there."""
    arm = Arm.preset(name)
    q = arm.sample_joints(20_000, seed=1)
    return np.maximum(np.percentile(np.abs(arm.singularity_factors(q)), 99, axis=0), 1e-12)


#: What the DH folders say of an arm without a DH table (the desktop arm).
NO_DH_TABLE = ("This arm has no DH table: its parallelogram makes θ3 the forearm's angle to the horizontal, not a "
               "turn about its own joint axis, and a DH row turns each joint about its own axis. Its map is written "
               "out instead (the arm's own folder).")


def factor_words(arm: Arm) -> tuple[str, list[tuple[str, str, str]]] | None:
    """(what det J is, [(name, expression, what makes it zero)] per factor) as the model gives them, or None
    for a typed table (its det J is not derived)."""
    if arm.name in PRESETS:
        derivation = symbolic_arms.load(arm.name)
        return (f"det J = {derivation.constant} × the factors (derived with sympy from the DH table)",
                [(f.name, str(f.expression), f.meaning) for f in derivation.factors])
    words = getattr(arm.solver, "factor_words", None)
    if words is None:
        return None
    return f"det J_v = {arm.solver.det_constant} × the factors (the course's closed form)", list(words)


def factors_html(arm: Arm, q: np.ndarray) -> str:
    """det J's factors as gauges, green far from their singularity and red at it, with what each means."""
    measures = (f"manipulability {number(float(arm.manipulability(q)), '.4g')}, smallest singular value "
                f"{number(float(arm.smallest_singular_value(q)), '.4g')}")
    described = factor_words(arm)
    if described is None:  # a typed table has no derivation: the numbers that vanish at a singularity
        return f"<div>A typed table's det J is not derived; these go to zero at a singularity: {measures}</div>"
    heading, factors = described
    values = arm.singularity_factors(q)
    levels = np.clip(np.abs(values) / factor_scales(arm.name), 0.0, 1.0)
    parts = [f"<div>{heading}</div>"]
    for (name, expression, meaning), value, level in zip(factors, values, levels):
        colour = hex_color(blend(SAFE_GREEN, DANGER_RED, alarm(level)))
        parts.append(
            f"<div style='margin:4px 0'><b>{name}</b> <code>{expression}</code> = {number(value, '+.4f')}"
            "<div style='height:8px;background:#e9ecef;border-radius:4px'>"
            f"<div class='gauge-{name}' style='height:8px;width:{100 * level:.1f}%;border-radius:4px;"
            f"background:{colour}'></div></div><div style='font-size:0.85em'>zero when {meaning}</div></div>")
    parts.append(f"<div>{measures}</div>")
    return "<div style='font-size:0.9em'>" + "".join(parts) + "</div>"


class CourseSingularities(View):
    """det J's factors as gauges (the UR10's overlay panel, for any preset), and in 3D on the arm."""

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession") -> None:
        self._arm = session.arm
        folder = gui.add_folder("Singularities")
        self.folders = (folder,)
        overlay = session.scene.overlay
        with folder:
            self.show = (gui.add_checkbox("Show them on the arm", overlay.enabled,
                                          hint="The geometry each factor measures, red as it nears zero")
                         if overlay is not None else None)
            self.gauges = gui.add_html("")
        if self.show is not None:
            def toggled(_) -> None:
                overlay.enabled = bool(self.show.value)
                session.redraw()

            self.show.on_update(session.guard(toggled))

    def render_panel(self, snapshot: CourseSnapshot) -> None:
        self.gauges.content = factors_html(self._arm, snapshot.q)


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


class CourseDHTable(View):
    """The DH table as the arm is defined and converted to the other convention; the frames and row highlight."""

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession") -> None:
        self._session = session
        arm = session.arm
        folder = gui.add_folder("DH table")
        self.folders = (folder,)
        if arm.dh is None:
            with folder:
                gui.add_markdown(f"**{arm.description}.** {NO_DH_TABLE}")
            return
        other = arm.dh.converted("modified" if arm.convention == "standard" else "standard")
        self.row_choices = ("none",) + tuple(f"row {i}" for i in range(1, len(arm.dh.rows) + 1))
        with folder:
            self.show_frames = gui.add_checkbox("Show DH frames (x red, z blue)", True)
            self.highlight = gui.add_dropdown("Show a row on the arm", self.row_choices, initial_value="none",
                                              hint="Its d and a as segments, its θ and α as arcs, with their values")
            self.row_values = gui.add_markdown("")
            gui.add_markdown(f"**{arm.description}.** As defined ({arm.convention} DH):\n\n" + dh_table_markdown(arm.dh)
                             + f"\n\nThe same chain in {other.convention} DH (the tool pose is the same; the "
                             "frames slide to the neighbouring joint axes):\n\n" + dh_table_markdown(other))
        self.show_frames.on_update(session.guard(lambda _: self._apply()))
        self.highlight.on_update(session.guard(lambda _: self._apply()))

    def _apply(self) -> None:
        choice = chosen(self.highlight, "row")
        frames = self._session.scene.dh_frames
        frames.shown = FRAMES_XZ if self.show_frames.value else FRAMES_NONE
        frames.highlight_row = None if choice == "none" else int(choice.split()[1])
        self._session.redraw()
        self._session.refresher.request(self._session)

    def render_panel(self, snapshot: CourseSnapshot) -> None:
        if self._session.arm.dh is None:
            return
        row = self._session.scene.dh_frames.highlight_row
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
        steps.append((text, FRAMES_XZ, row))
    return steps


class DHWalkthrough(View):
    """Step through the DH procedure on the arm: z axes, x axes, then each row's four parameters.

    ``frames`` draws them (:class:`ur10teach.features.dh_frames.DHFrames`; None for an arm without a DH table).
    """

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession", frames: DHFrames | None) -> None:
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
        frames = self._frames
        if self.step < 0:
            frames.shown, frames.highlight_row = frames.at_rest, None
            self.text.content = "Press **Next** to build this arm's frames the DH way, one step at a time."
        else:
            text, frames_shown, row = self.steps[self.step]
            frames.shown, frames.highlight_row = frames_shown, row
            values = "" if row is None else "\n\n" + row_values_markdown(self._session.arm, self._session.state.last.q, row)
            self.text.content = f"{text}{values}\n\n*Step {self.step + 1} of {len(self.steps)}*"
        self._session.redraw()

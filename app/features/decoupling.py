"""Kinematic decoupling (docs/kinematics.md §7.3), for any arm: where the arm has a spherical wrist, the wrist centre
WC named in 3D and the pose split there in numbers (WC from the tool pose, then R3_6 = R0_3ᵀ R and its Z-Y-Z Euler
angles, which are the wrist's three joints); elsewhere, why the pose does not split, and for the UR family the
course's separation of variables instead (§4.1), step by step from its wrist-2 point P5."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.branches import wrap
from ur10core.solvers.spherical_wrist import WristSplit, spherical_wrist, wrist_split
from ur10core.solvers.ur import SeparationSteps, separation_steps

from ..state import Snapshot
from ..style import WRIST_COLOR, number, sentence
from ..view import HELD_BACK, Session, View

INTRO = ("Where the last three axes meet in one point, the **wrist centre WC**, the wrist's joints cannot move it: "
         "the first three joints place WC, and the wrist then turns the tool. The pose splits in two (Pieper).")
#: What the folder says where the arm has no spherical wrist, after the core's reason
ELSEWHERE = (" The pose does not split at a wrist centre here: its closed form (or the numerical search) solves the "
             "joints otherwise (docs/kinematics.md §4, §7.3).")
#: ... and for the UR family, whose steps the folder then shows
SEPARATED = (" The course separates the variables instead (docs/kinematics.md §4.1): the wrist-2 point **P5** = p − d6·z6, "
             "on axes 5 and 6, does not move with θ5 or θ6 and fixes θ1; then R gives θ5, θ6 and θ234, and joints 2–3 "
             "are a planar two-link arm. For this pose:")


def _degrees(angles: np.ndarray) -> str:
    return ", ".join(f"{number(np.degrees(a), '.1f')}°" for a in angles)


def _matrix(R: np.ndarray) -> str:
    rows = "\n".join("| " + " | ".join(number(value, ".3f") for value in row) + " |" for row in R)
    return "| | | |\n|---:|---:|---:|\n" + rows


def split_markdown(split: WristSplit, q: np.ndarray, joint_names: tuple[str, ...], revolute: np.ndarray) -> str:
    """The folder's text: WC from the pose, the joints that place it, R3_6 and its Z-Y-Z Euler angles."""
    c = split.centre_in_tool
    if not c.any():
        where = "The tool frame is at the wrist centre (d6 = 0): **WC = p**"
    elif abs(c[0]) < 1e-12 and abs(c[1]) < 1e-12:
        back = number(-1000 * c[2], ".0f")
        where = f"WC is {back} mm back along the tool's z axis: **WC = p − {back} mm · z**"
    else:
        where = f"**WC = p + R c**, c = ({', '.join(number(1000 * v, '.0f') for v in c)}) mm in the tool frame"
    placed = ", ".join(f"{name} = {number(np.degrees(v), '.1f') + '°' if turns else number(1000 * v, '.0f') + ' mm'}"
                       for name, v, turns in zip(joint_names[:-3], q[:-3], revolute[:-3]))
    s5, s6 = split.signs
    name4, name5, name6 = joint_names[-3:]  # a typed table may have more joints before its wrist
    theta5, theta6 = (name5 if s5 > 0 else f"−{name5}"), (name6 if s6 > 0 else f"−{name6}")
    before = "" if abs(split.twist) < 1e-12 else f"Rx({number(np.degrees(-split.twist), '.0f')}°) "
    text = (f"{where} = ({', '.join(number(1000 * v, '.0f') for v in split.centre)}) mm.\n\n"
            f"**Joints 1–{len(q) - 3} place WC:** {placed}.\n\n"
            f"**The wrist turns the rest:** R3_6 = R0_3ᵀ R =\n\n{_matrix(split.R3_6)}\n\n"
            f"{before}R3_6 = Rz({name4}) Ry({theta5}) Rz({theta6}), so ")
    if abs(np.sin(split.euler[1])) < 1e-9:
        return text + (f"its Z-Y-Z Euler angles fix only {name4} {'+' if s6 > 0 else '−'} {name6} here ({name5} = 0: "
                       f"axes 4 and 6 in line): (φ, θ, ψ) = ({_degrees(split.euler)}).")
    arm_joints = np.asarray(q[-3:])
    second = bool(np.abs(wrap(split.wrist[1] - arm_joints)).max() < np.abs(wrap(split.wrist[0] - arm_joints)).max())
    own, other = (split.euler_flipped, split.euler) if second else (split.euler, split.euler_flipped)
    return text + (f"its Z-Y-Z Euler angles (φ, θ, ψ) = **({_degrees(own)})** give the arm's {name4}, {name5}, "
                   f"{name6} = ({_degrees(arm_joints)}); the other solution, ({_degrees(other)}), is the wrist "
                   f"{'not flipped' if q[-2] < 0 else 'flipped'} ({name5} {'≥' if q[-2] < 0 else '≤'} 0).")


def _mm(*values: float) -> str:
    return ", ".join(number(1000 * v, ".1f") for v in values)


def steps_markdown(steps: SeparationSteps, arm) -> str:
    """The folder's text for a UR-family arm: the course's five steps with this pose's numbers, ending at its joints."""
    left, right = (_degrees([theta]) for theta in steps.theta1)
    shoulder = "right" if steps.reach >= 0 else "left"
    lines = [f"**1. θ1.** P5 = ({_mm(*steps.p5)}) mm is ρ = {_mm(steps.rho)} mm from the base axis (at least "
             f"d4 = {_mm(arm.d4)} mm), so A = ±√(ρ² − d4²): θ1 = {left} (shoulder left) or {right} (right). "
             f"This arm: A = {_mm(steps.reach)} mm, **θ1 = {_degrees([steps.theta1[steps.reach >= 0]])}** "
             f"(shoulder {shoulder})."]
    flipped = "flipped" if steps.theta5 < 0 else "not flipped"
    lines.append(f"**2. θ5.** c5 = r13 s1 − r23 c1 = {number(steps.c5, '.4f')}, θ5 = ±acos(c5): this arm "
                 f"**θ5 = {_degrees([steps.theta5])}** (wrist {flipped}).")
    if steps.wrist_singular:
        lines.append(f"**3–4. θ6, θ234.** s5 = 0: axes 4 and 6 in line, and R fixes only θ234 ± θ6. The arm keeps "
                     f"**θ6 = {_degrees([steps.theta6])}**, so θ234 = {_degrees([steps.theta234])} (docs §4.3).")
    else:
        lines.append(f"**3. θ6** from s5 c6 = r21 c1 − r11 s1, −s5 s6 = r22 c1 − r12 s1: **θ6 = {_degrees([steps.theta6])}**.")
        lines.append(f"**4. θ234** from c234 s5 = r13 c1 + r23 s1, s234 s5 = r33: θ234 = {_degrees([steps.theta234])}.")
    lines.append(f"**5. θ3, θ2, θ4.** The frame-4 origin is at (h4, v4) = (A + d5 s234, P5z − d1 − d5 c234) = "
                 f"({_mm(*steps.frame4)}) mm from the shoulder, r = {_mm(steps.r)} mm: c3 = (r² − a2² − a3²) / (2 a2 a3) "
                 f"= {number(steps.c3, '.4f')}, θ3 = ±acos(c3): this arm **θ3 = {_degrees([steps.theta3])}**; "
                 f"θ2 = atan2(v4, h4) − atan2(a3 s3, a2 + a3 c3) = **{_degrees([steps.theta2])}**; "
                 f"θ4 = θ234 − θ2 − θ3 = **{_degrees([steps.theta4])}**.")
    lines.append(f"The arm is on branch {steps.slot + 1} ({arm.slot_labels[steps.slot]}): the IK target's branch "
                 f"{steps.slot + 1}.")
    return "\n\n".join(lines)


class DecouplingView(View):
    """The "Wrist centre (decoupling)" folder, and WC named in 3D when asked; for an arm without a spherical wrist
    (the UR family, the small arms), the folder says why its pose does not split, and the UR family's shows its
    own steps instead, with P5 named in 3D when asked."""

    #: the UR family's steps give both θ1; a split gives WC; both start from the tool pose (P5 and WC are p moved
    #: along the tool's axes; the Stanford arm's WC is p)
    answers = ("theta1", "wrist_centre", "position")

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        arm = self._arm = session.arm
        self._centre_in_tool: np.ndarray | None = None  #: c: WC = p + R c
        #: the UR family's: its steps from P5 (frame 5's origin) in place of a split
        self._separated = arm.name in arm.UR_PRESETS
        try:
            self._centre_in_tool = spherical_wrist(arm)[1]
            self.why_not = ""
        except ValueError as reason:  #: why the pose does not split, if it does not
            self.why_not = sentence(str(reason)) + "." + (SEPARATED if self._separated else ELSEWHERE)
        folder = gui.add_folder("Wrist centre (decoupling)", expand_by_default=False)
        self.folders = (folder,)
        self._point = "P5" if self._separated else "WC"  #: the point it names in 3D
        with folder:
            gui.add_markdown(INTRO)
            if self._separated:  # the reason, then the steps, which the checkbox names P5 of
                self.readout = gui.add_markdown(self.why_not)
            self.shown = (gui.add_checkbox(f"Name {self._point} on the arm", False, hint=f"{self._point}, named in 3D")
                          if self._separated or not self.why_not else None)
            if not self._separated:
                self.readout = gui.add_markdown(self.why_not)
            self.steps = gui.add_markdown("", visible=self._separated)
        self._centre: np.ndarray | None = None  #: where WC (or P5) is, while named
        if self.shown is not None:
            self.shown.on_update(session.guard(lambda _: session.redraw()))

    def render(self, snapshot: Snapshot) -> None:
        if self.shown is None or not self.shown.value:
            self._centre = None
        elif self._separated:
            self._centre = snapshot.frames[5][:3, 3]
        else:
            tool = snapshot.flange
            self._centre = tool[:3, 3] + tool[:3, :3] @ self._centre_in_tool

    def names(self) -> list[tuple]:
        return [] if self.shown is None else [(self._centre, self._point, WRIST_COLOR)]

    def render_panel(self, snapshot: Snapshot) -> None:
        if self.held:
            (self.steps if self._separated else self.readout).content = HELD_BACK
        elif self._separated:
            self.steps.content = steps_markdown(separation_steps(self._arm, snapshot.q, snapshot.frames), self._arm)
        elif not self.why_not:
            split = wrist_split(self._arm, snapshot.q, snapshot.frames)
            self.readout.content = split_markdown(split, snapshot.q, self._arm.joint_names, self._arm.revolute)

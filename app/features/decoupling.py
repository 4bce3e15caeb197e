"""Kinematic decoupling (docs/kinematics.md §7.3), for any arm: where the arm has a spherical wrist, the wrist centre
WC named in 3D and the pose split there in numbers (WC from the tool pose, then R3_6 = R0_3ᵀ R and its Z-Y-Z Euler
angles, which are the wrist's three joints); elsewhere, why the pose does not split."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.branches import wrap
from ur10core.solvers.spherical_wrist import WristSplit, spherical_wrist, wrist_split

from ..state import Snapshot
from ..style import WRIST_COLOR, number, sentence
from ..view import Session, View

INTRO = ("Where the last three axes meet in one point, the **wrist centre WC**, the wrist's joints cannot move it: "
         "the first three joints place WC, and the wrist then turns the tool. The pose splits in two (Pieper).")
#: What the folder says where the arm has no spherical wrist, after the core's reason
ELSEWHERE = (" The pose does not split at a wrist centre here: its closed form (or the numerical search) solves the "
             "joints otherwise (docs/kinematics.md §4, §7.3).")


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


class DecouplingView(View):
    """The "Wrist centre (decoupling)" folder, and WC named in 3D when asked; for an arm without a spherical wrist
    (the UR family, the small arms), the folder says why its pose does not split."""

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        self._arm = session.arm
        self._centre_in_tool: np.ndarray | None = None  #: c: WC = p + R c
        try:
            self._centre_in_tool = spherical_wrist(self._arm)[1]
            self.why_not = ""
        except ValueError as reason:
            self.why_not = sentence(str(reason)) + "." + ELSEWHERE  #: why the pose does not split, if it does not
        folder = gui.add_folder("Wrist centre (decoupling)", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(INTRO)
            self.shown = None if self.why_not else gui.add_checkbox("Name WC on the arm", False,
                                                                     hint="The wrist centre, named in 3D")
            self.readout = gui.add_markdown(self.why_not)
        self._centre: np.ndarray | None = None  #: where WC is, while named
        if self.shown is not None:
            self.shown.on_update(session.guard(lambda _: session.redraw()))

    def render(self, snapshot: Snapshot) -> None:
        tool = snapshot.flange
        shown = self.shown is not None and self.shown.value
        self._centre = tool[:3, 3] + tool[:3, :3] @ self._centre_in_tool if shown else None

    def names(self) -> list[tuple]:
        return [] if self.why_not else [(self._centre, "WC", WRIST_COLOR)]

    def render_panel(self, snapshot: Snapshot) -> None:
        if not self.why_not:
            split = wrist_split(self._arm, snapshot.q, snapshot.frames)
            self.readout.content = split_markdown(split, snapshot.q, self._arm.joint_names, self._arm.revolute)

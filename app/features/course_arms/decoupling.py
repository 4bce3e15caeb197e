"""Kinematic decoupling, for any arm with a spherical wrist (docs/kinematics.md §7.3): the wrist centre WC named in
3D, and a folder that splits the pose there in numbers: WC from the tool pose, then R3_6 = R0_3ᵀ R and its Z-Y-Z
Euler angles, which are the wrist's three joints."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.branches import wrap
from ur10core.solvers.spherical_wrist import WristSplit, wrist_split

from ...state import Snapshot
from ...style import WRIST_COLOR, number
from ...view import Session, View

INTRO = ("The last three axes meet in one point, the **wrist centre WC**. The wrist's joints cannot move it, so the "
         "first three joints place WC, and the wrist then turns the tool: the pose splits in two.")


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
        where = f"WC is {number(-1000 * c[2], '.0f')} mm back along the tool's z axis: **WC = p − {number(-1000 * c[2], '.0f')} mm · z**"
    else:
        where = f"**WC = p + R c**, c = ({', '.join(number(1000 * v, '.0f') for v in c)}) mm in the tool frame"
    placed = ", ".join(f"{name} = {number(np.degrees(v), '.1f') + '°' if turns else number(1000 * v, '.0f') + ' mm'}"
                       for name, v, turns in zip(joint_names[:3], q[:3], revolute[:3]))
    s5, s6 = split.signs
    name4, name5, name6 = joint_names[3:6]
    theta5, theta6 = (name5 if s5 > 0 else f"−{name5}"), (name6 if s6 > 0 else f"−{name6}")
    before = "" if abs(split.twist) < 1e-12 else f"Rx({number(np.degrees(-split.twist), '.0f')}°) "
    text = (f"{where} = ({', '.join(number(1000 * v, '.0f') for v in split.centre)}) mm.\n\n"
            f"**Joints 1–3 place WC:** {placed}.\n\n"
            f"**The wrist turns the rest:** R3_6 = R0_3ᵀ R =\n\n{_matrix(split.R3_6)}\n\n"
            f"{before}R3_6 = Rz({name4}) Ry({theta5}) Rz({theta6}), so ")
    if abs(np.sin(q[4])) < 1e-9:
        return text + (f"its Z-Y-Z Euler angles fix only {name4} {'+' if s6 > 0 else '−'} {name6} here ({name5} = 0: "
                       f"axes 4 and 6 in line): (φ, θ, ψ) = ({_degrees(split.euler)}).")
    arm_joints = np.asarray(q[3:6])
    second = bool(np.abs(wrap(split.wrist[1] - arm_joints)).max() < np.abs(wrap(split.wrist[0] - arm_joints)).max())
    own, other = (split.euler_flipped, split.euler) if second else (split.euler, split.euler_flipped)
    return text + (f"its Z-Y-Z Euler angles (φ, θ, ψ) = **({_degrees(own)})** give the arm's {name4}, {name5}, {name6} = "
                   f"({_degrees(arm_joints)}); the other solution, ({_degrees(other)}), is the wrist "
                   f"{'not flipped' if q[4] < 0 else 'flipped'} ({name5} {'≥' if q[4] < 0 else '≤'} 0).")


class DecouplingView(View):
    """The "Wrist centre" folder of an arm with a spherical wrist, and WC named in 3D while it is open."""

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        self._arm = session.arm
        folder = gui.add_folder("Wrist centre (decoupling)", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(INTRO)
            self.shown = gui.add_checkbox("Name WC on the arm", False, hint="The wrist centre, named in 3D")
            self.readout = gui.add_markdown("")
        self._centre: np.ndarray | None = None  #: where WC is, while named
        self.shown.on_update(session.guard(lambda _: session.redraw()))

    def render(self, snapshot: Snapshot) -> None:
        self._centre = wrist_split(self._arm, snapshot.q).centre if self.shown.value else None

    def names(self) -> list[tuple]:
        return [(self._centre, "WC", WRIST_COLOR)]

    def render_panel(self, snapshot: Snapshot) -> None:
        self.readout.content = split_markdown(wrist_split(self._arm, snapshot.q), snapshot.q, self._arm.joint_names,
                                              self._arm.revolute)


def decoupling_lessons(scene: viser.SceneApi, gui: viser.GuiApi, session: Session) -> tuple[View, ...]:
    """The folder every arm with a spherical wrist has (the Stanford arm, the elbow arms, the cylindrical arm's)."""
    return (DecouplingView(gui, session),)

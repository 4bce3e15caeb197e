"""The KR210's gripper pose, read and typed in the DH convention or in its simulation model's (ROS/Gazebo URDF)."""

from __future__ import annotations

import math

import numpy as np
import viser

from ur10core.orientation import rotation_from_xyz_fixed, xyz_fixed
from ur10core.serial import kr210_from_urdf, kr210_to_urdf

from ...feedback import Beside
from ...state import Snapshot
from ...style import number, typed_fields
from ...view import HELD_BACK, Session, View
from ..ik_target import check_target_position


def pose_text(T: np.ndarray) -> str:
    """``x y z`` in mm and roll, pitch, yaw (X-Y-Z fixed, as ROS writes them) in degrees."""
    roll, pitch, yaw = np.degrees(xyz_fixed(T[:3, :3], check=False))
    x, y, z = 1000 * T[:3, 3]
    return " ".join(number(v, ".1f") for v in (x, y, z, roll, pitch, yaw))


def parse_pose(text: str) -> np.ndarray:
    """The pose typed as ``x y z roll pitch yaw`` (mm, degrees), (4, 4); ``ValueError`` saying what is wrong."""
    fields = typed_fields(text, "the pose")
    if len(fields) != 6:
        raise ValueError(f"type six numbers, x y z (mm) roll pitch yaw (°); got {len(fields)}")
    try:
        values = [float(f) for f in fields]
    except ValueError:
        raise ValueError(f"x y z roll pitch yaw must be numbers, got {text!r:.60}") from None
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"x y z roll pitch yaw must be finite numbers, got {text!r:.60}")
    check_target_position(np.array(values[:3]))
    T = np.eye(4)
    T[:3, :3] = rotation_from_xyz_fixed(np.radians(values[3:]))
    T[:3, 3] = np.array(values[:3]) / 1000
    return T


class GripperPose(View):
    """The "Gripper pose" folder of the KR210: the target in either convention, and a pose to go to."""

    answers = ("position",)  # the target is on the tool once the joints are set

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        self._session = session
        folder = gui.add_folder("Gripper pose", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.urdf = gui.add_checkbox("ROS/Gazebo gripper convention", False,
                                         hint="The simulation model's gripper frame: R_DH = R_URDF · Rz(180°) · Ry(−90°)")
            self.readout = gui.add_markdown("")
            self.typed = gui.add_text("x y z (mm) roll pitch yaw (°)", "")  # (filled by render_panel unless held)
            self.go = gui.add_button("Go to this pose", icon=viser.Icon.ARROW_RIGHT)
            self.refusal = Beside(gui)
        self._filled = False  #: the box has had the target's pose put in (since the last challenge that asked p)
        self.urdf.on_update(session.guard(lambda _: self._convention_changed()))
        self.go.on_click(session.guard(lambda _: self._go(), beside=self.refusal))

    def _shown(self, T: np.ndarray) -> np.ndarray:
        return kr210_to_urdf(T) if self.urdf.value else T

    def _convention_changed(self) -> None:
        self._filled = False  # the target's pose again, in the convention chosen
        self._session.refresher.request(self._session)

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        if self.held and self._filled:  # the box is filled with the target's pose, and the target is on the tool
            self.typed.value, self._filled = "", False

    def _go(self) -> None:
        T = parse_pose(str(self.typed.value))
        if self.urdf.value:
            T = kr210_from_urdf(T)
        self._session.apply(lambda state: state.move_target(T, cause="typed"))

    def render_panel(self, snapshot: Snapshot) -> None:
        if self.held:
            self.readout.content = HELD_BACK
            return
        shown = pose_text(self._shown(snapshot.target))
        if not self._filled:  # first, after a switch of convention, or after a challenge that asked p
            self.typed.value, self._filled = shown, True
        name = "URDF (ROS/Gazebo)" if self.urdf.value else "DH (frame G)"
        self.readout.content = f"Target in the {name} convention: **{shown}**"

"""The KR210's own folders: its gripper pose in either convention (``gripper``) and its report's slip in its IK
(docs/kinematics.md §7.3), the arm that formula gives for the target drawn dashed beside the right one."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.serial import ReportSlip, report_slip

from ...state import Snapshot
from ...style import number
from ...view import HELD_BACK, Session, View
from ..dh_frames import show
from .gripper import GripperPose
from .scene import skeleton

#: A purple apart (CIE76 ΔE ≥ 16 for normal, protan and deutan vision) from the DH axes' red and blue, the ghosts'
#: slot colours and the charcoal arm
SLIP_COLOR = (118, 42, 131)
INTRO = ("The pick-and-place report finds θ2 and θ3 from the wrist centre's distance beyond the shoulder, which "
         "it writes **√(WC_x² + WC_y² − a1)**: a length taken from an area. It is **√(WC_x² + WC_y²) − a1**. "
         "The rest of its method is right for the distance it is given, so its arm puts the wrist centre, and the "
         "gripper with it, where the wrong distance would be the right one. Drag the target and watch the gap.")


def dashed(segments: np.ndarray, dash: float) -> np.ndarray:
    """(k, 2, 3) a dashed line along ``segments`` (m, 2, 3): each cut into an odd number of pieces about ``dash``
    long, every other one kept, so that each segment starts and ends with a dash.

    >>> dashed(np.array([[[0.0, 0, 0], [0.5, 0, 0]]]), 0.1)[:, :, 0].round(2).tolist()
    [[0.0, 0.1], [0.2, 0.3], [0.4, 0.5]]
    """
    pieces = []
    for start, end in segments:
        count = max(1, int(round(np.linalg.norm(end - start) / dash))) | 1
        points = start + np.linspace(0.0, 1.0, count + 1)[:, None] * (end - start)
        pieces.append(np.stack([points[:-1:2], points[1::2]], axis=1))
    return np.concatenate(pieces)


def slip_markdown(slip: ReportSlip | None, slot: int, joint_names: tuple[str, ...]) -> str:
    """What the report's formula does to this target, in numbers, and its joints beside the right ones."""
    if slip is None:
        return "The target is out of reach: there is no right answer for the report's formula to miss."
    if slip.reached is None:
        return (f"Here the report's code stops with an error: the wrist centre is so near axis 1 that WC_x² + WC_y² "
                f"is smaller than a1, and √(WC_x² + WC_y² − a1) is the square root of {number(slip.radicand, '.3f')}.")
    text = (f"The wrist centre is **{number(1000 * slip.distance, '.0f')} mm** beyond the shoulder; the report's formula "
            f"makes it **{number(1000 * slip.slipped, '.0f')} mm**, so its gripper ends **{number(1000 * slip.gap, '.0f')} mm** "
            f"{'farther out' if slip.slipped > slip.distance else 'nearer in'} than the target.")
    if slip.q is None:
        text += " That is beyond the arm's reach: the report's law of cosines has no angle there."
    if slot >= 4:
        text += " (The report solves the shoulder-front branches only: its arm is drawn on the front one.)"
    if slip.q is not None and slip.right is not None:  # what a student checking their own code compares
        rows = [f"| {name} | {number(np.degrees(mine), '.1f')}° | {number(np.degrees(right), '.1f')}° |"
                for name, mine, right in zip(joint_names, slip.q, slip.right)]
        text += "\n\n| joint | the report's | right |\n|---|---:|---:|\n" + "\n".join(rows)
    return text


class ReportSlipView(View):
    """The KR210's "The report's slip" folder, and the arm the report's formula gives, dashed, with its gripper named."""

    answers = ("wrist_centre",)  # how far the wrist centre is beyond the shoulder: with θ1, WC_x and WC_y

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session) -> None:
        self._arm = session.arm
        size = session.drawing.size
        self._dash = 0.03 * size
        folder = gui.add_folder("The report's slip", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(INTRO)
            self.enabled = gui.add_checkbox("Show the report's arm", False,
                                            hint="Dashed: the arm the report's formula gives for this target")
            self.readout = gui.add_markdown("")
        root = f"{session.drawing.root}/report_slip"
        empty = np.zeros((1, 2, 3))
        self.arm_lines = scene.add_line_segments(f"{root}/arm", empty, SLIP_COLOR, thickness=0.009 * size, visible=False)
        self.miss = scene.add_line_segments(f"{root}/miss", empty, SLIP_COLOR, thickness=0.005 * size, visible=False)
        self._gripper: tuple[np.ndarray, str] | None = None  #: where the report's gripper is and its name, while drawn
        self._last: tuple = (None, None)  #: (snapshot, its slip): the drawing's, which the panel then reads again
        self.enabled.on_update(session.guard(lambda _: session.redraw()))

    def _slip(self, snapshot: Snapshot) -> ReportSlip | None:
        seen, slip = self._last
        if seen is not snapshot:
            slip = report_slip(self._arm, snapshot.target, snapshot.slot, snapshot.q) if snapshot.slot >= 0 else None
            self._last = (snapshot, slip)
        return slip

    def render(self, snapshot: Snapshot) -> None:
        slip = self._slip(snapshot) if self.enabled.value else None
        drawn = slip is not None and slip.q is not None
        if drawn:
            self.arm_lines.points = dashed(skeleton(self._arm.dh, self._arm.frames(slip.q)), self._dash)
            self.miss.points = dashed(np.array([[slip.reached[:3, 3], snapshot.target[:3, 3]]]), self._dash / 2)
        self._gripper = (slip.reached[:3, 3], f"the report's gripper, {number(1000 * slip.gap, '.0f')} mm off") if drawn else None
        show(self.arm_lines, drawn)
        show(self.miss, drawn)

    def names(self) -> list[tuple]:
        point, text = self._gripper or (None, "the report's gripper")
        return [(point, text, SLIP_COLOR)]

    def render_panel(self, snapshot: Snapshot) -> None:
        self.readout.content = HELD_BACK if self.held else slip_markdown(self._slip(snapshot), snapshot.slot,
                                                                          self._arm.joint_names)

    def close(self) -> None:
        """The session has gone: so does the dashed arm, even from a scene everyone shares."""
        for node in (self.arm_lines, self.miss):
            node.remove()


def kr210_lessons(scene: viser.SceneApi, gui: viser.GuiApi, session: Session) -> tuple[View, ...]:
    """The KR210's own folders beside the features every arm has: its gripper pose, its report's slip."""
    return GripperPose(gui, session), ReportSlipView(scene, gui, session)

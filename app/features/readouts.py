"""Live readouts: T06 in millimetres and the orientation the four ways the course reads it."""

from __future__ import annotations

import numpy as np
import viser

from ur10core import JOINT_NAMES, Arm, to_controller
from ur10core.orientation import angle_axis_from_quaternion, quaternion, xyz_fixed, zyx_euler

from ..state import Snapshot
from ..style import number
from ..view import View


def pose_markdown(T: np.ndarray) -> str:
    """T06 as a table: rotation entries and the position in mm."""
    rows = ["| | | | p (mm) |", "|---:|---:|---:|---:|"]
    for i in range(3):
        rows.append("| " + " | ".join(number(T[i, j], "+.4f") for j in range(3)) + f" | **{number(T[i, 3] * 1000, '+.1f')}** |")
    rows.append("| 0 | 0 | 0 | 1 |")
    return "\n".join(rows)


def orientation_markdown(R: np.ndarray, wxyz: np.ndarray | None = None) -> str:
    """The four readouts of a rotation that came from the core (not re-validated).

    ``wxyz`` is its quaternion when the caller has it already.
    """
    alpha, beta, gamma = np.degrees(zyx_euler(R, check=False))
    fixed = np.degrees(xyz_fixed(R, check=False))
    w, x, y, z = quaternion(R, check=False) if wxyz is None else wxyz
    theta, axis = angle_axis_from_quaternion((w, x, y, z))
    return "\n".join(
        [
            f"- **Z-Y-X Euler** (α, β, γ) = ({_degrees(alpha, beta, gamma)})",
            f"- **X-Y-Z fixed** (γ, β, α) = ({_degrees(*fixed)})",
            f"- **Angle–axis** θ = {number(np.degrees(theta), '.2f')}°, k̂ = ({', '.join(number(v, '+.4f') for v in axis)})",
            f"- **Quaternion** (w, x, y, z) = ({', '.join(number(v, '+.4f') for v in (w, x, y, z))})",
        ]
    )


def _degrees(*angles: float) -> str:
    return ", ".join(f"{number(angle, '.2f')}°" for angle in angles)


def flange_markdown(snapshot: Snapshot) -> str:
    return pose_markdown(snapshot.flange) + "\n\n" + orientation_markdown(snapshot.flange[:3, :3], snapshot.flange_wxyz)


def joints_markdown(q: np.ndarray, with_controller: bool) -> str:
    """The joint angles in degrees, and the teach pendant's beside them when asked."""
    course = np.degrees(q)
    if not with_controller:
        return " · ".join(f"{name} {number(value, '.2f')}°" for name, value in zip(JOINT_NAMES, course))
    controller = np.degrees(to_controller(q))
    rows = ["| joint | course | UR controller |", "|---|---:|---:|"]
    rows += [f"| {name} | {number(a, '.2f')}° | {number(b, '.2f')}° |" for name, a, b in zip(JOINT_NAMES, course, controller)]
    rows.append("\nThe controller uses standard DH with a2, a3 < 0: shoulder + 180°, flange turned 180° about z6.")
    return "\n".join(rows)


def dh_markdown(arm: Arm) -> str:
    rows = ["| i | α(i−1) | a(i−1) (mm) | d(i) (mm) | θ(i) |", "|---:|---:|---:|---:|---|"]
    for i, (alpha, a, d) in enumerate(arm.dh_table, start=1):
        rows.append(f"| {i} | {np.degrees(alpha):+.0f}° | {a * 1000:.1f} | {d * 1000:.1f} | θ{i} |")
    return "\n".join(rows)


class Readouts(View):
    """The "Flange pose" folder."""

    def __init__(self, gui: viser.GuiApi, arm: Arm, first: Snapshot) -> None:
        pose = gui.add_folder("Flange pose T06")
        with pose:
            self.pose = gui.add_markdown(flange_markdown(first))
        table = gui.add_folder(f"DH table ({arm.name})", expand_by_default=False)
        with table:
            gui.add_markdown(dh_markdown(arm))
        self.folders = (pose, table)

    def render_panel(self, snapshot: Snapshot) -> None:
        self.pose.content = flange_markdown(snapshot)

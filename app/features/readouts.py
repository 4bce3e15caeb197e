"""Live readouts: the tool pose T0n in millimetres and its orientation the five ways the course reads it."""

from __future__ import annotations

import numpy as np
import viser

from ur10core.orientation import (
    angle_axis_from_quaternion,
    quaternion,
    xyz_fixed,
    zyx_euler,
    zyz_euler,
)

from ..state import Snapshot
from ..style import number
from ..view import HELD_BACK, View


def pose_markdown(T: np.ndarray) -> str:
    """T06 as a table: its columns n, o, a (the tool's x, y, z axes, as the course's reports name them) and the
    position p in mm."""
    rows = ["| n | o | a | p (mm) |", "|---:|---:|---:|---:|"]
    for i in range(3):
        rows.append("| " + " | ".join(number(T[i, j], "+.4f") for j in range(3)) + f" | **{number(T[i, 3] * 1000, '+.1f')}** |")
    rows.append("| 0 | 0 | 0 | 1 |")
    return "\n".join(rows)


def orientation_markdown(R: np.ndarray, wxyz: np.ndarray | None = None) -> str:
    """The five readouts of a rotation that came from the core (not re-validated).

    ``wxyz`` is its quaternion when the caller has it already.
    """
    alpha, beta, gamma = np.degrees(zyx_euler(R, check=False))
    fixed = np.degrees(xyz_fixed(R, check=False))
    paul = np.degrees(zyz_euler(R, check=False))
    other = np.degrees(zyz_euler(R, check=False, flip=True))
    paul_text = _degrees(*paul) + ("" if np.allclose(paul, other) else f") or ({_degrees(*other)}")
    w, x, y, z = quaternion(R, check=False) if wxyz is None else wxyz
    theta, axis = angle_axis_from_quaternion((w, x, y, z))
    return "\n".join(
        [
            f"- **Z-Y-X Euler** (α, β, γ) = ({_degrees(alpha, beta, gamma)})",
            f"- **X-Y-Z fixed** (γ, β, α) = ({_degrees(*fixed)})",
            f"- **Z-Y-Z Euler** (φ, θ, ψ) = ({paul_text}), as the Stanford report reads T6",
            f"- **Angle–axis** θ = {number(np.degrees(theta), '.2f')}°, k̂ = ({', '.join(number(v, '+.4f') for v in axis)})",
            f"- **Quaternion** (w, x, y, z) = ({', '.join(number(v, '+.4f') for v in (w, x, y, z))})",
        ]
    )


def _degrees(*angles: float) -> str:
    return ", ".join(f"{number(angle, '.2f')}°" for angle in angles)


def flange_markdown(snapshot: Snapshot) -> str:
    return pose_markdown(snapshot.flange) + "\n\n" + orientation_markdown(snapshot.flange[:3, :3], snapshot.flange_wxyz)


def pose_title(snapshot: Snapshot) -> str:
    """``Tool pose T06``: the base-to-tool transform, named by the tool's frame."""
    return f"Tool pose T0{len(snapshot.frames) - 1}"


class Readouts(View):
    """The "Tool pose" folder."""

    answers = ("position",)

    def __init__(self, gui: viser.GuiApi, first: Snapshot) -> None:
        folder = gui.add_folder(pose_title(first), expand_by_default=False)
        with folder:
            self.pose = gui.add_markdown("")  # (filled by the first render_panel, held back if a challenge asks p)
        self.folders = (folder,)

    def render_panel(self, snapshot: Snapshot) -> None:
        self.pose.content = HELD_BACK if self.held else flange_markdown(snapshot)

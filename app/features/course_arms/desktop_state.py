"""The course's 3-DOF desktop arm in the app's world: where it stands, and one browser's (or the class's) joints."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ur10core import Arm

#: The course's y = 0 (the shoulder) stands this high above the floor, so that every reach stays above it.
SHOULDER_HEIGHT = 1.5
#: The course's base frame (y up) turned into the app's world (z up): Rx(90°), so x stays, y → z, z → −y.
COURSE_TO_WORLD = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def to_world(points: np.ndarray) -> np.ndarray:
    """(..., 3) points of the course's base frame → the app's world (the shoulder raised off the floor)."""
    return points @ COURSE_TO_WORLD.T + (0.0, 0.0, SHOULDER_HEIGHT)


@dataclass(frozen=True)
class DesktopSnapshot:
    """The arm at one instant: the views draw from it."""

    q: np.ndarray  #: (3,) joints (rad)
    rates: np.ndarray  #: (3,) joint rates (rad/s): zero unless a path is playing
    tool: np.ndarray  #: (4, 4) ``arm.fk(q)``, in the course's frame
    points: np.ndarray  #: (4, 3) world: the pedestal's foot, the shoulder, the elbow, the tool

    @property
    def frames(self) -> np.ndarray:
        """(4, 4, 4) the same points as frames, for the camera."""
        out = np.tile(np.eye(4), (len(self.points), 1, 1))
        out[:, :3, 3] = self.points
        return out

    @property
    def target(self) -> np.ndarray:
        return self.frames[-1]

    @property
    def lowest(self) -> tuple[np.ndarray]:
        return (self.points[0],)


class DesktopArmState:
    """The arm's joints; every change returns a new :class:`DesktopSnapshot`."""

    def __init__(self, arm: Arm, q=None) -> None:
        self.arm = arm
        self.lock = threading.RLock()
        self.last = self._snapshot(arm.specs.home if q is None else np.array(q, dtype=float), np.zeros(3))

    def _snapshot(self, q: np.ndarray, rates: np.ndarray) -> DesktopSnapshot:
        frames = self.arm.frames(q)
        points = to_world(np.vstack([[0.0, -SHOULDER_HEIGHT, 0.0], frames[:, :3, 3]]))
        return DesktopSnapshot(q, rates, frames[-1], points)

    def set_joints(self, q, rates=(0.0, 0.0, 0.0), cause: str = "joints") -> DesktopSnapshot:
        """Move to ``q`` (3,) rad, within the joint ranges, turning at ``rates`` (3,) rad/s (``cause``, as
        for the UR10's state: what moved it)."""
        q = np.array(q, dtype=float)
        rates = np.array(rates, dtype=float)
        if q.shape != (3,) or rates.shape != (3,) or not (np.isfinite(q).all() and np.isfinite(rates).all()):
            raise ValueError("the desktop arm takes three finite joint angles")
        for label, value, (low, high) in zip(self.arm.joint_names, q, self.arm.limits):
            if not low - 1e-9 <= value <= high + 1e-9:
                raise ValueError(f"{label}: from {math.degrees(low):.0f}° to {math.degrees(high):.0f}°, "
                                 f"got {math.degrees(value):.1f}°")
        self.last = self._snapshot(q, rates)
        return self.last

    def set_joint(self, index: int, value: float) -> DesktopSnapshot:
        q = self.last.q.copy()
        q[index] = value
        return self.set_joints(q)

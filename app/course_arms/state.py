"""One browser's course arm: its joints, its IK target and the branches that reach it."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ur10core.branches import BranchSet
from ur10core.serial import SerialArm

#: Where each arm starts: a pose away from every singularity, so that all its branches show.
HOMES = {
    "kr210": (0.0, math.radians(15), math.radians(-30), math.radians(20), math.radians(40), math.radians(10)),
    "stanford": (math.radians(30), math.radians(60), 0.254, math.radians(20), math.radians(40), math.radians(10)),
    "elbow": (math.radians(20), math.radians(40), math.radians(60), math.radians(20), math.radians(40), math.radians(10)),
    "scara": (math.radians(30), math.radians(60), 0.1, math.radians(20)),
    "planar_elbow": (math.radians(30), math.radians(60)),
    "cylindrical": (math.radians(30), 0.35, 0.35),
}


@dataclass(frozen=True)
class CourseSnapshot:
    """What one change left: the views draw from it (never from the live state)."""

    q: np.ndarray  #: (n,) joints: radians and metres
    frames: np.ndarray  #: (rows + 1, 4, 4) every DH frame
    target: np.ndarray  #: (4, 4) where the student put the target (what the arm controls of it)
    solution: BranchSet  #: the branches of ``target``
    chosen: int  #: the slot the arm is in, −1 if none reaches
    reason: str  #: why the target is out of reach ("" if it is reached)

    @property
    def lowest(self) -> tuple[np.ndarray]:
        """The lowest frame origin (the camera keeps it in view)."""
        points = self.frames[:, :3, 3]
        return (points[np.argmin(points[:, 2])],)


def project_target(arm: SerialArm, T: np.ndarray, current: np.ndarray) -> np.ndarray:
    """The part of a gizmo pose ``T`` the arm can follow (``arm.task``), the rest from its own tool pose ``current``.

    A SCARA keeps its tool pointing down and takes only the gizmo's yaw; an arm that places
    only a position keeps its own orientation; the planar elbow stays in its plane z = 0.
    """
    out = np.array(T, dtype=float)
    if arm.task == "position and yaw":
        yaw = math.atan2(T[1, 0], T[0, 0])
        c, s = math.cos(yaw), math.sin(yaw)
        out[:3, :3] = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])  # Rz(yaw) Rx(π)
    elif arm.task == "position":
        out[:3, :3] = current[:3, :3]
        if arm.name == "planar_elbow":
            out[2, 3] = 0.0
    return out


class CourseArmState:
    """The joints and target of one course arm; every change returns a new :class:`CourseSnapshot`."""

    def __init__(self, arm: SerialArm, q=None) -> None:
        self.arm = arm
        self.lock = threading.RLock()  # the drag queue holds it while it calls drag_to, which applies under it
        self.last = self._solved(np.array(HOMES.get(arm.name, np.zeros(arm.n_joints)) if q is None else q, dtype=float))

    def _solved(self, q: np.ndarray, target: np.ndarray | None = None) -> CourseSnapshot:
        frames = self.arm.frames(q)
        reached = target is None
        if target is None:
            target = frames[-1]
        solution = self.arm.ik(target, hint=q)
        chosen = solution.nearest(q, self.arm.revolute) if reached else -1
        return CourseSnapshot(q, frames, target, solution, chosen, "")

    def set_joint(self, index: int, value: float) -> CourseSnapshot:
        q = self.last.q.copy()
        q[index] = value
        return self.set_joints(q)

    def set_joints(self, q) -> CourseSnapshot:
        q = self.arm.dh.joints(q).astype(float)
        low, high = self.arm.limits.T
        if ((q < low) | (q > high)).any():
            raise ValueError("joint values must stay within the arm's limits")
        self.last = self._solved(q)
        return self.last

    def move_target(self, T: np.ndarray) -> CourseSnapshot:
        """Solve for the gizmo pose ``T``: the valid branch nearest the current joints, or stay and say why."""
        previous = self.last
        target = project_target(self.arm, T, previous.frames[-1])
        solution = self.arm.ik(target, hint=previous.q)
        chosen = solution.nearest(previous.q, self.arm.revolute)
        if chosen < 0:
            self.last = CourseSnapshot(previous.q, previous.frames, target, solution, -1, solution.unreachable_reason())
        else:
            q = solution.q[chosen]
            self.last = CourseSnapshot(q, self.arm.frames(q), target, solution, int(chosen), "")
        return self.last

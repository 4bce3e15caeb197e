"""One browser's course arm (any arm but the UR10, the desktop arm included): its joints, its IK target and the
branches that reach it."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ur10core.branches import IKSolution
from ur10core import Arm
from ur10core.serial import project_target


@dataclass(frozen=True)
class CourseSnapshot:
    """What one change left: the views draw from it (never from the live state)."""

    q: np.ndarray  #: (n,) joints: radians and metres
    frames: np.ndarray  #: (rows + 1, 4, 4) every DH frame
    target: np.ndarray  #: (4, 4) where the student put the target (what the arm controls of it)
    solution: IKSolution | None  #: the branches of ``target``; None until searched, for a numerical arm
    chosen: int  #: the slot the arm is in, −1 if none reaches (or not searched)
    reason: str  #: why the target is out of reach ("" if it is reached)
    rates: np.ndarray | None = None  #: (n,) the joints' rates while a lesson plays a path (None at rest)

    @property
    def ghosts(self) -> np.ndarray:
        """(k,) bool: the slots drawn as ghosts, every valid one but the arm's own."""
        if self.solution is None:  # a typed table's branches, until searched
            return np.zeros(0, bool)
        shown = self.solution.valid.copy()
        if self.chosen >= 0:
            shown[self.chosen] = False
        return shown

    @property
    def flange(self) -> np.ndarray:
        """(4, 4) the tool frame (the UR10's flange), where the views that act at the tool draw."""
        return self.frames[-1]

    @property
    def lowest(self) -> tuple[np.ndarray]:
        """The lowest frame origin (the camera keeps it in view)."""
        points = self.frames[:, :3, 3]
        return (points[np.argmin(points[:, 2])],)


class CourseArmState:
    """The joints and target of one course arm; every change returns a new :class:`CourseSnapshot`.

    An arm with a closed form gets every branch on every change. A typed table's numerical
    IK follows the target from the current joints only (a millisecond or so a step); its
    other branches come from its search from many starts (``BranchSearch``), when the student asks.
    """

    def __init__(self, arm: Arm, q=None) -> None:
        self.arm = arm
        self.numerical = arm.numerical
        self.lock = threading.RLock()  # the drag queue holds it while it calls drag_to, which applies under it
        if q is None:
            q = arm.specs.home
        self.last = self._solved(np.array(q, dtype=float))

    def _solved(self, q: np.ndarray, rates: np.ndarray | None = None) -> CourseSnapshot:
        frames = self.arm.frames(q)
        target = frames[-1]
        if self.numerical:
            return CourseSnapshot(q, frames, target, None, -1, "", rates)
        solution = self.arm.ik(target, hint=q)
        return CourseSnapshot(q, frames, target, solution, int(solution.nearest(q).slot), "", rates)

    def set_joint(self, index: int, value: float) -> CourseSnapshot:
        q = self.last.q.copy()
        q[index] = value
        return self.set_joints(q)

    def set_joints(self, q, cause: str = "joints", rates=None) -> CourseSnapshot:
        """Put the arm at ``q`` (``cause``, as for the UR10's state: what moved it, e.g. "motion"), its joints
        turning at ``rates`` (a lesson playing a path; the arrows show them)."""
        arm = self.arm
        q = arm.joints(q).astype(float)
        if q.shape != (arm.n_joints,):
            raise ValueError(f"{arm.n_joints} joint values are needed, got shape {q.shape}")
        for name, kind, value, (low, high) in zip(arm.joint_names, arm.joint_types, q, arm.limits):
            if not low - 1e-9 <= value <= high + 1e-9:
                shown = (lambda v: f"{math.degrees(v):.0f}°") if kind == "R" else (lambda v: f"{1000 * v:.0f} mm")
                got = f"{math.degrees(value):.1f}°" if kind == "R" else f"{1000 * value:.1f} mm"
                raise ValueError(f"{name}: from {shown(low)} to {shown(high)}, got {got}")
        self.last = self._solved(q, None if rates is None else arm.joints(rates, "rates").astype(float))
        return self.last

    def move_target(self, T: np.ndarray) -> CourseSnapshot:
        """Solve for the gizmo pose ``T``: the valid branch nearest the current joints, or stay and say why."""
        previous = self.last
        target = project_target(self.arm, T, previous.frames[-1])
        if self.numerical:
            q, _ = self.arm.solver.follow(target, previous.q)
            error = float(self.arm.pose_error(q, target))
            if error <= 1e-9:
                self.last = CourseSnapshot(q, self.arm.frames(q), target, None, -1, "")
            else:
                self.last = CourseSnapshot(previous.q, previous.frames, target, None, -1,
                                           f"the search from the arm's joints came within {1000 * error:.3g} mm of it: it may be "
                                           "out of reach, or reachable only from another branch (Find every branch)")
            return self.last
        solution = self.arm.ik(target, hint=previous.q)
        branch = solution.nearest(previous.q)  # turned next to the current joints, within the limits
        if branch.slot < 0:
            self.last = CourseSnapshot(previous.q, previous.frames, target, solution, -1, solution.unreachable_reason())
        else:
            self.last = CourseSnapshot(branch.q, self.arm.frames(branch.q), target, solution, int(branch.slot), "")
        return self.last

    def with_branches(self, snapshot: CourseSnapshot, solution: IKSolution) -> CourseSnapshot:
        """The found branches shown, if the arm has not moved since they were searched for."""
        if self.last is not snapshot:
            return self.last
        reached = solution.valid.any()
        chosen = int(solution.nearest(snapshot.q).slot) if reached else -1
        reason = snapshot.reason if reached else solution.unreachable_reason()
        self.last = CourseSnapshot(snapshot.q, snapshot.frames, snapshot.target, solution, chosen, reason)
        return self.last

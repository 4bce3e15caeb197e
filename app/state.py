"""What one arm is doing: its joints, its IK target and the eight branches of that target.

No viser here — this is the app's logic, unit-tested without a browser. Every change
returns a :class:`Snapshot`, which is all the views need to draw.

All kinematics comes from :mod:`ur10core`; this module only decides *which* result to
use (the branch nearest the current joints, the last reachable pose, …) and checks the
values a user can type.
"""

from __future__ import annotations

import functools
import math
import threading
from dataclasses import dataclass

import numpy as np

from ur10core import JOINT_LIMIT, JOINT_NAMES, Arm, IKSolution, SingularityGeometry
from ur10core.ik import equivalent_near
from ur10core.orientation import quaternion
from ur10core.workspace import lowest_points


SINGULARITY_KINDS = ("shoulder", "elbow", "wrist")
#: A body this far below z = 0 is through the floor (the base's own underside sits on it).
FLOOR_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Snapshot:
    """Everything the views draw, computed once per change."""

    q: np.ndarray  #: (6,) current joints, rad
    frames: np.ndarray  #: (7, 4, 4) frames {0}..{6} of the solid arm
    target: np.ndarray  #: (4, 4) where the IK target is
    solution: IKSolution  #: the eight branches of the target pose
    ghost_frames: np.ndarray  #: (8, 7, 4, 4) frames of each branch (identity where invalid)
    slot: int  #: the branch the solid arm is on, −1 when the target is unreachable
    reachable: bool
    reason: str  #: why the target is unreachable ("" when it is reachable)
    link_wxyz: np.ndarray  #: (6, 4) rotation of T(i−1, i), i = 1..6, as quaternions (the solid arm's tree)
    ghost_wxyz: np.ndarray  #: (8, 7, 4) rotation of each branch's frames {0}..{6}, as quaternions
    flange_wxyz: np.ndarray  #: (4,) the flange orientation as a quaternion
    factors: np.ndarray  #: (3,) shoulder, elbow, wrist factors of det J
    body_points: np.ndarray  #: (7, P, 3) outline points of each link's body, in its frame (ArmState's)
    cause: str  #: "joints", "target" (dragged), "typed", "branch", "singularity", "reset" or "motion" (a played path): what made this change
    arm: Arm

    @property
    def flange(self) -> np.ndarray:
        return self.frames[6]

    @functools.cached_property
    def lowest(self) -> np.ndarray:
        """(9, 3) lowest body point of the solid arm, then of each branch (NaN where invalid).

        Computed when first asked for (the panel's redraw, the floor markers): not on the drag path.
        """
        frames = np.concatenate([self.frames[None], self.ghost_frames])
        lowest = lowest_points(frames, self.body_points)
        lowest[1:][~self.solution.valid] = np.nan
        return lowest

    @functools.cached_property
    def through_floor(self) -> np.ndarray:
        """(9,) bool: the solid arm, then each branch, reaches below the floor z = 0 (a real arm would hit it)."""
        with np.errstate(invalid="ignore"):
            return self.lowest[:, 2] < -FLOOR_TOLERANCE

    @functools.cached_property
    def det_j(self) -> float:
        """det J = a2 a3 × the three factors (docs/kinematics.md §5)."""
        return float(self.arm.a2 * self.arm.a3 * self.factors.prod())

    @functools.cached_property
    def geometry(self) -> SingularityGeometry:
        """The singularity overlay's points and axes (computed when first asked for: not on the drag path)."""
        return self.arm.singularity_geometry_from_frames(self.frames)


class ArmState:
    """One arm and its IK target. Thread-safe: callbacks of one browser may overlap.

    Parameters
    ----------
    arm : Arm
        The arm's dimensions.
    q : array_like, shape (6,), optional
        Starting joints (rad); the arm's home pose by default (``arm.specs``: for the UR10, the
        course's arbitrary pose).
    body_points : array_like, shape (7, P, 3), optional
        Points of each link's body in its DH frame (``ur10teach.meshes.body_points``), for the
        floor check; the frame origins alone by default.
    """

    def __init__(self, arm: Arm, q=None, body_points=None) -> None:
        self.arm = arm
        self.body_points = np.zeros((7, 1, 3)) if body_points is None else np.asarray(body_points, dtype=float)
        self.lock = threading.RLock()
        self._q = self.check_joints(arm.specs.home if q is None else q)
        self._target = arm.fk(self._q)
        self._solution = arm.ik(self._target, hint=self._q)
        self._slot = int(self._solution.nearest(self._q).slot)
        self._reason = ""
        self._before_singularity = self._q.copy()  #: where a row of singularity buttons started
        self._last = self._snapshot("reset")

    # ------------------------------------------------------------------ reading

    @property
    def q(self) -> np.ndarray:
        return self._q.copy()

    @property
    def last(self) -> Snapshot:
        """The most recent snapshot."""
        return self._last

    # ------------------------------------------------------------------ validation

    @staticmethod
    def check_joints(q) -> np.ndarray:
        """Six finite angles (rad) within the UR10's ±360°, else ``ValueError`` naming the joint."""
        try:
            q = np.array(q, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ValueError(f"joint angles must be six numbers, got {q!r:.60}") from None
        if q.shape != (6,):
            raise ValueError(f"six joint angles are needed, got {q.size}")
        for name, value in zip(JOINT_NAMES, q):
            if not math.isfinite(value):
                raise ValueError(f"{name}: {value} is not a number of degrees")
            if abs(value) > JOINT_LIMIT + 1e-9:
                raise ValueError(f"{name}: {math.degrees(value):.1f}° is outside the joint range ±360°")
        return np.clip(q, -JOINT_LIMIT, JOINT_LIMIT)

    @staticmethod
    def parse_degrees(text: str, count: int = 6, what: str = "joint angles") -> np.ndarray:
        """``"30, 45, 26, 50, 60, 80"`` (commas or spaces) → floats, with a message a student understands."""
        parts = [p for p in text.replace(",", " ").replace(";", " ").split() if p]
        if len(parts) != count:
            raise ValueError(f"{what}: expected {count} numbers, got {len(parts)} in {text!r:.60}")
        values = []
        for part in parts:
            try:
                value = float(part.replace("°", ""))
            except ValueError:
                raise ValueError(f"{what}: {part!r} is not a number") from None
            if not math.isfinite(value):
                raise ValueError(f"{what}: {part!r} is not a finite number")
            values.append(value)
        return np.array(values)

    # ------------------------------------------------------------------ changes

    def set_joints(self, q, cause: str = "joints") -> Snapshot:
        """Move the arm to ``q`` (rad); the target follows the flange."""
        q = self.check_joints(q)
        with self.lock:
            self._q = q
            self._target = self.arm.fk(q)
            self._solution = self.arm.ik(self._target, hint=q)
            self._slot = int(self._solution.nearest(q, prefer=self._slot).slot)
            self._reason = ""
            return self._remember(cause)

    def set_joint(self, index: int, value: float) -> Snapshot:
        """Change one joint (rad)."""
        with self.lock:
            q = self._q.copy()
            q[index] = value
            return self.set_joints(q)

    def move_target(self, T, cause: str = "target") -> Snapshot:
        """Move the IK target to ``T`` (4x4): the arm takes the branch nearest its joints.

        An unreachable target leaves the arm where it was and records why. ``cause`` is
        ``"target"`` for a drag (the user holds the gizmo there already) or ``"typed"``.
        """
        with self.lock:
            solution = self.arm.ik(T, hint=self._q)  # ValueError for a malformed pose
            self._target = np.array(T, dtype=float)
            self._solution = solution
            branch = solution.nearest(self._q, prefer=self._slot)
            if branch.slot < 0:
                self._slot = -1
                self._reason = solution.unreachable_reason()
            else:
                self._q = branch.q
                self._slot = int(branch.slot)
                self._reason = ""
            return self._remember(cause)

    def select_branch(self, slot: int) -> Snapshot:
        """Put the arm on branch ``slot`` of the current target (shifted next to the current joints)."""
        if isinstance(slot, bool) or not isinstance(slot, (int, np.integer)) or not 0 <= slot < 8:
            raise ValueError(f"branch must be 0..7, got {slot!r}")
        with self.lock:
            if not self._solution.valid[slot]:
                raise ValueError(
                    f"branch {slot + 1} ({self._solution.labels[slot]}) does not exist for this target"
                )
            self._q = equivalent_near(self._solution.q[slot], self._q, JOINT_LIMIT)
            self._slot = int(slot)
            self._reason = ""
            return self._remember("branch")

    def place_in_singularity(self, kind: str) -> Snapshot:
        """Move the arm exactly onto the shoulder, elbow or wrist singularity, and onto no other.

        Each one starts from the pose the arm had before the first of a row of these
        (pressing "wrist" after "elbow" must not leave the arm on both).
        """
        if kind not in SINGULARITY_KINDS:
            raise ValueError(f"kind must be one of {SINGULARITY_KINDS}, got {kind!r}")
        with self.lock:
            if self._last.cause != "singularity":
                self._before_singularity = self._q.copy()
            return self.set_joints(self.arm.singular_configuration(kind, self._before_singularity), cause="singularity")

    # ------------------------------------------------------------------ snapshot

    def _remember(self, cause: str) -> Snapshot:
        self._last = self._snapshot(cause)
        return self._last

    def _snapshot(self, cause: str) -> Snapshot:
        arm, solution = self.arm, self._solution
        # one frames() call for the solid arm and the eight ghosts
        joints = np.empty((9, 6))
        joints[0], joints[1:] = self._q, solution.q
        invalid = ~solution.valid
        some_invalid = invalid.any()
        if some_invalid:
            joints[1:][invalid] = 0.0
        frames = arm.frames(joints)
        ghost_frames = frames[1:]
        if some_invalid:
            ghost_frames[invalid] = np.eye(4)
        # every rotation the views draw, converted to quaternions in one vectorised call
        rotations = frames[:, :, :3, :3]
        links = arm.link_transforms(self._q)[:, :3, :3]  # T(i−1, i): the solid arm's tree
        wxyz = quaternion(np.concatenate([links, rotations[1:].reshape(-1, 3, 3), rotations[0, 6:]]), check=False)
        factors = arm.singularity_factors(self._q)
        return Snapshot(
            q=self._q.copy(),
            frames=frames[0],
            target=self._target.copy(),
            solution=solution,
            ghost_frames=ghost_frames,
            link_wxyz=wxyz[:6],
            ghost_wxyz=wxyz[6:-1].reshape(8, 7, 4),
            flange_wxyz=wxyz[-1],
            slot=self._slot,
            reachable=self._slot >= 0,
            reason=self._reason,
            factors=factors,
            body_points=self.body_points,
            cause=cause,
            arm=arm,
        )

"""What one arm is doing: its joints, its IK target and the branches of that target.

No viser here — this is the app's logic for any arm, unit-tested without a browser. Every
change returns a :class:`Snapshot`, which is all the views need to draw.

All kinematics comes from :mod:`ur10core`; this module only decides *which* result to
use (the branch nearest the current joints, the last reachable pose, …) and checks the
values a user can type.
"""

from __future__ import annotations

import functools
import itertools
import math
import re
import threading
from dataclasses import dataclass, field

import numpy as np

from ur10core import Arm, IKSolution
from ur10core.orientation import quaternion
from ur10core.serial import project_target
from ur10core.tolerances import FLOOR_TOLERANCE, LIMIT_TOLERANCE
from ur10core.workspace import heights_above_floor, lowest_points

from .style import half_width, number, typed_fields


@dataclass(frozen=True)
class Snapshot:
    """What one change left: the views draw from it (never from the live state).

    What only some drawings need (the quaternions, the det J factors, the floor check) is
    worked out when first asked for, once per snapshot.
    """

    q: np.ndarray  #: (n,) joints: radians and metres
    frames: np.ndarray  #: (L, 4, 4) every frame of the arm, the base's first and the tool's last
    target: np.ndarray  #: (4, 4) where the IK target is (what the arm controls of it)
    solution: IKSolution | None  #: the branches of ``target``; None until searched, for a typed table
    slot: int  #: the branch the arm is on, −1 if none reaches (or not searched)
    reason: str  #: why the target is out of reach ("" if it is reached)
    #: what made this change: "joints", "target" (dragged, still held), "dropped" (the drag's end), "typed",
    #: "branch", "singularity", "reset", "motion" (a played path: the typing box is left to the student)
    cause: str
    arm: Arm
    ghost_frames: np.ndarray  #: (k, L, 4, 4) frames of each branch (identity where it does not reach)
    rates: np.ndarray | None = None  #: (n,) the joints' rates while a path plays (None at rest)
    body_points: np.ndarray | None = None  #: (L, P, 3) outline points of each body in its frame, for the floor check
    #: made after every snapshot of a lower order (a panel drawn late can tell what the student did since)
    order: int = field(default_factory=itertools.count().__next__, compare=False)

    @property
    def reachable(self) -> bool:
        return not self.reason

    @property
    def flange(self) -> np.ndarray:
        """(4, 4) the tool frame (the UR10's flange), where the views that act at the tool draw."""
        return self.frames[-1]

    @property
    def ghosts(self) -> np.ndarray:
        """(k,) bool: the slots drawn as ghosts, every valid one but the arm's own."""
        if self.solution is None:
            return np.zeros(0, bool)
        shown = self.solution.valid.copy()
        if self.slot >= 0:
            shown[self.slot] = False
        return shown

    @functools.cached_property
    def _wxyz(self) -> np.ndarray:
        """Every rotation a drawing turns (the links' T(i−1, i), the ghosts' frames, the tool) as quaternions, in one call."""
        link_transforms = getattr(self.arm.solver, "link_transforms", None)  # the UR family's: its meshes hang on them
        links = np.zeros((0, 3, 3)) if link_transforms is None else link_transforms(self.q)[:, :3, :3]
        ghosts = self.ghost_frames[:, :, :3, :3].reshape(-1, 3, 3)
        return quaternion(np.concatenate([links, ghosts, self.frames[-1:, :3, :3]]), check=False)

    @property
    def link_wxyz(self) -> np.ndarray:
        """(n, 4) rotation of T(i−1, i) as quaternions: a mesh arm's tree of link nodes."""
        return self._wxyz[:len(self.q)]

    @property
    def ghost_wxyz(self) -> np.ndarray:
        """(k, L, 4) rotation of each branch's frames, as quaternions."""
        slots, frames = self.ghost_frames.shape[:2]
        return self._wxyz[-1 - slots * frames:-1].reshape(slots, frames, 4)

    @property
    def flange_wxyz(self) -> np.ndarray:
        return self._wxyz[-1]

    @functools.cached_property
    def factors(self) -> np.ndarray:
        """The factors of det J the arm's model gives (the UR10's: shoulder, elbow, wrist)."""
        return self.arm.singularity_factors(self.q)

    @functools.cached_property
    def lowest(self) -> np.ndarray:
        """(1 + k, 3) lowest body point of the arm, then of each branch (NaN where invalid)."""
        points = np.zeros((len(self.frames), 1, 3)) if self.body_points is None else self.body_points
        lowest = lowest_points(np.concatenate([self.frames[None], self.ghost_frames]), points, self.arm.up)
        if self.solution is not None:
            lowest[1:][~self.solution.valid] = np.nan
        return lowest

    @functools.cached_property
    def through_floor(self) -> np.ndarray:
        """(1 + k,) bool: the arm, then each branch, reaches below its floor (a real arm would hit it)."""
        with np.errstate(invalid="ignore"):
            return heights_above_floor(self.arm, self.lowest) < -FLOOR_TOLERANCE


def joint_value_text(kind: str, value: float, digits: str = ".1f") -> str:
    """A joint value as a student reads it: degrees for a revolute joint, millimetres for a prismatic one."""
    return number(math.degrees(value), digits) + "°" if kind == "R" else number(1000 * value, digits) + " mm"


class ArmState:
    """One arm and its IK target. Thread-safe: callbacks of one browser may overlap.

    An arm with a closed form gets every branch on every change. A typed table's numerical
    IK follows the target from the current joints only (a millisecond or so a step); its
    other branches come from its search from many starts, when the student asks
    (:meth:`with_branches`).

    Parameters
    ----------
    arm : Arm
        Any arm of the course, or a typed table.
    q : array_like, shape (n,), optional
        Starting joints; the arm's home pose by default (``arm.specs``).
    body_points : array_like, shape (L, P, 3), optional
        Points of each link's body in its frame (``ur10teach.meshes.body_points``), for the
        floor check; the frame origins alone by default.
    """

    def __init__(self, arm: Arm, q=None, body_points=None) -> None:
        self.arm = arm
        self.numerical = arm.numerical
        self.body_points = None if body_points is None else np.asarray(body_points, dtype=float)
        self.lock = threading.RLock()  # the drag queue holds it while it calls drag_to, which applies under it
        self._before_singularity: np.ndarray | None = None  #: where a row of singularity buttons started
        self.last: Snapshot | None = None
        self.last = self._solved(self.check_joints(arm.specs.home if q is None else q), "reset")

    @property
    def q(self) -> np.ndarray:
        return self.last.q.copy()

    # ------------------------------------------------------------------ validation

    def check_joints(self, q) -> np.ndarray:
        """n finite joint values within the arm's limits, else ``ValueError`` naming the joint."""
        arm = self.arm
        try:
            q = np.array(q, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise ValueError(f"joint values must be {arm.n_joints} numbers, got {q!r:.60}") from None
        if q.shape != (arm.n_joints,):
            raise ValueError(f"{arm.n_joints} joint values are needed, got {q.size}")
        low, high = arm.limits[:, 0], arm.limits[:, 1]
        for name, kind, value, lo, hi in zip(arm.joint_names, arm.joint_types, q.tolist(), low, high):
            if not math.isfinite(value):
                raise ValueError(f"{name}: {value} is not a number")
            if not lo - LIMIT_TOLERANCE <= value <= hi + LIMIT_TOLERANCE:
                # as the slider shows them: the SCARA's ±157.5°, not ±158° beside "got 158.0°"
                lowest, highest = (re.sub(r"\.0(?=°| mm)", "", joint_value_text(kind, v)) for v in (lo, hi))
                raise ValueError(f"{name}: from {lowest} to {highest}, got {joint_value_text(kind, value)}")
        return np.clip(q, low, high)

    @staticmethod
    def parse_numbers(text: str, count: int, what: str = "joint values") -> np.ndarray:
        """``"30, 45, 26, 50, 60, 80"`` (commas or spaces, a ° allowed) → floats, with a message a student understands."""
        text = half_width(text)  # (the decimal-comma question below reads it too)
        parts = typed_fields(text, what)
        numbers = f"{count} number{'s' * (count != 1)}"
        if len(parts) != count:
            dotted = re.sub(r"(\d),(\d)", r"\1.\2", text.strip())  # decimal commas as points
            decimals = typed_fields(dotted, what)  # (not "1.184.3", from 1.184,3: no question then)
            if "," in text and len(decimals) == count and all(f.lstrip("+-").replace(".", "", 1).isdigit() for f in decimals):
                raise ValueError(f"{what}: {numbers} here? Write decimals with a point: {dotted:.60}")
            if not parts:
                raise ValueError(f"{what}: the box is empty; type {numbers} in it")
        values = []
        for part in parts:  # a word first: "512 mm 30 mm" is a unit typed, not six numbers for three
            try:
                value = float(part)
            except ValueError:
                raise ValueError(f"{what}: {part!r:.40} is not a number; type the numbers alone") from None
            if not math.isfinite(value):
                raise ValueError(f"{what}: {part!r:.40} is not a finite number")
            values.append(value)
        if len(values) != count:
            raise ValueError(f"{what}: expected {numbers}, got {len(parts)} in {text!r:.60}")
        return np.array(values)

    # ------------------------------------------------------------------ changes

    def _solved(self, q: np.ndarray, cause: str, rates=None) -> Snapshot:
        """The arm at ``q``, the target on its tool, with every branch of it."""
        target = self.arm.fk(q)
        if self.numerical:
            return self._remember(q, target, None, -1, "", cause, rates)
        solution = self.arm.ik(target, hint=q)
        slot = int(solution.nearest(q, prefer=None if self.last is None else self.last.slot).slot)
        return self._remember(q, target, solution, slot, "", cause, rates)

    def _remember(self, q, target, solution, slot, reason, cause, rates=None) -> Snapshot:
        # one frames() call for the arm and every branch (on the drag path: no more numpy calls than needed)
        slots = 0 if solution is None else len(solution.valid)
        joints = np.empty((1 + slots, len(q)))
        joints[0] = q
        invalid = None
        if slots:
            joints[1:] = solution.q
            invalid = ~solution.valid
            if invalid.any():
                joints[1:][invalid] = 0.0
            else:
                invalid = None
        frames = self.arm.frames(joints)
        ghost_frames = frames[1:]
        if invalid is not None:
            ghost_frames[invalid] = np.eye(4)
        self.last = Snapshot(q, frames[0], target, solution, slot, reason, cause, self.arm, ghost_frames, rates, self.body_points)
        return self.last

    def set_joints(self, q, cause: str = "joints", rates=None) -> Snapshot:
        """Put the arm at ``q``; the target follows the tool. ``rates``: the joints' rates while a path plays."""
        q = self.check_joints(q)
        with self.lock:
            return self._solved(q, cause, None if rates is None else self.arm.joints(rates, "rates").astype(float))

    def set_joint(self, index: int, value: float) -> Snapshot:
        """Change one joint (rad or m)."""
        with self.lock:
            q = self.last.q.copy()
            q[index] = value
            return self.set_joints(q)

    def move_target(self, T, cause: str = "target") -> Snapshot:
        """Move the IK target to ``T`` (4, 4): the arm takes the branch nearest its joints.

        An unreachable target leaves the arm where it was and records why. ``cause`` is
        ``"target"`` for a drag (the user holds the gizmo there already) or ``"typed"``.
        """
        with self.lock:
            previous = self.last
            # the whole pose for an arm that controls it (the IK checks it); what it controls of it otherwise
            target = np.array(T, dtype=float) if self.arm.task == "pose" else project_target(self.arm, T, previous.flange)
            if self.numerical:
                q, _ = self.arm.solver.follow(target, previous.q)
                error = float(self.arm.pose_error(q, target))
                if error > 1e-9:
                    return self._remember(previous.q, target, None, -1,
                                          f"the search from the arm's joints came within {1000 * error:.3g} mm of it: it "
                                          "may be out of reach, or reachable only from another branch (Find every branch)",
                                          cause)
                found = np.full((len(self.arm.slot_labels), len(q)), np.nan)  # the one branch followed, as a solution
                found[0] = q
                solution = IKSolution(found, np.arange(len(found)) == 0, np.zeros(len(found), np.int8), self.arm)
            else:
                solution = self.arm.ik(target, hint=previous.q)  # ValueError for a malformed pose
            branch, reason = self._branch_within_limits(solution, previous.q, prefer=previous.slot)
            if reason:
                if self.numerical:  # the search followed one branch only
                    return self._remember(previous.q, target, None, -1, f"{reason}: another branch may reach it "
                                          "within them (Find every branch)", cause)
                return self._remember(previous.q, target, solution, -1, reason, cause)
            if self.numerical:
                return self._remember(branch.q, target, None, -1, "", cause)
            return self._remember(branch.q, target, solution, int(branch.slot), "", cause)

    def _branch_within_limits(self, solution: IKSolution, q: np.ndarray, prefer: int | None = None) -> tuple:
        """(the branch of ``solution`` the arm takes from its joints ``q``, "") or (no branch, why not).

        Turned next to the joints. A real arm cannot take a branch beyond a joint limit (and every slider would
        then be refused until a pose button): a target only such branches reach is out of reach, and the reason
        names the nearest one's joint, e.g. "reachable only beyond a joint limit (d3: from 0 mm to 762 mm, got
        -50.0 mm)".
        """
        branch = solution.nearest(q, prefer=prefer, within_limits=True)
        if branch.slot >= 0:
            return branch, ""
        if not solution.valid.any():
            return branch, solution.unreachable_reason()
        try:
            self.check_joints(solution.nearest(q).q)
        except ValueError as beyond:
            return branch, f"reachable only beyond a joint limit ({beyond})"
        return branch, "reachable only beyond a joint limit"  # another branch, farther away, is the one beyond them

    def select_branch(self, slot: int) -> Snapshot:
        """Put the arm on branch ``slot`` of the current target (turned next to the current joints)."""
        with self.lock:
            solution = self.last.solution
            if solution is None:
                raise ValueError("this arm's branches have not been searched for yet: press Find every branch")
            slots = len(solution.labels)
            if isinstance(slot, bool) or not isinstance(slot, (int, np.integer)) or not 0 <= slot < slots:
                raise ValueError(f"branch must be 1..{slots}, got {slot!r} (counting from 0)")
            if not solution.valid[slot]:
                raise ValueError(f"branch {slot + 1} ({solution.labels[slot]}) does not exist for this target")
            q = solution.take(slot, self.last.q)
            try:  # a real arm cannot go there, and every slider would then be refused until a pose button
                q = self.check_joints(q)
            except ValueError as beyond:
                raise ValueError(f"branch {slot + 1} ({solution.labels[slot]}) is beyond a joint limit ({beyond})") from None
            return self._remember(q, self.last.target, solution, int(slot), "", "branch")

    def place_in_singularity(self, kind: str) -> Snapshot:
        """Move the arm exactly onto one singularity of its det J (``kind``: one of ``arm.factor_names``), and onto
        no other where it can (:meth:`ur10core.Arm.singular_configuration`).

        Each one starts from the pose the arm had before the first of a row of these
        (pressing "wrist" after "elbow" must not leave the arm on both).
        """
        with self.lock:  # the core refuses a kind the arm has not (a typed table has none), naming its own
            if self.last.cause != "singularity" or self._before_singularity is None:
                self._before_singularity = self.last.q.copy()
            return self.set_joints(self.arm.singular_configuration(kind, self._before_singularity), cause="singularity")

    def with_branches(self, snapshot: Snapshot, solution: IKSolution) -> Snapshot:
        """A typed table's found branches shown, if the arm has not moved since they were searched for. An arm whose
        own search had stopped short of the target takes the nearest branch found within its limits."""
        with self.lock:
            if self.last is not snapshot:
                return self.last
            if snapshot.reachable and solution.valid.any():  # the arm is at the target: on the branch nearest its joints
                return self._remember(snapshot.q, snapshot.target, solution, int(solution.nearest(snapshot.q).slot), "",
                                      "branch")
            # the arm's own search stopped short of the target (or beyond a limit): it takes the nearest branch
            # found within the limits, as a preset's arm takes its nearest
            branch, reason = self._branch_within_limits(solution, snapshot.q)
            if reason:
                return self._remember(snapshot.q, snapshot.target, solution, -1, reason, "branch")
            return self._remember(branch.q, snapshot.target, solution, int(branch.slot), "", "branch")

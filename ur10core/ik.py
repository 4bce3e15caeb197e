"""All-eight-branch analytic inverse kinematics (COURSE_NOTES §4).

The method is the course's separation of variables, written so that every branch is
computed from a handful of ``atan2`` and square roots, with no sine or cosine of an
intermediate angle (they are formed algebraically instead):

1. θ1 from ``(py − d6 r23) c1 + (d6 r13 − px) s1 = −d4``. With the wrist-2 point
   ``P5 = p − d6 z6`` at horizontal distance ρ from the base axis and
   ``A = ±sqrt(ρ² − d4²)`` (its reach along the arm's forward axis x1),
   ``c1 = (P5x A − P5y d4)/ρ²`` and ``s1 = (P5y A + P5x d4)/ρ²``; ``A ≤ 0`` is the
   course's ``θ1 = atan2(P5y, P5x) + π/2 + acos(d4/ρ)``, ``A ≥ 0`` the ``−acos``.
2. θ5 = ±acos(r13 s1 − r23 c1), taken as ``atan2(±|s5|, c5)`` with
   ``|s5| = |(r21 c1 − r11 s1, r12 s1 − r22 c1)|`` so it stays accurate near s5 = 0.
3. θ6 from ``s5 c6 = r21 c1 − r11 s1`` and ``−s5 s6 = r22 c1 − r12 s1``. At the wrist
   singularity (|s5| < :data:`WRIST_TOLERANCE`, axes 4 and 6 parallel) only
   θ234 ± θ6 is determined (θ4 ± θ6 for a fixed forearm): θ6 is taken from the hint
   (the current joints) and θ2, θ3, θ4 follow from it.
4. θ234 from ``c234 s5 = r13 c1 + r23 s1``, ``s234 s5 = r33``, blended with the
   third row ``c234 = s6 r31 + c6 r32``, ``c5 s234 = c6 r31 − s6 r32`` (weights s5, c5²)
   so that it is exact at every θ5, including the wrist singularity.
5. The planar 2R problem of joints 2–3 for the frame-4 origin
   ``P4 = P5 − d5 y4`` (in the arm plane: ``h4 = A + d5 s234``,
   ``v4 = P5z − d1 − d5 c234``), then θ3 = ±acos(c3), θ2 and θ4 = θ234 − θ2 − θ3.

Slots
-----
Slot ``k = 4 i + 2 j + l`` always holds the same branch:

* ``i = 0`` takes θ1 with ``+acos`` (shoulder **left**, A ≤ 0), ``i = 1`` with
  ``−acos`` (shoulder **right**, A ≥ 0). Geometrically: facing from the base axis
  towards the wrist-2 point P5, the shoulder offset d4 carries the wrist to the right
  of the upper arm's plane (like a right arm reaching forward) or to its left (the
  arm turned round, reaching back over its shoulder).
* ``j = 0`` takes θ5 ≥ 0 (wrist **not flipped**), ``j = 1`` θ5 ≤ 0 (wrist
  **flipped**). θ5 is the angle from axis 4 to the tool axis z6 (``c5 = z4·z6``),
  positive towards x4 — the forearm's direction when θ4 = 0 — so a flipped wrist
  points the tool to the other side of the wrist-1 link.
* ``l = 0`` takes θ3 ≥ 0, ``l = 1`` θ3 ≤ 0. The label says where the elbow is:
  walking from the shoulder to the wrist in the direction the arm reaches, the elbow
  is **up** when the forearm turns downwards there (the elbow is a peak, above the
  shoulder–wrist-1 line) and **down** otherwise. With the shoulder right that is
  θ3 ≤ 0; with the shoulder left (arm reaching the other way) θ3 ≥ 0.

A branch that does not exist for a pose is ``valid = False`` (its angles NaN) and
never shifts the others.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, NamedTuple

import numpy as np

from . import _kernels
from ._validate import homogeneous_transform, joint_vector

if TYPE_CHECKING:
    from .arm import Arm

#: Distance (m) within which the shoulder and elbow count as exactly singular: the two
#: θ1 (or θ3) branches coincide and a pose that far outside the reach is clamped onto it.
LENGTH_TOLERANCE = 1e-9
#: |s5| below which the wrist counts as exactly singular and θ6 comes from the hint.
WRIST_TOLERANCE = 1e-9

#: Why a slot has no solution (``IKSolution.failure``).
REACHABLE = 0
WRIST_INSIDE_CYLINDER = 1  #: P5 closer than d4 to the base axis: no θ1 at all
ELBOW_TOO_FAR = 2  #: the frame-4 origin is beyond a2 + a3 from the shoulder
ELBOW_TOO_CLOSE = 3  #: the frame-4 origin is closer than |a2 - a3| to the shoulder

_PI = math.pi
_TAU = 2.0 * math.pi


class Slot(NamedTuple):
    """One of the eight fixed IK branches."""

    index: int
    shoulder: str  #: "left" (θ1 with +acos) or "right" (−acos)
    elbow: str  #: "up" or "down" (see the module docstring)
    wrist: str  #: "not flipped" (θ5 ≥ 0) or "flipped" (θ5 ≤ 0)
    theta5_sign: int  #: +1 for θ5 ≥ 0, −1 for θ5 ≤ 0
    theta3_sign: int  #: +1 for θ3 ≥ 0, −1 for θ3 ≤ 0

    @property
    def label(self) -> str:
        return f"shoulder {self.shoulder}, elbow {self.elbow}, wrist {self.wrist}"

    @property
    def short_label(self) -> str:
        """Three letters, e.g. ``"R U N"``: shoulder Left/Right, elbow Up/Down, wrist Not flipped/Flipped."""
        return f"{self.shoulder[0].upper()} {self.elbow[0].upper()} {'F' if self.wrist == 'flipped' else 'N'}"


def _make_slots() -> tuple[Slot, ...]:
    slots = []
    for i, shoulder in enumerate(("left", "right")):
        for j, wrist in enumerate(("not flipped", "flipped")):
            for l in range(2):
                theta3_sign = 1 if l == 0 else -1
                # Shoulder right: θ3 ≤ 0 is elbow up; shoulder left reaches the other way round.
                elbow_up = (theta3_sign < 0) if shoulder == "right" else (theta3_sign > 0)
                slots.append(
                    Slot(4 * i + 2 * j + l, shoulder, "up" if elbow_up else "down", wrist,
                         1 if j == 0 else -1, theta3_sign)
                )
    return tuple(slots)


#: The eight slots, indexed by ``k = 4 i + 2 j + l``.
SLOTS: tuple[Slot, ...] = _make_slots()
SLOT_LABELS: tuple[str, ...] = tuple(slot.label for slot in SLOTS)


class Branch(NamedTuple):
    """A branch picked by :func:`nearest_branch`."""

    q: np.ndarray  #: (..., 6) joint angles, each within π of the current one (NaN if none valid)
    slot: np.ndarray  #: (...,) int slot index, −1 where no slot is valid


@dataclass(eq=False, slots=True)
class IKSolution:
    """The eight IK branches of one or many poses (leading shape ``...``).

    Attributes
    ----------
    q : ndarray, shape (..., 8, 6)
        Joint angles in (−π, π]; NaN in invalid slots.
    valid : ndarray of bool, shape (..., 8)
    wrist_singular : ndarray of bool, shape (..., 8)
        |s5| < :data:`WRIST_TOLERANCE`: θ6 was taken from the hint, θ4 derived.
    elbow_singular : ndarray of bool, shape (..., 8)
        |c3| = 1 (stretched or folded): the two elbow slots coincide.
    shoulder_singular : ndarray of bool, shape (...)
        P5 at distance d4 from the base axis: the two shoulder slots coincide.
    failure : ndarray of int8, shape (..., 8)
        :data:`REACHABLE`, :data:`WRIST_INSIDE_CYLINDER`, :data:`ELBOW_TOO_FAR` or
        :data:`ELBOW_TOO_CLOSE`.
    wrist2_radius : ndarray, shape (...)
        ρ, the horizontal distance of the wrist-2 point P5 from the base axis (m).
    elbow_distance : ndarray, shape (..., 8)
        Distance from the shoulder to the frame-4 origin in the arm plane (m), the
        planar 2R reach; NaN where θ1 does not exist.
    arm : Arm
        The arm solved for (its lengths word :meth:`unreachable_reason`).
    """

    q: np.ndarray
    valid: np.ndarray
    wrist_singular: np.ndarray
    elbow_singular: np.ndarray
    shoulder_singular: np.ndarray
    failure: np.ndarray
    wrist2_radius: np.ndarray
    elbow_distance: np.ndarray
    arm: "Arm"

    labels: ClassVar[tuple[str, ...]] = SLOT_LABELS
    slots: ClassVar[tuple[Slot, ...]] = SLOTS

    @property
    def reachable(self) -> np.ndarray:
        """(...) bool: at least one slot is valid."""
        return self.valid.any(axis=-1)

    def nearest(self, q_current, joint_limit: float = _TAU, prefer=None) -> Branch:
        """The valid branch nearest ``q_current``; see :func:`nearest_branch`."""
        return nearest_branch(self, q_current, joint_limit, prefer)

    def unreachable_reason(self, index: tuple[int, ...] = ()) -> str:
        """Why the pose at ``index`` has no solution, with the numbers (mm); ``""`` if it has one."""
        valid = self.valid[index]
        if valid.any():
            return ""
        arm = self.arm
        failure = self.failure[index]
        if (failure == WRIST_INSIDE_CYLINDER).all():
            rho = float(self.wrist2_radius[index])
            return (
                f"unreachable: the wrist-2 point P5 is {1e3 * (arm.d4 - rho):.1f} mm inside the "
                f"shoulder cylinder (it is {1e3 * rho:.1f} mm from the base axis; it must be at "
                f"least d4 = {1e3 * arm.d4:.1f} mm)"
            )
        distance = self.elbow_distance[index]
        outer, inner = arm.a2 + arm.a3, abs(arm.a2 - arm.a3)
        excess = np.where(failure == ELBOW_TOO_FAR, distance - outer, inner - distance)
        if np.isnan(excess).all():  # coordinates so large that the distances overflowed
            return (
                f"unreachable: elbow reach — the target is too far away to measure "
                f"(the arm reaches a2 + a3 = {1e3 * outer:.1f} mm from the shoulder)"
            )
        k = int(np.nanargmin(excess))
        if failure[k] == ELBOW_TOO_FAR:
            return (
                f"unreachable: elbow reach — the wrist-1 centre would be {1e3 * distance[k]:.1f} mm "
                f"from the shoulder, {1e3 * excess[k]:.1f} mm beyond a2 + a3 = {1e3 * outer:.1f} mm"
            )
        return (
            f"unreachable: elbow reach — the wrist-1 centre would be {1e3 * distance[k]:.1f} mm "
            f"from the shoulder, {1e3 * excess[k]:.1f} mm closer than |a2 − a3| = {1e3 * inner:.1f} mm"
        )


#: Squared joint distances (rad²) closer than this count as a tie in :func:`nearest_branch`.
TIE_TOLERANCE = 1e-10


def nearest_branch(solution: IKSolution, q_current, joint_limit: float = _TAU, prefer=None) -> Branch:
    """The valid branch nearest the current joints, shifted next to them.

    Each joint of each valid slot is replaced by the 2π-equivalent nearest the current
    angle that stays within ``±joint_limit`` (the UR10's ±360° by default); the slot
    with the smallest Euclidean joint-space distance wins. At the wrist singularity the
    solver already took θ6 from its hint, so passing the current joints as the hint
    keeps θ6 where it was.

    Parameters
    ----------
    solution : IKSolution
        Result of :meth:`Arm.ik`, leading shape ``...``.
    q_current : array_like, shape (..., 6)
        The current joint angles (radians).
    joint_limit : float
        Each returned angle stays within ±joint_limit (radians).
    prefer : int or array of int, shape (...), optional
        A slot to keep when it ties with the nearest (at a singularity two slots
        coincide): an app showing "the arm is on branch k" then does not flip labels.

    Returns
    -------
    Branch
        ``q`` (..., 6) and ``slot`` (...); where no slot is valid, ``q`` is NaN and
        ``slot`` is −1.

    Example
    -------
    >>> from ur10core import Arm
    >>> arm = Arm.preset("course")
    >>> q = np.radians([30, 45, 26, 50, 60, -280])  # the course lists θ6 = −280°, i.e. 80°
    >>> branch = arm.ik(arm.fk(q)).nearest(q)
    >>> np.degrees(branch.q).round(6).tolist(), int(branch.slot)
    ([30.0, 45.0, 26.0, 50.0, 60.0, -280.0], 4)
    """
    q_current = joint_vector(q_current, "q_current")
    if solution.q.shape == (8, 6) and q_current.shape == (6,) and (prefer is None or np.ndim(prefer) == 0):
        return _nearest_one(solution, q_current, joint_limit, prefer)
    current = np.expand_dims(q_current, -2)  # (..., 1, 6)
    with np.errstate(invalid="ignore"):
        shifted = equivalent_near(solution.q, current, joint_limit)
        distance = np.where(solution.valid, ((shifted - current) ** 2).sum(axis=-1), np.inf)
    slot = np.argmin(distance, axis=-1)
    flat_distance = distance.reshape(-1, 8)
    rows = np.arange(len(flat_distance))
    if prefer is not None:
        prefer = np.broadcast_to(np.asarray(prefer), slot.shape).reshape(-1)
        candidate = np.clip(prefer, 0, 7)
        tie = (prefer == candidate) & (flat_distance[rows, candidate] <= flat_distance[rows, slot.reshape(-1)] + TIE_TOLERANCE)
        slot = np.where(tie, candidate, slot.reshape(-1)).reshape(slot.shape)
    any_valid = solution.valid.any(axis=-1)
    best = shifted.reshape(-1, 8, 6)[rows, slot.reshape(-1)].reshape(slot.shape + (6,))
    best = np.where(any_valid[..., None], best, np.nan)
    return Branch(best, np.where(any_valid, slot, -1))


def _nearest_one(solution: IKSolution, q_current: np.ndarray, joint_limit: float, prefer) -> Branch:
    """:func:`nearest_branch` for one pose, in the compiled kernel (the app calls it on every drag event)."""
    preferred = int(prefer) if prefer is not None and 0 <= int(prefer) < 8 else -1
    slot, q = _kernels.nearest_one(
        np.ascontiguousarray(solution.q, dtype=float), np.ascontiguousarray(solution.valid, dtype=bool),
        np.ascontiguousarray(q_current, dtype=float), float(joint_limit), preferred, TIE_TOLERANCE,
    )
    return Branch(q, np.array(slot))


def equivalent_near(q, q_current, joint_limit: float = _TAU) -> np.ndarray:
    """Each angle of ``q`` replaced by its 2π-equivalent nearest ``q_current``, kept within ±joint_limit.

    Shapes broadcast; where the nearest equivalent would leave the joint range the one a
    turn back is taken instead. Used by :func:`nearest_branch` and wherever a branch is
    applied to an arm that has turned some joints past ±180°.

    >>> np.degrees(equivalent_near(np.radians([170.0, -10.0]), np.radians([-170.0, 350.0]))).round(6).tolist()
    [-190.0, 350.0]
    """
    q = np.asarray(q, dtype=float)
    shifted = q + _TAU * np.round((q_current - q) / _TAU)
    shifted = np.where(shifted > joint_limit, shifted - _TAU, shifted)
    return np.where(shifted < -joint_limit, shifted + _TAU, shifted)


# --------------------------------------------------------------------------- reference


def _wrap(angle: float) -> float:
    """Into (−π, π]."""
    angle = math.remainder(angle, _TAU)
    return angle + _TAU if angle <= -_PI else angle


def solve_reference(arm: "Arm", T, theta6_hint: float = 0.0) -> IKSolution:
    """The course's IK of one pose, step by step in plain Python (COURSE_NOTES §4).

    This is the readable statement of the method; the compiled kernel
    (``ur10core/_kernels.c``) that :meth:`Arm.ik` runs is a line-for-line port of it,
    and the tests hold the two to each other. Same arguments and result as
    :meth:`Arm.ik` for a single pose.
    """
    T = homogeneous_transform(T)
    if T.shape != (4, 4):
        raise ValueError(f"solve_reference takes one pose of shape (4, 4), got {T.shape}")
    (r11, r12, r13, px), (r21, r22, r23, py), (r31, r32, r33, pz), _ = T.tolist()
    d1, a2, a3, d4, d5, d6 = arm.d1, arm.a2, arm.a3, arm.d4, arm.d5, arm.d6
    sqrt, atan2, hypot = math.sqrt, math.atan2, math.hypot
    nan = math.nan

    # Step 1: the wrist-2 point P5 = p − d6 z6 and its distance ρ from the base axis.
    p5x, p5y, p5z = px - d6 * r13, py - d6 * r23, pz - d6 * r33
    rho2 = p5x * p5x + p5y * p5y
    rho = sqrt(rho2)
    values = [nan] * 48
    elbow_distance = [nan] * 8
    wrist_singular = [False] * 8
    elbow_singular = [False] * 8
    failure = [WRIST_INSIDE_CYLINDER] * 8
    shoulder_singular = abs(rho - d4) <= LENGTH_TOLERANCE
    if rho >= d4 - LENGTH_TOLERANCE:
        reach = sqrt(max(rho2 - d4 * d4, 0.0))
        outer, inner = a2 + a3, abs(a2 - a3)
        a2a3x2, a2sq_a3sq = 2.0 * a2 * a3, a2 * a2 + a3 * a3
        theta6_hint = _wrap(theta6_hint)
        c6_hint, s6_hint = math.cos(theta6_hint), math.sin(theta6_hint)
        for i, A in ((0, -reach), (1, reach)):  # A: signed reach of P5 along x1
            c1 = (p5x * A - p5y * d4) / rho2
            s1 = (p5y * A + p5x * d4) / rho2
            theta1 = _wrap(atan2(s1, c1))
            # Step 2: c5 = z4·z6; |s5| from the row pair of step 3.
            c5 = r13 * s1 - r23 * c1
            c6s5 = r21 * c1 - r11 * s1
            s6s5 = r12 * s1 - r22 * c1
            s5_abs = hypot(c6s5, s6s5)
            c234s5 = r13 * c1 + r23 * s1
            singular_wrist = s5_abs < WRIST_TOLERANCE
            for j, sign in ((0, 1.0), (1, -1.0)):
                s5 = sign * s5_abs
                theta5 = _wrap(atan2(s5, c5))
                if singular_wrist:  # only θ234 ± θ6 is determined: keep the hint's θ6
                    c6, s6, theta6 = c6_hint, s6_hint, theta6_hint
                else:  # Step 3
                    c6, s6 = sign * c6s5 / s5_abs, sign * s6s5 / s5_abs
                    theta6 = _wrap(atan2(s6, c6))
                # Step 4, blended with the third row so that it holds at every θ5.
                c234 = s5 * c234s5 + c5 * c5 * (s6 * r31 + c6 * r32)
                s234 = s5 * r33 + c5 * (c6 * r31 - s6 * r32)
                norm = hypot(c234, s234)
                c234, s234 = c234 / norm, s234 / norm
                theta234 = atan2(s234, c234)
                # Step 5: the planar 2R problem for the frame-4 origin.
                h4 = A + d5 * s234
                v4 = p5z - d1 - d5 * c234
                r = hypot(h4, v4)
                base = 4 * i + 2 * j
                elbow_distance[base] = elbow_distance[base + 1] = r
                if not r <= outer + LENGTH_TOLERANCE:  # NaN too: a target so far that r overflowed
                    failure[base] = failure[base + 1] = ELBOW_TOO_FAR
                    continue
                if r < inner - LENGTH_TOLERANCE:
                    failure[base] = failure[base + 1] = ELBOW_TOO_CLOSE
                    continue
                failure[base] = failure[base + 1] = REACHABLE
                wrist_singular[base] = wrist_singular[base + 1] = singular_wrist
                elbow_singular[base] = elbow_singular[base + 1] = (
                    r >= outer - LENGTH_TOLERANCE or r <= inner + LENGTH_TOLERANCE
                )
                c3 = min(1.0, max(-1.0, (r * r - a2sq_a3sq) / a2a3x2))
                s3 = sqrt(1.0 - c3 * c3)
                theta3 = atan2(s3, c3)
                beta = atan2(v4, h4)
                gamma = atan2(a3 * s3, a2 + a3 * c3)
                for l, (t3, t2) in enumerate(((theta3, beta - gamma), (-theta3, beta + gamma))):
                    t3, t2 = _wrap(t3), _wrap(t2)
                    offset = 6 * (base + l)
                    values[offset : offset + 6] = (
                        theta1, t2, t3, _wrap(theta234 - t2 - t3), theta5, theta6,
                    )
    valid = [code == REACHABLE for code in failure]
    flags = np.array(valid + wrist_singular + elbow_singular + [shoulder_singular])
    floats = np.array(values + elbow_distance + [rho])
    return IKSolution(
        q=floats[:48].reshape(8, 6),
        valid=flags[:8],
        wrist_singular=flags[8:16],
        elbow_singular=flags[16:24],
        shoulder_singular=flags[24:].reshape(()),
        failure=np.array(failure, dtype=np.int8),
        wrist2_radius=floats[56:].reshape(()),
        elbow_distance=floats[48:56],
        arm=arm,
    )


# --------------------------------------------------------------------------- compiled path

#: Poses per task that :func:`solve_batch` hands to the thread pool.
BLOCK = 16384
_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=os.cpu_count() or 1, thread_name_prefix="ur10core")
    return _POOL


def solve_one(arm: "Arm", T: np.ndarray, theta6_hint: float) -> IKSolution | None:
    """The compiled kernel on one C-contiguous float64 (4, 4) pose; ``None`` if ``T`` is not a valid pose."""
    result = _kernels.ik_one(T, theta6_hint, arm.dh_lengths)
    if result is None:
        return None
    q, valid, wrist, elbow, shoulder, failure, rho, distance = result
    return IKSolution(q, valid, wrist, elbow, shoulder, failure, rho, distance, arm)


def solve_batch(arm: "Arm", T: np.ndarray, theta6_hint: np.ndarray) -> IKSolution | int:
    """The compiled kernel on poses ``T`` (..., 4, 4), ``theta6_hint`` broadcast to (...).

    Blocks of :data:`BLOCK` poses run on a thread pool; the kernel releases the GIL.
    Returns the flat index of the first pose that is not a valid transform instead of a
    result, so that the caller can word the error.
    """
    shape = T.shape[:-2]
    flat = np.ascontiguousarray(T, dtype=float).reshape(-1, 16)
    n = flat.shape[0]
    hint = np.ascontiguousarray(np.broadcast_to(theta6_hint, shape), dtype=float).reshape(-1)
    q = np.empty((n, 8, 6))
    valid = np.empty((n, 8), dtype=bool)
    wrist = np.empty((n, 8), dtype=bool)
    elbow = np.empty((n, 8), dtype=bool)
    shoulder = np.empty(n, dtype=bool)
    failure = np.empty((n, 8), dtype=np.int8)
    rho = np.empty(n)
    distance = np.empty((n, 8))
    outputs = (q, valid, wrist, elbow, shoulder, failure, rho, distance)

    def run(start: int) -> int:
        block = slice(start, min(start + BLOCK, n))
        bad = _kernels.ik_batch(flat[block], hint[block], arm.dh_lengths, *(out[block] for out in outputs))
        return -1 if bad < 0 else start + bad

    starts = range(0, n, BLOCK)
    bad = [run(0)] if n <= BLOCK else list(_pool().map(run, starts))
    invalid = [index for index in bad if index >= 0]
    if invalid:
        return min(invalid)
    return IKSolution(
        q.reshape(shape + (8, 6)),
        valid.reshape(shape + (8,)),
        wrist.reshape(shape + (8,)),
        elbow.reshape(shape + (8,)),
        shoulder.reshape(shape),
        failure.reshape(shape + (8,)),
        rho.reshape(shape),
        distance.reshape(shape + (8,)),
        arm,
    )

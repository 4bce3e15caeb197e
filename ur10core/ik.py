"""All-eight-branch analytic inverse kinematics (docs/kinematics.md §4).

The method is the course's separation of variables, written so that every branch is
computed from a handful of ``atan2`` and square roots, with no sine or cosine of an
intermediate angle (they are formed algebraically instead). Its readable statement is
:func:`ur10core.ik_reference.solve_pose`; this module holds the slots, the result type,
the nearest-branch pick and the dispatch to the backend (compiled or numpy).

1. θ1 from ``(py − d6 r23) c1 + (d6 r13 − px) s1 = −d4``. With the wrist-2 point
   ``P5 = p − d6 z6`` at horizontal distance ρ from the base axis and
   ``A = ±sqrt(ρ² − d4²)`` (its reach along the arm's forward axis x1),
   ``c1 = (P5x A − P5y d4)/ρ²`` and ``s1 = (P5y A + P5x d4)/ρ²``; ``A ≤ 0`` is the
   course's ``θ1 = atan2(P5y, P5x) + π/2 + acos(d4/ρ)``, ``A ≥ 0`` the ``−acos``.
2. θ5 = ±acos(r13 s1 − r23 c1), taken as ``atan2(±|s5|, c5)`` with
   ``|s5| = |(r21 c1 − r11 s1, r12 s1 − r22 c1)|`` so it stays accurate near s5 = 0.
3. θ6 from ``s5 c6 = r21 c1 − r11 s1`` and ``−s5 s6 = r22 c1 − r12 s1``. Near the wrist
   singularity (axes 4 and 6 parallel) the pose fixes only θ234 ± θ6: the hint's θ6 is
   kept wherever it reproduces the pose within ``WRIST_TURN_TOLERANCE`` (always at
   s5 = 0), and where a θ6 leaves the elbow out of reach the feasible θ6 nearest it is
   taken, in closed form (docs/kinematics.md §4.3).
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
from typing import TYPE_CHECKING, Callable, NamedTuple

import numpy as np

from . import _numpy_kernels, ik_reference
from ._backend import kernels
from ._validate import as_float_array, homogeneous_transform, joint_vector, within_reason
from .branches import Branch, IKSolution
from .ik_reference import ELBOW_TOO_CLOSE, ELBOW_TOO_FAR, REACHABLE, WRIST_INSIDE_CYLINDER
from .tolerances import LENGTH_TOLERANCE, TIE_TOLERANCE, WRIST_TOLERANCE, WRIST_TURN_TOLERANCE

if TYPE_CHECKING:
    from .arm import Arm

__all__ = [
    "ELBOW_TOO_CLOSE", "ELBOW_TOO_FAR", "LENGTH_TOLERANCE", "REACHABLE", "WRIST_INSIDE_CYLINDER",
    "WRIST_TOLERANCE", "WRIST_TURN_TOLERANCE", "Branch", "IKSolution", "SLOTS", "SLOT_LABELS", "Slot",
    "equivalent_near", "nearest_branch", "solve_reference",
]

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
        A UR-family arm's result of :meth:`Arm.ik`, leading shape ``...`` (8 slots of 6 joints).
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
    q_current = within_reason(joint_vector(q_current, "q_current"), "q_current")
    joint_limit = _joint_limit(joint_limit)
    prefer = _preferred_slot(prefer)
    if solution.q.shape == (8, 6) and q_current.shape == (6,) and type(prefer) is int:
        slot, q = kernels.nearest_one(
            np.ascontiguousarray(solution.q, dtype=float), np.ascontiguousarray(solution.valid, dtype=bool),
            np.ascontiguousarray(q_current), joint_limit, prefer, TIE_TOLERANCE,
        )
        return Branch(q, np.array(slot))
    current = np.expand_dims(q_current, -2)  # (..., 1, 6)
    shifted = _numpy_kernels.shift_near(solution.q, current, joint_limit)
    with np.errstate(invalid="ignore"):
        distance = np.where(solution.valid, ((shifted - current) ** 2).sum(axis=-1), np.inf)
    slot = np.argmin(distance, axis=-1)
    flat_distance = distance.reshape(-1, 8)
    rows = np.arange(len(flat_distance))
    try:
        prefer = np.broadcast_to(prefer, slot.shape).reshape(-1)
    except ValueError:
        raise ValueError(f"prefer of shape {np.shape(prefer)} does not broadcast against poses of shape {slot.shape}") from None
    candidate = np.maximum(prefer, 0)
    tie = (prefer >= 0) & (flat_distance[rows, candidate] <= flat_distance[rows, slot.reshape(-1)] + TIE_TOLERANCE)
    slot = np.where(tie, candidate, slot.reshape(-1)).reshape(slot.shape)
    any_valid = solution.valid.any(axis=-1)
    best = shifted.reshape(-1, 8, 6)[rows, slot.reshape(-1)].reshape(slot.shape + (6,))
    best = np.where(any_valid[..., None], best, np.nan)
    return Branch(best, np.where(any_valid, slot, -1))


def _joint_limit(joint_limit) -> float:
    """``joint_limit`` (radians, ≥ π so that every angle has a turn within ±joint_limit; inf: no limit)."""
    if type(joint_limit) is float and _PI <= joint_limit:
        return joint_limit
    if isinstance(joint_limit, bool) or not isinstance(joint_limit, (int, float, np.integer, np.floating)):
        raise ValueError(f"joint_limit must be a number of radians, got {joint_limit!r:.60}")
    if not _PI <= joint_limit:  # NaN too
        raise ValueError(f"joint_limit must be at least π (every angle then has a turn within ±joint_limit), got {joint_limit!r}")
    return float(joint_limit)


def _preferred_slot(prefer, slots: int = 8) -> int | np.ndarray:
    """``prefer`` as an int (or int array) with values −1 (none) or 0..slots−1; ValueError otherwise."""
    if prefer is None:
        return -1
    if type(prefer) is int and -1 <= prefer < slots:  # the app's one-pose call, without numpy's overhead
        return prefer
    value = np.asarray(prefer)
    if value.dtype == bool or not np.issubdtype(value.dtype, np.integer):
        raise ValueError(f"prefer must be a slot number 0..{slots - 1} (or −1 for none), got {prefer!r:.60}")
    if ((value < -1) | (value >= slots)).any():
        raise ValueError(f"prefer must be a slot number 0..{slots - 1} (or −1 for none), got {prefer!r:.60}")
    return int(value) if value.ndim == 0 else value.astype(np.intp)


def equivalent_near(q, q_current, joint_limit: float = _TAU) -> np.ndarray:
    """Each angle of ``q`` replaced by its 2π-equivalent nearest ``q_current``, kept within ±joint_limit.

    Shapes broadcast. Where the nearest equivalent would leave the joint range, it is
    moved by whole turns back into it (``joint_limit ≥ π``, so there always is one).
    Used by :func:`nearest_branch` and wherever a branch is applied to an arm that has
    turned some joints past ±180°.

    >>> np.degrees(equivalent_near(np.radians([170.0, -10.0]), np.radians([-170.0, 350.0]))).round(6).tolist()
    [-190.0, 350.0]
    >>> round(float(np.degrees(equivalent_near(np.radians(10.0), 20.0))), 9)  # 20 rad is beyond ±360°
    10.0
    """
    return _numpy_kernels.shift_near(as_float_array(q, "q"), as_float_array(q_current, "q_current"), _joint_limit(joint_limit))


# --------------------------------------------------------------------------- solving


def solve_reference(arm: "Arm", T, hint=None) -> IKSolution:
    """The IK of one pose by :func:`ur10core.ik_reference.solve_pose`, in plain Python.

    The readable statement of the method, whatever the backend; same arguments and
    result as :meth:`Arm.ik` for a single pose.
    """
    T = homogeneous_transform(T)
    if T.shape != (4, 4):
        raise ValueError(f"solve_reference takes one pose of shape (4, 4), got {T.shape}")
    hint = None if hint is None else joint_vector(hint, "hint")
    if hint is not None and hint.shape != (6,):
        raise ValueError(f"solve_reference takes one hint of shape (6,), got {hint.shape}")
    lengths = arm.solver.dh_lengths
    hints = ik_reference.hint_values(None if hint is None else hint.tolist(), lengths)
    q, valid, wrist, elbow, shoulder, failure, rho, distance = ik_reference.solve_pose(T.tolist(), *hints, lengths)
    return _solution(arm, np.array(q).reshape(8, 6), np.array(valid), np.array(wrist), np.array(elbow), np.array(shoulder),
                     np.array(failure, dtype=np.int8), np.array(rho), np.array(distance))


#: What the kernels add to the one result type (``IKSolution.extra``), by name.
EXTRA_NAMES = ("wrist_singular", "elbow_singular", "shoulder_singular", "wrist2_radius", "elbow_distance")


def _solution(arm: "Arm", q, valid, wrist, elbow, shoulder, failure, rho, distance) -> IKSolution:
    """The kernels' arrays as the one result type (:data:`EXTRA_NAMES`); a UR arm's slots are all within its ±360°."""
    return IKSolution(q, valid, failure, arm, None, None, valid, (wrist, elbow, shoulder, rho, distance))


#: Poses per task that :func:`solve_batch` hands to the thread pool.
BLOCK = 16384
_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=os.cpu_count() or 1, thread_name_prefix="ur10core")
    return _POOL


def in_blocks(n: int, run: Callable[[int], int]) -> int:
    """``run(start)`` for the blocks of :data:`BLOCK` of ``n`` poses, on the pool when there are several.

    ``run`` returns the index of the first invalid pose of its block, or −1; so does this.
    """
    bad = [run(0)] if n <= BLOCK else list(_pool().map(run, range(0, n, BLOCK)))
    invalid = [index for index in bad if index >= 0]
    return min(invalid) if invalid else -1


def solve_one(arm: "Arm", T: np.ndarray, hints: tuple[float, float, float]) -> IKSolution | None:
    """The backend on one C-contiguous float64 (4, 4) pose; ``None`` if ``T`` is not a valid pose.

    ``hints`` are :func:`ur10core.ik_reference.hint_values`.
    """
    result = kernels.ik_one(T, *hints, arm.solver.dh_lengths)
    if result is None:
        return None
    return _solution(arm, *result)


def solve_batch(arm: "Arm", T: np.ndarray, hints: np.ndarray) -> IKSolution | int:
    """The backend on poses ``T`` (..., 4, 4); ``hints`` (..., 3) are (θ6, A, θ3), broadcast.

    Blocks of :data:`BLOCK` poses run on a thread pool (the compiled kernel releases the
    GIL, as numpy does inside its loops). Returns the flat index of the first pose that
    is not a valid transform instead of a result, so that the caller can word the error.
    """
    shape = T.shape[:-2]
    flat = np.ascontiguousarray(T, dtype=float).reshape(-1, 16)
    n = flat.shape[0]
    theta6_hint, reach_hint, theta3_hint = (
        np.ascontiguousarray(np.broadcast_to(hints[..., k], shape), dtype=float).reshape(-1) for k in range(3)
    )
    lengths = arm.solver.dh_lengths
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
        bad = kernels.ik_batch(
            flat[block], theta6_hint[block], reach_hint[block], theta3_hint[block], lengths,
            *(out[block] for out in outputs),
        )
        return -1 if bad < 0 else start + bad

    bad = in_blocks(n, run)
    if bad >= 0:
        return bad
    return _solution(arm, q.reshape(shape + (8, 6)), valid.reshape(shape + (8,)), wrist.reshape(shape + (8,)),
                     elbow.reshape(shape + (8,)), shoulder.reshape(shape), failure.reshape(shape + (8,)),
                     rho.reshape(shape), distance.reshape(shape + (8,)))

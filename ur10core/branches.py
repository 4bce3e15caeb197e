"""The one IK result of every arm: each branch in a fixed, labelled slot (docs/kinematics.md §4, §7.3).

Whatever solved it (the UR family's kernels, Pieper's decoupling, a planar closed form,
the desktop arm's, or the numerical search of a typed table), :meth:`ur10core.Arm.ik`
returns an :class:`IKSolution`: the same slots for the same arm, valid flags, why an empty
slot is empty (one set of failure codes), and one :meth:`IKSolution.nearest`.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ._validate import within_reason
from .tolerances import LIMIT_TOLERANCE

if TYPE_CHECKING:
    from .arm import Arm

#: Why a slot is empty (``IKSolution.failure``); ``detail`` holds the number behind it.
REACHED = 0
INSIDE_OFFSET = 1  #: detail: the point's distance from the base axis (m), below the shoulder offset
TOO_FAR = 2  #: detail: the distance the arm would have to span (m)
TOO_CLOSE = 3  #: detail: the same, below the shortest span
ORIENTATION = 4  #: detail: the angle (rad) between the tool axis asked for and the one the arm can have
OUT_OF_PLANE = 5  #: detail: the distance (m) from the plane the arm moves in
NOT_FOUND = 6  #: detail: the smallest pose error the numerical solver reached

_TAU = 2.0 * math.pi


def mm_apart(length: float, bound: float) -> tuple[str, str, str]:
    """``length`` and ``bound`` (m) in mm and how far apart they are, with as many decimals (1 to 4) as it takes to
    tell them apart: a pose typed from a readout rounded to 0.1 mm can lie 11 µm beyond the reach, and "1184.5 mm,
    0.0 mm beyond 1184.5 mm" read as a fault.

    A length of a million metres or more has four figures and a power of ten: a target typed 1e300 m out read as
    300 digits.

    >>> mm_apart(1.1845109, 1.1845), mm_apart(2.0, 1.5), mm_apart(1e300, 0.6)
    (('1184.511', '1184.500', '0.011'), ('2000.0', '1500.0', '500.0'), ('1e+303', '600.0', '1e+303'))
    """
    gap = abs(1000.0 * (length - bound))
    decimals = 1 if not gap or not math.isfinite(gap) or gap >= 0.05 else min(4, math.ceil(-math.log10(gap)) + 1)
    return tuple(f"{1000.0 * value:.4g}" if abs(value) >= 1e6 else f"{1000.0 * value:.{decimals}f}"
                 for value in (length, bound, abs(length - bound)))


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in (−π, π]."""
    return -np.remainder(-np.asarray(angle) + math.pi, _TAU) + math.pi


def wrap_revolute(values: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """``values`` (..., n) with those of the revolute joints (``revolute``, bool, broadcast against them) in (−π, π]:
    a difference of joints as the shorter way round for a turning joint, as it is for a sliding one."""
    return np.where(revolute, wrap(values), values)


class Branch(NamedTuple):
    """The branch :meth:`IKSolution.nearest` picks."""

    q: np.ndarray  #: (..., n) joint values, revolute ones turned next to the current ones (NaN if none valid)
    slot: np.ndarray  #: (...,) int slot index, −1 where no slot is valid


class IKSolution:
    """The IK branches of one or many poses (leading shape ``...``): k slots of n joints.

    Attributes
    ----------
    q : ndarray, shape (..., k, n)
        Joint values (radians in (−π, π] for revolute joints, metres for prismatic ones);
        NaN in invalid slots.
    valid : ndarray of bool, shape (..., k)
        The slot reaches the pose (every component the arm controls, see :attr:`task`).
    within_limits : ndarray of bool, shape (..., k)
        Valid and inside every joint limit. A valid slot beyond a limit stays valid.
    singular : ndarray of bool, shape (..., k)
        A joint value was chosen, not computed (the pose does not fix it: a wrist with
        axes 4 and 6 aligned, a wrist centre on axis 1, two slots that coincide); the hint's
        value is kept there. Also where the pose fixes a joint less well than the limits'
        tolerance (the Stanford arm's θ2 over a stroke of µm, a wrist's θ4 with θ5 within
        about 1e-8 rad of 0), or the hint's value was kept where the pose fixes the joint only
        loosely: such a slot is searched and settled within the limits (:meth:`Arm.ik`).
    failure, detail : ndarray, shape (..., k)
        Why a slot is empty (:data:`TOO_FAR`, ...) and the number behind it.
    labels : tuple of str
        What each slot is, e.g. ``"shoulder right, elbow down, wrist not flipped"``.
    method : str
        ``"analytic"`` or ``"found numerically"``.
    task : str
        What of the pose the arm controls: ``"pose"``, ``"position and yaw"`` or ``"position"``.
    arm : Arm
        The arm solved for.

    A family may add its own numbers (``extra``, named by its solver's ``extra_names``), read
    as attributes: the UR family's ``wrist_singular``, ``elbow_singular``, ``shoulder_singular``,
    ``wrist2_radius`` and ``elbow_distance`` (:mod:`ur10core.ik`). ``detail``, ``singular``
    and ``within_limits`` are then worked out from them when first read, which keeps the
    UR10's one-pose call as fast as it was.
    """

    __slots__ = ("q", "valid", "failure", "arm", "extra", "_detail", "_singular", "_within_limits")

    def __init__(self, q, valid, failure, arm: "Arm", detail=None, singular=None, within_limits=None,
                 extra: tuple = ()) -> None:
        self.q, self.valid, self.failure, self.arm = q, valid, failure, arm
        self._detail, self._singular, self._within_limits = detail, singular, within_limits
        self.extra = extra

    def __getattr__(self, name: str):
        if not name.startswith("_"):
            names = getattr(self.arm.solver, "extra_names", ())
            if name in names:
                return self.extra[names.index(name)]
        raise AttributeError(f"IKSolution has no attribute {name!r}")

    def __repr__(self) -> str:
        return f"IKSolution({self.arm.name!r}, poses {self.valid.shape[:-1]}, {len(self.labels)} slots)"

    # ------------------------------------------------------------------ what the family says

    @property
    def labels(self) -> tuple[str, ...]:
        return self.arm.solver.labels

    @property
    def method(self) -> str:
        return getattr(self.arm.solver, "method", "analytic")

    @property
    def task(self) -> str:
        return self.arm.task

    @property
    def detail(self) -> np.ndarray:
        if self._detail is None:
            self._detail = self.arm.solver.derived(self, "detail")
        return self._detail

    @property
    def singular(self) -> np.ndarray:
        if self._singular is None:
            self._singular = self.arm.solver.derived(self, "singular")
        return self._singular

    @property
    def within_limits(self) -> np.ndarray:
        if self._within_limits is None:
            self._within_limits = self.valid & self.arm.within_limits(np.where(self.valid[..., None], self.q, 0.0))
        return self._within_limits

    # ------------------------------------------------------------------ reading it

    @property
    def reachable(self) -> np.ndarray:
        """(...) bool: at least one slot is valid."""
        return self.valid.any(axis=-1)

    def unreachable_reason(self, index: tuple[int, ...] = ()) -> str:
        """Why the pose at ``index`` has no branch, with the numbers; ``""`` if it has one."""
        if self.valid[index].any():
            return ""
        words = getattr(self.arm.solver, "unreachable_reason", None)
        if words is not None:  # a family with more to say than a failure code and its number
            return words(self, index)
        failure, detail = self.failure[index], self.detail[index]
        order = np.argsort(np.where(failure > 0, detail, np.inf), kind="stable")  # the slot that came nearest says most
        reasons = dict.fromkeys(self.arm.solver.explain(int(failure[k]), float(detail[k])) for k in order if failure[k])
        return "; ".join(reasons) or "no branch reaches this pose"

    def nearest(self, q_current, joint_limit: float | None = None, prefer=None, within_limits: bool = False) -> Branch:
        """The valid branch nearest the current joints ``q_current`` (..., n), turned next to them.

        Each revolute joint of each valid slot is replaced by the whole-turn equivalent nearest
        the current value that stays within the arm's limits (for the UR family, ``joint_limit``
        may set another ±limit than its ±360°); the slot with the smallest Euclidean joint-space distance
        wins. ``prefer`` (int or (...) ints, −1 for none) is a slot kept when it ties with the
        nearest, so that an app showing "the arm is on branch k" does not flip at a singularity.
        ``within_limits``: only the slots inside every joint limit, the ones a real arm can take.
        Where no slot is valid, ``q`` is NaN and ``slot`` −1.

        >>> from ur10core import Arm
        >>> arm = Arm.preset("scara")
        >>> q = np.array([0.3, -0.9, 0.1, 0.4])
        >>> branch = arm.ik(arm.fk(q)).nearest(q)
        >>> int(branch.slot), np.allclose(branch.q, q)
        (1, True)
        >>> stanford = Arm.preset("stanford")   # the wrist centre 1 mm behind the shoulder: d3 = -1 mm is nearest
        >>> near = np.array([0.3, 0.8, -0.001, 0.2, 0.5, 0.1])
        >>> solution = stanford.ik(stanford.fk(near))
        >>> [round(1000 * float(solution.nearest(near, within_limits=only).q[2])) for only in (False, True)]
        [-1, 1]
        """
        limit = getattr(self.arm.solver, "turn_limit", None)
        if limit is not None:  # symmetric ±limit on every joint: the UR family's kernels (every slot is inside it)
            return _ik().nearest_branch(self, q_current, limit if joint_limit is None else joint_limit, prefer)
        if joint_limit is not None:
            raise ValueError(f"joint_limit is the UR family's (±360° on every joint); the {self.arm.name!r} arm's "
                             "joints turn within its own limits")
        branch = _nearest_within_limits(self, q_current, prefer)
        if not within_limits:
            return branch
        # one pose whose nearest branch is inside them (a drag, mostly) needs no check of every slot
        if not (self.q.ndim == 2 and (branch.slot < 0 or _inside(branch.q, self.arm.limits))):
            inside = self.valid & self.within_limits
            branch = IKSolution(self.q, inside, self.failure, self.arm, within_limits=inside, extra=self.extra).nearest(
                q_current, prefer=prefer)
        # a value a rounding beyond a limit (a pose on it) is the limit, so that a slider takes it
        return Branch(np.minimum(np.maximum(branch.q, self.arm.limits[:, 0]), self.arm.limits[:, 1]), branch.slot)


    def take(self, slot: int, q_current) -> np.ndarray:
        """(n,) slot ``slot`` of one pose, each revolute joint turned next to ``q_current`` as :meth:`nearest` turns it.

        Raises ``ValueError`` if the slot does not reach the pose.

        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> q = np.array([0.1, -1.2, 1.0, -0.4, 1.1, 0.3])
        >>> solution = arm.ik(arm.fk(q), hint=q)
        >>> turned = q - [0, 0, 0, 0, 0, 2 * np.pi]  # wrist 3 a whole turn back: the slot follows it
        >>> np.allclose(solution.take(int(solution.nearest(q).slot), turned), turned)
        True
        """
        if self.valid.ndim != 1 or not 0 <= slot < len(self.labels):
            raise ValueError(f"take: one pose's slot 0..{len(self.labels) - 1} is needed, got {slot!r}")
        if not self.valid[slot]:
            raise ValueError(f"slot {slot} ({self.labels[slot]}) does not reach the pose")
        only = np.zeros_like(self.valid)
        only[slot] = True
        return IKSolution(self.q, only, self.failure, self.arm, extra=self.extra).nearest(q_current).q


@functools.cache
def _ik():
    from . import ik  # it imports this module

    return ik


def _nearest_within_limits(solution: IKSolution, q_current, prefer) -> Branch:
    from .ik import _preferred_slot
    from .tolerances import TIE_TOLERANCE

    arm = solution.arm
    q_current = within_reason(arm.joints(q_current, "q_current"), "q_current")
    prefer = _preferred_slot(prefer, len(solution.labels))
    low, high = arm.limits[:, 0], arm.limits[:, 1]
    if solution.q.ndim == 2 and type(prefer) is int:  # one pose (the drag path): a dozen floats, not numpy calls
        return _nearest_one(solution, q_current.tolist(), prefer, (low - LIMIT_TOLERANCE).tolist(),
                            (high + LIMIT_TOLERANCE).tolist(), TIE_TOLERANCE)
    current = q_current[..., None, :]
    turns = np.round((current - solution.q) / _TAU)
    shifted = solution.q + turns * _TAU
    # back inside the limits by a whole turn where the nearest turn leaves them (and a turn fits)
    low, high = low - LIMIT_TOLERANCE, high + LIMIT_TOLERANCE
    shifted = np.where((shifted < low) & (shifted + _TAU <= high), shifted + _TAU, shifted)
    shifted = np.where((shifted > high) & (shifted - _TAU >= low), shifted - _TAU, shifted)
    shifted = np.where(arm.revolute, shifted, solution.q)
    with np.errstate(invalid="ignore"):
        distance = np.where(solution.valid, ((shifted - current) ** 2).sum(axis=-1), np.inf)
    slot = np.argmin(distance, axis=-1)
    try:
        prefer = np.broadcast_to(prefer, slot.shape)
    except ValueError:
        raise ValueError(f"prefer of shape {np.shape(prefer)} does not broadcast against poses of shape {slot.shape}") from None
    candidate = np.maximum(prefer, 0)
    best = np.take_along_axis(distance, slot[..., None], -1)[..., 0]
    tie = (prefer >= 0) & (np.take_along_axis(distance, candidate[..., None], -1)[..., 0] <= best + TIE_TOLERANCE)
    slot = np.where(tie, candidate, slot)
    any_valid = solution.valid.any(axis=-1)
    q = np.take_along_axis(shifted, slot[..., None, None], -2)[..., 0, :]
    return Branch(np.where(any_valid[..., None], q, np.nan), np.where(any_valid, slot, -1))


def _inside(q: np.ndarray, limits: np.ndarray) -> bool:
    """One pose's joints (n,) within ``limits`` (n, 2), to LIMIT_TOLERANCE, as a slider accepts them."""
    return all(low - LIMIT_TOLERANCE <= value <= high + LIMIT_TOLERANCE
               for value, (low, high) in zip(q.tolist(), limits.tolist()))


def _nearest_one(solution: IKSolution, current: list, prefer: int, low: list, high: list, tie: float) -> Branch:
    """:func:`_nearest_within_limits` for one pose, in plain Python."""
    revolute = solution.arm.revolute.tolist()
    chosen, chosen_distance, chosen_q = -1, math.inf, None
    distances, turned = [], []
    for k, (values, valid) in enumerate(zip(solution.q.tolist(), solution.valid.tolist())):
        if not valid:
            distances.append(math.inf)
            turned.append(None)
            continue
        shifted = []
        for value, now, lo, hi, rotates in zip(values, current, low, high, revolute):
            if rotates:
                value += round((now - value) / _TAU) * _TAU
                if value < lo and value + _TAU <= hi:
                    value += _TAU
                elif value > hi and value - _TAU >= lo:
                    value -= _TAU
            shifted.append(value)
        # (a - b) * (a - b): a float's ** 2 raises OverflowError past 1e154 (a slide typed 1e300 m out), a product is inf
        distance = sum((a - b) * (a - b) for a, b in zip(shifted, current))
        distances.append(distance)
        turned.append(shifted)
        if distance < chosen_distance or (chosen < 0 and distance == math.inf):  # (every distance inf: the first)
            chosen, chosen_distance, chosen_q = k, distance, shifted
    if chosen < 0:
        return Branch(np.full(len(current), np.nan), np.array(-1))
    if prefer >= 0 and distances[prefer] <= chosen_distance + tie:
        chosen, chosen_q = prefer, turned[prefer]
    return Branch(np.array(chosen_q), np.array(chosen))


def empty_branches(batch: tuple[int, ...], slots: int, joints: int) -> dict[str, np.ndarray]:
    """Arrays for the branches of ``batch`` poses, every slot invalid."""
    return dict(
        q=np.full(batch + (slots, joints), np.nan),
        valid=np.zeros(batch + (slots,), bool),
        singular=np.zeros(batch + (slots,), bool),
        failure=np.zeros(batch + (slots,), np.int8),
        detail=np.full(batch + (slots,), np.nan),
    )


#: Values of a free joint tried by :func:`keep_free_values_within_limits`, evenly over its range (4.7° apart on ±170°):
#: any value is an exact solution, and the nearest of these is at most half a step farther than the nearest of all.
FREE_VALUES = 73
#: A joint that moves less than this (rad or m) when the hint's value of another changes is not moved by it.
_UNMOVED = 1e-9


def keep_free_values_within_limits(solution: IKSolution, solve, T, hint) -> None:
    """Where a singular pose left a joint free and the hint's value of it put a slot beyond a joint limit, the value
    nearest the hint that keeps the slot within them, of :data:`FREE_VALUES` over the joint's range (in place); where
    none of those does, the one value between two of them that does, if there is one (a golden-section search).

    A closed form keeps the hint's value of a joint the pose leaves free (docs/kinematics.md §7.3): the Stanford
    arm's θ4 at θ5 = 0, where only θ4 + θ6 is fixed. With its wrist's ±170°, the hint's θ4 can leave θ6 at 175°
    while θ4 turned by 5° puts both within: the slot would read "beyond a joint limit" of a pose it reaches within
    them. ``solve(T, hint)`` is the closed form (:meth:`Arm.ik` without this step). A joint is free in a slot where
    another hint value of it moves that slot's joints; it is searched only where it moves every joint that is beyond
    a limit (turning θ4 cannot pull a reversed stroke back into its range). Nearest: the smallest largest turn of any
    joint from the hint.
    """
    if not np.count_nonzero(solution.singular):  # the usual case, told in a fraction of a µs (a drag's every step)
        return
    arm, n = solution.arm, solution.arm.n_joints
    slots = solution.valid.shape[-1]
    flagged = (solution.valid & solution.singular).reshape(-1, slots)
    rows = np.flatnonzero(flagged.any(axis=-1))  # the poses with a singular slot: a batch's others cost nothing
    q = solution.q.reshape(-1, slots, n)[rows]  # (pose, slot, n) of those poses, as are the arrays below
    beyond = ~arm.joints_within_limits(np.where(np.isfinite(q), q, 0.0))
    # a joint a pose leaves free turns the arm about an axis, and no stroke changes as it turns: a slot with a stroke
    # beyond its range (a point beyond the arm's reach, on a reach map) is not probed
    stuck = flagged[rows] & beyond.any(axis=-1) & ~(beyond & ~arm.revolute).any(axis=-1)
    if not stuck.any():
        return
    T = np.broadcast_to(np.asarray(T, dtype=float), solution.valid.shape[:-1] + (4, 4)).reshape(-1, 4, 4)[rows]
    hint = np.zeros((len(rows), n)) if hint is None else np.broadcast_to(
        arm.joints(hint, "hint"), solution.valid.shape[:-1] + (n,)).reshape(-1, n)[rows]
    poses = np.flatnonzero(stuck.any(axis=-1))
    low, high = arm.limits[:, 0], arm.limits[:, 1]
    # each joint's hint value moved a third of its range (at most 60°) towards its farther end, one joint at a time:
    # (pose, joint, n); never a whole turn, which a revolute joint's value would not show
    shift = np.minimum(high - low, math.pi) / 3
    probes = np.repeat(hint[poses, None], n, axis=1)
    probes[:, np.arange(n), np.arange(n)] = hint[poses] + np.where(hint[poses] - low > high - hint[poses], -shift, shift)
    probed = solve(np.broadcast_to(T[poses, None], probes.shape[:-1] + (4, 4)), probes).q  # (pose, joint, slot, n)
    gap = probed - q[poses, None]
    moved = np.abs(wrap_revolute(gap, arm.revolute)) > _UNMOVED
    searched = stuck[poses, None] & (moved | ~beyond[poses, None]).all(axis=-1) & moved.any(axis=-1)  # (pose, joint, slot)
    search, joint = np.nonzero(searched.any(axis=-1))  # one search per pose and free joint, for all its slots
    if not len(search):  # only slots no free joint can bring within (a reversed stroke)
        return
    pose = poses[search]
    values = np.linspace(low[joint], high[joint], FREE_VALUES, axis=-1)  # (search, value)
    tries = np.repeat(hint[pose, None], FREE_VALUES, axis=1)  # (search, value, n)
    tries[np.arange(len(pose)), :, joint] = values
    found = solve(np.broadcast_to(T[pose, None], tries.shape[:-1] + (4, 4)), tries)
    gap = found.q - hint[pose, None, None]  # (search, value, slot, n)
    gap = np.where(found.within_limits, np.abs(wrap_revolute(gap, arm.revolute)).max(axis=-1), np.inf)
    best = np.full(q.shape[:2], np.inf)  # (pose, slot): the largest turn of any joint, for the value taken
    for k, slot in zip(*np.nonzero(searched[search, joint])):
        nearest = np.argmin(gap[k, :, slot])
        if gap[k, nearest, slot] < best[pose[k], slot]:
            best[pose[k], slot] = gap[k, nearest, slot]
            q[pose[k], slot] = found.q[k, nearest, slot]
    # a slot within the limits for one value of the free joint alone, between two of the grid's (the elbow arm's θ5
    # on its limit where it is least over the free θ1): that value, from the grid's value nearest to within them
    missed = searched[search, joint] & ~np.isfinite(best[pose])  # (search, slot)
    if missed.any():
        k, slot = np.nonzero(missed)
        beyond_by = _beyond_limits_by(found.q[k, :, slot], arm)  # (missed, value)
        closest = np.argmin(beyond_by, axis=-1)
        step = (high[joint[k]] - low[joint[k]]) / (FREE_VALUES - 1)
        centre = values[k, closest]
        tries = hint[pose[k]].copy()

        def solved(value: np.ndarray) -> np.ndarray:
            tries[np.arange(len(k)), joint[k]] = value
            return solve(T[pose[k]], tries).q[np.arange(len(k)), slot]

        value = _golden_minimum(lambda value: _beyond_limits_by(solved(value), arm),
                                np.maximum(centre - step, low[joint[k]]), np.minimum(centre + step, high[joint[k]]))
        refined = solved(value)
        for m in np.flatnonzero(arm.within_limits(refined)):
            turn = np.abs(wrap_revolute(refined[m] - hint[pose[k[m]]], arm.revolute)).max()
            if turn < best[pose[k[m]], slot[m]]:
                best[pose[k[m]], slot[m]] = turn
                q[pose[k[m]], slot[m]] = refined[m]
    every = solution.q.reshape(-1, slots, n)  # a view of ik's own array: a batch is not copied for a few poses
    every[rows] = q
    solution.q, solution._within_limits = every.reshape(solution.q.shape), None


def _beyond_limits_by(q: np.ndarray, arm: Arm) -> np.ndarray:
    """(...) how far (rad or m) the joint of ``q`` (..., n) farthest beyond its limits is from them: 0 within, ∞ for
    an empty slot."""
    from .solvers.numerical import into_limits  # (that module builds on this one)

    finite = np.where(np.isfinite(q), q, 0.0)
    beyond = np.abs(wrap_revolute(finite - into_limits(finite, arm.limits, arm.revolute), arm.revolute)).max(axis=-1)
    return np.where(np.isfinite(q).all(axis=-1), beyond, np.inf)


def _golden_minimum(f, low: np.ndarray, high: np.ndarray, iterations: int = 60) -> np.ndarray:
    """(m,) where each of ``f``'s m functions, evaluated together (``f((m,)) -> (m,)``), is least on [low, high]
    (a minimum, where there are several), by golden-section search: to 1e-12 of the bracket's width."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iterations):
        left = fc <= fd  # the least is in [a, d]: d goes to c, a new c is tried; else in [c, b]
        a, b = np.where(left, a, c), np.where(left, d, b)
        tried = np.where(left, b - ratio * (b - a), a + ratio * (b - a))
        f_tried = f(tried)
        c, d = np.where(left, tried, d), np.where(left, c, tried)
        fc, fd = np.where(left, f_tried, fd), np.where(left, fc, f_tried)
    return np.where(fc <= fd, c, d)

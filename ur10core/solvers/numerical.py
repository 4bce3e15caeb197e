"""Numerical IK for any DH table: damped least squares from many starts (docs/kinematics.md §7.4).

Each pose is solved from ``starts`` joint vectors at once (the hint first, then random
ones spread over the joint ranges), by Levenberg–Marquardt steps on the pose error
``e = [p_target − p; log(R_target Rᵀ)]``, or what of it the chain controls (:func:`task_of`):

    Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e

λ shrinks after a step that lowers the error and grows after one that does not (the step
is then not taken), so a start near a singularity slows down instead of jumping. Starts
that converge to within 1e-10 of the pose, checked once more by FK to 1e-9, are the
solutions. Near a singularity the damped steps close in slowly, not quadratically (J's smallest
singular value is below the least λ, which holds back the very step that remains): a start that
stopped within 1e-3 of the pose takes twenty undamped Gauss–Newton steps, Δq = J⁺ e.
Where the pose leaves the joints free along a curve (a wrist with axes 4 and 6 in line, a
roll at the tool point of a position-only chain), a solution is moved along it to the hint's
value of its last joint. Solutions closer than 1e-6 in every joint are one, and so are
solutions up to 1e-2 apart whose midpoint is as close to the pose as they are; the hint's is
kept first, and they are sorted so that the same pose always lists them in the same order,
labelled "found numerically". Solutions within the joint limits come before the others; where no
start ends within them, the starts go again with every step kept within them
(:func:`into_limits`), a joint at a stop that the step would take further held.
"""

from __future__ import annotations

import math

import numpy as np

from ..branches import NOT_FOUND, TOO_FAR, empty_branches, mm_apart, wrap_revolute
from ..dh import DHTable
from ..differential import task_gap
from ..tolerances import LENGTH_TOLERANCE, LIMIT_TOLERANCE

#: Joint vectors each pose is searched from: the hint, then random ones. At 48, a typed UR10 missed 6 of the 2,162
#: branches its closed form has within the limits over 300 random poses (a start now and then misses a basin); at 64,
#: none, in about the same time per pose (the solving is batched over the starts).
STARTS = 64
#: A start has converged when its error (m and rad) is below this.
CONVERGED = 1e-12
#: A start whose error is below this (and whose FK is within 1e-9 of the pose) is a solution.
REACHED = 1e-10
#: Solutions closer than this in every joint (rad or m) are the same solution; so are solutions up to
#: NEAR apart whose midpoint is as close to the pose as they are (:meth:`NumericalIK._distinct`).
SAME, NEAR = 1e-6, 1e-2
#: A singular value of J below this is a direction the joints can move in without moving the tool
#: (:meth:`NumericalIK._pinned`): a turn of π along it moves the pose by 3e-10 at most, about what
#: the search stops at (the closed forms' wrist is free below |s5| = 3e-11). Solutions of the
#: Stanford arm with its stroke a few µm long (1e-11 to 1e-10) may then be listed as fewer than its
#: closed form's eight: to within 1e-11 of the pose, a few µm of stroke and 1e-5 rad of θ1 join them.
NULL_SINGULAR_VALUE = 1e-10
#: Damped steps that bring a solution moved along a curve of solutions back onto it, one joint held.
PIN_STEPS = 40
#: Values of a pinned joint tried over its range where the hint's leaves another joint beyond its limits
#: (:meth:`NumericalIK._pinned`; 14° apart on ±170°).
PIN_VALUES = 25
#: λ never shrinks below this: λ² = 1e-12 keeps J Jᵀ + λ² I invertible in floating point.
MIN_DAMPING = 1e-6
#: A start that stopped short of the pose but this close (m and rad) takes this many undamped
#: steps (see :meth:`NumericalIK._newton`).
NEARLY_REACHED, NEWTON_STEPS = 1e-3, 20
#: Steps that move a redundant chain's joints towards the middle of their travel, each half of what is left of the way
#: where J's null space allows (:meth:`NumericalIK._centred`).
CENTRING_STEPS = 8
#: A closed form's slot with no joint beyond its limits by more than this (rad or m) is tried with them on their
#: limits (:func:`settle_on_limits`): the Stanford arm's θ2 over a stroke of 30 nm or more, fixed to 0.5° or better
#: (a shorter stroke's θ2 is fixed by rounding alone, and the closed form chooses it below 1 nm).
SETTLE_BEYOND = 1e-2
#: Gauss–Newton steps that take the other joints back to the pose: from 0.5° away three reach it in nearly every
#: slot that reaches it at all (1,101 of 1,102 in a probe).
SETTLE_STEPS = 6


def within_limits(q: np.ndarray, limits: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(..., n) bool: which joints of ``q`` (..., n) lie within ``limits`` (n, 2), to :data:`LIMIT_TOLERANCE`, a
    revolute joint also one turn either way (what :meth:`ur10core.Arm.within_limits` counts): −195° is 165°.

    >>> within_limits(np.radians([[175.0, 30.0], [-195.0, 30.0]]), np.radians([[-170, 170], [0, 90]]), np.array([True, True])).tolist()
    [[False, True], [True, True]]
    """
    low, high = limits[:, 0] - LIMIT_TOLERANCE, limits[:, 1] + LIMIT_TOLERANCE
    inside = (q >= low) & (q <= high)
    turned = np.where(revolute, (q + 2 * math.pi >= low) & (q + 2 * math.pi <= high)
                      | (q - 2 * math.pi >= low) & (q - 2 * math.pi <= high), False)
    return inside | turned


def into_limits(q: np.ndarray, limits: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """``q`` (..., n) with each joint beyond its ``limits`` (n, 2) put on the nearer one: a sliding joint's stroke
    clipped, a turning joint's angle first turned by a whole turn where that brings it within (as
    :func:`within_limits` counts it), else set to the limit the shorter way round from it.

    >>> np.degrees(into_limits(np.radians([[175.0, -20.0], [-195.0, 100.0], [-100.0, 30.0]]),
    ...                        np.radians([[-170, 170], [0, 90]]), np.array([True, True]))).round(6).tolist()
    [[170.0, 0.0], [165.0, 90.0], [-100.0, 30.0]]
    """
    low, high = limits[:, 0], limits[:, 1]
    turned = low + np.mod(q - low, 2.0 * math.pi)  # in [low, low + 2π): within where not past high
    nearer = np.where(turned - high <= low + 2.0 * math.pi - turned, high, low)
    angle = np.where((q >= low) & (q <= high), q, np.where(turned <= high, turned, nearer))
    return np.where(revolute, np.where(high - low >= 2.0 * math.pi, q, angle), np.clip(q, low, high))


def sampling_range(limits: np.ndarray, revolute: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) per joint to draw joint vectors from: the limits, and one turn within them for a revolute joint
    whose limits span a turn or more (every pose once: (−π, π) where they allow it, as the UR10's ±360° do). A range
    short of a turn is kept as it is, past ±π or not: cut to (−π, π), the KR210's A3 (−210° to 65°) lost its poses
    beyond −180°, and 250° to 340° had none left.

    >>> [np.degrees(v).round().tolist() for v in sampling_range(np.radians([[-360, 360], [-210, 65]]), np.array([True, True]))]
    [[-180.0, -210.0], [180.0, 65.0]]
    """
    low, high = np.array(limits[:, 0], dtype=float), np.array(limits[:, 1], dtype=float)
    turn = np.asarray(revolute, bool) & (high - low >= 2.0 * math.pi)
    centre = np.clip(0.0, low + math.pi, high - math.pi)[turn]
    low[turn], high[turn] = centre - math.pi, centre + math.pi
    return low, high


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vector of (..., 3, 3) rotations: axis × angle, angle in [0, π]."""
    trace = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    skew = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    sin2 = np.linalg.norm(skew, axis=-1)  # 2 sin(angle)
    angle = np.arctan2(sin2, trace - 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(sin2 > 1e-300, angle / sin2, 0.5)
    vector = skew * scale[..., None]
    # near π the skew part vanishes: take the axis from the symmetric part
    near_pi = angle > math.pi - 1e-4
    if near_pi.any():
        Rn = R[near_pi]
        B = (Rn + np.swapaxes(Rn, -1, -2)) / 2 - np.eye(3) * ((np.trace(Rn, axis1=-2, axis2=-1) - 1) / 2)[:, None, None]
        column = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        axis = B[np.arange(len(Rn)), :, column]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        sign = np.sign(np.einsum("ni,ni->n", axis, skew[near_pi]))
        axis *= np.where(sign == 0, 1.0, sign)[:, None]
        vector[near_pi] = axis * angle[near_pi][:, None]
    return vector


def most_solutions(n_joints: int) -> int:
    """How many IK solutions a chain of ``n_joints`` can have for its task (docs/kinematics.md §7.4).

    A joint reaching a point: 1; two joints: 2; three (the position of the tool): 4; six (the
    pose): 16. Four, five or more than six joints are redundant (a continuum of solutions):
    at most 16 of them are kept.

    >>> [most_solutions(n) for n in (1, 2, 3, 6)]
    [1, 2, 4, 16]
    """
    return {1: 1, 2: 2, 3: 4}.get(n_joints, 16)


def task_of(table: DHTable) -> str:
    """What of a pose a typed chain controls (docs/kinematics.md §7.4): the pose with six joints or more; its
    position and its yaw about z0 where every joint axis stays parallel to z0 (every α a multiple of 180°),
    with three revolute joints or more and a prismatic one, as a SCARA; else its position.

    >>> scara = [(0.325, 0, 0.387, 0, "R"), (0.275, math.pi, 0, 0, "R"), (0, 0, 0, 0, "P"), (0, 0, 0, 0, "R")]
    >>> task_of(DHTable(scara, "standard"))
    'position and yaw'
    """
    kinds = table.joint_types
    if table.n_joints >= 6:
        return "pose"
    if all(abs(math.sin(row.alpha)) < 1e-12 for row in table.rows) and kinds.count("R") >= 3 and "P" in kinds:
        return "position and yaw"
    return "position"


def reach_bound(table: DHTable, limits: np.ndarray) -> float:
    """No joint values within ``limits`` (n, 2) put the tool of ``table`` farther from the base origin than this (m):
    every row's |a| and |d| laid end to end, a sliding joint's with the end of its stroke farthest from 0
    (docs/kinematics.md §7.4)."""
    strokes = [max(abs(low), abs(high)) for (low, high), kind in zip(np.asarray(limits).tolist(), table.joint_types)
               if kind == "P"]
    return float(sum(abs(row.a) + abs(row.d) for row in table.rows) + sum(strokes))


def _damped_step(J: np.ndarray, error: np.ndarray, damping: np.ndarray) -> np.ndarray:
    """(k, n) damped least-squares steps Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e for Jacobians ``J`` (k, m, n), errors ``e``
    (k, m) and dampings λ (k,)."""
    A = J @ np.swapaxes(J, -1, -2) + (damping**2)[:, None, None] * np.eye(error.shape[-1])
    try:
        weights = np.linalg.solve(A, error[..., None])[..., 0]
    except np.linalg.LinAlgError:  # a chain that cannot move along some direction at all: J Jᵀ has zero rows
        weights = np.einsum("kij,kj->ki", np.linalg.pinv(A), error)
    return np.einsum("kji,kj->ki", J, weights)


def task_error(tool: np.ndarray, J: np.ndarray, target: np.ndarray, task: str) -> tuple[np.ndarray, np.ndarray]:
    """Pose error ``e = [p_target − p; log(R_target Rᵀ)]`` (…, m) of tool poses ``tool`` (…, 4, 4) from ``target``, and
    the rows of their geometric Jacobians ``J`` (…, 6, n) that go with it: m = 6, 4 (position and yaw) or 3
    (position), as ``task`` has it."""
    position = target[..., :3, 3] - tool[..., :3, 3]
    if task == "position":
        return position, J[..., :3, :]
    turn = rotation_log(target[..., :3, :3] @ np.swapaxes(tool[..., :3, :3], -1, -2))
    if task == "position and yaw":
        return np.concatenate([position, turn[..., 2:]], axis=-1), J[..., [0, 1, 2, 5], :]
    return np.concatenate([position, turn], axis=-1), J


def gauss_newton(error_of, q: np.ndarray, steps: int, bounds=None) -> tuple[np.ndarray, np.ndarray]:
    """``steps`` undamped Gauss–Newton steps q ← q + J⁺ e from joints ``q`` (…, n) already near a solution, where
    ``error_of(q)`` gives (e, J) as :func:`task_error` does: the best joints each start passed through, and their
    error size. ``bounds``: (limits, revolute), each step ended within the limits (:func:`into_limits`).

    Near a singularity J's smallest singular value falls below :data:`MIN_DAMPING`, and damped
    least squares then holds back the very step that remains. The pseudo-inverse takes it whole;
    its first step may raise the error before the next ones close it, so every step is taken.
    """
    error, J = error_of(q)
    best_q, best = q, np.linalg.norm(error, axis=-1)
    for _ in range(steps):
        q = q + np.einsum("...ij,...j->...i", np.linalg.pinv(J), error)
        if bounds is not None:
            q = into_limits(q, *bounds)
        error, J = error_of(q)
        size = np.linalg.norm(error, axis=-1)
        best_q, best = np.where((size < best)[..., None], q, best_q), np.minimum(size, best)
    return best_q, best


def settle_on_limits(solution, T) -> None:
    """Where a closed form's singular slot (one whose pose fixes a joint loosely or not at all) reaches its pose with
    joints beyond their limits by at most :data:`SETTLE_BEYOND`: those joints put on their limits and the others
    moved to reach the pose again by :func:`gauss_newton`, wherever they then reach it as the search's own solutions
    do (:data:`REACHED`, in place).

    Near a singularity a closed form's value of a joint carries the pose's rounding over a short lever: the Stanford
    arm's θ2 over a stroke of 1 µm, from the reach √(ρ² − d2²) of a wrist centre near the d2 cylinder, is fixed only
    to about 2e-5 rad. With θ2 on its 170° limit the slot read 170.001°, "beyond a joint limit" of a pose the arm
    reaches within them (docs/kinematics.md §7.3).
    """
    if not np.count_nonzero(solution.singular):  # the usual case, told in a fraction of a µs (a drag's every step)
        return
    arm = solution.arm
    flagged = np.nonzero(solution.valid & solution.singular)  # (pose indices..., slot)
    q = solution.q[flagged]
    on_limits = into_limits(q, arm.limits, arm.revolute)
    beyond_by = np.abs(wrap_revolute(on_limits - q, arm.revolute))
    near = (beyond_by.max(axis=-1) > LIMIT_TOLERANCE) & (beyond_by.max(axis=-1) <= SETTLE_BEYOND)
    if not near.any():
        return
    on_limits, moving = on_limits[near], (beyond_by[near] == 0.0).astype(float)
    target = np.broadcast_to(np.asarray(T, dtype=float)[..., None, :, :], solution.valid.shape + (4, 4))[flagged][near]
    # (the error's size does not depend on which joints move: gauss_newton's is the settled joints' own)
    settled, size = gauss_newton(lambda q: task_error(arm.fk(q), arm.jacobian(q) * moving[:, None, :], target, arm.task),
                                 on_limits, SETTLE_STEPS, (arm.limits, arm.revolute))
    reached = (size <= REACHED) & (task_gap(arm.fk(settled), target, arm.task) <= 1e-9) & arm.within_limits(settled)
    if not reached.any():
        return
    rows = np.flatnonzero(near)[reached]
    q[rows] = wrap_revolute(settled[reached], arm.revolute)
    solution.q[flagged] = q  # ik's own array
    solution._within_limits = None


class NumericalIK:
    """Damped least squares from ``starts`` starts; up to ``slots`` distinct solutions per pose
    (by default as many as the chain can have, :func:`most_solutions`)."""

    method = "found numerically"

    def __init__(self, table: DHTable, limits: np.ndarray, starts: int = STARTS, iterations: int = 150,
                 slots: int | None = None, seed: int = 0) -> None:
        self.table = table
        self.limits = np.asarray(limits, dtype=float)
        self.starts, self.iterations, self.seed = starts, iterations, seed
        self.task = task_of(table)
        if slots is None:  # three parallel revolute axes place x, y and the yaw as a planar 3R: two ways at most
            slots = 2 if self.task == "position and yaw" and table.n_joints == 4 else most_solutions(table.n_joints)
        self.labels = tuple(f"found numerically {k + 1}" for k in range(slots))
        self.revolute = np.array([t == "R" for t in table.joint_types])
        #: The joints with ends to their travel: a sliding one, a turning one with less than a turn between its limits.
        self.has_stops = ~self.revolute | (self.limits[:, 1] - self.limits[:, 0] < 2.0 * math.pi)
        #: More joints than the task needs: a continuum of solutions for each pose.
        self.redundant = table.n_joints > {"pose": 6, "position and yaw": 4, "position": 3}[self.task]
        self.reach = reach_bound(table, self.limits)

    def explain(self, failure: int, detail: float) -> str:
        if failure == TOO_FAR:
            at, bound, _ = mm_apart(detail, self.reach)
            return (f"the target is {at} mm from the base; this chain, every length and stroke laid "
                    f"end to end, reaches {bound} mm at most")
        return (f"the numerical search found no joints that reach this {self.task} from {self.starts} starts "
                f"(the nearest came within {1000 * detail:.3g} mm / mrad)")

    def _starts(self, hint: np.ndarray | None, count: int) -> np.ndarray:
        """(count, starts, n): the hint first (if any), then the same random spread for every pose."""
        low, high = sampling_range(self.limits, self.revolute)
        spread = np.random.default_rng(self.seed).uniform(low, high, (self.starts, len(low)))
        q = np.broadcast_to(spread, (count,) + spread.shape).copy()
        if hint is not None:
            q[:, 0] = hint
        return q

    def _search(self, starts: np.ndarray, target: np.ndarray, hint: np.ndarray | None,
                bounded: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every start ``starts`` (N, s, n) taken to ``target`` (N, s, 4, 4): (joints, whether they reach it, error
        size). ``bounded``: every step kept within the limits (:func:`into_limits`)."""
        q, size = self._converge(starts, target, self.iterations, bounded)
        ok = self._reached(q, target, size=size)
        return self._pinned(q, target, ok, hint), ok, size

    def _error(self, q: np.ndarray, target: np.ndarray, moving=None) -> tuple[np.ndarray, np.ndarray]:
        """Pose error and Jacobian rows (:func:`task_error`) at joints ``q`` (…, n). ``moving`` (…, n), 1 or 0:
        the columns of the joints it does not mark are zero, so that no step moves them."""
        frames = self.table.frames(q)
        J = self.table.jacobian_from_frames(frames)
        return task_error(frames[..., -1, :, :], J if moving is None else J * moving[..., None, :], target, self.task)

    def _descend(self, q: np.ndarray, target: np.ndarray, iterations: int,
                 moving=None, bounded: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Levenberg–Marquardt from the starts ``q`` (..., n) towards ``target`` (..., 4, 4): (joints, error size).
        ``moving``: as for :meth:`_error`. ``bounded``: each step ends within the limits (:func:`into_limits`)."""
        if bounded:
            q[...] = into_limits(q, self.limits, self.revolute)
        damping = np.full(q.shape[:-1], 1e-2)
        error, J = self._error(q, target, moving)
        size = np.linalg.norm(error, axis=-1)
        for _ in range(iterations):
            active = size > CONVERGED
            if not active.any():
                break
            step = _damped_step(J[active], error[active], damping[active])
            trial = q[active] + step
            if bounded:  # a joint at a limit that the step would take past it is held, and the step found without it
                low, high = self.limits[:, 0], self.limits[:, 1]
                held = self.has_stops & ((q[active] >= high) & (step > 0) | (q[active] <= low) & (step < 0))
                if held.any():
                    step = _damped_step(J[active] * ~held[:, None, :], error[active], damping[active])
                trial = into_limits(q[active] + step, self.limits, self.revolute)
            trial_error, trial_J = self._error(trial, target[active], None if moving is None else moving[active])
            trial_size = np.linalg.norm(trial_error, axis=-1)
            better = trial_size < size[active]
            index = tuple(np.argwhere(active)[better].T)
            q[index], error[index], J[index], size[index] = trial[better], trial_error[better], trial_J[better], trial_size[better]
            damping[active] = np.where(better, np.maximum(damping[active] / 3, MIN_DAMPING), np.minimum(damping[active] * 4, 1e3))
        return wrap_revolute(q, self.revolute), size

    def _newton(self, q: np.ndarray, target: np.ndarray, steps: int, moving=None,
                bounded: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """:func:`gauss_newton` from starts ``q`` (..., n) already near ``target``: (joints, error size). ``moving``
        (..., n), 1 or 0: only the joints it marks move. ``bounded``: each step ends within the limits."""
        bounds = (self.limits, self.revolute) if bounded else None
        q, size = gauss_newton(lambda q: self._error(q, target, moving), q, steps, bounds)
        return wrap_revolute(q, self.revolute), size

    def _converge(self, starts: np.ndarray, target: np.ndarray, iterations: int,
                  bounded: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_descend` from (a copy of) ``starts`` (..., n), then :meth:`_finish`: (joints, error size)."""
        q, size = self._descend(starts.copy(), target, iterations, bounded=bounded)
        return self._finish(q, target, size, bounded)

    def _finish(self, q: np.ndarray, target: np.ndarray, size: np.ndarray,
                bounded: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The starts that stopped short of ``target`` but within :data:`NEARLY_REACHED`, taken the rest of the way
        by :meth:`_newton`: near a singularity the damped steps converge slowly, not quadratically."""
        stuck = (size > REACHED) & (size < NEARLY_REACHED)
        if stuck.any():
            q[stuck], size[stuck] = self._newton(q[stuck], target[stuck], NEWTON_STEPS, bounded=bounded)
        return q, size

    def _pinned(self, q: np.ndarray, target: np.ndarray, ok: np.ndarray, hint: np.ndarray | None) -> np.ndarray:
        """Solutions ``q`` (N, starts, n) (where ``ok``) on a curve of solutions, moved along it to where the last
        joint that moves along it has the hint's value (else 0), where the tool still reaches ``target`` there;
        where that value leaves a joint beyond its limits, to the value nearest it that keeps them all within.

        Where the pose leaves one direction of the joints free (J has one null direction: a spherical wrist
        with axes 4 and 6 in line, whose θ4 + θ6 alone is fixed; the UR10's at θ5 = 0, its four parallel axes;
        a roll about the tool point of a chain that places a position; a seventh joint), every point of that
        curve reaches, and each start would bring back another point of it, filling the slots with one
        branch. The closed forms keep the hint's value there; so does this: a step along the null direction,
        then damped steps with that joint held. A solution they do not bring as close to the pose as it was
        stays as it was (next to a singularity, a step along a direction that barely moves the tool still
        moves it), and so does one within the limits that no value tried keeps within them."""
        n = self.table.n_joints
        if not ok.any():
            return q
        error, J = self._error(q[ok], target[ok])
        _, sigma, Vt = np.linalg.svd(J)  # the last row of Vt: the direction that moves the tool least
        line = (sigma > NULL_SINGULAR_VALUE).sum(axis=-1) == n - 1  # one free direction, no more
        if not line.any():
            return q
        at = tuple(np.argwhere(ok)[line].T)
        free = Vt[line, -1, :]
        # the last joint it moves by a fiftieth of the most or more, the same joint all along one curve (a wrist's θ6)
        moves = np.abs(free) >= 0.02 * np.abs(free).max(axis=-1, keepdims=True)
        joint = (n - 1 - np.argmax(moves[:, ::-1], axis=-1))[:, None]
        wanted = (np.clip(0.0, self.limits[:, 0], self.limits[:, 1]) if hint is None
                  else np.asarray(hint, dtype=float)[:, None, :])
        wanted = np.broadcast_to(wanted, q.shape)[at]
        on_curve, targets, held = q[at], target[at], (np.arange(n) != joint).astype(float)
        close_as = np.maximum(2 * np.linalg.norm(error[line], axis=-1), 10 * CONVERGED)

        def pin(rows: np.ndarray, value: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """Solutions ``rows`` moved along their curve to where their pinned joint has ``value`` (rows, 1): the
            joints, and whether they still reach the pose."""
            offset = value - np.take_along_axis(on_curve[rows], joint[rows], -1)
            offset = wrap_revolute(offset, self.revolute[joint[rows]])
            moved = on_curve[rows] + offset / np.take_along_axis(free[rows], joint[rows], -1) * free[rows]
            moved, size = self._descend(moved, targets[rows], PIN_STEPS, moving=held[rows])
            stuck = (size > REACHED) & (size < NEARLY_REACHED)
            if stuck.any():
                moved[stuck], _ = self._newton(moved[stuck], targets[rows][stuck], NEWTON_STEPS, moving=held[rows][stuck])
            return moved, self._reached(moved, targets[rows], close_as[rows])

        moved, still = pin(np.arange(len(joint)), np.take_along_axis(wanted, joint, -1))
        # the hint's value can leave another joint beyond its limits (a wrist whose θ4 + θ6 alone is fixed, each
        # ±170°): there, of PIN_VALUES over the pinned joint's range, the nearest the hint that keeps them within
        outside = np.flatnonzero(still & ~within_limits(moved, self.limits, self.revolute).all(axis=-1))
        if len(outside):
            low, high = self.limits[joint[outside], 0], self.limits[joint[outside], 1]
            nearest = np.full(len(outside), np.inf)
            for share in np.linspace(0.0, 1.0, PIN_VALUES):
                tried, reached = pin(outside, low + share * (high - low))
                gap = tried - wanted[outside]
                gap = np.abs(wrap_revolute(gap, self.revolute)).max(axis=-1)
                gap[~(reached & within_limits(tried, self.limits, self.revolute).all(axis=-1))] = np.inf
                better = gap < nearest
                moved[outside[better]], nearest[better] = tried[better], gap[better]
        # a solution within the limits stays where it is if no value of its pinned joint keeps them within
        still &= within_limits(moved, self.limits, self.revolute).all(axis=-1) | ~within_limits(
            on_curve, self.limits, self.revolute).all(axis=-1)
        q = q.copy()
        q[tuple(index[still] for index in at)] = moved[still]
        return q

    def _reached(self, q: np.ndarray, target: np.ndarray, within: float = REACHED, size=None) -> np.ndarray:
        """(...) bool: joints ``q`` (..., n) put the tool on ``target`` (..., 4, 4) in what the arm controls, to
        ``within`` (by default the error the search stops at) and to 1e-9 in every entry of FK. ``size``: their
        error's size, where the search has it already."""
        if size is None:
            size = np.linalg.norm(self._error(q, target)[0], axis=-1)
        return (size <= within) & (task_gap(self.table.fk(q), target, self.task) <= 1e-9)

    def _distinct(self, q: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Rows of ``q`` (m, n), solutions of ``target`` (4, 4), with near-duplicates dropped, the first of each kept.

        Two are one where they are :data:`SAME` apart, or up to :data:`NEAR` apart with their midpoint as
        close to the pose as they are: next to a singularity the pose fixes the joints only to about
        √rounding (a stretched elbow's θ2 to 1e-5 rad) or along a line, and two starts stop at two points
        of one branch. Two branches that close are apart by a curve: their midpoint misses the pose by
        more, however little the pose fixes them."""
        sizes = np.linalg.norm(self._error(q, np.broadcast_to(target, q.shape[:-1] + (4, 4)))[0], axis=-1).tolist()
        kept: list[tuple[np.ndarray, float]] = []
        for row, size in zip(q, sizes):
            for other, other_size in kept:
                step = wrap_revolute(row - other, self.revolute)
                apart = np.abs(step).max()
                if apart <= SAME or apart <= NEAR and self._reached(other + step / 2, target,
                                                                     2 * max(size, other_size)):
                    break
            else:
                kept.append((row, size))
        return np.array([row for row, _ in kept]).reshape(-1, q.shape[-1])

    def follow(self, T: np.ndarray, hint: np.ndarray, iterations: int = 30) -> tuple[np.ndarray, float]:
        """One pose (4, 4) from the current joints ``hint`` (n,) only: (joints, their pose error).

        What a drag needs: the target moves a little between events, so the arm's own
        joints are a start that converges in a few steps, in about a millisecond per step;
        the other branches come from :meth:`solve`'s many starts. Joints that end beyond
        their limits are searched for again with every step kept within them, and taken
        where they reach the pose as closely (a redundant chain that can keep clear of a stop);
        a redundant chain stalled at a stop that way tries once more from its joints moved
        towards the middle of their travel first (:meth:`_centred`).
        """
        T = np.asarray(T, dtype=float)
        distance = math.hypot(*T[:3, 3].tolist())  # scaled: no overflow
        if distance > self.reach + LENGTH_TOLERANCE:  # nowhere to go (and a huge error's square would overflow)
            return np.array(hint, dtype=float), distance - self.reach
        start = np.array(hint, dtype=float)[None]
        q, size = self._converge(start, T[None], iterations)
        if not within_limits(q, self.limits, self.revolute).all():
            kept, kept_size = self._converge(start, T[None], iterations, bounded=True)
            if kept_size[0] > max(size[0], REACHED) and self.redundant:
                kept, kept_size = self._converge(self._centred(start[0])[None], T[None], iterations, bounded=True)
            if kept_size[0] <= max(size[0], REACHED):
                return kept[0], float(kept_size[0])
        return q[0], float(size[0])

    def _centred(self, q: np.ndarray, steps: int = CENTRING_STEPS) -> np.ndarray:
        """Joints ``q`` (n,) of a redundant chain moved towards the middle of the travel of the joints with stops,
        along the null space of J, where the tool stays (to first order): q ← q + ½ (I − J⁺J)(q_middle − q).

        A drag follows the target by the shortest step, so a chain with joints to spare drifts until one meets
        its stop, and stalls there short of a target its other solutions reach within the limits. From joints
        away from the stops the same search reaches it.
        """
        middle = self.limits.mean(axis=1)
        for _ in range(steps):
            _, J = self._error(q[None], np.eye(4)[None])
            null = np.eye(len(q)) - np.linalg.pinv(J[0]) @ J[0]
            q = into_limits(q + 0.5 * null @ np.where(self.has_stops, middle - q, 0.0), self.limits, self.revolute)
        return q

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        N, n, slots = len(T), self.table.n_joints, len(self.labels)
        out = empty_branches((N,), slots, n)
        distance = np.hypot(np.hypot(T[:, 0, 3], T[:, 1, 3]), T[:, 2, 3])  # scaled: no overflow
        too_far = distance > self.reach + LENGTH_TOLERANCE
        out["failure"][too_far], out["detail"][too_far] = TOO_FAR, distance[too_far, None]
        if too_far.any():  # not searched: nothing reaches, and a huge error's square would overflow
            near = np.flatnonzero(~too_far)
            if len(near):
                part = self.solve(T[near], None if hint is None else hint[near])
                for key, value in part.items():
                    out[key][near] = value
            return out
        starts = self._starts(hint, N)
        target = np.broadcast_to(T[:, None], starts.shape[:-1] + (4, 4))
        q, ok, size = self._search(starts, target, hint)
        # where no start ended within the limits, the starts again with every step kept within them: the steps that
        # led out (a stroke below 0, a redundant chain's drift) may have passed by a solution within them
        again = np.flatnonzero(~(ok & within_limits(q, self.limits, self.revolute).all(axis=-1)).any(axis=-1))
        if len(again):
            kept, kept_ok, kept_size = self._search(starts[again], target[again],
                                                    None if hint is None else hint[again], bounded=True)
            q, ok = np.concatenate([np.zeros_like(q), q], axis=1), np.concatenate([np.zeros_like(ok), ok], axis=1)
            size = np.concatenate([np.full_like(size, np.inf), size], axis=1)
            q[again, :self.starts], ok[again, :self.starts], size[again, :self.starts] = kept, kept_ok, kept_size
        # those within the limits first, each kind in the starts' order (the hint's first): kept however many others
        inside = within_limits(q, self.limits, self.revolute).all(axis=-1)
        for k in range(N):
            found = self._distinct(q[k][ok[k]][np.argsort(~inside[k][ok[k]], kind="stable")], T[k])[:slots]
            found = found[np.lexsort(found.T[::-1])] if len(found) else found
            out["q"][k, : len(found)] = found
            out["valid"][k, : len(found)] = True
            if not len(found):
                out["failure"][k] = NOT_FOUND
                out["detail"][k] = size[k].min()
        return out

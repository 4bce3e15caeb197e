"""Moving between two poses: the tool along a straight line (resolved-rate motion), or the joints
along straight lines (joint interpolation), over the same time (docs/kinematics.md §8.7).

Both follow the cubic time scaling s(t) = 3τ² − 2τ³, τ = t / T: they start and stop at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import as_float_array, check_finite
from .differential import TASK_ROWS, damped_inverse
from .orientation import rotation_from_angle_axis
from .solvers.numerical import rotation_log
from .tolerances import LIMIT_TOLERANCE

#: Closed-loop gain of the resolved-rate motion (1/s): a drift from the line is corrected within
#: a few tenths of a second rather than accumulated step after step.
CORRECTION_GAIN = 20.0


@dataclass(frozen=True)
class Path:
    """A motion sampled at times ``t``.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Seconds from the start.
    q, qdot : ndarray, shape (m, n)
        Joints and joint rates (rad, rad/s; m, m/s for prismatic joints).
    tool : ndarray, shape (m, 3)
        The tool origin, base frame (m).
    damping : ndarray, shape (m,)
        λ of the damped inverse at each sample (0 where the arm was far from a singularity;
        always 0 for joint interpolation, which needs no inverse).
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    tool: np.ndarray
    damping: np.ndarray


def _time_scaling(duration: float, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if not (isinstance(duration, (int, float)) and 0.0 < duration <= 600.0):
        raise ValueError(f"duration must be from 0 to 600 s, got {duration!r:.40}")
    if not (isinstance(steps, int) and 2 <= steps <= 100_000):
        raise ValueError(f"steps must be a whole number from 2 to 100000, got {steps!r:.40}")
    t = np.linspace(0.0, duration, steps)
    tau = t / duration
    return t, 3 * tau**2 - 2 * tau**3, (6 * tau - 6 * tau**2) / duration


def _joints(arm, q, name: str) -> np.ndarray:
    q = as_float_array(q, name)
    if q.shape != (arm.n_joints,):
        raise ValueError(f"{name} must be {arm.n_joints} joint value{'s' * (arm.n_joints != 1)}, got shape {q.shape}")
    check_finite(q, name)
    return q


def joint_interpolation(arm, q_start, q_goal, duration: float = 4.0, steps: int = 200) -> Path:
    """Every joint from ``q_start`` to ``q_goal`` at once, q(t) = q_start + s(t) (q_goal − q_start).

    The joints move evenly; the tool, in general, along a curve.
    """
    start, goal = _joints(arm, q_start, "q_start"), _joints(arm, q_goal, "q_goal")
    t, s, sdot = _time_scaling(duration, steps)
    q = start + s[:, None] * (goal - start)
    return Path(t, q, sdot[:, None] * (goal - start), arm.fk(q)[:, :3, 3], np.zeros(len(t)))


def straight_line(arm, q_start, T_goal, duration: float = 4.0, steps: int = 200) -> Path:
    """The tool from its pose at ``q_start`` to ``T_goal`` along a straight line, by resolved rates.

    The desired pose moves as p(t) = p0 + s(t) (p1 − p0), R(t) = R0 exp(s(t) [r]×) with
    r = log(R0ᵀ R1); each step asks for the line's twist over that step plus
    :data:`CORRECTION_GAIN` times the pose error, takes the joint rates :func:`damped_inverse` gives (only the rows the arm
    controls: ``arm.task``), and integrates them (explicit Euler, ``steps`` samples).
    Near a singularity the rates grow until the damping bounds them, and ``damping`` shows
    where; where the line leaves the arm's reach the path leaves the line. Neither is hidden:
    :func:`line_deviation` measures the path against the line, :func:`line_out_of_reach`
    finds where the line cannot be reached, :func:`out_of_range` a joint beyond its limits.
    """
    start = _joints(arm, q_start, "q_start")
    goal = as_float_array(T_goal, "T_goal")
    if goal.shape != (4, 4):
        raise ValueError(f"T_goal must be a 4 × 4 pose, got shape {goal.shape}")
    check_finite(goal, "T_goal")
    t, s, _ = _time_scaling(duration, steps)
    rows = TASK_ROWS[getattr(arm, "task", "pose")]
    T0 = arm.fk(start)
    p0, R0 = T0[:3, 3], T0[:3, :3]
    move = goal[:3, 3] - p0
    turn = _turn(R0, goal, rows)
    dt = t[1] - t[0]
    gain = min(CORRECTION_GAIN, 0.5 / dt)  # a step corrects at most half of the error: never overshoots
    # the line's own rate over each step, exact for the step (a derivative at its start lags the line)
    step_rate = np.append(np.diff(s) / dt, 0.0)
    q = np.empty((len(t), arm.n_joints))
    qdot = np.zeros_like(q)
    lam = np.zeros(len(t))
    q[0] = start
    desired = line_poses(T0, goal, s, turn)
    for k in range(len(t)):
        T = arm.fk(q[k])
        error = np.concatenate([desired[k, :3, 3] - T[:3, 3], rotation_log(desired[k, :3, :3] @ T[:3, :3].T)])
        twist = np.concatenate([step_rate[k] * move, step_rate[k] * (R0 @ turn)]) + gain * error
        J = arm.jacobian(q[k])[rows]
        qdot[k], lam[k] = damped_inverse(J, twist[rows])
        if k + 1 < len(t):
            q[k + 1] = q[k] + dt * qdot[k]
    return Path(t, q, qdot, arm.fk(q)[:, :3, 3], lam)


def _turn(R0: np.ndarray, goal: np.ndarray, rows) -> np.ndarray:
    """r = log(R0ᵀ R1), or none for an arm that does not control its tool's orientation."""
    return rotation_log(R0.T @ goal[:3, :3]) if len(rows) > 3 else np.zeros(3)


def line_poses(T_start: np.ndarray, T_goal: np.ndarray, s: np.ndarray, turn: np.ndarray | None = None) -> np.ndarray:
    """(m, 4, 4) the poses of the straight line at the fractions ``s`` (m,) of the way (docs/kinematics.md §8.7).

    p(s) = p0 + s (p1 − p0), R(s) = R0 exp(s [r]×), r = ``turn`` (default log(R0ᵀ R1)).

    >>> T1 = np.eye(4); T1[:3, 3] = (1.0, 0.0, 0.0)
    >>> line_poses(np.eye(4), T1, np.array([0.0, 0.25, 1.0]))[:, 0, 3].tolist()
    [0.0, 0.25, 1.0]
    """
    turn = rotation_log(T_start[:3, :3].T @ T_goal[:3, :3]) if turn is None else turn
    angle = float(np.linalg.norm(turn))
    poses = np.tile(np.eye(4), (len(s), 1, 1))
    poses[:, :3, 3] = T_start[:3, 3] + s[:, None] * (T_goal[:3, 3] - T_start[:3, 3])
    for k, fraction in enumerate(s):
        turned = rotation_from_angle_axis(angle * fraction, turn / angle) if angle * fraction > 0 else np.eye(3)
        poses[k, :3, :3] = T_start[:3, :3] @ turned
    return poses


def line_deviation(path: Path) -> float:
    """How far (m) the tool gets from the straight segment between where the path starts and ends.

    For :func:`straight_line` it is the error the resolved rates left; for
    :func:`joint_interpolation`, how far the tool's curve bows away from the line.
    """
    start, end = path.tool[0], path.tool[-1]
    chord = end - start
    length2 = float(chord @ chord)
    along = np.clip((path.tool - start) @ chord / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(path.tool))
    return float(np.linalg.norm(path.tool - start - along[:, None] * chord, axis=1).max())


def line_out_of_reach(arm, q_start, T_goal, samples: int = 101) -> tuple[float, float, str] | None:
    """The stretch of the straight line from the tool at ``q_start`` to ``T_goal`` that no branch of the
    arm reaches: (first, last) fraction of the way and why, or None where every sample is reached.

    Only for arms with a closed-form IK (a typed table's search would take seconds): None for the others.

    >>> from ur10core import Arm
    >>> arm = Arm.preset("planar_elbow")
    >>> first, last, why = line_out_of_reach(arm, np.radians([0, 90]), arm.fk(np.radians([180, 90])))
    >>> round(first, 2), round(last, 2), why[:40]   # the line passes the base, inside the folded reach
    (0.43, 0.57, 'the target is 89.6 mm from the first joi')
    """
    if arm.numerical:
        return None
    start = _joints(arm, q_start, "q_start")
    T0, goal = arm.fk(start), as_float_array(T_goal, "T_goal")
    s = np.linspace(0.0, 1.0, samples)
    solution = arm.ik(line_poses(T0, goal, s, _turn(T0[:3, :3], goal, TASK_ROWS[arm.task])))
    missed = np.flatnonzero(~solution.valid.any(axis=1))
    if not len(missed):
        return None
    return float(s[missed[0]]), float(s[missed[-1]]), solution.unreachable_reason((int(missed[0]),))


def out_of_range(arm, path: Path) -> str:
    """Which joint of ``path`` leaves the arm's limits first, when, and how far it goes ("" if none does).

    >>> from ur10core import Arm
    >>> arm = Arm.preset("ur10")
    >>> path = joint_interpolation(arm, np.zeros(6), np.zeros(6))
    >>> out_of_range(arm, path)
    ''
    """
    low, high = arm.limits[:, 0] - LIMIT_TOLERANCE, arm.limits[:, 1] + LIMIT_TOLERANCE
    outside = (path.q < low) | (path.q > high)
    if not outside.any():
        return ""
    k, joint = np.argwhere(outside)[0]
    above = bool(path.q[k, joint] > high[joint])
    limit = arm.limits[joint, 1 if above else 0]
    furthest = path.q[:, joint].max() if above else path.q[:, joint].min()
    revolute = arm.joint_types[joint] == "R"
    shown = (lambda v: f"{np.degrees(v):.1f}°") if revolute else (lambda v: f"{1000 * v:.0f} mm")
    # a path only just beyond would read "reach 65.0°, outside its range … to 65.0°"
    far = (f"up to {shown(furthest)}" if shown(furthest) != shown(limit)
           else f"by less than {'0.1°' if revolute else '1 mm'}")
    return (f"{arm.joint_names[joint]} would go beyond its limit of {shown(limit)} at {path.t[k]:.2f} s, {far} "
            f"(its range is {shown(arm.limits[joint, 0])} to {shown(arm.limits[joint, 1])})")

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
        raise ValueError(f"{name} must be {arm.n_joints} joint values, got shape {q.shape}")
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
    Near a singularity the rates grow until the damping bounds them; the path then leaves the
    line a little, and ``damping`` shows where.
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
    turn = rotation_log(R0.T @ goal[:3, :3]) if len(rows) > 3 else np.zeros(3)
    dt = t[1] - t[0]
    gain = min(CORRECTION_GAIN, 0.5 / dt)  # a step corrects at most half of the error: never overshoots
    # the line's own rate over each step, exact for the step (a derivative at its start lags the line)
    step_rate = np.append(np.diff(s) / dt, 0.0)
    q = np.empty((len(t), arm.n_joints))
    qdot = np.zeros_like(q)
    lam = np.zeros(len(t))
    q[0] = start
    for k in range(len(t)):
        T = arm.fk(q[k])
        angle = float(np.linalg.norm(turn)) * s[k]
        R_desired = R0 @ (rotation_from_angle_axis(angle, turn / np.linalg.norm(turn)) if angle > 0 else np.eye(3))
        error = np.concatenate([p0 + s[k] * move - T[:3, 3], rotation_log(R_desired @ T[:3, :3].T)])
        twist = np.concatenate([step_rate[k] * move, step_rate[k] * (R0 @ turn)]) + gain * error
        J = arm.jacobian(q[k])[rows]
        qdot[k], lam[k] = damped_inverse(J, twist[rows])
        if k + 1 < len(t):
            q[k + 1] = q[k] + dt * qdot[k]
    return Path(t, q, qdot, arm.fk(q)[:, :3, 3], lam)

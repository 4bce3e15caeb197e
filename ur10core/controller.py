"""The UR controller's joint convention (docs/kinematics.md §6).

UR's controller (and ROS) use *standard* DH with a2, a3 negative. With the same link
lengths the two conventions differ by a half turn of the shoulder:

    q_controller = q_course + (0, π, 0, 0, 0, 0)

Both give the same flange position; the controller's flange frame is the course's
turned by π about its own z axis (``T_controller = T_course @ Rz(π)``). A student who
types the angles from a real teach pendant needs this mapping.

Example
-------
>>> import numpy as np
>>> np.degrees(to_controller(np.zeros(6))).round(3).tolist()
[0.0, 180.0, 0.0, 0.0, 0.0, 0.0]
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, homogeneous_transform, joint_vector

#: Added to the course's joint angles to get the controller's (radians).
CONTROLLER_OFFSET = np.array([0.0, np.pi, 0.0, 0.0, 0.0, 0.0])
#: The flange frame turn between the two conventions: ``T_controller = T_course @ FLANGE_TURN``.
FLANGE_TURN = np.diag([-1.0, -1.0, 1.0, 1.0])

_FULL_TURN = 2.0 * np.pi


def _keep_in_joint_range(q: np.ndarray) -> np.ndarray:
    # The UR10's joints turn ±360°; a shifted shoulder that leaves the range is the same
    # physical angle one turn back, which is what a teach pendant would show.
    shoulder = q[..., 1]
    shoulder = np.where(shoulder > _FULL_TURN, shoulder - _FULL_TURN, shoulder)
    q[..., 1] = np.where(shoulder < -_FULL_TURN, shoulder + _FULL_TURN, shoulder)
    return q


def to_controller(q) -> np.ndarray:
    """Course joint angles → the UR controller's, ``q + (0, π, 0, 0, 0, 0)``.

    Parameters
    ----------
    q : array_like, shape (..., 6)
        Joint angles in the course's convention, radians.

    Returns
    -------
    ndarray, shape (..., 6)
        The controller's joint angles. The shoulder is kept within ±2π (the joint
        range) by a full turn where the offset would push it out, so the result equals
        the plain offset modulo 2π.
    """
    q = joint_vector(q)
    return _keep_in_joint_range(q + CONTROLLER_OFFSET)


def from_controller(q_controller) -> np.ndarray:
    """The UR controller's joint angles → the course's, ``q − (0, π, 0, 0, 0, 0)``.

    Inverse of :func:`to_controller` (exact while the shoulder stays within ±2π, else
    equal modulo 2π).
    """
    q_controller = joint_vector(q_controller, "q_controller")
    return _keep_in_joint_range(q_controller - CONTROLLER_OFFSET)


def flange_to_controller(T) -> np.ndarray:
    """Course flange pose (..., 4, 4) → the controller's flange pose (turned π about z6)."""
    T = homogeneous_transform(T)
    return T @ FLANGE_TURN


def flange_from_controller(T_controller) -> np.ndarray:
    """The controller's flange pose (..., 4, 4) → the course's (``FLANGE_TURN`` is its own inverse)."""
    T_controller = homogeneous_transform(as_float_array(T_controller, "T_controller"), "T_controller")
    return T_controller @ FLANGE_TURN

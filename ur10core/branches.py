"""The IK result of a general arm: every branch in a fixed, labelled slot (docs/kinematics.md §7.3).

The UR family has its own richer result (:class:`ur10core.ik.IKSolution`); the other arms
share this one, whether their branches come from a closed form or from the numerical
solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

#: Why a slot is empty (``BranchSet.failure``); ``detail`` holds the number behind it.
REACHED = 0
TOO_FAR = 1  #: detail: the distance the arm would have to span (m)
TOO_CLOSE = 2  #: detail: the same, below the shortest span
INSIDE_OFFSET = 3  #: detail: the point's distance from the base axis (m), below the shoulder offset
ORIENTATION = 4  #: detail: the angle (rad) between the tool axis asked for and the one the arm can have
OUT_OF_PLANE = 5  #: detail: the distance (m) from the plane the arm moves in
NOT_FOUND = 6  #: detail: the smallest pose error the numerical solver reached

_TAU = 2.0 * math.pi


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in (−π, π]."""
    return -np.remainder(-np.asarray(angle) + math.pi, _TAU) + math.pi


@dataclass(frozen=True)
class BranchSet:
    """The IK branches of one or many poses (leading shape ``...``), k slots of n joints.

    Attributes
    ----------
    q : ndarray, shape (..., k, n)
        Joint values (radians in (−π, π] for revolute joints, metres for prismatic); NaN
        in invalid slots.
    valid : ndarray of bool, shape (..., k)
        The slot reaches the pose (every component the arm controls, see ``task``).
    within_limits : ndarray of bool, shape (..., k)
        Valid and inside every joint limit. A valid slot beyond a limit stays valid.
    singular : ndarray of bool, shape (..., k)
        A joint value was chosen, not computed (the pose does not fix it: a spherical
        wrist with axes 4 and 6 aligned, a wrist centre on axis 1); the hint's value is
        used there.
    failure, detail : ndarray, shape (..., k)
        Why a slot is empty (:data:`TOO_FAR`, ...) and the number behind it.
    labels : tuple of str
        What each slot is, e.g. ``"shoulder front, elbow up, wrist not flipped"``.
    method : str
        ``"analytic"`` or ``"found numerically"``.
    task : str
        What of the pose the arm controls: ``"pose"``, ``"position and yaw"`` or ``"position"``.
    explain : callable
        ``explain(failure, detail) -> str``, the arm's words for a failure.
    """

    q: np.ndarray
    valid: np.ndarray
    within_limits: np.ndarray
    singular: np.ndarray
    failure: np.ndarray
    detail: np.ndarray
    labels: tuple[str, ...]
    method: str
    task: str
    explain: Callable[[int, float], str]

    @property
    def reachable(self) -> np.ndarray:
        """(...) bool: at least one slot is valid."""
        return self.valid.any(axis=-1)

    def unreachable_reason(self, index: tuple[int, ...] = ()) -> str:
        """Why the pose at ``index`` has no branch, with the numbers; ``""`` if it has one."""
        if self.valid[index].any():
            return ""
        failure, detail = self.failure[index], self.detail[index]
        # the slot that came nearest says most
        order = np.argsort(np.where(failure > 0, detail, np.inf), kind="stable")
        reasons = dict.fromkeys(self.explain(int(failure[k]), float(detail[k])) for k in order if failure[k])
        return "; ".join(reasons) or "no branch reaches this pose"

    def nearest(self, q_current, revolute: np.ndarray | None = None) -> int | np.ndarray:
        """Index of the valid slot nearest ``q_current`` (…, n) in joint space, −1 where none is valid.

        Revolute differences are wrapped to (−π, π]; ``revolute`` (n,) says which joints are.
        """
        q_current = np.asarray(q_current, dtype=float)
        difference = self.q - q_current[..., None, :]
        if revolute is not None:
            difference = np.where(revolute, wrap(difference), difference)
        distance = np.where(self.valid, np.abs(difference).max(axis=-1), np.inf)
        best = np.argmin(distance, axis=-1)
        best = np.where(self.valid.any(axis=-1), best, -1)
        return int(best) if best.ndim == 0 else best


def empty_branches(batch: tuple[int, ...], slots: int, joints: int) -> dict[str, np.ndarray]:
    """Arrays for a BranchSet of ``batch`` poses, every slot invalid."""
    return dict(
        q=np.full(batch + (slots, joints), np.nan),
        valid=np.zeros(batch + (slots,), bool),
        singular=np.zeros(batch + (slots,), bool),
        failure=np.zeros(batch + (slots,), np.int8),
        detail=np.full(batch + (slots,), np.nan),
    )

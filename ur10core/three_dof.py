"""The course's 3-DOF desktop arm: its position map, its Jacobian, and the course's joint path
(docs/kinematics.md §8.6); its statics exercise is ``specs.largest_torque``.

Joint 3 drives the forearm through a parallelogram, so θ3 is the forearm's *absolute* angle,
not its angle to the upper arm. The base frame has **y vertical**. The tool position is

    p = Ry(θ1) · (l1 c3 − l5 c2,  l1 s3 − l5 s2,  0)

and the tool turns as R = Ry(θ1) Rz(θ2), which is what the course's J_ω integrates to:
ω = (s1 θ̇2, θ̇1, c1 θ̇2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ._validate import as_float_array, check_finite, homogeneous_transform
from .branches import TOO_CLOSE, TOO_FAR, IKSolution, empty_branches, wrap
from .solvers.planar import _reach_words, _two_link
from .tolerances import LENGTH_TOLERANCE

if TYPE_CHECKING:
    from .arm import Arm

#: The course's lengths (its simulation's numbers; read here as metres): upper arm l5, forearm l1.
UPPER_ARM, FOREARM = 1.35, 1.28
#: Joint ranges assumed for the statics search (the course gives none): the base turns ±90°, the
#: upper arm ±90° about the horizontal, the forearm 0…180°. They hold the course's path.
LIMITS = np.radians([[-90.0, 90.0], [-90.0, 90.0], [0.0, 180.0]])


def _ry(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(angle), np.ones_like(angle)
    return np.stack([np.stack([c, zero, s], -1), np.stack([zero, one, zero], -1), np.stack([-s, zero, c], -1)], -2)


def _rz(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(angle), np.ones_like(angle)
    return np.stack([np.stack([c, -s, zero], -1), np.stack([s, c, zero], -1), np.stack([zero, zero, one], -1)], -2)


@dataclass(frozen=True)
class DesktopArm:
    """The course's 3-DOF desktop arm's closed forms (docs/kinematics.md §8.6): the solver of
    ``Arm.preset("three_dof")``. It has no DH table: the parallelogram makes θ3 absolute.

    Example: upper arm straight up (θ2 = −90°), forearm level (θ3 = 0): the tool is l1 out, l5 up.

    >>> from ur10core import Arm
    >>> arm = Arm.preset("three_dof")
    >>> arm.fk(np.radians([0, -90, 0]))[:3, 3].round(6).tolist()
    [1.28, 1.35, 0.0]
    """

    upper_arm: float = UPPER_ARM
    forearm: float = FOREARM

    task = "position"
    method = "analytic"
    #: det J_v = −l1 l5 · (l1 c3 − l5 c2) · sin(θ2 − θ3): each factor of :meth:`singularity_factors` as
    #: (name, expression, what makes it zero), as ``ur10core.symbolic_arms`` words the other arms'.
    factor_words = (("reach", "l1 c3 − l5 c2", "the tool is on the base's vertical axis"),
                    ("fold", "sin(θ2 − θ3)", "the upper arm and the forearm are in one line, stretched or folded"))
    det_constant = "−l1 l5"
    #: Its vertical: the course's base frame has y up (every other arm of the core: z).
    up = (0.0, 1.0, 0.0)

    def joints(self, q, name: str = "q") -> np.ndarray:
        q = as_float_array(q, name)
        if q.ndim == 0 or q.shape[-1] != 3:
            raise ValueError(f"{name} must have shape (..., 3) (θ1, θ2, θ3), got shape {q.shape}")
        check_finite(q, name)
        return q


    def _planar(self, q: np.ndarray) -> np.ndarray:
        """(..., 3) the tool in the arm's vertical plane, before the base turns it."""
        reach = self.forearm * np.cos(q[..., 2]) - self.upper_arm * np.cos(q[..., 1])
        height = self.forearm * np.sin(q[..., 2]) - self.upper_arm * np.sin(q[..., 1])
        return np.stack([reach, height, np.zeros_like(reach)], axis=-1)

    def fk(self, q) -> np.ndarray:
        """Base → tool, (..., 4, 4): position p(q) and the orientation R = Ry(θ1) Rz(θ2)."""
        q = self.joints(q)
        T = np.zeros(q.shape[:-1] + (4, 4))
        base = _ry(q[..., 0])
        T[..., :3, :3] = base @ _rz(q[..., 1])
        T[..., :3, 3] = np.einsum("...ij,...j->...i", base, self._planar(q))
        T[..., 3, 3] = 1.0
        return T

    def frames(self, q) -> np.ndarray:
        """(..., 3, 4, 4): the shoulder (base turned by θ1), the elbow and the tool, for drawing."""
        q = self.joints(q)
        base = _ry(q[..., 0])
        elbow = np.einsum("...ij,...j->...i", base, np.stack(
            [-self.upper_arm * np.cos(q[..., 1]), -self.upper_arm * np.sin(q[..., 1]), np.zeros(q.shape[:-1])], -1))
        out = np.zeros(q.shape[:-1] + (3, 4, 4))
        out[..., :, :3, :3] = base[..., None, :, :]
        out[..., 1, :3, 3] = elbow
        out[..., 2, :, :] = self.fk(q)
        out[..., :, 3, 3] = 1.0
        return out

    def jacobian(self, q) -> np.ndarray:
        """The course's J = [J_v; J_ω], (..., 6, 3): J_v = ∂p/∂θ, J_ω = [[0, s1, 0], [1, 0, 0], [0, c1, 0]]."""
        q = self.joints(q)
        s1, c1 = np.sin(q[..., 0]), np.cos(q[..., 0])
        s2, c2 = np.sin(q[..., 1]), np.cos(q[..., 1])
        s3, c3 = np.sin(q[..., 2]), np.cos(q[..., 2])
        reach = self.forearm * c3 - self.upper_arm * c2
        J = np.zeros(q.shape[:-1] + (6, 3))
        # p = (c1·reach, l1 s3 − l5 s2, −s1·reach)
        J[..., 0, 0], J[..., 2, 0] = -s1 * reach, -c1 * reach
        J[..., 0, 1], J[..., 1, 1], J[..., 2, 1] = c1 * self.upper_arm * s2, -self.upper_arm * c2, -s1 * self.upper_arm * s2
        J[..., 0, 2], J[..., 1, 2], J[..., 2, 2] = -c1 * self.forearm * s3, self.forearm * c3, s1 * self.forearm * s3
        J[..., 3, 1], J[..., 4, 0], J[..., 5, 1] = s1, 1.0, c1
        return J

    #: The four slots of :meth:`ik`: the tool in front of the arm's plane (as along the course's path:
    #: the forearm reaching out past the upper arm, −x of the turned plane) or behind it (the base
    #: turned half a turn), the elbow above or below the line from the shoulder to the tool.
    labels = ("in front, elbow above", "in front, elbow below", "behind, elbow above", "behind, elbow below")

    def ik(self, arm: "Arm", T, hint=None) -> IKSolution:
        """Every joint vector that puts the tool at the position of ``T`` (..., 4, 4) (docs/kinematics.md §8.6).

        The base turns the arm's vertical plane: p = Ry(θ1) (r, h, 0). With ρ = √(p_x² + p_z²),
        the tool is in front (r = −ρ, θ1 = atan2(p_z, −p_x)) or behind (r = ρ, θ1 + π). In the plane
        the upper arm points along θ2 + π (its end is −l5 (c2, s2)) and the forearm along
        θ3, the parallelogram's absolute angle: a planar two-link arm of l5 then l1, solved
        with the elbow above or below the shoulder–tool line. 4 slots (:attr:`labels`); only
        the position is matched (``task``). On the vertical axis (ρ = 0) θ1 is free: the
        hint's, or 0, and the slots are marked singular.

        >>> from ur10core import Arm
        >>> arm = Arm.preset("three_dof")
        >>> sol = arm.ik(arm.fk(np.radians([20, -30, 60])))
        >>> np.degrees(sol.q[1]).round(6).tolist(), sol.within_limits.tolist()
        ([20.0, -30.0, 60.0], [False, True, False, False])
        >>> float(np.abs(arm.fk(sol.q)[:, :3, 3] - arm.fk(np.radians([20, -30, 60]))[:3, 3]).max()) < 1e-12
        True
        """
        T = homogeneous_transform(T)
        batch = T.shape[:-2]
        flat = T.reshape(-1, 4, 4)
        n = len(flat)
        if hint is not None:
            hint = np.broadcast_to(self.joints(hint), batch + (3,)).reshape(-1, 3)
        out = empty_branches((n,), 4, 3)
        x, height, z = flat[:, 0, 3], flat[:, 1, 3], flat[:, 2, 3]
        rho = np.hypot(x, z)
        on_axis = rho <= LENGTH_TOLERANCE
        front = np.where(on_axis, 0.0 if hint is None else hint[:, 0], np.arctan2(z, -x))
        for side, (theta1, reach) in enumerate(((front, -rho), (wrap(front + np.pi), rho))):
            for above in (True, False):
                slot = 2 * side + (0 if above else 1)
                # _two_link's "down" puts the elbow below the line where the plane's r axis points at
                # the tool (behind); in front the r axis points away from it, and the sense is mirrored
                upper, bend, too_far, too_close, span = _two_link(reach, height, self.upper_arm, self.forearm,
                                                                  down=above if side == 0 else not above)
                ok = ~(too_far | too_close)
                q = np.stack([theta1, wrap(upper - np.pi), wrap(upper + bend)], axis=-1)
                out["q"][ok, slot] = q[ok]
                out["valid"][:, slot] = ok
                out["singular"][:, slot] = ok & (on_axis | (np.abs(np.sin(bend)) <= 1e-12))
                out["failure"][:, slot] = np.where(too_far, TOO_FAR, np.where(too_close, TOO_CLOSE, 0))
                out["detail"][:, slot] = span
        shape = lambda a, *tail: a.reshape(batch + (4,) + tail)  # noqa: E731
        return IKSolution(shape(out["q"], 3), shape(out["valid"]), shape(out["failure"]), arm,
                          detail=shape(out["detail"]), singular=shape(out["singular"]))

    def explain(self, failure: int, detail: float) -> str:
        return (_reach_words(failure, detail, self.upper_arm, self.forearm, "the tool", "the shoulder")
                or "no branch reaches this position")

    def singularity_factors(self, q) -> np.ndarray:
        """(..., 2) the factors of det J_v = −l1 l5 · (l1 c3 − l5 c2) · sin(θ2 − θ3) (docs/kinematics.md §8.6).

        The first is the tool's distance from the base's vertical axis (m, signed): at zero the
        base turns the tool in place. The second is zero when the upper arm and the forearm lie
        along one line, stretched or folded: then neither can move the tool along that line.

        >>> DesktopArm().singularity_factors(np.radians([0, -90, 0])).round(6).tolist()
        [1.28, -1.0]
        """
        q = self.joints(q)
        reach = self.forearm * np.cos(q[..., 2]) - self.upper_arm * np.cos(q[..., 1])
        return np.stack([reach, np.sin(q[..., 1] - q[..., 2])], axis=-1)


def course_path(t) -> tuple[np.ndarray, np.ndarray]:
    """The course's joint path: q(t) and q̇(t), each (..., 3), for times ``t`` (s).

    θ̇ = (π/6 cos t, π/6 cos t, π/8 cos t), starting from (0, 0, 3π/4): so θ1 = θ2 = (π/6) sin t
    and θ3 = 3π/4 + (π/8) sin t, as the course drives it.
    """
    t = as_float_array(t, "t")
    check_finite(t, "t")
    rates = np.array([math.pi / 6, math.pi / 6, math.pi / 8])
    q = np.array([0.0, 0.0, 3 * math.pi / 4]) + np.sin(t)[..., None] * rates
    return q, np.cos(t)[..., None] * rates

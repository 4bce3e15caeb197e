"""What the Jacobian does: tool velocities, the joint rates a velocity needs, torques for a tool
wrench, and the manipulability ellipsoids (docs/kinematics.md §8).

Every arm of the core (``Arm`` and ``Arm``) has these as methods through
:class:`JacobianUses`, from its own geometric Jacobian ``J(q)`` (6 × n, rows [v; ω], at the
tool origin, in the base frame).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import vectors

#: Below this smallest singular value (of the rows J maps joint rates into, in m/rad or rad/rad)
#: the joint rates are damped (docs/kinematics.md §8.2).
DAMPING_THRESHOLD = 0.01
#: The damping λ at a singularity itself; it fades to zero at :data:`DAMPING_THRESHOLD`.
MAX_DAMPING = 0.02


@dataclass(frozen=True)
class JointRates:
    """Joint rates for a tool twist, and what the damping cost (docs/kinematics.md §8.2).

    Attributes
    ----------
    qdot : ndarray, shape (..., n)
        rad/s for revolute joints, m/s for prismatic ones.
    damping : ndarray, shape (...)
        λ used: 0 away from a singularity.
    achieved : ndarray, shape (..., 6)
        ``J q̇``: the twist the rates really give. It differs from the one asked for where
        damping trades accuracy for bounded rates, or where the arm cannot move that way at all.
    """

    qdot: np.ndarray
    damping: np.ndarray
    achieved: np.ndarray


@dataclass(frozen=True)
class Ellipsoid:
    """The manipulability ellipsoid of one half of J (translation or rotation), docs/kinematics.md §8.4.

    Attributes
    ----------
    axes : ndarray, shape (..., 3, 3)
        Unit principal directions as columns (base frame), longest velocity axis first.
    velocity : ndarray, shape (..., 3)
        Semi-axis lengths of {J q̇ : ‖q̇‖ ≤ 1}: the singular values σ (m/s or rad/s per unit of joint rate).
    force : ndarray, shape (..., 3)
        Semi-axis lengths of {F : ‖Jᵀ F‖ ≤ 1} along the same axes: 1/σ, infinite where σ = 0.
    """

    axes: np.ndarray
    velocity: np.ndarray
    force: np.ndarray


def damping(smallest_singular_value: np.ndarray) -> np.ndarray:
    """λ for a smallest singular value σ_min: 0 from :data:`DAMPING_THRESHOLD` up, growing to
    :data:`MAX_DAMPING` at σ_min = 0 as λ² = (1 − (σ_min/ε)²) λ_max² (docs/kinematics.md §8.2)."""
    share = np.clip(smallest_singular_value / DAMPING_THRESHOLD, 0.0, 1.0)
    return MAX_DAMPING * np.sqrt(1.0 - share**2)


#: The rows of [v; ω] each kind of task controls: a SCARA keeps its tool vertical, a 3-DOF arm places a point.
TASK_ROWS = {"pose": [0, 1, 2, 3, 4, 5], "position and yaw": [0, 1, 2, 5], "position": [0, 1, 2]}


def task_gap(T, T_goal, task: str) -> np.ndarray:
    """How far poses ``T`` are from ``T_goal`` (..., 4, 4) in what a ``task`` controls: the largest difference of an
    entry, shape (...). A SCARA's tool axis is its own: its position and the x, y axes' yaw are compared."""
    difference = np.abs(np.asarray(T, dtype=float) - np.asarray(T_goal, dtype=float))
    if task == "position":
        return difference[..., :3, 3].max(axis=-1)
    if task == "position and yaw":
        return np.maximum(difference[..., :3, 3].max(axis=-1), difference[..., :2, :2].max(axis=(-2, -1)))
    return difference[..., :3, :].max(axis=(-2, -1))


def damped_inverse(J: np.ndarray, twist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q̇, λ): ``Σ σ_k / (σ_k² + λ²) · v_k u_kᵀ twist`` for J (..., m, n) and twist (..., m), λ from :func:`damping`."""
    U, sigma, Vt = np.linalg.svd(J, full_matrices=False)
    lam = damping(sigma[..., -1])
    gain = np.where(sigma > 0.0, sigma / (sigma**2 + lam[..., None] ** 2), 0.0)
    components = np.einsum("...ki,...k->...i", U, twist) * gain
    return np.einsum("...ij,...i->...j", Vt, components), lam


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u × v over the last axis, (..., 3): ``np.cross`` spends most of its time moving axes for three-vectors."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], axis=-1)


#: A singular value of the held rows at most this share of their largest counts as zero (``np.linalg.pinv``'s default).
NULL_SPACE_RCOND = 1e-15
#: An ellipsoid's semi-axis at most this share of its longest is 0 (its force axis ∞): on a singularity, the axis it
#: takes away comes out of the SVD as rounding, 1e-17 to 2e-15 of the longest on the presets' singularity buttons.
FLAT = 1e-12


def _on_null_space(M: np.ndarray, held: np.ndarray) -> np.ndarray:
    """M (..., k, n) acting on the null space of ``held`` (..., m, n) alone, as a (..., k, n) matrix.

    ``M (I − held⁺ held)`` has the singular values and left singular vectors of ``M Vᵀ W``,
    V from held's SVD and W keeping the columns of its null directions (V is orthogonal):
    one SVD instead of a pseudo-inverse, a projector and their products.
    """
    _, sigma, Vt = np.linalg.svd(held, full_matrices=True)
    free = np.ones(sigma.shape[:-1] + (Vt.shape[-1],), dtype=bool)
    free[..., : sigma.shape[-1]] = sigma <= NULL_SPACE_RCOND * sigma[..., :1]
    return (M @ np.swapaxes(Vt, -1, -2)) * free[..., None, :]


def _ellipsoid(J: np.ndarray) -> Ellipsoid:
    """The ellipsoid of J (..., 3, n): left singular vectors, singular values (0 past n, and within rounding of 0) and
    their inverses (∞ where 0: a flat velocity axis, an endless force axis, not 1e-17 and 1e17)."""
    U, sigma, _ = np.linalg.svd(J, full_matrices=J.shape[-1] < 3)  # U (..., 3, 3) either way
    sigma[sigma <= FLAT * sigma[..., :1]] = 0.0  # (the SVD's own array)
    lengths = sigma if sigma.shape[-1] == 3 else np.concatenate(
        [sigma, np.zeros(sigma.shape[:-1] + (3 - sigma.shape[-1],))], axis=-1)
    force = np.divide(1.0, lengths, out=np.full_like(lengths, np.inf), where=lengths > 0.0)
    return Ellipsoid(U, lengths, force)


class JacobianUses:
    """Tool twists, joint rates, static torques and ellipsoids from ``self.jacobian(q)``.

    The class using it has ``jacobian(q) -> (..., 6, n)`` and ``n_joints``.
    """

    def _joints(self, q) -> np.ndarray:
        return vectors(q, "q", self.n_joints)

    def tool_twist(self, q, qdot) -> np.ndarray:
        """The tool's twist (v, ω) in the base frame for joint rates ``qdot``: ``J(q) q̇``, (..., 6).

        docs/kinematics.md §8.1. ``q``, ``qdot``: (..., n), broadcast together; rad and
        rad/s (m and m/s for a prismatic joint). v is the tool origin's velocity (m/s), ω
        the tool's angular velocity (rad/s).

        Example: the course's UR10 turning its base at 1 rad/s with the arm stretched out
        along x moves the flange along y at its distance from the axis.

        >>> import numpy as np
        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> q = np.radians([0, -90, 0, -90, 0, 0])
        >>> v = arm.tool_twist(q, [1, 0, 0, 0, 0, 0])[:3]
        >>> bool(np.isclose(v[1], arm.fk(q)[0, 3]))
        True
        """
        J = self.jacobian(self._joints(q))
        qdot = vectors(qdot, "qdot", self.n_joints)
        return np.einsum("...ij,...j->...i", J, qdot)

    def joint_rates(self, q, twist) -> JointRates:
        """The joint rates that give the tool ``twist`` (v, ω), by a damped pseudo-inverse (docs/kinematics.md §8.2).

        ``q̇ = Σ σ_k / (σ_k² + λ²) · v_k u_kᵀ · twist`` over J's singular triplets: the least-squares
        rates away from a singularity (λ = 0), bounded near one, where λ grows as
        :func:`damping` says from the smallest singular value. An arm that controls less than
        a pose solves only the rows it controls (:data:`TASK_ROWS`: its tool's position, and a
        SCARA's yaw): asking a position-only arm for ω = 0 as well traded the asked v for it.
        ``achieved`` is the whole twist the rates give.

        Parameters
        ----------
        q : array_like, shape (..., n)
        twist : array_like, shape (..., 6)
            (vx, vy, vz) in m/s, (ωx, ωy, ωz) in rad/s, base frame.

        Example: near the wrist singularity a small tool rotation needs fast wrist joints,
        and the damping keeps them bounded.

        >>> import numpy as np
        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> rates = arm.joint_rates(np.radians([0, -60, 80, -110, 0.01, 0]), [0, 0, 0, 0.1, 0, 0])
        >>> float(rates.damping) > 0 and bool(np.abs(rates.qdot).max() < 100)
        True
        """
        J = self.jacobian(self._joints(q))
        twist = vectors(twist, "twist", 6)
        J = np.broadcast_to(J, np.broadcast_shapes(J.shape[:-2], twist.shape[:-1]) + J.shape[-2:])
        rows = TASK_ROWS[getattr(self, "task", "pose")]
        qdot, lam = damped_inverse(J, twist) if len(rows) == 6 else damped_inverse(J[..., rows, :], twist[..., rows])
        return JointRates(qdot, lam, np.einsum("...ij,...j->...i", J, qdot))

    def static_torques(self, q, force, moment=(0.0, 0.0, 0.0)) -> np.ndarray:
        """The joint torques that hold a wrench at the tool: ``τ = Jᵀ [F; M]``, (..., n) (docs/kinematics.md §8.3).

        ``force`` (N) and ``moment`` (N·m) are what the tool must exert on its surroundings,
        in the base frame; τ is in N·m (N for a prismatic joint), the torques the joints
        must supply. By virtual work, τ · q̇ equals the power [F; M] · J q̇ for any rates.

        Example: pushing down with 100 N at the stretched UR10's flange loads the shoulder
        with 100 N times the flange's horizontal distance from the shoulder axis.

        >>> import numpy as np
        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> q = np.radians([0, -90, 0, -90, 0, 0])
        >>> tau = arm.static_torques(q, [0, 0, -100])
        >>> bool(np.isclose(abs(tau[1]), 100 * arm.fk(q)[0, 3]))
        True
        """
        J = self.jacobian(self._joints(q))
        wrench = np.concatenate(np.broadcast_arrays(vectors(force, "force", 3), vectors(moment, "moment", 3)), axis=-1)
        return np.einsum("...ij,...i->...j", J, wrench)

    def ellipsoids(self, q) -> tuple[Ellipsoid, Ellipsoid]:
        """The translational and rotational manipulability ellipsoids at the tool (docs/kinematics.md §8.4).

        Velocity ellipsoid: the tool velocities of unit-norm joint rates, {J_v q̇ : ‖q̇‖ ≤ 1},
        whose semi-axes are the singular values σ of the map along its left singular vectors.
        Force ellipsoid: the forces the joints hold with unit-norm torques, the same axes with
        lengths 1/σ. An arm that controls its tool's whole pose keeps the other half still:
        the translational ellipsoid is that of the rates that do not turn the tool (J_v on the
        null space of J_ω), the rotational one that of the rates that do not move it. So at
        every singularity one of them flattens (the lost twist direction) and its force
        ellipsoid stretches without bound; a wrist can no longer hide it by swinging the
        flange. A SCARA keeps its yaw for the translational one; a positioning arm has J_v as it is.

        Example: the course's planar elbow arm cannot move its tool along z.

        >>> import numpy as np
        >>> from ur10core import Arm
        >>> translation, _ = Arm.preset("planar_elbow").ellipsoids(np.radians([30, 60]))
        >>> float(translation.velocity[-1]), bool(np.isinf(translation.force[-1]))
        (0.0, True)
        """
        J = self.jacobian(self._joints(q))
        return self._translation(J), self._rotation(J)

    def translation_ellipsoid(self, q) -> Ellipsoid:
        """The translational half of :meth:`ellipsoids` alone (what the app draws at the flange, on every drag)."""
        return self._translation(self.jacobian(self._joints(q)))

    def _translation(self, J: np.ndarray) -> Ellipsoid:
        task = getattr(self, "task", "pose")
        held = {"pose": J[..., 3:, :], "position and yaw": J[..., 5:, :]}.get(task)
        return _ellipsoid(J[..., :3, :] if held is None else _on_null_space(J[..., :3, :], held))

    def _rotation(self, J: np.ndarray) -> Ellipsoid:
        held = J[..., :3, :] if getattr(self, "task", "pose") == "pose" else None
        return _ellipsoid(J[..., 3:, :] if held is None else _on_null_space(J[..., 3:, :], held))

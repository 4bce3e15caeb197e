"""Any serial arm from its DH table, with the course's other arms as presets (docs/kinematics.md §7).

:class:`SerialArm` answers what :class:`ur10core.Arm` answers for the UR family — FK,
frames, Jacobian, IK with every branch in a labelled slot, workspace samples — for any
chain: the course's KR210 and Stanford arm, the lecture notes' SCARA, elbow arm, planar
elbow and cylindrical arm, and any table a student types (:meth:`SerialArm.from_dh`, with
the numerical IK). ``Arm.preset(name)`` returns one of these for the non-UR names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import homogeneous_transform
from .branches import BranchSet, wrap
from .differential import TASK_ROWS, JacobianUses
from .specs import HasSpecs
from .dh import MODIFIED, PRISMATIC, REVOLUTE, STANDARD, DHRow, DHTable
from .solvers.numerical import NumericalIK, sampling_range
from .solvers.planar import Cylindrical, PlanarElbow, Scara
from .solvers.spherical_wrist import ArticulatedArm, StanfordArm

_PI = math.pi
_DEG = math.pi / 180


@dataclass(frozen=True)
class _Preset:
    description: str
    rows: tuple
    convention: str
    limits: tuple  # (low, high) per joint: radians or metres
    solver: type
    joint_names: tuple[str, ...]


#: The rows of J [v; ω] that each task controls.


def _degrees(*pairs) -> tuple:
    return tuple((low * _DEG, high * _DEG) for low, high in pairs)


#: docs/kinematics.md §7.5: where each number comes from.
PRESETS: dict[str, _Preset] = {
    "kr210": _Preset(
        "KUKA KR210 (the course's pick-and-place report): spherical wrist, gripper frame G",
        ((0, 0, 0.75, 0, "R"), (0.35, -_PI / 2, 0, -_PI / 2, "R"), (1.25, 0, 0, 0, "R"),
         (-0.054, -_PI / 2, 1.50, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, -_PI / 2, 0, 0, "R"),
         (0, 0, 0.303, 0, None)),
        MODIFIED, _degrees((-185, 185), (-45, 85), (-210, 65), (-350, 350), (-125, 125), (-350, 350)),
        ArticulatedArm, ("A1", "A2", "A3", "A4", "A5", "A6")),
    "stanford": _Preset(
        "Stanford arm (the course's MATLAB GUI report): RRP + spherical wrist, d2 = 6.375 in",
        ((0, -_PI / 2, 0, 0, "R"), (0, _PI / 2, 0.161925, 0, "R"), (0, 0, 0, 0, "P"),
         (0, -_PI / 2, 0, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, 0, 0, 0, "R")),
        STANDARD, _degrees((-170, 170), (-170, 170)) + ((0.0, 0.762),) + _degrees((-170, 170), (-90, 90), (-170, 170)),
        StanfordArm, ("θ1", "θ2", "d3", "θ4", "θ5", "θ6")),
    "elbow": _Preset(
        "Articulated (elbow) arm with a spherical wrist, as in the DH lecture notes",
        ((0, _PI / 2, 0.6, 0, "R"), (0.5, 0, 0, 0, "R"), (0, _PI / 2, 0, 0, "R"),
         (0, -_PI / 2, 0.45, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, 0, 0.1, 0, "R")),
        STANDARD, _degrees((-170, 170), (-90, 150), (-150, 150), (-180, 180), (-120, 120), (-180, 180)),
        ArticulatedArm, ("θ1", "θ2", "θ3", "θ4", "θ5", "θ6")),
    "scara": _Preset(
        "SCARA (RRP + roll), the numbers of an Omron/Adept Cobra 600",
        ((0.325, 0, 0.387, 0, "R"), (0.275, _PI, 0, 0, "R"), (0, 0, 0, 0, "P"), (0, 0, 0, 0, "R")),
        STANDARD, _degrees((-105, 105), (-157.5, 157.5)) + ((0.0, 0.21),) + _degrees((-360, 360)),
        Scara, ("θ1", "θ2", "d3", "θ4")),
    "planar_elbow": _Preset(
        "Two-link planar elbow (RR), links 0.5 m and 0.4 m",
        ((0.5, 0, 0, 0, "R"), (0.4, 0, 0, 0, "R")),
        STANDARD, _degrees((-180, 180), (-180, 180)),
        PlanarElbow, ("θ1", "θ2")),
    "cylindrical": _Preset(
        "Three-link cylindrical arm (RPP): base column 0.3 m, lift d2, reach d3",
        ((0, 0, 0.3, 0, "R"), (0, -_PI / 2, 0, 0, "P"), (0, 0, 0, 0, "P")),
        STANDARD, _degrees((-180, 180)) + ((0.0, 0.7), (0.1, 0.6)),
        Cylindrical, ("θ1", "d2", "d3")),
}


class SerialArm(JacobianUses, HasSpecs):
    """A serial arm: its DH table, joint limits and an IK solver (analytic or numerical).

    Parameters
    ----------
    table : DHTable
    limits : array_like, shape (n, 2)
        (low, high) per joint, radians or metres.
    solver : object, optional
        An analytic solver built on ``table`` (:mod:`ur10core.solvers`); default the
        numerical one.
    name, description : str
    joint_names : sequence of str, optional

    Example
    -------
    >>> arm = SerialArm.preset("kr210")
    >>> (arm.fk(np.zeros(6))[:3, 3] * 1000).round(1).tolist()   # the gripper at the zero pose
    [2153.0, 0.0, 1946.0]
    >>> q = np.radians([10, 20, -30, 40, 50, 60])
    >>> sol = arm.ik(arm.fk(q))
    >>> int(sol.valid.sum()), int(sol.within_limits.sum())   # turned back, the shoulder cannot reach
    (4, 2)
    >>> k = sol.nearest(q, arm.revolute)
    >>> sol.labels[k], np.degrees(sol.q[k]).round(6).tolist()
    ('shoulder front, elbow up, wrist not flipped', [10.0, 20.0, -30.0, 40.0, 50.0, 60.0])
    """

    def __init__(self, table: DHTable, limits, solver=None, name: str = "custom", description: str = "",
                 joint_names=None) -> None:
        self.dh = table
        self.name = name
        self.description = description or f"custom arm ({table.joint_types}, {table.convention} DH)"
        limits = np.array(limits, dtype=float)
        if limits.shape != (table.n_joints, 2) or not np.isfinite(limits).all() or (limits[:, 0] > limits[:, 1]).any():
            raise ValueError(f"limits must be {table.n_joints} finite (low, high) pairs with low ≤ high, got {limits.tolist()}")
        self.limits = limits
        self.joint_names = tuple(joint_names or (f"joint {k + 1}" for k in range(table.n_joints)))
        self.solver = solver if solver is not None else NumericalIK(table, limits)
        self.revolute = np.array([t == REVOLUTE for t in table.joint_types])

    def __repr__(self) -> str:
        return f"SerialArm({self.name!r}, {self.dh!r})"

    # ------------------------------------------------------------------ construction

    PRESETS = tuple(PRESETS)

    @classmethod
    def preset(cls, name: str) -> "SerialArm":
        """One of :data:`PRESETS` (docs/kinematics.md §7.5), with its analytic IK."""
        try:
            spec = PRESETS[name]
        except KeyError:
            raise ValueError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}") from None
        table = DHTable(spec.rows, spec.convention)
        return cls(table, spec.limits, spec.solver(table), name, spec.description, spec.joint_names)

    @classmethod
    def from_dh(cls, rows, convention: str = STANDARD, joint_types: str | None = None, limits=None,
                name: str = "custom") -> "SerialArm":
        """An arm from a DH table a student types; its IK is the numerical one.

        Parameters
        ----------
        rows : sequence of (a, alpha, d, theta) or (a, alpha, d, theta, joint)
            Metres and radians; ``theta`` (revolute) or ``d`` (prismatic) is the joint's
            offset. In the modified convention ``a``, ``alpha`` are a_{i-1}, α_{i-1}.
        convention : ``"standard"`` or ``"modified"``
        joint_types : str, optional
            One letter per row: ``R`` revolute, ``P`` prismatic, ``F`` fixed. Default: all R
            (or each row's fifth entry).
        limits : array_like (n, 2), optional
            Default ±π for revolute joints, 0…1 m for prismatic ones.

        >>> arm = SerialArm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR")
        >>> arm.ik(arm.fk(np.radians([30, 60]))).method
        'found numerically'
        """
        rows = list(rows)
        if joint_types is not None:
            if not isinstance(joint_types, str) or len(joint_types) != len(rows) or set(joint_types.upper()) - set("RPF"):
                raise ValueError(f"joint_types must be one letter R, P or F per row ({len(rows)} rows), got {joint_types!r}")
            parsed = []
            for k, (row, kind) in enumerate(zip(rows, joint_types.upper())):
                values = tuple(row)
                if len(values) not in (4, 5):
                    raise ValueError(f"DH row {k + 1} must be (a, alpha, d, theta), got {row!r:.80}")
                parsed.append(values[:4] + ({"R": REVOLUTE, "P": PRISMATIC, "F": None}[kind],))
            rows = parsed
        else:
            rows = [tuple(row) + (REVOLUTE,) if len(tuple(row)) == 4 else tuple(row) for row in rows]
        table = DHTable(rows, convention)
        if limits is None:
            limits = [(-_PI, _PI) if t == REVOLUTE else (0.0, 1.0) for t in table.joint_types]
        return cls(table, limits, None, name)

    # ------------------------------------------------------------------ what it is

    @property
    def n_joints(self) -> int:
        return self.dh.n_joints

    @property
    def joint_types(self) -> str:
        """``"R"`` / ``"P"`` per joint, e.g. ``"RRPRRR"``."""
        return self.dh.joint_types

    @property
    def convention(self) -> str:
        return self.dh.convention

    @property
    def task(self) -> str:
        """What of a pose the arm controls: ``"pose"``, ``"position and yaw"`` or ``"position"``."""
        return self.solver.task

    @property
    def slot_labels(self) -> tuple[str, ...]:
        return self.solver.labels

    # ------------------------------------------------------------------ kinematics

    def fk(self, q) -> np.ndarray:
        """Base → tool pose (the last row of the table), (..., 4, 4)."""
        return self.dh.fk(q)

    def frames(self, q) -> np.ndarray:
        """Every row's frame in the base frame, (..., rows + 1, 4, 4)."""
        return self.dh.frames(q)

    def jacobian(self, q) -> np.ndarray:
        """Geometric Jacobian at the tool origin, base frame, (..., 6, n), rows [v; ω]."""
        return self.dh.jacobian(q)

    def within_limits(self, q) -> np.ndarray:
        """(...) bool: every joint inside its limits (revolute joints also one turn either way)."""
        q = self.dh.joints(q)
        inside = (q >= self.limits[:, 0]) & (q <= self.limits[:, 1])
        turned = np.where(self.revolute, (q + 2 * _PI >= self.limits[:, 0]) & (q + 2 * _PI <= self.limits[:, 1])
                          | (q - 2 * _PI >= self.limits[:, 0]) & (q - 2 * _PI <= self.limits[:, 1]), False)
        return (inside | turned).all(axis=-1)

    def ik(self, T, hint=None) -> BranchSet:
        """Every IK branch of base → tool poses, in fixed labelled slots (docs/kinematics.md §7.3).

        Parameters
        ----------
        T : array_like, shape (..., 4, 4)
            Poses (metres). Only what the arm controls is matched (:attr:`task`).
        hint : array_like, shape (..., n), optional
            The current joints: where the pose leaves a joint free (a singular wrist, a
            wrist centre on axis 1), the hint's value is kept; the numerical IK starts there.

        Returns
        -------
        BranchSet
            ``q`` (..., k, n), ``valid``, ``within_limits``, labels, and why empty slots are empty.
        """
        T = homogeneous_transform(T)
        batch = T.shape[:-2]
        if hint is not None:
            hint = self.dh.joints(hint, "hint")
            try:
                batch = np.broadcast_shapes(batch, hint.shape[:-1])
            except ValueError:
                raise ValueError(f"hint of shape {hint.shape} does not broadcast against poses of shape {T.shape}") from None
            hint = np.broadcast_to(hint, batch + (self.n_joints,)).reshape(-1, self.n_joints)
        flat = np.ascontiguousarray(np.broadcast_to(T, batch + (4, 4)).reshape(-1, 4, 4))
        out = self.solver.solve(flat, hint)
        q, valid = out["q"], out["valid"]
        inside = valid & self.within_limits(np.where(valid[..., None], q, 0.0))
        slots = q.shape[1]
        shape = lambda a, *tail: a.reshape(batch + (slots,) + tail)  # noqa: E731
        return BranchSet(
            q=shape(q, self.n_joints), valid=shape(valid), within_limits=shape(inside),
            singular=shape(out["singular"]), failure=shape(out["failure"]), detail=shape(out["detail"]),
            labels=tuple(self.solver.labels), method=getattr(self.solver, "method", "analytic"),
            task=self.task, explain=self.solver.explain,
        )

    def pose_error(self, q, T) -> np.ndarray:
        """How far FK(q) is from ``T`` in what the arm controls (max abs entry), shape (...)."""
        difference = np.abs(self.fk(q) - np.asarray(T, dtype=float))
        if self.task == "position":
            return difference[..., :3, 3].max(axis=-1)
        if self.task == "position and yaw":  # the tool axis is the arm's own: compare p and x, y axes' yaw
            return np.maximum(difference[..., :3, 3].max(axis=-1), difference[..., :2, :2].max(axis=(-2, -1)))
        return difference[..., :3, :].max(axis=(-2, -1))

    # ------------------------------------------------------------------ singularities

    def singularity_factors(self, q) -> np.ndarray:
        """The factors of det J at joints ``q`` (..., n), shape (..., k) (docs/kinematics.md §7.6).

        ``det J`` is a constant times their product; each is zero on one singularity, named
        with its meaning in ``ur10core.symbolic_arms.load(name).factors``. Presets only.
        """
        from . import symbolic_arms

        if self.name not in PRESETS:
            raise ValueError(f"{self.name!r} has no derived factors (a custom table): use smallest_singular_value or manipulability")
        return symbolic_arms.load(self.name).evaluate(self.dh.joints(q))

    def wrist_centre(self, q) -> np.ndarray:
        """The point nearest the last three joint axes at joints ``q`` (..., n), shape (..., 3).

        For a spherical wrist (the KR210, the elbow arm, the Stanford arm) the three axes meet
        there: it is the wrist centre Pieper's decoupling solves for (docs/kinematics.md §7.3),
        and the point the shoulder and elbow singularities are about (§7.6). ``ValueError``
        for an arm whose last three joints are not all revolute.

        Example: the Stanford arm's d6 = 0 puts its tool frame at the wrist centre.

        >>> arm = SerialArm.preset("stanford")
        >>> q = np.array([0.3, 1.0, 0.4, 0.2, 0.5, 0.1])
        >>> bool(np.allclose(arm.wrist_centre(q), arm.fk(q)[:3, 3]))
        True
        """
        if self.n_joints < 3 or self.joint_types[-3:] != "RRR":
            raise ValueError(f"{self.name!r} has no wrist of three revolute joints: no wrist centre")
        z, o = self.dh.joint_axes(self.frames(q))
        z, o = z[..., -3:, :], o[..., -3:, :]
        # least squares: Σ (I − z zᵀ)(c − o) = 0 over the three axes
        projector = np.eye(3) - z[..., :, None] * z[..., None, :]
        A = projector.sum(axis=-3)
        b = (projector @ o[..., None]).sum(axis=-3)
        return np.linalg.solve(A, b)[..., 0]

    def gravity_torques(self, q, payload_kg: float = 0.0) -> np.ndarray:
        """Gravity loads need link masses: the course gives them for the UR10 only (``ValueError`` here)."""
        from . import dynamics

        dynamics.link_masses(self)  # raises, naming the arms that have them
        raise AssertionError("unreachable")  # pragma: no cover

    def smallest_singular_value(self, q) -> np.ndarray:
        """σ_min of the rows of J the arm controls, shape (...): how close to losing a direction."""
        J = self.jacobian(q)[..., TASK_ROWS[self.task], :]
        return np.linalg.svd(J, compute_uv=False)[..., -1]

    # ------------------------------------------------------------------ workspace

    def manipulability(self, q) -> np.ndarray:
        """Yoshikawa's measure ``sqrt(det(J_t J_tᵀ))`` over the rows the arm controls, shape (...).

        For a square J (six joints, or a SCARA's four) it is |det J|; it is zero exactly at a singularity.
        """
        J = self.jacobian(q)[..., TASK_ROWS[self.task], :]
        if J.shape[-2] == J.shape[-1]:  # as accurate as det J itself (the square root would lift rounding to ~1e-10)
            return np.abs(np.linalg.det(J))
        if J.shape[-2] > J.shape[-1]:  # fewer joints than task rows: the measure of Jᵀ J
            J = np.swapaxes(J, -1, -2)
        return np.sqrt(np.clip(np.linalg.det(J @ np.swapaxes(J, -1, -2)), 0.0, None))

    def sample_joints(self, n: int, seed: int = 0) -> np.ndarray:
        """``n`` joint vectors drawn uniformly within the limits, (n, n_joints).

        The joints behind :meth:`sample_workspace`'s cloud, without its forward kinematics:
        the same ``n`` and ``seed`` give the same vectors.
        """
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"n must be a positive integer number of samples, got {n!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        low, high = sampling_range(self.limits, self.revolute)
        return np.random.default_rng(int(seed)).uniform(low, high, (int(n), self.n_joints))

    def sample_workspace(self, n: int, seed: int = 0, return_joints: bool = False):
        """Tool positions of ``n`` joint vectors drawn uniformly within the limits, and their manipulability.

        Returns points (n, 3) in metres, manipulability (n,) and, with ``return_joints``,
        the joints (n, n_joints) (:meth:`sample_joints`). The same ``n`` and ``seed`` give the same cloud.
        """
        q = self.sample_joints(n, seed)
        points = np.empty((int(n), 3))
        manipulability = np.empty(int(n))
        for start in range(0, int(n), 65536):
            block = q[start:start + 65536]
            frames = self.dh.frames(block)
            points[start:start + len(block)] = frames[:, -1, :3, 3]
            manipulability[start:start + len(block)] = self.manipulability(block)
        if return_joints:
            return points, manipulability, q
        return points, manipulability


#: docs/kinematics.md §7.5: the KR210 simulation model (URDF, ROS/Gazebo) puts its gripper frame
#: differently: R_DH = R_URDF · Rz(π) · Ry(−π/2). The URDF frame's x axis is the DH frame's z (the approach).
KR210_URDF_TURN = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
    [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def kr210_from_urdf(T) -> np.ndarray:
    """A KR210 gripper pose read in the URDF (ROS/Gazebo) convention, as the DH table's G frame, (..., 4, 4).

    >>> T = kr210_from_urdf(np.eye(4))
    >>> T[:3, 2].tolist()   # the DH approach axis z_G is the URDF's x
    [1.0, 0.0, 0.0]
    """
    T = homogeneous_transform(T).copy()
    T[..., :3, :3] = T[..., :3, :3] @ KR210_URDF_TURN
    return T


def kr210_to_urdf(T) -> np.ndarray:
    """The inverse of :func:`kr210_from_urdf`: a DH gripper pose in the URDF convention, (..., 4, 4)."""
    T = homogeneous_transform(T).copy()
    T[..., :3, :3] = T[..., :3, :3] @ KR210_URDF_TURN.T
    return T


__all__ = ["DHRow", "DHTable", "KR210_URDF_TURN", "PRESETS", "SerialArm", "kr210_from_urdf", "kr210_to_urdf", "wrap"]


def project_target(arm, T, current) -> np.ndarray:
    """The part of a target pose ``T`` (4, 4) the arm can follow (``arm.task``), the rest from its
    own tool pose ``current`` (4, 4).

    A SCARA keeps its tool pointing down and takes only the target's yaw; an arm that places
    only a position keeps its own orientation; the planar elbow stays in its plane z = 0
    (docs/kinematics.md §7.5).
    """
    out = np.array(T, dtype=float)
    if out.shape != (4, 4) or not np.isfinite(out).all():
        raise ValueError(f"T must be one finite 4 × 4 pose, got shape {out.shape}")
    if arm.task == "position and yaw":
        yaw = math.atan2(out[1, 0], out[0, 0])
        c, s = math.cos(yaw), math.sin(yaw)
        out[:3, :3] = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])  # Rz(yaw) Rx(π)
    elif arm.task == "position":
        out[:3, :3] = np.asarray(current, dtype=float)[:3, :3]
        if arm.name == "planar_elbow":
            out[2, 3] = 0.0
    return out

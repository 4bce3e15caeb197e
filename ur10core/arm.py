"""One model of a serial arm: its table, limits and physical data, and its family's IK solver.

Every arm of the course is an :class:`Arm` (docs/kinematics.md §2, §7, §8.6): the UR10 and
its kin (``"course"``, ``"ur10"``, ``"ur10e"``), the KUKA KR210, the Stanford arm, the elbow
arm, the SCARA, the planar elbow, the cylindrical arm (alone and with a spherical wrist),
the 3-DOF desktop arm, and any DH table a student types (:meth:`Arm.from_dh`). What differs
between them is their *solver* (``arm.solver``, :mod:`ur10core.solvers`): the UR family's
kernels, Pieper's decoupling, the planar closed forms, the desktop arm's closed form, or the
numerical search. A solver may also supply faster closed forms of the arm's FK, frames,
Jacobian, det J factors and workspace samples; the arm uses them where it has them and its
DH table otherwise. Every arm's :meth:`Arm.ik` returns an
:class:`ur10core.branches.IKSolution`.

Units are metres and radians. Every method accepts any leading batch shape ``...``.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math

import numpy as np

from .branches import IKSolution, keep_free_values_within_limits
from .dh import PRISMATIC, REVOLUTE, STANDARD, DHTable
from .differential import FLAT, TASK_ROWS, JacobianUses, task_gap
from .specs import HasSpecs
from .solvers.numerical import NumericalIK, reach_bound, sampling_range, settle_on_limits, within_limits
from .serial import PRESETS as COURSE_ARMS
from .solvers.ur import DESCRIPTIONS, DH_ALPHA, JOINT_LIMIT, JOINT_NAMES, LENGTHS, SingularityGeometry, URFamily
from .workspace import sample_horizontal_section, tool_heights
from ._validate import homogeneous_transform, poses_and_hints, sample_size

__all__ = ["Arm", "DH_ALPHA", "JOINT_LIMIT", "JOINT_NAMES", "SingularityGeometry", "factor_scales"]

_PI = math.pi
#: The UR family's presets (:class:`ur10core.solvers.ur.URFamily`).
UR_PRESETS = tuple(LENGTHS)
#: Every preset: the UR family, the course's other arms (docs/kinematics.md §7.5), the desktop arm (§8.6).
PRESETS = (*UR_PRESETS, *COURSE_ARMS, "three_dof")


class Arm(JacobianUses, HasSpecs):
    """A serial arm: its DH table, joint types and limits, named poses and physical data, and its IK solver.

    Parameters
    ----------
    table : DHTable or None
        The arm's DH table (either convention). ``None`` only for an arm whose solver
        supplies its geometry (the desktop arm's parallelogram has no DH table).
    limits : array_like, shape (n, 2)
        (low, high) per joint, radians or metres.
    solver : object, optional
        The family's IK (:mod:`ur10core.solvers`); default the numerical one.
    name, description : str
    joint_names : sequence of str, optional
    joint_types : str, optional
        ``"R"``/``"P"`` per joint, needed only without a table.

    Its named poses and published numbers are :attr:`specs` (:mod:`ur10core.specs`); its
    link masses, where known, ``dynamics.link_masses(arm)``. What only one family has (the
    UR's lengths ``arm.d4`` and singularity geometry, the desktop arm's ``upper_arm``) is
    its solver's, reached through the arm as ``arm.solver.d4`` or simply ``arm.d4``.

    Example
    -------
    >>> arm = Arm.preset("course")
    >>> (arm.fk([0, 0, 0, 0, 0, 0])[:3, 3] * 1000).round(1).tolist()   # docs/kinematics.md §3
    [1184.5, -256.1, 243.7]
    >>> arm = Arm.preset("kr210")
    >>> q = np.radians([10, 20, -30, 40, 50, 60])
    >>> sol = arm.ik(arm.fk(q))
    >>> int(sol.valid.sum()), int(sol.within_limits.sum())   # turned back, the shoulder cannot reach
    (4, 2)
    >>> branch = sol.nearest(q)
    >>> sol.labels[branch.slot], np.degrees(branch.q).round(6).tolist()
    ('shoulder front, elbow up, wrist not flipped', [10.0, 20.0, -30.0, 40.0, 50.0, 60.0])
    """

    def __init__(self, table: DHTable | None, limits, solver=None, name: str = "custom", description: str = "",
                 joint_names=None, joint_types: str | None = None) -> None:
        if table is None and (solver is None or joint_types is None or not hasattr(solver, "fk")):
            raise ValueError("an arm without a DH table needs a solver that gives its FK, and its joint types")
        self.dh = table
        self.solver = solver if solver is not None else NumericalIK(table, limits)
        self.joint_types = table.joint_types if table is not None else joint_types
        n = len(self.joint_types)
        self.name = name
        self.description = description or f"custom arm ({self.joint_types}, {table.convention} DH)"
        limits = np.array(limits, dtype=float)
        if limits.shape != (n, 2) or not np.isfinite(limits).all() or (limits[:, 0] > limits[:, 1]).any():
            raise ValueError(f"limits must be {n} finite (low, high) pairs with low ≤ high, got {limits.tolist()}")
        self.limits = limits
        self.joint_names = tuple(joint_names or (f"joint {k + 1}" for k in range(n)))
        self.revolute = np.array([t == REVOLUTE for t in self.joint_types])
        # the solver's closed forms where it has them (the UR10's drag path), else the table's
        self._geometry = self.solver if hasattr(self.solver, "fk") else table
        self._own_ik = getattr(self.solver, "ik", None)
        self._own_factors = getattr(self.solver, "singularity_factors", None)
        # a joint's range narrower than a turn can leave the hint's value of a free joint beyond a limit (a closed
        # form's only; the numerical search keeps within them itself)
        self._free_values_meet_limits = not isinstance(self.solver, NumericalIK) and bool(
            (~self.revolute | (self.limits[:, 1] - self.limits[:, 0] < 2 * _PI)).any())
        # the UR family's kernels, whose joints turn two turns: called straight from ik, the drag's one-pose path
        self._straight_ik = None if self._free_values_meet_limits else self._own_ik
        self._identity = self._key()  # arms are keys of caches: compared and hashed often
        # the drag path calls these hundreds of times a second: straight to the closed form, not through a method here
        self.fk, self.frames, self.jacobian = self._geometry.fk, self._geometry.frames, self._geometry.jacobian

    def __getattr__(self, name: str):
        """What only this arm's family has (``arm.d4``, ``arm.singularity_geometry(q)``): its solver's."""
        if name.startswith("_") or name in ("solver", "dh", "name"):
            raise AttributeError(name)
        try:
            found = getattr(self.solver, name)
        except AttributeError:
            raise AttributeError(f"{self.name!r} arm ({type(self.solver).__name__}) has no {name!r}") from None
        setattr(self, name, found)  # the solver does not change: found once, then an attribute of the arm
        return found

    def _key(self) -> tuple:
        table = None if self.dh is None else (self.dh.convention, tuple(self.dh.rows))
        # a family of lengths compares by them; any other solver is made from the table and the limits
        solver = self.solver if dataclasses.is_dataclass(self.solver) else type(self.solver).__name__
        return (self.name, table, self.joint_types, self.limits.tobytes(), solver)

    def __eq__(self, other) -> bool:
        return isinstance(other, Arm) and self._identity == other._identity

    def __hash__(self) -> int:
        return hash(self._identity)

    def __repr__(self) -> str:
        return f"Arm({self.name!r}, {type(self.solver).__name__}, {self.joint_types})"

    # ------------------------------------------------------------------ construction

    PRESETS = PRESETS
    UR_PRESETS = UR_PRESETS

    @classmethod
    def preset(cls, name: str) -> "Arm":
        """``"course"`` (docs/kinematics.md §2), ``"ur10"``, ``"ur10e"``, the course's other arms
        (``"kr210"``, ``"stanford"``, ``"elbow"``, ``"scara"``, ``"planar_elbow"``, ``"cylindrical"``,
        ``"cylindrical_wrist"``, §7.5) or its 3-DOF desktop arm (``"three_dof"``, §8.6), each with its
        analytic IK."""
        if name in LENGTHS:
            return cls.ur_family(name=name, **LENGTHS[name])
        if name in COURSE_ARMS:
            spec = COURSE_ARMS[name]
            table = DHTable(spec.rows, spec.convention)
            return cls(table, spec.limits, spec.solver(table), name, spec.description, spec.joint_names)
        if name == "three_dof":
            from .three_dof import LIMITS, DesktopArm

            return cls(None, LIMITS, DesktopArm(), "three_dof",
                       "the course's 3-DOF desktop arm (parallelogram forearm, y vertical)",
                       ("θ1 base", "θ2 upper arm", "θ3 forearm"), "RRR")
        raise ValueError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")

    @classmethod
    def ur_family(cls, d1: float, a2: float, a3: float, d4: float, d5: float, d6: float, name: str = "custom") -> "Arm":
        """A UR-type 6R arm with the course's DH structure (docs/kinematics.md §2) and these lengths (m)."""
        family = URFamily(d1, a2, a3, d4, d5, d6)
        limits = np.tile([-JOINT_LIMIT, JOINT_LIMIT], (6, 1))
        return cls(family.table(), limits, family, name, DESCRIPTIONS.get(name, "UR-type 6R arm"), JOINT_NAMES)

    @classmethod
    def from_dh(cls, rows, convention: str = STANDARD, joint_types: str | None = None, limits=None,
                name: str = "custom") -> "Arm":
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

        >>> arm = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR")
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
        return len(self.joint_types)

    @property
    def convention(self) -> str | None:
        return None if self.dh is None else self.dh.convention

    @property
    def task(self) -> str:
        """What of a pose the arm controls: ``"pose"``, ``"position and yaw"`` or ``"position"``."""
        return self.solver.task

    @property
    def slot_labels(self) -> tuple[str, ...]:
        return self.solver.labels

    @property
    def numerical(self) -> bool:
        """Its IK is the numerical search (a typed table), not a closed form."""
        return isinstance(self.solver, NumericalIK)

    @property
    def planar(self) -> bool:
        """Its tool moves in one plane square to z0: revolute joints only, each axis parallel to z0 (every α
        a multiple of 180°), as the course's planar elbow (docs/kinematics.md §7.5).

        >>> Arm.preset("planar_elbow").planar, Arm.preset("scara").planar, Arm.preset("ur10").planar
        (True, False, False)
        """
        return self.dh is not None and all(row.joint != PRISMATIC and abs(math.sin(row.alpha)) < 1e-12
                                           for row in self.dh.rows)

    @property
    def up(self) -> tuple[float, float, float]:
        """Its vertical in the base frame: z, or y for the course's desktop arm."""
        return getattr(self.solver, "up", (0.0, 0.0, 1.0))

    @property
    def upright(self) -> np.ndarray:
        """(3, 3) the rotation from its base frame to one whose z is its vertical (:attr:`up`): the identity, or
        for the desktop arm the turn of +90° about x that takes its y to z (and its z to −y).

        >>> Arm.preset("three_dof").upright @ Arm.preset("three_dof").up
        array([0., 0., 1.])
        """
        if tuple(self.up) == (0.0, 0.0, 1.0):
            return np.eye(3)
        if tuple(self.up) == (0.0, 1.0, 0.0):
            return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
        raise ValueError(f"no upright frame for an arm whose vertical is {self.up}")  # (no arm has another)

    @functools.cached_property
    def reach_bound(self) -> float:
        """An upper bound on the tool's distance from the base (m), whatever the joints: the table's lengths laid end
        to end (each row's |a| and |d|, a sliding joint's with the end of its stroke farthest from 0), or the desktop
        arm's two links (docs/kinematics.md §8.6).

        >>> round(Arm.preset("course").reach_bound * 1000, 1)   # 128 + 612.9 + 571.6 + 163.9 + 115.7 + 92.2 mm
        1684.3
        """
        if self.dh is None:
            return float(self.solver.upper_arm + self.solver.forearm)
        return reach_bound(self.dh, self.limits)

    @property
    def base_height(self) -> float:
        """How high its base frame's origin stands above the floor, along :attr:`up` (m): 0 for an arm standing
        on it, more for one whose table starts at its shoulder (``specs.base_height``).

        >>> Arm.preset("kr210").base_height, Arm.preset("stanford").base_height, Arm.preset("three_dof").base_height
        (0.0, 0.412, 1.5)
        """
        return float(self.specs.base_height)

    def joints(self, q, name: str = "q") -> np.ndarray:
        """``q`` checked: finite, shape (..., n); ``ValueError`` naming what is wrong."""
        return self._geometry.joints(q, name)

    # ------------------------------------------------------------------ kinematics

    def fk(self, q) -> np.ndarray:
        """Base → tool pose (the last row of the table; the UR family's flange, docs/kinematics.md §3), (..., 4, 4).

        >>> arm = Arm.preset("course")
        >>> (arm.fk(np.radians([30, 45, 26, 50, 60, 80]))[:3, 3] * 1000).round(3).tolist()
        [519.984, 57.726, 1110.697]
        """
        return self._geometry.fk(q)

    def frames(self, q) -> np.ndarray:
        """Every row's frame in the base frame, (..., rows + 1, 4, 4); the last is :meth:`fk`."""
        return self._geometry.frames(q)

    def jacobian(self, q) -> np.ndarray:
        """Geometric Jacobian at the tool origin, base frame, (..., 6, n), rows [v; ω] (docs/kinematics.md §5, §7.6)."""
        return self._geometry.jacobian(q)

    def within_limits(self, q) -> np.ndarray:
        """(...) bool: every joint inside its limits (revolute joints also one turn either way), to
        :data:`~ur10core.tolerances.LIMIT_TOLERANCE`."""
        return self.joints_within_limits(q).all(axis=-1)

    def joints_within_limits(self, q) -> np.ndarray:
        """(..., n) bool: which joints of ``q`` are inside their limits, as :meth:`within_limits` counts them."""
        return within_limits(self.joints(q), self.limits, self.revolute)

    def ik(self, T, hint=None) -> IKSolution:
        """Every IK branch of base → tool poses, in fixed labelled slots (docs/kinematics.md §4, §7.3).

        Parameters
        ----------
        T : array_like, shape (..., 4, 4)
            Poses (metres). Only what the arm controls is matched (:attr:`task`). A pose that
            is not a proper transform raises ``ValueError``; an unreachable one does not.
        hint : array_like, shape (..., n), optional
            The current joints: where the pose leaves a joint free (a singular wrist, a
            wrist centre on axis 1), the hint's value is kept, or the value nearest it that
            keeps the slot within the joint limits where the hint's does not
            (:func:`~ur10core.branches.keep_free_values_within_limits`); the numerical IK starts there.
            Without a hint too, a joint the pose fixes only loosely that came out just beyond a
            limit is put on it (:func:`~ur10core.solvers.numerical.settle_on_limits`).

        Returns
        -------
        IKSolution
            ``q`` (..., k, n), ``valid``, ``within_limits``, labels, and why empty slots are empty.

        >>> arm = Arm.preset("course")
        >>> q = np.radians([30, 45, 26, 50, 60, 80])
        >>> sol = arm.ik(arm.fk(q))
        >>> int(sol.valid.sum()), np.degrees(sol.q[4]).round(6).tolist(), sol.labels[4]
        (8, [30.0, 45.0, 26.0, 50.0, 60.0, 80.0], 'shoulder right, elbow down, wrist not flipped')
        """
        if self._straight_ik is not None:
            return self._straight_ik(self, T, hint)
        solution = self._branches(T, hint)
        if self._free_values_meet_limits and np.count_nonzero(solution.singular):  # the usual case has no singular slot
            keep_free_values_within_limits(solution, self._branches, T, hint)
            settle_on_limits(solution, T)
        return solution

    def _branches(self, T, hint) -> IKSolution:
        """:meth:`ik` as the family's solver gives it: a free joint at the hint's value, whatever its limits."""
        if self._own_ik is not None:  # the family solves whole batches itself (the UR kernels, the desktop arm)
            return self._own_ik(self, T, hint)
        T = homogeneous_transform(T)
        batch = T.shape[:-2]
        if hint is not None:
            hint = self.joints(hint, "hint")
            batch = poses_and_hints(T, hint)
            hint = np.broadcast_to(hint, batch + (self.n_joints,)).reshape(-1, self.n_joints)
        flat = np.ascontiguousarray(np.broadcast_to(T, batch + (4, 4)).reshape(-1, 4, 4))
        out = self.solver.solve(flat, hint)
        slots = out["q"].shape[1]
        shape = lambda a, *tail: a.reshape(batch + (slots,) + tail)  # noqa: E731
        return IKSolution(shape(out["q"], self.n_joints), shape(out["valid"]), shape(out["failure"]), self,
                          detail=shape(out["detail"]), singular=shape(out["singular"]))

    def pose_error(self, q, T) -> np.ndarray:
        """How far FK(q) is from ``T`` in what the arm controls (max abs entry), shape (...)."""
        return task_gap(self.fk(q), homogeneous_transform(T), self.task)

    # ------------------------------------------------------------------ singularities

    def singularity_factors(self, q) -> np.ndarray:
        """The factors of det J at joints ``q`` (..., n), shape (..., k) (docs/kinematics.md §5, §7.6, §8.6).

        ``det J`` is a constant times their product; each is zero on one singularity. The UR
        family's three (shoulder, elbow, wrist) and the desktop arm's two are closed forms;
        the course's other arms' are derived (``ur10core.symbolic_arms.load(name).factors``
        names them). ``ValueError`` for a typed table.

        >>> Arm.preset("course").singularity_factors(np.radians([0, 90, 0, 0, 90, 0])).round(4).tolist()
        [-0.1157, 0.0, 1.0]
        """
        if self._own_factors is not None:
            return self._own_factors(q)
        from . import symbolic_arms

        if self.name not in COURSE_ARMS:
            raise ValueError(f"{self.name!r} has no derived factors (a custom table): use smallest_singular_value or manipulability")
        return symbolic_arms.load(self.name).evaluate(self.joints(q))

    @property
    def factor_names(self) -> tuple[str, ...]:
        """The names of :meth:`singularity_factors`, in order (the UR family's: shoulder, elbow, wrist).

        >>> Arm.preset("stanford").factor_names
        ('stroke', 'shoulder', 'wrist')
        """
        if self.name in COURSE_ARMS:
            from . import symbolic_arms

            return tuple(factor.name for factor in symbolic_arms.load(self.name).factors)
        words = getattr(self.solver, "factor_words", None)
        if words is None:
            raise ValueError(f"{self.name!r} has no derived factors (a custom table)")
        return tuple(name for name, _, _ in words)

    @property
    def singularities_in_closed_form(self) -> bool:
        """Whether :meth:`singular_configuration` is a closed form (the UR family's: microseconds) rather than
        a search (the other arms': milliseconds).

        >>> Arm.preset("ur10").singularities_in_closed_form, Arm.preset("kr210").singularities_in_closed_form
        (True, False)
        """
        return hasattr(self.solver, "singular_configuration")

    def singular_configuration(self, kind: str, q) -> np.ndarray:
        """Joints ``q`` (..., n) changed as little as needed to sit exactly on the singularity where the
        factor ``kind`` of det J is zero, (..., n) (docs/kinematics.md §5.2).

        The UR family's are closed forms (:meth:`ur10core.solvers.ur.URFamily.singular_configuration`).
        Every other arm with factors turns (or slides) the *one* joint that reaches a zero of that
        factor with the least motion, as a share of the joint's range, within its limits: the zeros
        are bracketed on a grid along each joint and refined to machine precision. Where no one joint
        can, two of the joints the factor depends on move together, to the nearest zero on a grid over
        the pair (the desktop arm's tool onto its base axis from its home pose). A pose on which
        another factor is also near zero is passed over while another will do. ``ValueError`` naming
        the factor when the arm has no such factor, or when no pose within the limits is found (the
        cylindrical arm's stroke keeps d3 ≥ 100 mm, off its reach singularity d3 = 0).

        >>> arm = Arm.preset("kr210")
        >>> q = arm.singular_configuration("wrist", np.radians([10, 20, -30, 40, 50, 60]))
        >>> np.degrees(q).round(9).tolist()   # θ5 turned to 0: axes 4 and 6 in line
        [10.0, 20.0, -30.0, 40.0, 0.0, 60.0]
        """
        if self.singularities_in_closed_form:
            return self.solver.singular_configuration(kind, q)
        names = self.factor_names
        if kind not in names:
            raise ValueError(f"{self.name!r} has no {kind!r} singularity: its factors of det J are {', '.join(names)}")
        q = self.joints(q)
        flat = q.reshape(-1, self.n_joints)
        found = np.stack([_onto_zero(self, names.index(kind), row) for row in flat])
        if np.isnan(found).any():
            if self.name in COURSE_ARMS:
                from . import symbolic_arms

                meaning = symbolic_arms.load(self.name).factors[names.index(kind)].meaning
            else:
                meaning = self.solver.factor_words[names.index(kind)][2]
            # a student reads this in the browser: "this arm", not the preset's key ("cylindrical_wrist")
            raise ValueError(f"within its joint limits, no pose near this one puts this arm on its {kind} "
                             f"singularity ({meaning}): det J's {kind} factor stays clear of zero")
        return found.reshape(q.shape)

    def wrist_centre(self, q) -> np.ndarray:
        """The point nearest the last three joint axes at joints ``q`` (..., n), shape (..., 3).

        For a spherical wrist (the KR210, the elbow arm, the Stanford arm) the three axes meet
        there: it is the wrist centre Pieper's decoupling solves for (docs/kinematics.md §7.3),
        and the point the shoulder and elbow singularities are about (§7.6). ``ValueError``
        for an arm whose last three joints are not all revolute.

        Example: the Stanford arm's d6 = 0 puts its tool frame at the wrist centre.

        >>> arm = Arm.preset("stanford")
        >>> q = np.array([0.3, 1.0, 0.4, 0.2, 0.5, 0.1])
        >>> bool(np.allclose(arm.wrist_centre(q), arm.fk(q)[:3, 3]))
        True
        """
        if self.dh is None or self.n_joints < 3 or self.joint_types[-3:] != "RRR":
            raise ValueError(f"{self.name!r} has no wrist of three revolute joints: no wrist centre")
        z, o = self.dh.joint_axes(self.dh.frames(q))
        z, o = z[..., -3:, :], o[..., -3:, :]
        # least squares: Σ (I − z zᵀ)(c − o) = 0 over the three axes
        projector = np.eye(3) - z[..., :, None] * z[..., None, :]
        A = projector.sum(axis=-3)
        b = (projector @ o[..., None]).sum(axis=-3)
        return np.linalg.solve(A, b)[..., 0]

    def gravity_torques(self, q, payload_kg: float = 0.0) -> np.ndarray:
        """The joint torques (N·m) that hold the arm still against gravity at joints ``q``, (..., n).

        From the arm's published link masses and centres of mass (docs/kinematics.md §8.5:
        UR's, for ``ur10`` and ``course``), ``payload_kg`` at the flange; the sense of
        roboticstoolbox-python's ``gravload``. ``ValueError`` naming the arms that have
        masses, for one without them.

        Example: stretched out horizontally, the shoulder holds the most.

        >>> arm = Arm.preset("ur10")
        >>> tau = arm.gravity_torques(np.radians([0, 0, 0, -90, 0, 0]))
        >>> int(np.argmax(np.abs(tau))), bool(100 < abs(tau[1]) < 200)
        (1, True)
        """
        from . import dynamics

        dynamics.link_masses(self)  # raises, naming the arms that have them
        return dynamics.gravity_torques(self, self.joints(q), payload_kg)

    @property
    def det_rows(self) -> list[int]:
        """The rows of J that det J is taken over: those the arm controls (``TASK_ROWS``); a planar arm's,
        its plane's v_x and v_y (docs/kinematics.md §7.6)."""
        return [0, 1] if self.planar else TASK_ROWS[self.task]

    def det_jacobian(self, q) -> np.ndarray:
        """det J over :attr:`det_rows`, shape (...): a constant times the product of :meth:`singularity_factors`
        (docs/kinematics.md §5, §7.6, §8.6). ``ValueError`` where those rows are not as many as the joints.

        >>> arm = Arm.preset("planar_elbow")                     # det J = a1 a2 s2
        >>> q = np.radians([10.0, 30.0])
        >>> bool(np.isclose(arm.det_jacobian(q), arm.dh.rows[0].a * arm.dh.rows[1].a * np.sin(q[1])))
        True
        """
        if hasattr(self.solver, "det_jacobian"):  # the UR family's closed form
            return self.solver.det_jacobian(q)
        rows = self.det_rows
        if len(rows) != self.n_joints:
            raise ValueError(f"the {self.name} arm has {self.n_joints} joints and controls {len(rows)} rows of J: "
                             "its J is not square, so it has no det J")
        return np.linalg.det(self.jacobian(q)[..., rows, :])

    def smallest_singular_value(self, q) -> np.ndarray:
        """σ_min of the rows of J the arm controls, shape (...): how close to losing a direction. 0 where it is
        rounding, at most :data:`~ur10core.differential.FLAT` of the largest (7e-18 on the UR10's shoulder
        singularity), as the ellipsoids count an axis (docs/kinematics.md §8.4)."""
        J = self.jacobian(q)[..., TASK_ROWS[self.task], :]
        sigma = np.linalg.svd(J, compute_uv=False)
        return np.where(sigma[..., -1] <= FLAT * sigma[..., 0], 0.0, sigma[..., -1])

    # ------------------------------------------------------------------ workspace

    def manipulability(self, q) -> np.ndarray:
        """Yoshikawa's measure ``sqrt(det(J_t J_tᵀ))`` over the rows the arm controls, shape (...).

        For a square J (six joints, or a SCARA's four, or the desktop arm's J_v) it is |det J|;
        it is zero exactly at a singularity.
        """
        J = self.jacobian(q)[..., TASK_ROWS[self.task], :]
        if J.shape[-2] == J.shape[-1]:  # as accurate as det J itself
            return np.abs(np.linalg.det(J))
        if J.shape[-2] < J.shape[-1]:  # more joints than rows: the measure of J Jᵀ, that of Jᵀ's QR
            J = np.swapaxes(J, -1, -2)
        # |det R| of J = QR is √det(Jᵀ J): the root itself lifted rounding to 5e-9 on a singularity (the planar elbow
        # stretched, where σ_min is 2e-17); an SVD is as exact, and 17 times slower on a cloud
        return np.abs(np.prod(np.diagonal(np.linalg.qr(J, mode="r"), axis1=-2, axis2=-1), axis=-1))

    def sample_joints(self, n: int, seed: int = 0) -> np.ndarray:
        """``n`` joint vectors drawn uniformly within the limits, (n, n_joints).

        The joints behind :meth:`sample_workspace`'s cloud, without its forward kinematics:
        the same ``n`` and ``seed`` give the same vectors. ``n`` is at most ten million
        (:data:`ur10core._validate.MAX_SAMPLES`), for either.
        """
        n, seed = sample_size(n, seed)
        low, high = sampling_range(self.limits, self.revolute)
        return np.random.default_rng(seed).uniform(low, high, (n, self.n_joints))

    def sample_workspace(self, n: int, seed: int = 0, return_joints: bool = False):
        """Tool positions of ``n`` joint vectors drawn uniformly within the limits, and their manipulability.

        Returns points (n, 3) in metres, manipulability (n,) and, with ``return_joints``,
        the joints (n, n_joints) (:meth:`sample_joints`; the UR family draws every joint over
        one turn, in closed form, on all cores). The same ``n`` and ``seed`` give the same cloud.
        """
        own = getattr(self.solver, "sample_workspace", None)
        if own is not None:
            return own(n, seed, return_joints)
        q = self.sample_joints(n, seed)
        points = np.empty((int(n), 3))
        manipulability = np.empty(int(n))
        for start in range(0, int(n), 65536):
            block = q[start:start + 65536]
            points[start:start + len(block)] = self.fk(block)[:, :3, 3]
            manipulability[start:start + len(block)] = self.manipulability(block)
        if return_joints:
            return points, manipulability, q
        return points, manipulability

    def sample_horizontal_section(self, height: float, n: int, seed: int = 0, return_joints: bool = False):
        """Up to ``n`` tool positions exactly ``height`` (m) above the floor, their manipulability and, with
        ``return_joints``, their joints (m, n_joints): a horizontal section of :meth:`sample_workspace` sampled in
        its plane, one joint solved for the height (:func:`ur10core.workspace.sample_horizontal_section`).

        >>> points, _ = Arm.preset("scara").sample_horizontal_section(0.3, 3)   # its sliding joint sets the height
        >>> points[:, 2].round(12).tolist()
        [0.3, 0.3, 0.3]
        """
        return sample_horizontal_section(self, height, n, seed, return_joints)

    @property
    def tool_heights(self) -> tuple[float, float]:
        """(lowest, highest) height of the tool above the floor (m) among 20 000 draws, a little within its reach;
        one height twice for an arm whose tool moves in one horizontal plane (:func:`ur10core.workspace.tool_heights`).

        >>> [round(v, 2) for v in Arm.preset("ur10").tool_heights]   # within d1 ∓ (a2 + a3 + √(d5² + d6²)) = -1.2, 1.46
        [-1.2, 1.45]
        >>> [round(v, 3) for v in Arm.preset("planar_elbow").tool_heights]
        [0.0, 0.0]
        """
        return tool_heights(self)


#: Points along each joint's range where :func:`_onto_zero` looks for a factor's sign change or dip.
_ZERO_GRID = 721
#: Another factor at most this share of its scale: the pose is on that singularity too.
_ALSO_SINGULAR = 0.02


def _onto_zero(arm: Arm, k: int, q: np.ndarray) -> np.ndarray:
    """(n,) ``q`` with the one joint changed that puts factor ``k`` of det J at zero with the least
    motion (a share of that joint's range), else two joints, other factors clear of zero; failing
    that, onto the nearest zero whatever the others (from where only θ3 moves the KR210's elbow factor,
    its zero may lie on the shoulder singularity too); NaN where there is none.

    Along each joint the factor is evaluated on a grid over the joint's limits; a sign change is
    bisected and a dip of ``|factor|`` (a double zero, the Stanford arm's d3²) golden-sectioned.
    """
    for clear in (_clear_of_zero(arm, k, q), np.zeros(len(arm.factor_names) - 1)):
        found = _moved_onto_zero(arm, k, q, clear)
        if not np.isnan(found).any():
            break
    return found


def _moved_onto_zero(arm: Arm, k: int, q: np.ndarray, clear: np.ndarray) -> np.ndarray:
    """:func:`_onto_zero` with the other factors kept at least ``clear`` of zero (shares of their scales)."""
    scales = factor_scales(arm)
    n = arm.n_joints
    low, high = arm.limits[:, 0], arm.limits[:, 1]

    def along(joint: int, values: np.ndarray) -> np.ndarray:
        poses = np.repeat(q[None], len(values), axis=0)
        poses[:, joint] = values
        return arm.singularity_factors(poses)

    best, best_move = np.full(n, np.nan), np.inf
    depends = np.zeros(n, bool)
    for joint in range(n):
        grid = np.linspace(low[joint], high[joint], _ZERO_GRID)
        f = along(joint, grid)[:, k]
        step = grid[1] - grid[0]
        crossings = np.flatnonzero(np.signbit(f[:-1]) != np.signbit(f[1:]))
        depends[joint] = np.ptp(f) > 1e-12 * scales[k]
        if not depends[joint]:
            continue
        size = np.abs(f)
        dips = np.flatnonzero((size < np.r_[np.inf, size[:-1]]) & (size <= np.r_[size[1:], np.inf])
                              & (size <= _ALSO_SINGULAR * scales[k]))  # a double zero lies in a shallow dip
        candidates = [_bisect(lambda x: along(joint, np.array([x]))[0, k], grid[i], grid[i + 1]) for i in crossings]
        candidates += [_golden(lambda x: abs(along(joint, np.array([x]))[0, k]), max(grid[i] - step, low[joint]),
                               min(grid[i] + step, high[joint])) for i in dips]
        if not candidates:
            continue
        values = np.array(candidates)
        factors = along(joint, values)
        levels = np.abs(factors) / scales
        good = (np.abs(factors[:, k]) <= 1e-10 * scales[k]) & (np.delete(levels, k, axis=1) >= clear).all(axis=1)
        moves = np.abs(values - q[joint]) / max(high[joint] - low[joint], 1e-12)
        moves[~good] = np.inf
        pick = int(np.argmin(moves))
        if moves[pick] < best_move:
            best_move, best = moves[pick], q.copy()
            best[joint] = values[pick]
    if np.isnan(best).any():  # no one joint reaches it (the desktop arm's reach from its home): move them together
        best = _two_onto_zero(arm, k, q, depends, clear)
    return best


def _clear_of_zero(arm: Arm, k: int, q: np.ndarray) -> np.ndarray:
    """(m − 1,) how far from zero the other factors must stay, as shares of their scales: :data:`_ALSO_SINGULAR`,
    or half as far as at ``q`` where ``q`` is already that near (a pose near two singularities keeps its second)."""
    levels = np.delete(np.abs(arm.singularity_factors(q)) / factor_scales(arm), k)
    return np.minimum(_ALSO_SINGULAR, 0.5 * levels)


def _two_onto_zero(arm: Arm, k: int, q: np.ndarray, depends: np.ndarray, clear: np.ndarray) -> np.ndarray:
    """(n,) ``q`` with two of the joints factor ``k`` ``depends`` on changed, onto one of its zeros with the
    other factors ``clear`` of zero: the zero nearest ``q`` (in shares of the joints' ranges) found on a
    grid over the pair's limits, refined along the second joint. NaN if none."""
    scales = factor_scales(arm)
    low, high = arm.limits[:, 0], arm.limits[:, 1]
    span = np.maximum(high - low, 1e-12)
    best, best_move = np.full(len(q), np.nan), np.inf
    for i, j in itertools.permutations(np.flatnonzero(depends), 2):
        rows, columns = np.linspace(low[i], high[i], 121), np.linspace(low[j], high[j], 241)
        poses = np.broadcast_to(q, (len(rows), len(columns), len(q))).copy()
        poses[..., i], poses[..., j] = rows[:, None], columns[None]
        f = arm.singularity_factors(poses)[..., k]
        r, c = np.nonzero(np.signbit(f[:, :-1]) != np.signbit(f[:, 1:]))
        moves = np.hypot((rows[r] - q[i]) / span[i], (columns[c] - q[j]) / span[j])
        for cell in np.argsort(moves)[:16]:  # the nearest crossings, until one is clear of the other factors
            pose = q.copy()
            pose[i] = rows[r[cell]]

            def along(x: float, pose=pose) -> float:
                pose[j] = x
                return float(arm.singularity_factors(pose)[k])

            pose[j] = _bisect(along, columns[c[cell]], columns[c[cell] + 1])
            levels = np.abs(arm.singularity_factors(pose)) / scales
            move = float(np.hypot((pose[i] - q[i]) / span[i], (pose[j] - q[j]) / span[j]))
            if levels[k] <= 1e-10 and (np.delete(levels, k) >= clear).all():
                if move < best_move:
                    best, best_move = pose, move
                break
    return best


def _bisect(f, a: float, b: float) -> float:
    """A zero of ``f`` between ``a`` and ``b``, where ``f`` changes sign, to the last bit."""
    fa = f(a)
    for _ in range(200):
        middle = 0.5 * (a + b)
        if middle in (a, b):
            break
        fm = f(middle)
        if fm == 0.0:
            return middle
        if np.signbit(fm) == np.signbit(fa):
            a, fa = middle, fm
        else:
            b = middle
    return a if abs(fa) <= abs(f(b)) else b


def _golden(f, a: float, b: float) -> float:
    """The least of ``f`` ≥ 0 over [a, b] (one dip), golden-section searched, the ends included."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    lo, hi = a, b
    for _ in range(120):
        c, d = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        if f(c) <= f(d):
            hi = d
        else:
            lo = c
        if hi - lo <= 1e-15 * max(1.0, abs(lo)):
            break
    return min((a, b, 0.5 * (lo + hi)), key=f)


@functools.lru_cache(maxsize=64)
def factor_scales(arm: Arm) -> np.ndarray:
    """Per factor of det J, its typical size: the 99th percentile of ``|factor|`` over the arm's joint range, (k,).

    What "close to zero" means for a factor with units of its own (the UR10's shoulder factor is
    a length, its wrist factor a sine): the overlay's gauges are full at it, and a challenge's
    tolerance is a share of it. ``ValueError`` for a typed table (no factors).
    """
    q = arm.sample_joints(20_000, seed=1)
    return np.maximum(np.percentile(np.abs(arm.singularity_factors(q)), 99, axis=0), 1e-12)

"""The UR family (UR10, UR10e, the course's table): its closed forms and its IK kernels (docs/kinematics.md §2–§5).

:class:`URFamily` is the solver behind ``Arm.preset("course" | "ur10" | "ur10e")``: the
six lengths of the course's modified DH table

====  ==========  =========  =====  ======
 i    alpha_i-1    a_i-1      d_i   theta_i
====  ==========  =========  =====  ======
 1     0           0          d1     θ1
 2     +π/2        0          0      θ2
 3     0           a2         0      θ3
 4     0           a3         d4     θ4
 5     −π/2        0          d5     θ5
 6     +π/2        0          d6     θ6
====  ==========  =========  =====  ======

and what the general :class:`ur10core.Arm` takes from it: FK in closed form, the frames and
IK from the compiled (or numpy) kernels, det J's three factors, the singularities' geometry
and a fast workspace sampler. Units are metres and radians; every method takes any leading
batch shape ``...``, and single poses take a pure-Python fast path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, NamedTuple

import numpy as np

from .. import ik as _ik
from .. import ik_reference
from .._backend import kernels
from .._validate import (
    as_float_array, check_finite, homogeneous_transform, joint_vector, one_joint_vector, poses_and_hints, refuse_pose,
    sample_size,
)
from ..branches import INSIDE_OFFSET, TOO_FAR, IKSolution, mm_apart, wrap
from ..tolerances import WRIST_TOLERANCE

if TYPE_CHECKING:
    from ..arm import Arm

#: alpha_{i-1} of the course's DH table, rows i = 1..6.
DH_ALPHA = (0.0, math.pi / 2, 0.0, 0.0, -math.pi / 2, math.pi / 2)
JOINT_NAMES = ("base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3")
#: The UR10's joint range, every joint (docs/kinematics.md §1): ±360°.
JOINT_LIMIT = 2.0 * math.pi

#: The family's members (metres).
LENGTHS = {
    # docs/kinematics.md §2: the course's table.
    "course": dict(d1=0.128, a2=0.6129, a3=0.5716, d4=0.1639, d5=0.1157, d6=0.0922),
    # UR's own numbers (standard DH, same structure; a2, a3 given as magnitudes).
    "ur10": dict(d1=0.1273, a2=0.612, a3=0.5723, d4=0.163941, d5=0.1157, d6=0.0922),
    "ur10e": dict(d1=0.1807, a2=0.6127, a3=0.57155, d4=0.17415, d5=0.11985, d6=0.11655),
}
DESCRIPTIONS = {
    "course": "UR10, the course's DH table",
    "ur10": "UR10 (CB3), UR's own numbers",
    "ur10e": "UR10e, UR's own numbers",
}


@dataclass(frozen=True)
class SingularityGeometry:
    """What the singularity overlay draws for joint angles ``q`` (leading shape ``...``).

    docs/kinematics.md §5. All points and directions in the base frame, metres.

    * **shoulder**: singular when the wrist-2 point ``p5`` lies on the cylinder of
      radius ``cylinder_radius`` (= d4) about the base axis (the z axis).
    * **elbow**: singular when the frame-4 origin ``p4`` lies on one of the two circles
      of radii ``elbow_radii`` (a2 + a3 stretched, |a2 − a3| folded) about
      ``elbow_center`` in the arm plane spanned by ``arm_forward`` (x1) and z. As θ1
      turns they sweep spheres of radii ``sqrt(r² + d4²)`` about ``shoulder``.
    * **wrist**: singular when ``axis4`` and ``axis6`` are parallel.
    """

    shoulder: np.ndarray  #: (..., 3) origin of frames 1 and 2, (0, 0, d1)
    elbow: np.ndarray  #: (..., 3) origin of frame 3
    p4: np.ndarray  #: (..., 3) origin of frame 4 (wrist-1 centre)
    p5: np.ndarray  #: (..., 3) origin of frame 5 (wrist-2 point)
    flange: np.ndarray  #: (..., 3) origin of frame 6
    axis4: np.ndarray  #: (..., 3) unit direction of joint axis 4
    axis6: np.ndarray  #: (..., 3) unit direction of joint axis 6 (tool axis)
    arm_forward: np.ndarray  #: (..., 3) x1, the arm plane's horizontal direction
    elbow_center: np.ndarray  #: (..., 3) shoulder + d4 z2: centre of the reach circles
    cylinder_radius: float  #: d4
    elbow_radii: tuple[float, float]  #: (a2 + a3, |a2 − a3|)


@dataclass(frozen=True)
class URFamily:
    """A UR-type 6R arm's lengths and closed forms: the solver of ``Arm.preset("course")`` and its kin.

    Example
    -------
    >>> from ur10core import Arm
    >>> arm = Arm.preset("course")
    >>> (arm.fk([0, 0, 0, 0, 0, 0])[:3, 3] * 1000).round(1).tolist()   # docs/kinematics.md §3
    [1184.5, -256.1, 243.7]
    >>> arm.solver.d4
    0.1639
    """

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float

    #: ``(d1, a2, a3, d4, d5, d6)``, set on construction (what the compiled kernel reads).
    dh_lengths: tuple[float, ...] = field(init=False, repr=False, compare=False)
    labels: ClassVar[tuple[str, ...]] = _ik.SLOT_LABELS
    slots: ClassVar[tuple[_ik.Slot, ...]] = _ik.SLOTS
    task: ClassVar[str] = "pose"
    method: ClassVar[str] = "analytic"
    extra_names: ClassVar[tuple[str, ...]] = _ik.EXTRA_NAMES
    #: :meth:`IKSolution.nearest` turns each joint within ±this (the UR10's ±360°), by the kernel.
    turn_limit: ClassVar[float] = JOINT_LIMIT
    #: det J's factors (docs/kinematics.md §5): (name, expression, what makes it zero), and the constant before them
    factor_words: ClassVar[tuple[tuple[str, str, str], ...]] = (
        ("shoulder", "a2 c2 + a3 c23 − d5 s234", "the wrist centre P5 touches the cylinder of radius d4 about axis 1"),
        ("elbow", "s3", "the arm is stretched or folded"),
        ("wrist", "s5", "axes 4 and 6 are parallel"))
    det_constant: ClassVar[str] = "a2 a3"

    def __post_init__(self) -> None:
        for name in ("d1", "a2", "a3", "d4", "d5", "d6"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"Arm.{name} must be a finite number of metres, got {value!r}")
            object.__setattr__(self, name, float(value))
        for name in ("a2", "a3", "d4", "d5", "d6"):
            if getattr(self, name) <= 0:
                raise ValueError(f"Arm.{name} must be positive, got {getattr(self, name)!r}")
        if self.a2 == self.a3:
            raise ValueError("Arm.a2 and Arm.a3 must differ (the folded elbow would put the wrist on the shoulder)")
        object.__setattr__(self, "dh_lengths", (self.d1, self.a2, self.a3, self.d4, self.d5, self.d6))

    def table(self):
        """The course's table as a general :class:`ur10core.dh.DHTable` (modified DH, docs/kinematics.md §2).

        Its FK, frames and Jacobian equal this family's closed forms, which are its fast path.
        """
        from ..dh import DHTable

        return DHTable([(a, alpha, d, 0.0, "R") for alpha, a, d in self.dh_table], "modified")

    def joints(self, q, name: str = "q") -> np.ndarray:
        return joint_vector(q, name)

    # ------------------------------------------------------------------ DH table

    @property
    def dh_table(self) -> tuple[tuple[float, float, float], ...]:
        """Rows ``(alpha_{i-1}, a_{i-1}, d_i)`` for i = 1..6 (docs/kinematics.md §2)."""
        a = (0.0, 0.0, self.a2, self.a3, 0.0, 0.0)
        d = (self.d1, 0.0, 0.0, self.d4, self.d5, self.d6)
        return tuple(zip(DH_ALPHA, a, d))

    def link_transforms(self, q) -> np.ndarray:
        """``T(i-1, i) = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(θi) TransZ(d_i)``, (..., 6, 4, 4).

        docs/kinematics.md §2, Craig form::

            [ cθ      -sθ      0     a     ]
            [ sθ·cα   cθ·cα   -sα   -sα·d  ]
            [ sθ·sα   cθ·sα    cα    cα·d  ]
            [ 0        0       0     1     ]
        """
        q = joint_vector(q)
        alpha, a, d = (np.array(column) for column in zip(*self.dh_table))
        ca, sa = np.cos(alpha), np.sin(alpha)
        ct, st = np.cos(q), np.sin(q)
        T = np.zeros(q.shape + (4, 4))
        T[..., 0, 0] = ct
        T[..., 0, 1] = -st
        T[..., 0, 3] = a
        T[..., 1, 0] = st * ca
        T[..., 1, 1] = ct * ca
        T[..., 1, 2] = -sa
        T[..., 1, 3] = -sa * d
        T[..., 2, 0] = st * sa
        T[..., 2, 1] = ct * sa
        T[..., 2, 2] = ca
        T[..., 2, 3] = ca * d
        T[..., 3, 3] = 1.0
        return T

    def frames(self, q) -> np.ndarray:
        """Frames {0}..{6} in the base frame, (..., 7, 4, 4): ``T0i = T01 T12 ... T(i-1,i)``.

        ``frames(q)[..., i, :, :]`` places link i's mesh; ``frames(q)[..., 6]`` equals ``fk(q)``.
        The product of :meth:`link_transforms`, computed by the compiled kernel (the app
        asks for nine arms' frames on every drag event).
        """
        q = joint_vector(q)
        flat = np.ascontiguousarray(q.reshape(-1, 6))
        out = np.empty((len(flat), 7, 4, 4))
        kernels.frames(flat, self.dh_lengths, out)
        return out.reshape(q.shape[:-1] + (7, 4, 4))

    # ------------------------------------------------------------------ FK

    def fk(self, q) -> np.ndarray:
        """Base → flange pose T06 in closed form (docs/kinematics.md §3), (..., 4, 4), metres.

        Example
        -------
        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> T = arm.fk(np.radians([30, 45, 26, 50, 60, 80]))
        >>> (T[:3, 3] * 1000).round(3).tolist()
        [519.984, 57.726, 1110.697]
        """
        if type(q) is np.ndarray and q.shape == (6,) and q.dtype == np.float64 and q.flags.c_contiguous:
            T = kernels.fk_one(q, self.dh_lengths)  # the same closed form for one pose, without numpy's overhead
            if T is not None:
                return T
        q = joint_vector(q)
        if q.shape == (6,):
            return kernels.fk_one(np.ascontiguousarray(q), self.dh_lengths)
        c1, c2, c3, c4, c5, c6 = np.moveaxis(np.cos(q), -1, 0)
        s1, s2, s3, s4, s5, s6 = np.moveaxis(np.sin(q), -1, 0)
        c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
        c234, s234 = c23 * c4 - s23 * s4, s23 * c4 + c23 * s4
        T = np.empty(q.shape[:-1] + (4, 4))
        u = -s1 * s5 + c1 * c5 * c234
        w = s5 * c1 + s1 * c5 * c234
        T[..., 0, 0] = c6 * u - s6 * s234 * c1
        T[..., 0, 1] = -s6 * u - s234 * c1 * c6
        T[..., 0, 2] = r13 = s1 * c5 + s5 * c1 * c234
        T[..., 1, 0] = c6 * w - s6 * s234 * s1
        T[..., 1, 1] = -s6 * w - s234 * s1 * c6
        T[..., 1, 2] = r23 = -c1 * c5 + s5 * s1 * c234
        T[..., 2, 0] = s6 * c234 + s234 * c5 * c6
        T[..., 2, 1] = c6 * c234 - s234 * c5 * s6
        T[..., 2, 2] = r33 = s5 * s234
        reach = self.a2 * c2 + self.a3 * c23 - self.d5 * s234
        T[..., 0, 3] = c1 * reach + self.d4 * s1 + self.d6 * r13
        T[..., 1, 3] = s1 * reach - self.d4 * c1 + self.d6 * r23
        T[..., 2, 3] = self.a2 * s2 + self.a3 * s23 + self.d1 + self.d5 * c234 + self.d6 * r33
        T[..., 3, :3] = 0.0
        T[..., 3, 3] = 1.0
        return T

    # ------------------------------------------------------------------ IK

    def ik(self, arm: "Arm", T, hint=None) -> IKSolution:
        """All eight analytic IK branches of base → flange poses (docs/kinematics.md §4), for ``arm``.

        Parameters
        ----------
        T : array_like, shape (..., 4, 4)
            Poses, metres. A rotation part that is not a proper rotation, a bottom row
            other than [0, 0, 0, 1] or a non-finite entry raises ``ValueError``; an
            unreachable pose does not (every slot is then invalid).
        hint : array_like, shape (..., 6), optional
            The current joints. Where the pose fixes a joint only loosely — θ6 near the
            wrist singularity (only θ234 ± θ6 is determined), the shoulder's reach near the
            shoulder singularity, θ3 at the stretched or folded elbow — the hint's value is
            kept whenever it reproduces the pose within the tolerances of
            :mod:`ur10core.tolerances`. Default: θ6 = 0.

        Returns
        -------
        IKSolution
            ``q`` (..., 8, 6) in (−π, π], ``valid`` (..., 8) and the flags; slot
            ``k = 4 i + 2 j + l`` as described in :mod:`ur10core.ik`.

        Example
        -------
        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> q = np.radians([30, 45, 26, 50, 60, 80])
        >>> sol = arm.ik(arm.fk(q))
        >>> int(sol.valid.sum()), np.degrees(sol.q[4]).round(6).tolist()
        (8, [30.0, 45.0, 26.0, 50.0, 60.0, 80.0])
        >>> sol.labels[4]
        'shoulder right, elbow down, wrist not flipped'
        """
        T = as_float_array(T, "T")
        values = None if hint is None else one_joint_vector(hint, "hint")
        if T.shape == (4, 4) and (hint is None or values is not None):
            solution = _ik.solve_one(
                arm, T if T.flags.c_contiguous else np.ascontiguousarray(T), ik_reference.hint_values(values, self.dh_lengths),
            )
            if solution is None:
                refuse_pose(T, 0, ())
            return solution
        if hint is not None:
            hint = joint_vector(hint, "hint")
        if T.ndim < 2 or T.shape[-2:] != (4, 4):
            homogeneous_transform(T)  # raises: wrong shape
        if hint is None:
            hints = np.array([0.0, np.nan, np.nan])
        else:
            hints = np.stack([hint[..., 5], self.singularity_factors(hint)[..., 0], hint[..., 2]], axis=-1)
        batch = T.shape[:-2] if hint is None else poses_and_hints(T, hint)
        T = np.broadcast_to(T, batch + (4, 4))
        solution = _ik.solve_batch(arm, T, hints)
        if isinstance(solution, int):
            refuse_pose(T, solution, batch)
        return solution

    def derived(self, solution: IKSolution, name: str) -> np.ndarray:
        """``solution.detail`` (the number behind each failure) or ``solution.singular``, from the kernels' own."""
        if name == "detail":
            return np.where(solution.failure == INSIDE_OFFSET, solution.wrist2_radius[..., None], solution.elbow_distance)
        return solution.wrist_singular | solution.elbow_singular | solution.shoulder_singular[..., None]

    def unreachable_reason(self, solution: IKSolution, index: tuple[int, ...] = ()) -> str:
        """Why the pose at ``index`` has no branch, in this family's words and numbers (mm)."""
        failure = solution.failure[index]
        if (failure == INSIDE_OFFSET).all():
            at, bound, off = mm_apart(float(solution.wrist2_radius[index]), self.d4)
            return (
                f"unreachable: the wrist-2 point P5 is {off} mm inside the shoulder cylinder (it is {at} mm from the "
                f"base axis; it must be at least d4 = {bound} mm)"
            )
        distance = solution.elbow_distance[index]
        outer, inner = self.a2 + self.a3, abs(self.a2 - self.a3)
        excess = np.where(failure == TOO_FAR, distance - outer, inner - distance)
        if np.isnan(excess).all():  # coordinates so large that the distances overflowed
            return (
                f"unreachable: elbow reach — the target is too far away to measure "
                f"(the arm reaches a2 + a3 = {1e3 * outer:.1f} mm from the shoulder)"
            )
        k = int(np.nanargmin(excess))
        far = failure[k] == TOO_FAR
        at, bound, off = mm_apart(distance[k], outer if far else inner)
        if solution.wrist_singular[index][k]:
            where = (f"with the wrist singular (axes 4 and 6 parallel) no θ6 works: the wrist-1 centre "
                     f"{f'stays at least {at} mm from' if far else f'stays within {at} mm of'} the shoulder")
        else:
            where = f"the wrist-1 centre would be {at} mm from the shoulder"
        if far:
            return f"unreachable: elbow reach — {where}, {off} mm beyond a2 + a3 = {bound} mm"
        return f"unreachable: elbow reach — {where}, {off} mm closer than |a2 − a3| = {bound} mm"

    # ------------------------------------------------------------------ Jacobian

    def jacobian(self, q) -> np.ndarray:
        """Geometric Jacobian at the flange origin in the base frame, (..., 6, 6), rows [v; w].

        docs/kinematics.md §5: column i is ``[z_i × (o_6 − o_i); z_i]`` with z_i, o_i the axis
        and origin of frame {i} (every joint revolute), from the frames of :meth:`frames`
        (computed by the kernel, one pose without numpy's per-call overhead).

        >>> from ur10core import Arm
        >>> J = Arm.preset("course").jacobian(np.zeros(6))
        >>> (J[:3, 0] * 1000 + 0.0).round(1).tolist(), J[3:, 0].tolist()  # joint 1 turns the flange about z0
        ([256.1, 1184.5, 0.0], [0.0, 0.0, 1.0])
        """
        if type(q) is np.ndarray and q.shape == (6,) and q.dtype == np.float64 and q.flags.c_contiguous:
            J = kernels.jacobian_one(q, self.dh_lengths)
            if J is not None:
                return J
        q = joint_vector(q)
        flat = np.ascontiguousarray(q.reshape(-1, 6))
        out = np.empty((len(flat), 6, 6))
        kernels.jacobians(flat, self.dh_lengths, out)
        return out.reshape(q.shape[:-1] + (6, 6))

    def singularity_factors(self, q) -> np.ndarray:
        """The three factors of det J, (..., 3): shoulder, elbow, wrist (docs/kinematics.md §5).

        ``(a2 c2 + a3 c23 − d5 s234, s3, s5)``; ``det J = a2 a3`` times their product.
        The shoulder factor is the signed reach of the wrist-2 point along x1: it is zero
        when P5 lies on the cylinder of radius d4 about the base axis.
        """
        q = joint_vector(q)
        if q.shape == (6,):  # one pose: plain floats beat a dozen numpy calls
            _, t2, t3, t4, t5, _ = q.tolist()
            shoulder = self.a2 * math.cos(t2) + self.a3 * math.cos(t2 + t3) - self.d5 * math.sin(t2 + t3 + t4)
            return np.array([shoulder, math.sin(t3), math.sin(t5)])
        t2, t3, t4, t5 = np.moveaxis(q[..., 1:5], -1, 0)
        t23 = t2 + t3
        shoulder = self.a2 * np.cos(t2) + self.a3 * np.cos(t23) - self.d5 * np.sin(t23 + t4)
        return np.stack([shoulder, np.sin(t3), np.sin(t5)], axis=-1)

    def det_jacobian(self, q) -> np.ndarray:
        """``det J = a2 a3 (a2 c2 + a3 c23 − d5 s234) s3 s5`` (docs/kinematics.md §5), shape (...)."""
        return self.a2 * self.a3 * self.singularity_factors(q).prod(axis=-1)

    def singularity_geometry(self, q) -> SingularityGeometry:
        """Points, axes and surfaces of the three singularities for ``q``; see :class:`SingularityGeometry`."""
        return self.singularity_geometry_from_frames(self.frames(q))

    def singularity_geometry_from_frames(self, frames: np.ndarray) -> SingularityGeometry:
        """The same from frames {0}..{6} already computed by :meth:`frames`, (..., 7, 4, 4)."""
        frames = as_float_array(frames, "frames")
        if frames.shape[-3:] != (7, 4, 4):
            raise ValueError(f"frames must have shape (..., 7, 4, 4), got {frames.shape}")
        check_finite(frames, "frames")
        shoulder = frames[..., 2, :3, 3]
        return SingularityGeometry(
            shoulder=shoulder,
            elbow=frames[..., 3, :3, 3],
            p4=frames[..., 4, :3, 3],
            p5=frames[..., 5, :3, 3],
            flange=frames[..., 6, :3, 3],
            axis4=frames[..., 4, :3, 2],
            axis6=frames[..., 6, :3, 2],
            arm_forward=frames[..., 1, :3, 0],
            elbow_center=shoulder + self.d4 * frames[..., 2, :3, 2],
            cylinder_radius=self.d4,
            elbow_radii=(self.a2 + self.a3, abs(self.a2 - self.a3)),
        )

    def singular_configuration(self, kind: str, q) -> np.ndarray:
        """Joints ``q`` changed as little as needed to sit exactly on one singularity (docs/kinematics.md §5).

        * ``"elbow"``: θ3 = 0 (or the whole turn of it nearest θ3), the arm stretched (s3 = 0).
        * ``"wrist"``: θ5 = 0 (or the whole turn of it nearest θ5), axes 4 and 6 parallel (s5 = 0).
        * ``"shoulder"``: θ4 chosen so that ``a2 c2 + a3 c23 − d5 s234 = 0`` (P5 on the d4
          cylinder); if no θ4 can do it for these θ2, θ3, θ2 is first turned so that
          ``a2 c2 + a3 c23 = 0`` and then s234 = 0.

        Where two angles would do, the one nearest the current angle is taken.
        Returns a new joint vector of shape (6,) or (..., 6) like ``q``.

        >>> from ur10core import Arm
        >>> arm = Arm.preset("course")
        >>> q = arm.singular_configuration("shoulder", np.radians([30, 45, 26, 50, 60, 80]))
        >>> abs(float(arm.singularity_factors(q)[0])) < 1e-12
        True
        """
        q = joint_vector(q).copy()
        if kind == "elbow":
            q[..., 2] = _ik.equivalent_near(0.0, q[..., 2], JOINT_LIMIT)
        elif kind == "wrist":
            q[..., 4] = _ik.equivalent_near(0.0, q[..., 4], JOINT_LIMIT)
        elif kind == "shoulder":
            t2, t3 = q[..., 1], q[..., 2]
            ratio = (self.a2 * np.cos(t2) + self.a3 * np.cos(t2 + t3)) / self.d5
            feasible = np.abs(ratio) <= 1.0
            # otherwise turn θ2 so the upper arm and forearm together reach nowhere along x1
            c3, s3 = np.cos(t3), np.sin(t3)
            t2_zero = np.arctan2(self.a2 + self.a3 * c3, self.a3 * s3)
            t2_zero = _ik.equivalent_near(np.stack([t2_zero, t2_zero + math.pi], -1), t2[..., None], JOINT_LIMIT)
            t2_zero = np.take_along_axis(t2_zero, np.argmin(np.abs(t2_zero - t2[..., None]), -1)[..., None], -1)[..., 0]
            t2 = np.where(feasible, t2, t2_zero)
            s234_target = np.where(feasible, np.clip(ratio, -1.0, 1.0), 0.0)
            candidates = np.stack([np.arcsin(s234_target), math.pi - np.arcsin(s234_target)], -1)
            current_234 = (q[..., 1] + q[..., 2] + q[..., 3])[..., None]
            candidates = _ik.equivalent_near(candidates, current_234, np.inf)
            pick = np.argmin(np.abs(candidates - current_234), -1)[..., None]
            t234 = np.take_along_axis(candidates, pick, -1)[..., 0]
            q[..., 1] = t2
            q[..., 3] = _ik.equivalent_near(t234 - t2 - t3, q[..., 3], JOINT_LIMIT)
        else:
            raise ValueError(f"kind must be 'shoulder', 'elbow' or 'wrist', got {kind!r}")
        return q

    # ------------------------------------------------------------------ workspace

    def sample_workspace(self, n: int, seed: int = 0, return_joints: bool = False):
        """Flange positions of ``n`` random joint vectors and their manipulability.

        θ1..θ5 are drawn uniformly from (−π, π] (θ6 moves neither the flange origin nor
        det J, so it is 0); positions come from the closed form of docs/kinematics.md §3 and
        the manipulability is ``|det J| = |a2 a3 (a2 c2 + a3 c23 − d5 s234) s3 s5|`` (§5).
        The same ``n`` and ``seed`` always give the same cloud, on any number of threads.

        Returns
        -------
        points : ndarray, shape (n, 3)
            Metres, base frame.
        manipulability : ndarray, shape (n,)
            |det J| in m³.
        joints : ndarray, shape (n, 6)
            Only with ``return_joints=True``: the joint vectors sampled.
        """
        n, seed = sample_size(n, seed)
        points = np.empty((n, 3))
        manipulability = np.empty(n)
        joints = np.zeros((n, 6)) if return_joints else None
        block = 65536
        starts = range(0, n, block)
        streams = np.random.SeedSequence(seed).spawn(len(starts))

        def run(index: int) -> None:
            start = starts[index]
            stop = min(start + block, n)
            q = np.random.default_rng(streams[index]).uniform(-math.pi, math.pi, (5, stop - start))
            np.negative(q, out=q)  # uniform on (-π, π], the joint-angle convention
            self._positions_and_det(q, points[start:stop], manipulability[start:stop])
            if joints is not None:
                joints[start:stop, :5] = q.T

        if len(starts) > 1:
            list(_ik._pool().map(run, range(len(starts))))
        else:
            run(0)
        if return_joints:
            return points, manipulability, joints
        return points, manipulability

    def _positions_and_det(self, q: np.ndarray, points: np.ndarray, det_out: np.ndarray) -> None:
        c = np.cos(q)
        s = np.sin(q)
        c1, c2, c3, c4, c5 = c
        s1, s2, s3, s4, s5 = s
        c23, s23 = c2 * c3 - s2 * s3, s2 * c3 + c2 * s3
        c234, s234 = c23 * c4 - s23 * s4, s23 * c4 + c23 * s4
        reach = self.a2 * c2 + self.a3 * c23 - self.d5 * s234
        s5c234 = s5 * c234
        points[:, 0] = c1 * reach + self.d4 * s1 + self.d6 * (s1 * c5 + c1 * s5c234)
        points[:, 1] = s1 * reach - self.d4 * c1 - self.d6 * (c1 * c5 - s1 * s5c234)
        points[:, 2] = self.a2 * s2 + self.a3 * s23 + self.d1 + self.d5 * c234 + self.d6 * s5 * s234
        np.abs(self.a2 * self.a3 * reach * s3 * s5, out=det_out)


class SeparationSteps(NamedTuple):
    """The UR family's IK replayed on one pose, step by step, on the arm's own branch (:func:`separation_steps`).

    Lengths in metres, angles in radians; steps as docs/kinematics.md §4.1 numbers them.
    """

    p5: np.ndarray  #: (3,) step 1: the wrist-2 point P5 = p − d6 z6
    rho: float  #: step 1: P5's distance from the base axis, at least d4 (else no θ1)
    reach: float  #: step 1: A, P5's reach along x1 in the arm plane, ±√(ρ² − d4²): its sign is the shoulder
    theta1: tuple[float, float]  #: step 1: θ1 for A ≤ 0 (shoulder left) and for A ≥ 0 (right)
    c5: float  #: step 2: c5 = z4·z6 = r13 s1 − r23 c1, so θ5 = ±acos(c5)
    theta5: float  #: step 2: the sign of the arm's wrist
    theta6: float  #: step 3: from s5 c6 = r21 c1 − r11 s1, −s5 s6 = r22 c1 − r12 s1 (the arm's own where s5 = 0)
    theta234: float  #: step 4: from c234 s5 = r13 c1 + r23 s1, s234 s5 = r33 (the arm's θ2 + θ3 + θ4 where s5 = 0)
    wrist_singular: bool  #: s5 = 0 (to :data:`~ur10core.tolerances.WRIST_TOLERANCE`): steps 3 and 4 fix only θ234 ± θ6
    frame4: tuple[float, float]  #: step 5: (h4, v4) = (A + d5 s234, P5z − d1 − d5 c234), the frame-4 origin from the shoulder
    r: float  #: step 5: its distance from the shoulder, within |a2 − a3| … a2 + a3
    c3: float  #: step 5: (r² − a2² − a3²) / (2 a2 a3), so θ3 = ±acos(c3)
    theta2: float  #: step 5: atan2(v4, h4) − atan2(a3 s3, a2 + a3 c3)
    theta3: float  #: step 5: the sign of the arm's elbow
    theta4: float  #: step 5: θ234 − θ2 − θ3
    slot: int  #: k = 4 i + 2 j + l, the IK slot of the arm's branch (``arm.slot_labels[k]``)


def shoulder_angles(point: np.ndarray, d4: float) -> tuple[float, float]:
    """Both θ1 (rad; shoulder left, then right) that put ``point`` (3,) in the arm's plane, which passes ``d4``
    from the base axis: the IK's step 1 for P5 (docs/kinematics.md §4.1), ``py5 c1 − px5 s1 = −d4``, so that
    P5 = A x1 + d4 (s1, −c1). Where ``point`` is nearer the base axis than d4 (for P5, only by rounding), the two
    are one.

    >>> np.degrees(shoulder_angles(np.array([0.0, -0.5, 0.0]), 0.5)).round(6).tolist()   # on the circle: one θ1
    [0.0, 0.0]
    """
    x, y = float(point[0]), float(point[1])
    tangent = math.sqrt(max(x * x + y * y - d4 * d4, 0.0))
    left, right = (math.atan2(y * A + x * d4, x * A - y * d4) for A in (-tangent, tangent))
    return left, right


def separation_steps(arm: "Arm", q, frames: np.ndarray | None = None) -> SeparationSteps:
    """The course's IK of a UR-family arm (docs/kinematics.md §4.1) replayed on its own pose T06(q), one step at a time.

    The UR wrist is not spherical, so the pose does not split at a wrist centre: the course separates the variables.
    P5 = p − d6 z6 fixes θ1 (two tangents to the cylinder of radius d4), then θ5 = ±acos(r13 s1 − r23 c1), θ6 and
    θ234 from R, and joints 2–3 as a planar two-link arm reaching the frame-4 origin. Each choice is made as the
    arm's own joints make it, so the steps end at ``q`` (angles wrapped to (−π, π]); ``slot`` is that branch's
    IK slot. ``frames``: ``arm.frames(q)``, where the caller has them. ``ValueError`` for an arm outside the UR
    family or ``q`` that is not one pose.

    >>> from ur10core import Arm
    >>> steps = separation_steps(Arm.preset("course"), np.radians([30, 45, 26, 50, 60, 80]))   # §3's third example
    >>> (1000 * steps.p5).round(1).tolist(), round(1000 * steps.rho, 1), round(1000 * steps.reach, 1)
    ([532.5, 118.2, 1042.3], 545.5, 520.3)
    >>> np.degrees([steps.theta1[1], steps.theta5, steps.theta6, steps.theta2, steps.theta3, steps.theta4]).round(6).tolist()
    [30.0, 60.0, 80.0, 45.0, 26.0, 50.0]
    >>> Arm.preset("course").slot_labels[steps.slot]
    'shoulder right, elbow down, wrist not flipped'
    """
    solver = arm.solver
    if not isinstance(solver, URFamily):
        raise ValueError(f"the separation of variables is the UR family's IK (course, ur10, ur10e), not {arm.name!r}'s")
    q = arm.joints(q)
    if q.shape != (6,):
        raise ValueError(f"q must be one pose of 6 joints, got shape {q.shape}")
    d1, a2, a3, d4, d5, d6 = solver.dh_lengths
    T = (arm.frames(q) if frames is None else frames)[-1]
    (r11, r12, r13), (r21, r22, r23), (r31, r32, r33) = T[:3, :3].tolist()
    p5 = T[:3, 3] - d6 * T[:3, 2]
    x5, y5, z5 = p5.tolist()
    rho = math.hypot(x5, y5)
    theta1 = shoulder_angles(p5, d4)
    c1, s1 = math.cos(q[0]), math.sin(q[0])
    reach = x5 * c1 + y5 * s1  # P5 = A x1 + d4 (s1, −c1): the arm's side of the two
    c5, c6s5, s6s5 = r13 * s1 - r23 * c1, r21 * c1 - r11 * s1, r12 * s1 - r22 * c1
    j = 0 if math.sin(q[4]) >= 0.0 else 1
    s5 = (1 - 2 * j) * math.hypot(c6s5, s6s5)  # as √(1 − c5²), but not lost to rounding where c5 = ±1
    theta5 = math.atan2(s5, c5)
    wrist_singular = abs(s5) <= WRIST_TOLERANCE
    if wrist_singular:  # only θ234 ± θ6 is fixed: the arm's own split
        theta6, theta234 = float(wrap(q[5])), float(wrap(q[1] + q[2] + q[3]))
    else:
        theta6 = math.atan2(s6s5 / s5, c6s5 / s5)
        theta234 = math.atan2(r33 / s5, (r13 * c1 + r23 * s1) / s5)
    h4, v4 = reach + d5 * math.sin(theta234), z5 - d1 - d5 * math.cos(theta234)
    r = math.hypot(h4, v4)
    c3 = min(1.0, max(-1.0, (r * r - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)))
    elbow = 0 if math.sin(q[2]) >= 0.0 else 1  # l of k = 4 i + 2 j + l
    theta3 = (1 - 2 * elbow) * math.acos(c3)
    theta2 = math.atan2(v4, h4) - math.atan2(a3 * math.sin(theta3), a2 + a3 * c3)
    return SeparationSteps(p5, rho, reach, theta1, c5, theta5, theta6, theta234, wrist_singular, (h4, v4), r, c3,
                           float(wrap(theta2)), theta3, float(wrap(theta234 - theta2 - theta3)),
                           4 * (1 if reach >= 0.0 else 0) + 2 * j + elbow)
